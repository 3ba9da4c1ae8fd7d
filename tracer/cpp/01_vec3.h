// Slide "Ex 25: Three Ray Traced Spheres" - support classes Vec3 and Color.
//
// All geometry is in double precision: the course asks for "all calculations in global
// coordinates", and global coordinates of a distant camera or a huge sphere need the 53-bit
// mantissa (see 05_sphere.h). Images leave the core as float32.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstring>

namespace rt {

struct Vec3 {
    double x = 0, y = 0, z = 0;

    Vec3() = default;
    constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

    // Component i (0: x, 1: y, 2: z), read from the struct's bytes at i doubles from its start:
    // one load, not two comparisons (the triangle test indexes by axis). Not (&x)[i]: a pointer
    // to x points to one double, not into an array of three, so stepping it to y is undefined
    // behaviour, and Clang 19 compiled the triangle test into one that returned NaN for t (every
    // mesh test failed; GCC happened to do what was meant, and no sanitizer reports it). Bytes
    // of an object may be read through unsigned char, and the layout is checked below.
    double operator[](int i) const {
        double v;
        std::memcpy(&v, reinterpret_cast<const unsigned char *>(this) + sizeof(double) * i,
                    sizeof v);
        return v;
    }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3 operator+(const Vec3 &v) const { return {x + v.x, y + v.y, z + v.z}; }
    Vec3 operator-(const Vec3 &v) const { return {x - v.x, y - v.y, z - v.z}; }
    Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
    // One division and three multiplications (a division costs several multiplications); the
    // result may differ from x / s by an ulp, which nothing here depends on.
    Vec3 operator/(double s) const {
        double inv = 1 / s;
        return {x * inv, y * inv, z * inv};
    }
};
// operator[]'s reading of component i at i doubles from the start.
static_assert(offsetof(Vec3, x) == 0 && offsetof(Vec3, y) == sizeof(double) &&
                  offsetof(Vec3, z) == 2 * sizeof(double),
              "Vec3 is three doubles side by side");

inline Vec3 operator*(double s, const Vec3 &v) { return v * s; }
inline double dot(const Vec3 &a, const Vec3 &b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3 &a, const Vec3 &b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(const Vec3 &v) { return std::sqrt(dot(v, v)); }
inline Vec3 normalize(const Vec3 &v) { return v / length(v); }
inline Vec3 abs(const Vec3 &v) { return {std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}; }

// Light is "linearly additive" (slide "Specular Reflected Light"): a colour is a triple of
// intensities that we add and scale; it is kept apart from Vec3 so the two are never mixed up.
struct Color {
    double r = 0, g = 0, b = 0;

    Color() = default;
    constexpr Color(double r_, double g_, double b_) : r(r_), g(g_), b(b_) {}

    Color operator+(const Color &c) const { return {r + c.r, g + c.g, b + c.b}; }
    Color &operator+=(const Color &c) {
        r += c.r;
        g += c.g;
        b += c.b;
        return *this;
    }
    // Component-wise product: a white light on a red material gives red.
    Color operator*(const Color &c) const { return {r * c.r, g * c.g, b * c.b}; }
    Color operator*(double s) const { return {r * s, g * s, b * s}; }
};

inline Color operator*(double s, const Color &c) { return c * s; }

} // namespace rt
