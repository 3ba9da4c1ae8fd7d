// Slide "Efficiency and Complexity": "Efficiency is a HUGE deal". The same classic algorithm as
// 10_classic.h, traced for a packet of rays_per_packet rays at once, so that each arithmetic
// step runs on all of them in one SIMD instruction (GCC/Clang vector extensions; AVX-512 holds
// 8 doubles).
//
// It serves scenes of spheres and planes only (Ex 25's objects; packets_serve() below); a scene
// with other objects is traced one ray at a time. Those objects are reached through a virtual
// hit() per object and ray, and boxes, meshes, cylinders and tori each test one ray in their own
// coordinates; packets of them would need a second copy of every one of those files, and the
// lecture's code is kept as one plain copy. This file adds speed, not behaviour: every step
// below is the step of 05_sphere.h, 06_plane.h, 09_scene.h and 10_classic.h with the same
// operations in the same order (or fewer, where they provably give the same bits: the dot
// products with a normal that is an axis, dot_unit()), and the shared steps of 04_hit.h
// (face_the_ray(), secondary_ray(), shadow_ray_to(), shadow_ray_towards()) keep their names as
// overloads, so each lane computes bit for bit what the one-ray code computes (IEEE-754 add,
// mul, div and sqrt are correctly rounded in vector units too, and the build forbids fused
// multiply-add contraction). tests/tracer/test_packet.py renders every canonical scene of
// spheres and planes both ways and requires equal images, and compares packets' colours with
// single rays' in double precision (the binding Scene.trace_packet). Where lanes disagree (one
// hits a sphere, the next a plane), masks choose per lane; a lane whose ray has finished is
// masked off until the whole packet is done.
#pragma once

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include <immintrin.h>

#include "01_vec3.h"
#include "02_ray.h"
#include "03_camera.h"
#include "04_hit.h"
#include "05_sphere.h"
#include "06_plane.h"
#include "07_material.h"
#include "08_light.h"
#include "09_scene.h"
#include "11_render.h"
#include "14_box.h"
#include "constants.h"
#include "power.h"

namespace rt {

// Whether the packet tracer serves this scene: spheres and planes only (see above).
inline bool packets_serve(const Scene &scene) { return scene.objects.empty(); }

// rays_per_packet, Lanes and Mask are declared in power.h, which both tracers share.
inline Lanes splat(double v) { return broadcast<Lanes>(v); }
inline Mask mask_all(bool v) { return Mask{} + (v ? -1 : 0); }
// The lanes of a mask as the bits of an integer (lane k is bit k). The packet tracer asks
// "does any lane still need this?" before every costly step; written as a loop over the lanes,
// the compiler pulled each lane out of the vector register one by one and that question took
// a quarter of Ex 25's time (perf, issue 12). One instruction answers it: AVX-512's
// vptestmq, or AVX's vmovmskpd on each half; other machines keep the loop.
inline unsigned lane_bits(Mask m) {
#if defined(__AVX512F__)
    constexpr int per = sizeof(__m512i) / sizeof(int64_t);
    __m512i v[rays_per_packet / per];
#elif defined(__AVX__)
    constexpr int per = sizeof(__m256d) / sizeof(int64_t);
    __m256d v[rays_per_packet / per];
#endif
#if defined(__AVX512F__) || defined(__AVX__)
    static_assert(sizeof v == sizeof m);
    std::memcpy(&v, &m, sizeof m);
    unsigned b = 0;
    for (int h = 0; h < rays_per_packet / per; ++h)
#if defined(__AVX512F__)
        b |= unsigned(_mm512_test_epi64_mask(v[h], v[h])) << (per * h);
#else
        b |= unsigned(_mm256_movemask_pd(v[h])) << (per * h); // a true lane's sign bit is set
#endif
    return b;
#else
    unsigned b = 0;
    for (int k = 0; k < rays_per_packet; ++k) b |= unsigned(m[k] != 0) << k;
    return b;
#endif
}
inline int count(Mask m) { return __builtin_popcount(lane_bits(m)); }
// The first n lanes, by one comparison. (Set lane by lane, the mask was eight stores that the
// vector load of it after them could not take from the store buffer: a render of Ex 25's camera
// with no objects took 9.8 ms that way and 7.7 ms this way, issue 12.)
template <size_t... k> constexpr Mask lane_numbers(std::index_sequence<k...>) {
    return Mask{int64_t(k)...};
}
inline Mask first_lanes(int n) {
    constexpr Mask lane = lane_numbers(std::make_index_sequence<rays_per_packet>{}); // 0, 1, ...
    return lane < n;
}
inline bool any(Mask m) { return lane_bits(m) != 0; }

// Which lanes of a packet a condition holds in, as the packet tracer keeps it between its steps.
// Comparing two Lanes gives a Mask, a 64-bit integer a lane (all ones where true). With
// AVX-512 a comparison writes one bit a lane into a mask register instead, which the blends
// (select()) and the tests (any()) read as it is; but Clang keeps a Mask there only within one
// block of straight code. The packet tracer branches at every any(), and at each branch a Mask
// still needed went back into a vector register (a zeroing move) and came out of it again after
// (vptestmq): some 50 of the 650 operations a floor packet of Ex 25 issues on ports 0 and 5,
// the ports that bound it on the Intel Xeon, and a vector register held for each mask live
// across the loops over objects and lights. A vector of bools, Clang's type for one bit a lane,
// stays in a mask register from block to block: Ex 25 1.063x [1.054-1.074] on one thread of the
// Xeon and 1.058x on two (9 alternating rounds, the same bits; a floor packet 1,288 instructions
// to 1,224). GCC has no such type, and a machine without AVX-512 no mask registers: there a
// LaneMask holds the Mask, as before. (Issue 12.)
struct LaneMask {
#if defined(__clang__) && defined(__AVX512F__)
    typedef bool Bits __attribute__((ext_vector_type(rays_per_packet)));
    Bits bits;
    explicit LaneMask(Bits b) : bits(b) {}
    LaneMask(Mask m) : bits(__builtin_convertvector(m != 0, Bits)) {}
    // As a Mask: all ones where true (a bool converts to 1).
    Mask mask() const { return Mask{} - __builtin_convertvector(bits, Mask); }
    unsigned lanes() const { return __builtin_bit_cast(uint8_t, bits); }
    void set(int k, bool v) { bits[k] = v; }
#else
    typedef Mask Bits;
    Bits bits;
    LaneMask(Mask m) : bits(m) {}
    Mask mask() const { return bits; }
    unsigned lanes() const { return lane_bits(bits); }
    void set(int k, bool v) { bits[k] = v ? -1 : 0; }
#endif
    LaneMask() = default;
    LaneMask operator&(LaneMask m) const { return LaneMask(Bits(bits & m.bits)); }
    LaneMask operator|(LaneMask m) const { return LaneMask(Bits(bits | m.bits)); }
    LaneMask operator~() const { return LaneMask(Bits(~bits)); }
    LaneMask &operator&=(LaneMask m) { return *this = *this & m; }
    LaneMask &operator|=(LaneMask m) { return *this = *this | m; }
};
inline LaneMask operator&(const Mask &a, LaneMask b) { return LaneMask(a) & b; }
inline unsigned lane_bits(LaneMask m) { return m.lanes(); }
inline int count(LaneMask m) { return __builtin_popcount(m.lanes()); }
inline bool any(LaneMask m) { return m.lanes() != 0; }
inline Lanes select(LaneMask m, Lanes a, Lanes b) { return m.mask() ? a : b; }

// Each lane's correctly rounded square root, as std::sqrt gives it. Written as a loop over the
// lanes, GCC vectorised it at its preferred width, 256 bits on Intel even with AVX-512: two
// vsqrtpd on ymm halves stored to the stack and read back as one zmm, a load that cannot be
// forwarded from two stores, and the stall held the instruction after a point light's
// normalisation at 12% of trace_level's time on Ex 25 (perf, issue 12). So one instruction where
// the machine has it; elsewhere the loop, which needs -fno-math-errno (no errno check per lane).
inline Lanes sqrt(Lanes x) {
#if defined(__AVX512F__)
    static_assert(sizeof(Lanes) == sizeof(__m512d));
    __m512d v;
    std::memcpy(&v, &x, sizeof v);
    // Not _mm512_sqrt_pd: GCC 12 warns on its undefined source.
    v = _mm512_mask_sqrt_pd(v, __mmask8(0xff), v);
    std::memcpy(&x, &v, sizeof v);
    return x;
#else
    Lanes r;
    for (int k = 0; k < rays_per_packet; ++k) r[k] = std::sqrt(x[k]);
    return r;
#endif
}
inline Lanes fabs(Lanes x) {
    Mask bits;
    std::memcpy(&bits, &x, sizeof x);
    bits &= Mask{} + INT64_MAX; // clear the sign bit
    std::memcpy(&x, &bits, sizeof x);
    return x;
}
inline Lanes copysign(Lanes magnitude, Lanes sign) {
    Mask m, s;
    std::memcpy(&m, &magnitude, sizeof m);
    std::memcpy(&s, &sign, sizeof s);
    const Mask sign_bit = Mask{} + INT64_MIN;
    m = (m & ~sign_bit) | (s & sign_bit);
    std::memcpy(&magnitude, &m, sizeof m);
    return magnitude;
}

struct Vec3L {
    Lanes x, y, z;
    Vec3L operator-() const { return {-x, -y, -z}; }
    Vec3L operator+(const Vec3L &v) const { return {x + v.x, y + v.y, z + v.z}; }
    Vec3L operator-(const Vec3L &v) const { return {x - v.x, y - v.y, z - v.z}; }
    Vec3L operator*(Lanes s) const { return {x * s, y * s, z * s}; }
    Vec3L operator/(Lanes s) const { // as Vec3::operator/
        Lanes inv = 1 / s;
        return {x * inv, y * inv, z * inv};
    }
    void set(int k, const Vec3 &v) { x[k] = v.x, y[k] = v.y, z[k] = v.z; } // lane k
};
inline Vec3L splat(const Vec3 &v) { return {splat(v.x), splat(v.y), splat(v.z)}; }
inline Lanes dot(const Vec3L &a, const Vec3L &b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3L normalize(const Vec3L &v) { return v / sqrt(dot(v, v)); }
inline Vec3L abs(const Vec3L &v) { return {fabs(v.x), fabs(v.y), fabs(v.z)}; }
inline Vec3L select(LaneMask m, const Vec3L &a, const Vec3L &b) {
    return {select(m, a.x, b.x), select(m, a.y, b.y), select(m, a.z, b.z)};
}

// A normal that is a coordinate axis, as Ex 25's floor's (0, 1, 0): its dot product with a vector
// v is v.x * 0 + v.y * 1 + v.z * 0 in 06_plane.h and 10_classic.h. For finite v (every ray,
// point and error bound the tracer makes is finite) the two zero terms are zeros, and adding a
// zero changes a sum only where the sum is zero itself, and then only in the sign of that zero.
// So where the packet tracer takes of such a dot product only its sign (plane_t()'s t > 0, the
// sides of face_the_ray() and leaving_origin()), or its value where it is not zero (a light's
// N.L where it is > 0, reflect()'s d.N for a ray that met the plane and so is not parallel to
// it), v.y alone gives the same bits as dot()'s five operations; and with error bounds, whose
// coordinates are never below 0, dot(abs(N), p_error) is p_error.y exactly (away_origin()). A
// floor packet of Ex 25 takes some fifteen such dot products a level: its own, its shadow rays'
// and its reflection's with the floor's normal, and their tests of the floor. Each a coordinate
// instead of five operations on the two ports that bound a floor packet: Ex 25 1.060x
// [1.037-1.093] on one thread of the Intel Xeon and 1.051x [1.010-1.094] on two (9 alternating
// rounds, the same bits). The axis is found once, where the scene is made (Plane::axis): found
// at each test of the plane, from the normal's coordinates, it gave back a third of that
// (issue 12).
// unit_axis(): k where n is the unit vector of axis k (1 there, 0 elsewhere), or -1.
inline int unit_axis(const Vec3 &n) {
    for (int k = 0; k < 3; ++k)
        if (n[k] == 1 && n[(k + 1) % 3] == 0 && n[(k + 2) % 3] == 0) return k;
    return -1;
}
// dot(v, n) for such uses, where n is the unit vector of `axis` (unit_axis()); dot() itself
// where axis is -1.
inline Lanes dot_unit(const Vec3L &v, int axis, const Vec3L &n) {
    switch (axis) {
    case 0: return v.x;
    case 1: return v.y;
    case 2: return v.z;
    default: return dot(v, n);
    }
}

struct ColorL {
    Lanes r, g, b;
};
inline ColorL operator*(const ColorL &c, Lanes s) { return {c.r * s, c.g * s, c.b * s}; }
inline ColorL operator*(const ColorL &a, const ColorL &c) {
    return {a.r * c.r, a.g * c.g, a.b * c.b};
}
inline ColorL splat(const Color &c) { return {splat(c.r), splat(c.g), splat(c.b)}; }
// color += m ? add : 0, as `color += add` only in the lanes of m.
inline void add_where(LaneMask m, ColorL &color, const ColorL &add) {
    color.r = select(m, color.r + add.r, color.r);
    color.g = select(m, color.g + add.g, color.g);
    color.b = select(m, color.b + add.b, color.b);
}

struct RayL {
    Vec3L o, d;
    void set(int k, const Ray &r) { o.set(k, r.o), d.set(k, r.d); } // lane k
};

// 05_sphere.h sphere_t(), per lane: the nearest root in (0, max), or infinity. Most packets
// miss most spheres: when no live lane has a real root ahead, the roots' two divisions and the
// square root are skipped (they cost more than all the rest).
inline Lanes sphere_t(const Sphere &s, const RayL &ray, Lanes a, Lanes inv_a, Lanes max,
                      LaneMask active) {
    // BEGIN SOLUTION L13
    // PROMPT: The packet tracer's copy of 05_sphere.h sphere_t() with the robust quadratic, one ray
    // PROMPT: per lane: not part of the exercise, hidden until lessons L02 and L13 are done (the
    // PROMPT: lessons use the one-ray tracer).
    const Lanes inf = splat(infinity);
    Vec3L f = ray.o - splat(s.center);
    Lanes b = dot(f, ray.d);
    double r2 = s.radius * s.radius;
    Lanes c0 = dot(f, f) - r2;
    LaneMask away = (c0 > 0) & (b > 0);
    if (!any(active & ~away)) return inf;
    Vec3L l = f - ray.d * (b * inv_a);
    Lanes D = a * (r2 - dot(l, l));
    if (!any(active & ~away & (D >= 0))) return inf;
    Lanes q = -(b + copysign(sqrt(D), b));
    Lanes t0 = c0 / q, t1 = q * inv_a;
    LaneMask swap = t0 > t1;
    Lanes lo = select(swap, t1, t0), hi = select(swap, t0, t1);
    Lanes t = select((lo > 0) & (lo < max), lo, select((hi > 0) & (hi < max), hi, inf));
    return select(away | (D < 0) | (q == 0), inf, t);
    // END SOLUTION
}

// 06_plane.h plane_t(), per lane.
inline Lanes plane_t(const Plane &pl, const RayL &ray) {
    // BEGIN SOLUTION L03
    // PROMPT: The packet tracer's copy of 06_plane.h plane_t(), one ray per lane: not part of the
    // PROMPT: exercise, hidden until lesson L03 is done (the lessons use the one-ray tracer).
    const int axis = pl.axis; // dot_unit(): t is taken only where t > 0
    const Vec3L n = splat(pl.normal);
    Lanes denom = dot_unit(ray.d, axis, n);
    Lanes t = dot_unit(splat(pl.point) - ray.o, axis, n) / denom;
    return select(denom == 0, splat(infinity), t);
    // END SOLUTION
}

// The lanes whose ray may meet the plane at some t > 0: where plane_t()'s numerator and
// denominator are non-zero and of one sign. Elsewhere its quotient is <= 0 or NaN, or replaced by
// infinity (denom == 0), and no test here takes it (each asks t > 0, and t < a bound, which
// infinity never is). So a packet with no such lane skips plane_t() and its division; the two
// dot products are plane_t()'s own expressions, so their bits too. Ex 25's shadow rays
// leave the floor and the spheres upward, and the spheres' reflections mostly so: skipping
// those divisions, 1.02x on one and two Zen 4 threads (five and seven alternating rounds,
// Clang 19; tried before with GCC 12's build and lane-by-lane pixel stores, it had gained
// nothing; issue 12).
inline Mask may_be_ahead(const Plane &pl, const RayL &ray) {
    const int axis = pl.axis; // their signs: dot_unit()
    const Vec3L n = splat(pl.normal);
    const Lanes denom = dot_unit(ray.d, axis, n), num = dot_unit(splat(pl.point) - ray.o, axis, n);
    return ((num > 0) & (denom > 0)) | ((num < 0) & (denom < 0));
}

// The image points, in pixel units, that a set of rays passes through lie in [x0, x1] x [y0, y1].
struct ImageSpan {
    double x0, x1, y0, y1;
};

// Whether no primary ray through an image point of `span` can meet plane `pl`: may_be_ahead()
// is false in every lane of every packet of them. Its numerator, dot(point - eye, n), is the
// same number in every lane (every primary ray leaves the eye) and is computed here as there;
// where it is 0 (or NaN) no ray meets the plane. Otherwise a ray meets it only where its
// direction's dot product with n has the numerator's sign. The unnormalised direction,
// forward + right (x plane_width + window_shift) + true_up (y plane_height) (03_camera.h),
// depends affinely on the image point, and so does that dot product, which takes its extremes
// over the span at its corners. Where at every corner it has the other sign with a millionth of
// the size of its terms to spare (the normalisation and every rounding move the computed dot
// product by some ulps of those terms), no ray of the span meets the plane. The sky above Ex
// 25's floor is seen this way (render_tile_packets()).
inline bool plane_unseen(const Camera &cam, const Plane &pl, const ImageSpan &span) {
    const double num = dot(pl.point - cam.eye, pl.normal);
    if (!(num != 0)) return true;
    const double along = dot(cam.forward, pl.normal), across = dot(cam.right, pl.normal),
                 up = dot(cam.true_up, pl.normal);
    for (const double sx : {span.x0, span.x1})
        for (const double sy : {span.y0, span.y1}) {
            const double a = (sx / cam.width - 0.5) * cam.plane_width + cam.window_shift;
            const double b = (0.5 - sy / cam.height) * cam.plane_height;
            const double s = along + across * a + up * b;
            const double size = std::fabs(along) + std::fabs(across * a) + std::fabs(up * b);
            if (!((num > 0 ? -s : s) > 1e-6 * size)) return false;
        }
    return true;
}
// The centres of the pixels of columns [i0, i1) and rows [j0, j1).
inline ImageSpan pixel_centres(int i0, int i1, int j0, int j1) {
    return {i0 + 0.5, i1 - 0.5, j0 + 0.5, j1 - 0.5};
}

// The pixels whose primary rays may meet a box: a rectangle of the image, in pixel units (pixel
// (i, j) has its centre at (i + 0.5, j + 0.5)), or every pixel. A box wholly in front of the
// eye (every corner at positive depth along `forward`; then the eye is outside it) is seen
// through the convex hull of its corners' images on the image plane, so a ray through a pixel
// centre outside the rectangle around them misses the box. The rectangle is widened by two
// pixels, some twelve orders of magnitude more than the roundings of this projection and the
// slab test's widening of the box (2 gamma(3) of the distance, 14_box.h) move it, so no ray
// through a pixel outside it meets the box in any test here: skipping those rays' test
// changes nothing. 81% of the bunny's 1920 x 1024 primary rays miss its box; their packets'
// set-up (a normalisation and three divisions) was a tenth of the render (perf, issue 12).
// A sphere's rectangle is found exactly (sphere_rect()), and the packets of render_tile_packets()
// skip the spheres whose rectangles hold none of their pixels.
struct PixelRect {
    double i_min = -infinity, i_max = infinity, j_min = -infinity, j_max = infinity;

    // Whether a ray through some image point of `span` may meet it.
    bool may_meet(const ImageSpan &span) const {
        return span.x1 >= i_min && span.x0 <= i_max && span.y1 >= j_min && span.y0 <= j_max;
    }
    // Whether a ray through some pixel centre of columns [i0, i1) and rows [j0, j1) may meet it.
    bool may_meet(int i0, int i1, int j0, int j1) const {
        return may_meet(pixel_centres(i0, i1, j0, j1));
    }
};

// 03_camera.h primary_ray()'s d = forward + a right + b true_up solved for the image point, in
// pixel units: the column of a and the row of b (for one point, or a packet's lanes).
template <class T> T image_column(const Camera &cam, T a) {
    return ((a - cam.window_shift) * (1 / cam.plane_width) + 0.5) * cam.width;
}
template <class T> T image_row(const Camera &cam, T b) {
    return (0.5 - b * (1 / cam.plane_height)) * cam.height;
}

// A rectangle around image points widened by the margin (see above); every pixel where it is
// not finite.
inline PixelRect widened(PixelRect rect) {
    constexpr double margin = 2; // pixels
    rect.i_min -= margin, rect.i_max += margin, rect.j_min -= margin, rect.j_max += margin;
    if (!(rect.i_max - rect.i_min < infinity && rect.j_max - rect.j_min < infinity))
        return PixelRect{};
    return rect;
}

// Lanes k of corners first + k of a box (first a multiple of rays_per_packet): all ones where
// corner first + k takes the max on `axis`, which it does where bit `axis` of its number is set.
template <size_t... k> Mask corners_on(int first, int axis, std::index_sequence<k...>) {
    return Mask{((first + int(k)) >> axis & 1) != 0 ? int64_t(-1) : int64_t(0)...};
}

// The box's eight corners projected, a packet's lanes at once (all eight with AVX-512).
inline PixelRect pixel_rect(const Camera &cam, const AABB &box) {
    PixelRect rect{infinity, -infinity, infinity, -infinity};
    constexpr auto lanes = std::make_index_sequence<rays_per_packet>{};
    for (int first = 0; first < 8; first += rays_per_packet) {
        const Mask on_x = corners_on(first, 0, lanes), on_y = corners_on(first, 1, lanes),
                   on_z = corners_on(first, 2, lanes);
        const Vec3L c{on_x ? splat(box.max.x) : splat(box.min.x),
                      on_y ? splat(box.max.y) : splat(box.min.y),
                      on_z ? splat(box.max.z) : splat(box.min.z)};
        const Vec3L v = c - splat(cam.eye);
        const Lanes depth = dot(v, splat(cam.forward));
        if (any(~(depth > 0))) return PixelRect{}; // at or behind the eye (or not finite): all
        const Lanes inv = 1 / depth;
        const Lanes a = dot(v, splat(cam.right)) * inv, b = dot(v, splat(cam.true_up)) * inv;
        const Lanes i = image_column(cam, a), j = image_row(cam, b);
        for (int k = 0; k < rays_per_packet; ++k)
            rect.i_min = std::min(rect.i_min, i[k]), rect.i_max = std::max(rect.i_max, i[k]),
            rect.j_min = std::min(rect.j_min, j[k]), rect.j_max = std::max(rect.j_max, j[k]);
    }
    return widened(rect);
}

// The same for the convex hull of n points: where all lie in front of the eye, the hull (every
// point of it at positive depth too) is seen through the convex hull of their images.
inline PixelRect points_rect(const Camera &cam, const Vec3 *points, int n) {
    PixelRect rect{infinity, -infinity, infinity, -infinity};
    for (int k = 0; k < n; ++k) {
        const Vec3 v = points[k] - cam.eye;
        const double depth = dot(v, cam.forward);
        if (!(depth > 0)) return PixelRect{}; // at or behind the eye (or not finite): all
        const double i = image_column(cam, dot(v, cam.right) / depth),
                     j = image_row(cam, dot(v, cam.true_up) / depth);
        rect.i_min = std::min(rect.i_min, i), rect.i_max = std::max(rect.i_max, i);
        rect.j_min = std::min(rect.j_min, j), rect.j_max = std::max(rect.j_max, j);
    }
    return widened(rect);
}

// The pixels whose primary rays may meet a ball, exactly: a point x of it is seen at
// a = (x - eye).right / (x - eye).forward (and b likewise along true_up). The ball's points,
// taken along right and forward only, fill a disc of its radius around the centre's two
// coordinates (an orthogonal projection of a ball is a disc), and over a disc wholly in front
// of the eye (depth > radius) the ratio a takes its extremes on the two lines from the eye
// tangent to it: at the angles mid -+ half from forward, mid the centre's angle and
// sin(half) = radius / its distance. Not wholly in front, with a millionth of the distances to
// spare: every pixel. (The rectangle of its bounding box, which the spheres took until
// 2026-12-06, is 16% to 27% wider each way for Ex 25's spheres; with this one Ex 25's primary
// packets test a sphere 51,968 times a frame instead of 73,666. Issue 12.)
inline PixelRect sphere_rect(const Camera &cam, const Vec3 &centre, double radius) {
    const Vec3 v = centre - cam.eye;
    const double depth = dot(v, cam.forward);
    if (!(depth - radius > 1e-6 * (std::fabs(depth) + radius))) return PixelRect{};
    auto extent = [&](const Vec3 &across) { // the least and greatest ratio along `across`
        const double side = dot(v, across);
        const double mid = std::atan2(side, depth);
        const double half = std::asin(radius / std::hypot(side, depth));
        return std::pair{std::tan(mid - half), std::tan(mid + half)};
    };
    const auto [a_lo, a_hi] = extent(cam.right);
    const auto [b_lo, b_hi] = extent(cam.true_up);
    return widened({image_column(cam, a_lo), image_column(cam, a_hi), image_row(cam, b_hi),
                    image_row(cam, b_lo)});
}

// The same rectangles answer two more questions for a primary ray that meets a plane (Ex 25's
// floor, under most of the image), so that its reflected ray and its shadow rays skip the
// spheres they cannot meet:
// - Its reflected ray leaves the point p where it met the plane along the mirror image of its
//   direction, so it meets a sphere just where the primary ray, going on past p, would meet the
//   sphere's mirror image in the plane: the pixels of its reflection are those of the mirror
//   image (mirrored_rect()).
// - Its shadow ray runs from p to a point light (or towards a distant one). A sphere blocks it
//   only where the line from the light through p meets the sphere: inside the cone from a point
//   light that holds the sphere (half-angle asin(radius / distance)), or the cylinder around it
//   along a distant light's direction. A pyramid of `sides` faces around the cone (a prism around
//   the cylinder) holds it; where every edge of the pyramid meets the plane in front of the
//   light, each ray from the light through the pyramid meets the plane there too (its dot
//   product with the normal lies between the edges'), and the pyramid's section is the convex
//   polygon of those `sides` points (a central projection from the light onto the plane, or for
//   the prism a parallel one, keeps convex sets convex). The pixels that see that polygon are
//   those of the rectangle around its corners' images (shadow_rect()). Otherwise (a sphere up
//   to or above a point light's height, a light in the plane): every pixel. Around Ex 25's
//   spheres these rectangles are 39% to 64% as wide as those of the eight corners of their
//   bounding boxes' shadows, which the spheres took until 2026-12-06, and the floor's primary
//   packets test their shadow rays against a sphere 23,549 times a frame instead of 67,261. With
//   sphere_rect(): Ex 25 1.004x and 1.022x on one thread (build_ab, 9 and 11 rounds), 1.015x in
//   a harness of the core's headers, 0.993x on two (9 rounds): the tests left out were mostly
//   those that sphere_t()'s first early out ends (issue 12).
// The rays traced differ from these exact ones by the roundings of the hit point, of its offset
// (02_ray.h offset_ray_origin(), some ulps of the point) and of the direction, and sphere_t()
// finds a ray's miss by some ulps of the distances: the cone is widened by a millionth of a
// radian and the cylinder by a millionth of its radius and length, both far inside the
// two-pixel margin, so a skipped test is one that would find nothing (the images are compared
// with the one-ray tracer's, bit for bit, tests/tracer/test_packet.py). Where the polygon
// reaches more than a million times the light's distance from the sphere (a cone that grazes
// the plane), every pixel, so that the polygon's points stay within that reach.
inline PixelRect mirrored_rect(const Camera &cam, const Plane &pl, const Sphere &sp) {
    const Vec3 &n = pl.normal; // unit length
    return sphere_rect(cam, sp.center - n * (2 * dot(sp.center - pl.point, n)), sp.radius);
}

inline PixelRect shadow_rect(const Camera &cam, const Plane &pl, const Light &light,
                             const Sphere &sp) {
    constexpr int sides = 16;       // the polygon's corners lie 2% outside the cone's circle
    constexpr double spare = 1e-6;  // radians, or of the cylinder's radius and length (above)
    constexpr double reach = 1e6;   // of the light's distance (above)
    const Vec3 &n = pl.normal;
    const bool point = light.type == Light::Type::point;
    Vec3 axis;          // from the light through the sphere
    double spread = 0;  // a corner's distance from the axis: per unit along it, or for a prism
    double far = 0;     // how far from the sphere's centre a corner may lie
    if (point) {
        const Vec3 w = sp.center - light.position;
        const double distance = length(w);
        if (!(distance > sp.radius * (1 + spare))) return PixelRect{}; // the light in the ball
        axis = w / distance;
        const double half = std::asin(sp.radius / distance) + spare;
        spread = std::tan(half) / std::cos(pi / sides);
        far = reach * distance;
    } else {
        axis = light.direction;
        const double travel = std::fabs(dot(pl.point - sp.center, n) / dot(axis, n));
        spread = (sp.radius + spare * (sp.radius + travel)) / std::cos(pi / sides);
        far = reach * (sp.radius + travel);
    }
    // Two unit vectors perpendicular to the axis and to each other.
    const Vec3 e1 = normalize(cross(axis, std::fabs(axis.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}));
    const Vec3 e2 = cross(axis, e1);
    Vec3 corners[sides];
    for (int k = 0; k < sides; ++k) {
        const double angle = 2 * pi * k / sides;
        const Vec3 out = (e1 * std::cos(angle) + e2 * std::sin(angle)) * spread;
        const Vec3 from = point ? light.position : sp.center + out;
        const Vec3 along = point ? axis + out : axis;
        const double t = dot(pl.point - from, n) / dot(along, n);
        if (!(point ? t > 0 : std::isfinite(t))) return PixelRect{}; // an edge misses the plane
        corners[k] = from + along * t;
        if (!(length(corners[k] - sp.center) < far)) return PixelRect{};
    }
    return points_rect(cam, corners, sides);
}

// Whether sphere `b` can block no shadow ray that leaves sphere `a` for the light: for a point
// light, where no line from the light meets both (the angle between the centres, seen from the
// light, is more than the two spheres' angular radii: the cones do not overlap), or where all
// of `a` is nearer the light than all of `b`; for a distant light, where the two spheres'
// shadow cylinders do not overlap, or all of `a` is further towards the light than all of `b`.
// With a millionth to spare (of a radian, or of the distances), which covers the shadow ray's
// offset origin and every rounding here and in sphere_t() (a ray that misses a sphere by more
// than some ulps of its radius is not found to meet it, 05_sphere.h). Never for a == b.
inline bool cannot_shadow(const Sphere &a, const Sphere &b, const Light &light) {
    constexpr double spare = 1e-6;
    if (light.type == Light::Type::directional) {
        const Vec3 u = -light.direction, w = a.center - b.center;
        const double along = dot(w, u), across = length(w - u * along);
        const double apart = a.radius + b.radius + spare * (length(w) + a.radius + b.radius);
        return along > apart || across > apart;
    }
    const Vec3 va = a.center - light.position, vb = b.center - light.position;
    const double da = length(va), db = length(vb);
    if (!(da > a.radius * (1 + spare) && db > b.radius * (1 + spare))) return false; // inside
    if ((da + a.radius) * (1 + spare) < (db - b.radius) * (1 - spare)) return true;
    const double between = std::atan2(length(cross(va, vb)), dot(va, vb));
    return between > std::asin(a.radius / da) + std::asin(b.radius / db) + spare;
}

constexpr int max_culled = 32, max_culled_planes = 4, max_culled_lights = 8;

// What a render's packets may skip, built once a render (a few hundred operations a rectangle)
// for the first max_culled spheres, max_culled_planes planes and max_culled_lights lights: the
// image rectangles (render_tile_packets()) of each sphere (`seen`), of its mirror image in each
// plane, and of its shadow on each plane from each light; and for the points of each sphere, by
// each light, the spheres that cannot block their shadow rays (cannot_shadow(), bit b of
// unshadowing[a][l]), whatever ray met them.
struct PacketCulling {
    int spheres = 0, planes = 0, lights = 0;
    std::vector<PixelRect> seen, mirrored, shadowed; // [s], [k][s], [k][l][s]
    std::vector<unsigned> unshadowing;               // [a][l]

    explicit PacketCulling(const Scene &scene)
        : spheres(int(std::min<size_t>(scene.spheres.size(), max_culled))),
          planes(int(std::min<size_t>(scene.planes.size(), max_culled_planes))),
          lights(int(std::min<size_t>(scene.lights.size(), max_culled_lights))) {
        const Camera &cam = scene.camera;
        for (int s = 0; s < spheres; ++s) {
            const Sphere &sp = scene.spheres[size_t(s)];
            seen.push_back(sphere_rect(cam, sp.center, sp.radius));
        }
        for (int k = 0; k < planes; ++k)
            for (int s = 0; s < spheres; ++s)
                mirrored.push_back(mirrored_rect(cam, scene.planes[size_t(k)],
                                                 scene.spheres[size_t(s)]));
        for (int k = 0; k < planes; ++k)
            for (int l = 0; l < lights; ++l)
                for (int s = 0; s < spheres; ++s)
                    shadowed.push_back(shadow_rect(cam, scene.planes[size_t(k)],
                                                   scene.lights[size_t(l)],
                                                   scene.spheres[size_t(s)]));
        for (int a = 0; a < spheres; ++a)
            for (int l = 0; l < lights; ++l) {
                unsigned bits = 0;
                for (int b = 0; b < spheres; ++b)
                    if (b != a && cannot_shadow(scene.spheres[size_t(a)], scene.spheres[size_t(b)],
                                                scene.lights[size_t(l)]))
                        bits |= 1u << b;
                unshadowing.push_back(bits);
            }
    }

    // The spheres that cannot block a shadow ray to light l from a point of any of the spheres
    // of `met` (bit a for sphere a).
    unsigned cannot_block(unsigned met, int l) const {
        unsigned bits = ~0u;
        for (; met != 0; met &= met - 1)
            bits &= unshadowing[size_t(__builtin_ctz(met) * lights + l)];
        return bits;
    }
};

// A set of rectangles (one per sphere) sorted for a tile: the spheres no ray of the tile may
// meet (`skip`), and those some ray may (`maybe`), which each packet checks again.
struct TileBits {
    unsigned skip = 0, maybe = 0;
    void sort(const PixelRect *rects, int spheres, const ImageSpan &tile) {
        skip = maybe = 0;
        for (int s = 0; s < spheres; ++s) (rects[s].may_meet(tile) ? maybe : skip) |= 1u << s;
    }
    // The spheres no ray through the image points of `packet` (within the tile's) may meet.
    unsigned packet_skip(const PixelRect *rects, const ImageSpan &packet) const {
        unsigned bits = skip;
        for (unsigned m = maybe; m != 0; m &= m - 1) {
            const int s = __builtin_ctz(m);
            if (!rects[s].may_meet(packet)) bits |= 1u << s;
        }
        return bits;
    }
};

struct TileCulling {
    const PacketCulling &c;
    TileBits seen, mirrored[max_culled_planes], shadowed[max_culled_planes][max_culled_lights];

    // `span`: the image points of all the tile's primary rays.
    TileCulling(const PacketCulling &culling, const ImageSpan &span) : c(culling) {
        const int S = c.spheres;
        seen.sort(c.seen.data(), S, span);
        for (int k = 0; k < c.planes; ++k) {
            mirrored[k].sort(c.mirrored.data() + k * S, S, span);
            for (int l = 0; l < c.lights; ++l)
                shadowed[k][l].sort(c.shadowed.data() + (k * c.lights + l) * S, S, span);
        }
    }
};

// A packet of primary rays through the image points of `span` (within its tile's): the spheres
// its rays cannot meet, and, where every ray of it met plane k, those their reflections and
// their shadow rays to light l cannot meet (bit s for sphere s).
struct PrimaryPixels {
    const TileCulling &tile;
    ImageSpan span;

    int planes() const { return tile.c.planes; }
    int lights() const { return tile.c.lights; }
    unsigned seen() const { return tile.seen.packet_skip(tile.c.seen.data(), span); }
    unsigned reflected(int k) const {
        const PixelRect *rects = tile.c.mirrored.data() + k * tile.c.spheres;
        return tile.mirrored[k].packet_skip(rects, span);
    }
    unsigned shadowed(int k, int l) const {
        const PixelRect *rects = tile.c.shadowed.data() + (k * tile.c.lights + l) * tile.c.spheres;
        return tile.shadowed[k][l].packet_skip(rects, span);
    }
};

// 09_scene.h closest_hit(): per lane the closest t and which object: spheres are numbered 0,
// 1, ... and planes after them, -1 where nothing is hit. The numbers are kept in a vector of
// lanes, written by one select per object (a loop storing lane by lane cost more than the
// test it follows).
struct ClosestL {
    Lanes t;
    Mask id;
};

inline Mask select(LaneMask m, Mask a, Mask b) { return m.mask() ? a : b; }

// Whether `skip` holds every sphere of the scene. closest_hit() and any_hit() then leave out
// the spheres' set-up too: 1/(d.d), a division of eight lanes that no test takes. Nearly all of
// Ex 25's sky and floor packets skip every sphere at their first level, the floor's shadow rays
// and reflections too: four of a floor packet's eight divisions. On the Intel Xeon (a Sapphire
// Rapids-class core that reports Rocket Lake's model number) a 512-bit division holds the
// divider 16 cycles: Ex 25 1.049x [1.019-1.083] on one thread and 1.073x [1.061-1.096] on two
// (7 rounds, the same bits; reference/speed-log.md). On the Zen 4, whose divider is faster, the
// same change measured 0.984x in an older state of this code (within what a change's register
// allocation moves there).
inline bool every_sphere(const Scene &scene, unsigned skip) {
    const size_t n = scene.spheres.size();
    if (n > size_t(max_culled)) return false;
    const unsigned all = n == size_t(max_culled) ? ~0u : (1u << n) - 1;
    return (skip & all) == all;
}

// `skip`: bit i set where no ray of the packet can meet sphere i (i < 32; primary rays outside
// its image rectangle, render_tile_packets()): its test, which would find nothing, is left out
// (and counted all the same).
inline ClosestL closest_hit(const Scene &scene, const RayL &ray, LaneMask active, RayCounts &counts,
                            unsigned skip) {
    ClosestL c{splat(infinity), Mask{} - 1};
    counts.primitive_tests +=
        uint64_t(count(active)) * (scene.spheres.size() + scene.planes.size());
    if (!every_sphere(scene, skip)) {
        const Lanes a = dot(ray.d, ray.d), inv_a = 1 / a;
        for (size_t i = 0; i < scene.spheres.size(); ++i) {
            if (i < max_culled && (skip >> i & 1)) continue;
            Lanes t = sphere_t(scene.spheres[i], ray, a, inv_a, c.t, active);
            LaneMask closer = active & (t < c.t);
            if (!any(closer)) continue;
            c.t = select(closer, t, c.t);
            c.id = select(closer, Mask{} + int64_t(i), c.id);
        }
    }
    int64_t id = int64_t(scene.spheres.size()); // planes are numbered after the spheres
    for (size_t i = 0; i < scene.planes.size(); ++i, ++id) {
        if (!any(active & may_be_ahead(scene.planes[i], ray))) continue;
        Lanes t = plane_t(scene.planes[i], ray);
        LaneMask closer = active & (t > 0) & (t < c.t);
        if (!any(closer)) continue;
        c.t = select(closer, t, c.t);
        c.id = select(closer, Mask{} + id, c.id);
    }
    return c;
}

// 09_scene.h any_hit(), per lane, for the lanes of `active`. (Shadow rays to a point light all
// end at it: a lane whose ray leaves the cone in which the light sees a sphere, or a sphere
// outside the cone of the packet's rays, needs no test. Both were tried, with margins far
// above the roundings: they ruled out 2.6 of Ex 25's 3 sphere tests per packet of shadow rays
// and still cost more than the tests they saved: the packet's cone by its serial reductions,
// square roots and divisions (0.7x to 0.8x the speed), the per-lane one by its own work and
// branch (0.97x). The plane's division is skipped where no lane can have t > 0
// (may_be_ahead()); sphere_t()'s two early outs pay too: without them 0.7x. Issue 12. What
// pays is the same geometry worked out once a render instead of per packet: `skip`.)
// `skip`: as closest_hit()'s: the spheres that cannot shadow the points of the spheres the
// packet met, or for primary rays that all met a plane, the spheres whose shadow on it none of
// the packet's pixels sees (PacketCulling, PrimaryPixels).
// Counted as 09_scene.h counts: a lane's ray is tested against each object in turn until one
// blocks it, so it adds one test an object up to and including that one. Added up front for
// every object and taken back where an object blocks some lanes (for the objects after it),
// that is one count a call where nothing blocks (nearly every call: Ex 25's shadow rays are
// mostly lit) instead of one an object; a skipped sphere counts as a test that found nothing.
// Ex 25 1.017x [1.003-1.045] on one Xeon thread and 1.046x [1.005-1.071] on two (build_ab, 9
// rounds, the same image and counts; in a harness of these headers 1.020x, where leaving every
// count out altogether gave 1.029x). Issue 12.
inline LaneMask any_hit(const Scene &scene, const RayL &ray, Lanes max, LaneMask active,
                        RayCounts &counts, unsigned skip = 0) {
    LaneMask blocked = mask_all(false);
    const size_t objects = scene.spheres.size() + scene.planes.size();
    counts.primitive_tests += uint64_t(count(active)) * objects;
    if (!every_sphere(scene, skip)) {
        const Lanes a = dot(ray.d, ray.d), inv_a = 1 / a;
        for (size_t i = 0; i < scene.spheres.size(); ++i) {
            if (i < max_culled && (skip >> i & 1)) continue;
            const Sphere &s = scene.spheres[i];
            const LaneMask now = active & ~blocked &
                                 (sphere_t(s, ray, a, inv_a, max, active & ~blocked) != infinity);
            if (!any(now)) continue;
            counts.primitive_tests -= uint64_t(count(now)) * (objects - 1 - i); // not tested after
            blocked |= now;
            if (!any(active & ~blocked)) return blocked;
        }
    }
    for (size_t k = 0; k < scene.planes.size(); ++k) {
        const Plane &pl = scene.planes[k];
        if (!any(active & ~blocked & may_be_ahead(pl, ray))) continue;
        Lanes t = plane_t(pl, ray);
        const LaneMask now = active & ~blocked & (t > 0) & (t < max);
        if (!any(now)) continue;
        counts.primitive_tests -= uint64_t(count(now)) * (scene.planes.size() - 1 - k);
        blocked |= now;
        if (!any(active & ~blocked)) return blocked;
    }
    return blocked;
}

// 02_ray.h next_away() and offset_ray_origin(), per lane.
inline Lanes next_away(Lanes v, Lanes off) {
    Mask bits;
    std::memcpy(&bits, &v, sizeof v);
    Mask outward = (v > 0) == (off > 0);
    bits += outward ? Mask{} + 1 : Mask{} - 1;
    Lanes moved;
    std::memcpy(&moved, &bits, sizeof moved);
    Lanes tiny = select(off > 0, splat(DBL_TRUE_MIN), splat(-DBL_TRUE_MIN));
    return select(off == 0, v, select(v == 0, tiny, moved));
}

inline Vec3L offset_ray_origin(const Vec3L &p, const Vec3L &p_error, const Vec3L &N,
                               const Vec3L &toward) {
    // BEGIN SOLUTION L13
    // PROMPT: The packet tracer's copy of 02_ray.h offset_ray_origin(), per lane: not part of the
    // PROMPT: exercise, hidden until lesson L13 is done.
    Lanes d = dot(abs(N), p_error);
    Vec3L offset = N * d;
    offset = select(dot(toward, N) < 0, -offset, offset);
    Vec3L po = p + offset;
    return {next_away(po.x, offset.x), next_away(po.y, offset.y), next_away(po.z, offset.z)};
    // END SOLUTION
}

// The hit record of 05_sphere.h sphere_hit() and 06_plane.h plane_hit(), per lane (for spheres
// and planes the shading normal N is the geometric normal Ng).
struct HitL {
    Vec3L p, p_error, N, Ng;
    Mask material;
    unsigned spheres_met = 0; // bit s: some lane met sphere s (s < max_culled)
    bool others_met = false;  // some lane met a plane, or a sphere after those
    // Where every live lane met one plane whose normal (N and Ng in every lane) is an axis's
    // unit vector: that axis (unit_axis()); else -1.
    int axis = -1;
};

inline Vec3L select(LaneMask m, const Vec3 &a, const Vec3L &b) {
    return {select(m, splat(a.x), b.x), select(m, splat(a.y), b.y), select(m, splat(a.z), b.z)};
}

inline HitL hit_record(const Scene &scene, const RayL &ray, const ClosestL &c, LaneMask active) {
    // Each lane's object, by one select per object some lane hit: sphere centre and radius, or
    // plane point and normal.
    // 1/radius is selected too, a scalar division a sphere: sphere_hit()'s N = local / radius
    // is local * (1 / radius) (Vec3::operator/), so the same bits, and a sphere packet's
    // division fewer (Ex 25 1.015x and 1.020x on the Xeon's one and two threads, 7 rounds).
    Vec3L centre = {}, normal = {};
    Lanes radius = splat(1.0), inv_radius = splat(1.0);
    LaneMask is_sphere = mask_all(false);
    HitL h;
    h.material = Mask{};
    int64_t id = 0;
    for (const Sphere &s : scene.spheres) {
        const LaneMask here = active & (c.id == id++);
        if (!any(here)) continue;
        if (id - 1 < max_culled) h.spheres_met |= 1u << (id - 1);
        else h.others_met = true;
        centre = select(here, s.center, centre);
        radius = select(here, splat(s.radius), radius);
        inv_radius = select(here, splat(1 / s.radius), inv_radius);
        is_sphere |= here;
        h.material = select(here, Mask{} + s.material, h.material);
    }
    for (const Plane &pl : scene.planes) {
        const LaneMask here = active & (c.id == id++);
        if (!any(here)) continue;
        if (!any(active & ~here)) h.axis = pl.axis; // every live lane met this plane
        h.others_met = true;
        centre = select(here, pl.point, centre);
        normal = select(here, pl.normal, normal);
        h.material = select(here, Mask{} + pl.material, h.material);
    }
    Vec3L at = ray.o + ray.d * c.t;
    const bool spheres = any(active & is_sphere), planes = any(active & ~is_sphere);
    if (spheres) { // project onto the sphere
        Vec3L local = at - centre;
        Lanes len = sqrt(dot(local, local));
        const LaneMask degenerate = active & is_sphere & ~(len > 0); // as sphere_hit()
        if (any(degenerate)) {
            local = select(degenerate, -ray.d, local);
            len = select(degenerate, sqrt(dot(local, local)), len);
        }
        local = local * (radius / len);
        h.p = centre + local;
        h.p_error = abs(local) * splat(gamma(5)) + (abs(centre) + abs(local)) * splat(gamma(1));
        h.N = local * inv_radius;
    }
    if (planes) { // project back onto the plane
        Vec3L pp = at - normal * dot(at - centre, normal);
        Lanes e = (fabs(pp.x) + fabs(pp.y) + fabs(pp.z) + fabs(centre.x) + fabs(centre.y) +
                   fabs(centre.z)) *
                  gamma(8);
        if (!spheres) h.p = pp, h.p_error = {e, e, e}, h.N = normal;
        else {
            h.p = select(is_sphere, h.p, pp);
            h.p_error = select(is_sphere, h.p_error, Vec3L{e, e, e});
            h.N = select(is_sphere, h.N, normal);
        }
    }
    h.Ng = h.N;
    return h;
}

// 04_hit.h face_the_ray(), per lane. For spheres and planes hit.N is hit.Ng (hit_record()), and
// where no lane's Ng is turned round, N = (N.Ng < 0 ? -N : N) is N itself: N.N, a sum of
// squares, is never below 0. So a packet that sees only the outsides of spheres and the lit sides
// of planes (nearly all of Ex 25's) takes N as it is; elsewhere the lanes are faced as in
// 04_hit.h. Ex 25 1.021x [0.996-1.053] and 1.029x [0.992-1.202] on the Xeon's one and two
// threads (9 rounds; 1.022x and 0.998x in a first set of 7), the same bits (issue 12).
struct FacingL {
    Vec3L N, Ng;
    int axis = -1; // as HitL's
};
inline FacingL face_the_ray(const HitL &hit, const Vec3L &d) {
    // BEGIN SOLUTION L04
    // PROMPT: The packet tracer's copy of 04_hit.h face_the_ray(), one ray per lane: not part of
    // PROMPT: the exercise, hidden until lesson L04 is done (the lessons use the one-ray tracer).
    const LaneMask turned = dot_unit(d, hit.axis, hit.Ng) > 0; // its sign: dot_unit()
    if (!any(turned)) return {hit.N, hit.Ng, hit.axis};
    Vec3L Ng = select(turned, -hit.Ng, hit.Ng);
    Vec3L N = select(dot(hit.N, Ng) < 0, -hit.N, hit.N);
    return {N, Ng};
    // END SOLUTION
}

// 10_classic.h reflect(), per lane, for the rays that met the points of `f`.
inline Vec3L reflect(const Vec3L &d, const FacingL &f) {
    // BEGIN SOLUTION L06
    // PROMPT: The packet tracer's copy of 10_classic.h reflect(), one ray per lane: not part of the
    // PROMPT: exercise, hidden until lesson L06 is done (the lessons use the one-ray tracer).
    return d - f.N * (2 * dot_unit(d, f.axis, f.N)); // not 0 where d met a plane: dot_unit()
    // END SOLUTION
}

// 04_hit.h secondary_ray(), shadow_ray_to() and shadow_ray_towards(), and 10_classic.h
// shadow_ray() and in_shadow(), per lane.
// offset_ray_origin() depends on the direction the ray leaves in only through the side of Ng
// it leaves on (its select on dot(toward, N) < 0). A point's reflected ray and its shadow rays
// to the lights it faces all leave on Ng's side, so that origin is computed once a level
// (`away`, away_origin(): offset_ray_origin(p, p_error, Ng, Ng), since dot(Ng, Ng) < 0 is never
// true, as for any ray leaving on Ng's side or along its plane) and each ray takes it;
// offset_ray_origin() runs again only for a packet in which one of `lanes` leaves on the other
// side (leaving_origin()). Once a level instead of three times: Ex 25 1.06x on 1 and 2
// threads, the same bits (paired A/B, issue 12). The binding leaving_origins, which calls both,
// is tested lane by lane against the one-ray offset_ray_origin() (tests/tracer/test_packet.py).
// Where Ng is the unit vector of an axis (FacingL), away_origin() writes that call out: its turn
// of the offset, where dot(Ng, Ng) < 0, never happens; the offset's length dot(abs(Ng),
// p_error) is p_error's coordinate along the axis (dot_unit()), times Ng's 1 there; along the
// other axes the offset is Ng's zero times a length (a zero of that zero's sign, so Ng's
// coordinate itself), where next_away() leaves the coordinate as p + offset gives it.
inline Vec3L away_origin(const Vec3L &p, const Vec3L &p_error, const FacingL &f) {
    const Vec3L &Ng = f.Ng;
    switch (f.axis) {
    case 0: return {next_away(p.x + p_error.x, p_error.x), p.y + Ng.y, p.z + Ng.z};
    case 1: return {p.x + Ng.x, next_away(p.y + p_error.y, p_error.y), p.z + Ng.z};
    case 2: return {p.x + Ng.x, p.y + Ng.y, next_away(p.z + p_error.z, p_error.z)};
    default: return offset_ray_origin(p, p_error, Ng, Ng);
    }
}

inline Vec3L leaving_origin(const Vec3L &p, const Vec3L &p_error, const FacingL &f,
                            const Vec3L &away, const Vec3L &toward, LaneMask lanes) {
    const LaneMask back = dot_unit(toward, f.axis, f.Ng) < 0; // its sign: dot_unit()
    if (!any(back & lanes)) return away;
    return select(back, offset_ray_origin(p, p_error, f.Ng, toward), away);
}

inline RayL secondary_ray(const HitL &hit, const FacingL &f, const Vec3L &away,
                          const Vec3L &direction, LaneMask lanes) {
    return {leaving_origin(hit.p, hit.p_error, f, away, direction, lanes), direction};
}

struct ShadowRayL {
    RayL ray;
    double max_t; // the same reach for every lane: they go to the same light
};

inline ShadowRayL shadow_ray_to(const HitL &hit, const FacingL &f, const Vec3L &away,
                                const Vec3 &point, LaneMask lanes) {
    // BEGIN SOLUTION L05
    // PROMPT: The packet tracer's copy of 04_hit.h shadow_ray_to(), one ray per lane: not part of
    // PROMPT: the exercise, hidden until lesson L05 is done (the lessons use the one-ray tracer).
    const Vec3L to = splat(point);
    Vec3L o = leaving_origin(hit.p, hit.p_error, f, away, to - hit.p, lanes);
    return {{o, to - o}, 1.0};
    // END SOLUTION
}

inline ShadowRayL shadow_ray_towards(const HitL &hit, const FacingL &f, const Vec3L &away,
                                     const Vec3 &direction, LaneMask lanes) {
    // BEGIN SOLUTION L05
    // PROMPT: The packet tracer's copy of 04_hit.h shadow_ray_towards(), one ray per lane: not part
    // PROMPT: of the exercise, hidden until lesson L05 is done (the lessons use the one-ray
    // PROMPT: tracer).
    const Vec3L d = splat(direction);
    return {{leaving_origin(hit.p, hit.p_error, f, away, d, lanes), d}, infinity};
    // END SOLUTION
}

inline ShadowRayL shadow_ray(const HitL &hit, const FacingL &f, const Vec3L &away,
                             const Light &light, LaneMask lanes) {
    // BEGIN SOLUTION L05
    // PROMPT: The packet tracer's copy of 10_classic.h shadow_ray(), one ray per lane: not part of
    // PROMPT: the exercise, hidden until lesson L05 is done (the lessons use the one-ray tracer).
    if (light.type == Light::Type::directional)
        return shadow_ray_towards(hit, f, away, -light.direction, lanes);
    return shadow_ray_to(hit, f, away, light.position, lanes);
    // END SOLUTION
}

// The lanes of `active` whose shadow ray is blocked. `skip`: as any_hit()'s.
inline LaneMask in_shadow(const Scene &scene, const ShadowRayL &shadow, LaneMask active,
                      RayCounts &counts, unsigned skip = 0) {
    // BEGIN SOLUTION L05
    // PROMPT: The packet tracer's copy of 10_classic.h in_shadow(), one ray per lane: not part of
    // PROMPT: the exercise, hidden until lesson L05 is done (the lessons use the one-ray tracer).
    counts.shadow += uint64_t(count(active));
    return any_hit(scene, shadow.ray, splat(shadow.max_t), active, counts, skip);
    // END SOLUTION
}

// One turn of the loop of 10_classic.h trace(), for the rays of `active`: find the closest hit,
// add this level's light (or the background) times coef to `color`, then follow the mirror:
// coef *= reflectivity and the ray becomes the secondary ray. Returns the lanes that go on.
// `skip`: as closest_hit()'s. `culling`: the render's (PacketCulling), or null: where every ray
// met a sphere, shadow rays skip the spheres that cannot shadow those. `primary`: the pixels of
// a packet of primary rays, or null; where each of its rays met plane k, `reflected` is set to
// the spheres their reflections cannot meet (else 0), and their shadow rays skip the spheres
// they cannot meet.
// Always inlined into trace()'s loop over levels: called, it saved and restored registers and
// reloaded the packet's ray, coefficient and colour at every level (a frame of 3.5 KB), and
// its entry and return held 5% of Ex 25's time (perf); inlined, Ex 25 1.036x on one thread and
// 1.034x on two (Zen 4, five alternating rounds, the same bits).
[[gnu::always_inline]] inline LaneMask trace_level(const Scene &scene, RayL &ray, LaneMask active,
                                               Lanes &coef, ColorL &color, RayCounts &counts,
                                               unsigned skip, const PacketCulling *culling,
                                               const PrimaryPixels *primary,
                                               unsigned &reflected) {
    // BEGIN SOLUTION L07
    // PROMPT: The packet tracer's copy of one turn of the loop of 10_classic.h trace() with
    // PROMPT: local_color(), one ray per lane (it restates lessons L04 to L07): not part of the
    // PROMPT: exercise, hidden until lesson L07 is done (the lessons use the one-ray tracer).
    const Settings &s = scene.settings;
    ClosestL closest = closest_hit(scene, ray, active, counts, skip);
    LaneMask found = active & (closest.t != infinity);
    add_where(active & ~found, color, splat(s.background) * coef);
    active = found;
    reflected = 0;
    if (!any(active)) return active;
    HitL hit = hit_record(scene, ray, closest, active);
    const int first = __builtin_ctz(lane_bits(active));
    int plane = -1; // the plane every ray of a primary packet met (PrimaryPixels), or -1
    if (primary != nullptr) {
        const int64_t k = closest.id[first] - int64_t(scene.spheres.size());
        if (k >= 0 && k < primary->planes() && !any(active & (closest.id != closest.id[first])))
            plane = int(k);
    }

    // The lane's material, gathered (or splat, when all live lanes share one).
    ColorL m_color;
    Lanes ambient, diffuse, specular, shininess, reflectivity;
    const bool shared = !any(active & (hit.material != hit.material[first]));
    int whole_shininess = 0; // a shared material's shininess where it is whole (power_whole())
    if (shared) {
        const Material &m = scene.materials[size_t(hit.material[first])];
        whole_shininess = whole_exponent(m.shininess);
        m_color = splat(m.color);
        ambient = splat(m.ambient), diffuse = splat(m.diffuse), specular = splat(m.specular);
        shininess = splat(m.shininess), reflectivity = splat(m.reflectivity);
    } else {
        for (int k = 0; k < rays_per_packet; ++k) {
            const Material &m = scene.materials[size_t(hit.material[k])];
            m_color.r[k] = m.color.r, m_color.g[k] = m.color.g, m_color.b[k] = m.color.b;
            ambient[k] = m.ambient, diffuse[k] = m.diffuse, specular[k] = m.specular;
            shininess[k] = m.shininess, reflectivity[k] = m.reflectivity;
        }
    }
    const FacingL f = face_the_ray(hit, ray.d); // the side we see is the side we shade
    const Vec3L away = away_origin(hit.p, hit.p_error, f); // leaving_origin()
    Vec3L R = reflect(ray.d, f);

    // local_color()
    ColorL local = m_color * (splat(s.ambient_light) * ambient);
    LaneMask shaded = active & ~((diffuse == 0) & (specular == 0));
    for (size_t l = 0; l < scene.lights.size(); ++l) {
        const Light &light = scene.lights[l];
        if (!any(shaded)) break;
        Vec3L L;
        if (light.type == Light::Type::directional) L = splat(-light.direction);
        else L = normalize(splat(light.position) - hit.p);
        Lanes NL = dot_unit(L, f.axis, f.N); // taken where > 0: dot_unit()
        LaneMask lit = shaded & (NL > 0);
        if (!any(lit)) continue;
        unsigned cannot_block = 0;
        if (culling != nullptr && int(l) < culling->lights) {
            if (!hit.others_met) cannot_block = culling->cannot_block(hit.spheres_met, int(l));
            else if (plane >= 0) cannot_block = primary->shadowed(plane, int(l));
        }
        lit &= ~in_shadow(scene, shadow_ray(hit, f, away, light, lit), lit, counts,
                          cannot_block);
        if (!any(lit)) continue;
        const ColorL lc = splat(light.color);
        add_where(lit, local, (m_color * lc) * (diffuse * NL));
        LaneMask highlight = lit & (specular != 0);
        if (any(highlight)) {
            // Where R.L <= 0 the one-ray code adds (specular 0) light.color, +0 to a sum of
            // products of finite non-negative numbers (the scene reader takes finite values
            // only): nothing. So power() runs only when some lane has a highlight.
            // Its exponent is the shininess in those lanes and 1 in the others, whose results
            // are not taken: power() works lane by lane, so a lane's result does not depend on
            // another's exponent. Given the packet's shininess itself, power()'s tests of the
            // exponent (whole? which bits?) depend on nothing that changes from light to light,
            // and Clang 19 moved them out of the loop over the lights, to run for every packet,
            // the floor's (specular 0, no highlight) too: some 40 instructions a packet and
            // level. Ex 25 1.008x to 1.017x on one Zen 4 thread (four sets of five to nine
            // alternating rounds) and 1.016x on two, the floor alone 1.04x; the same image.
            Lanes cos_alpha = dot(R, L);
            highlight &= cos_alpha > 0;
            if (any(highlight)) {
                // Where the rays met one material whose shininess is whole, every lane takes
                // it as its exponent, those without a highlight too (their results are not
                // taken), and power_whole() squares by a plain integer's bits.
                const Lanes x_n = whole_shininess > 0
                                      ? power_whole(cos_alpha, whole_shininess)
                                      : power(cos_alpha, select(highlight, shininess, splat(1.0)));
                add_where(highlight, local, lc * (specular * x_n));
            }
        }
    }
    add_where(active, color, local * coef);
    active &= reflectivity != 0;
    coef *= reflectivity;
    if (any(active)) ray = secondary_ray(hit, f, away, R, active);
    if (plane >= 0 && any(active)) reflected = primary->reflected(plane);
    return active;
    // END SOLUTION
}

} // namespace rt

namespace rt {

// 10_classic.h trace() for a packet: the colours of the rays of `active`. (Packing the rays
// still going into full packets at each level, as a wavefront, was tried: the gathering and
// scattering cost more than the idle lanes it saves on these scenes.)
// `culling`: the render's (PacketCulling), or null. `primary`: the pixels of a packet of
// primary rays (what their rays, and on a plane their reflections and shadow rays, cannot meet:
// PrimaryPixels), or null.
// Always inlined into its callers (render_tile_packets()'s row of packets and its packets of
// samples), as trace_level() is into it: called once a packet, its ray (384 bytes) went by the
// stack and its colour back by memory, and the loop's state was saved and restored around it;
// inlined, Ex 25 1.059x on one thread and 1.061x on two (Zen 4, five alternating rounds, the
// same bits), and the extension no larger.
[[gnu::always_inline]] inline ColorL trace(const Scene &scene, RayL ray, LaneMask active,
                                           RayCounts &counts, const PacketCulling *culling,
                                           const PrimaryPixels *primary) {
    // BEGIN SOLUTION L07
    // PROMPT: The packet tracer's copy of 10_classic.h trace(), one ray per lane: not part of the
    // PROMPT: exercise, hidden until lesson L07 is done (the lessons use the one-ray tracer).
    const Settings &s = scene.settings;
    ColorL color{splat(0), splat(0), splat(0)};
    Lanes coef = splat(1.0);
    unsigned skip = primary != nullptr ? primary->seen() : 0; // closest_hit()'s, this level
    for (int level = 1; level <= s.max_depth; ++level) { // past the last level: black
        active &= ~(coef < s.min_coefficient);            // "coef << 1": black
        if (!any(active)) break;
        if (level > 1) counts.secondary += uint64_t(count(active));
        unsigned next = 0;
        active = trace_level(scene, ray, active, coef, color, counts, skip, culling,
                             level == 1 ? primary : nullptr, next);
        skip = next;
    }
    return color;
    // END SOLUTION
}

// 03_camera.h primary_ray() through the centres of pixels i0, i0 + 1, ... (one per lane) of
// row j.
inline RayL primary_rays(const Camera &cam, int i0, int j) {
    // BEGIN SOLUTION L01
    // PROMPT: The packet tracer's copy of 03_camera.h primary_ray(), one ray per lane: not part
    // PROMPT: of the exercise, hidden until lesson L01 is done (the lessons use the one-ray
    // PROMPT: tracer).
    Lanes sx;
    for (int k = 0; k < rays_per_packet; ++k) sx[k] = (i0 + k) + 0.5;
    Lanes x = sx / double(cam.width) - 0.5;
    double y = 0.5 - (j + 0.5) / cam.height;
    Vec3L d = splat(cam.forward) + splat(cam.right) * (x * cam.plane_width + cam.window_shift) +
              splat(cam.true_up * (y * cam.plane_height));
    return {splat(cam.eye), normalize(d)};
    // END SOLUTION
}

// primary_rays() in two steps, for a tile's rows: the direction's part that depends on the
// column only, forward + right (x plane_width + window_shift), is the same in every row, so a
// tile computes it once per packet of columns (its division by the width, its conversions and
// its multiplications were a tenth of Ex 25's time, perf, issue 12); each row adds its
// true_up (y plane_height) and normalises. The same operations in the same order as
// primary_rays(), so the same bits (tests/tracer/test_packet.py).
inline Vec3L primary_across(const Camera &cam, int i0) {
    Lanes sx;
    for (int k = 0; k < rays_per_packet; ++k) sx[k] = (i0 + k) + 0.5;
    Lanes x = sx / double(cam.width) - 0.5;
    return splat(cam.forward) + splat(cam.right) * (x * cam.plane_width + cam.window_shift);
}
inline RayL primary_rays(const Camera &cam, const Vec3L &across, int j) {
    double y = 0.5 - (j + 0.5) / cam.height;
    Vec3L d = across + splat(cam.true_up * (y * cam.plane_height));
    return {splat(cam.eye), normalize(d)};
}

// A packet's colours as the image's floats, r g b pixel after pixel. A whole packet is
// converted by three vector conversions (each lane rounded as float(double) rounds it: to
// nearest) and interleaved by three shuffles; written lane by lane, Clang 19 stored the three
// vectors to the stack at every pixel and read each lane back (some 80 instructions a packet):
// Ex 25 1.043x on one Zen 4 thread (seven alternating rounds, issue 12), the same bits.
typedef float FloatLanes __attribute__((vector_size(rays_per_packet * sizeof(float))));
typedef float FloatPairs __attribute__((vector_size(2 * rays_per_packet * sizeof(float))));
// Float i of the run r0 g0 b0 r1 g1 b1 ...: where it lies in rg (r, then g) followed by bb (b,
// then b again).
constexpr int interleaved_float(int i) {
    const int pixel = i / 3, channel = i % 3;
    return channel == 2 ? 2 * rays_per_packet + pixel : channel * rays_per_packet + pixel;
}
template <size_t... k> FloatPairs join(FloatLanes a, FloatLanes b, std::index_sequence<k...>) {
    return __builtin_shufflevector(a, b, int(k)...);
}
// Floats part * rays_per_packet, ... of the run.
template <int part, size_t... k>
FloatLanes interleaved_part(FloatPairs rg, FloatPairs bb, std::index_sequence<k...>) {
    return __builtin_shufflevector(rg, bb, interleaved_float(part * rays_per_packet + int(k))...);
}

inline void store_pixels(float *out, int width, int i0, int j, int n, const ColorL &c) {
    float *px = out + (size_t(j) * width + i0) * 3;
    if (n == rays_per_packet) {
        const auto floats = std::make_index_sequence<rays_per_packet>{};
        const auto pairs = std::make_index_sequence<2 * rays_per_packet>{};
        const FloatLanes r = __builtin_convertvector(c.r, FloatLanes),
                         g = __builtin_convertvector(c.g, FloatLanes),
                         b = __builtin_convertvector(c.b, FloatLanes);
        const FloatPairs rg = join(r, g, pairs), bb = join(b, b, pairs);
        const FloatLanes run[3] = {interleaved_part<0>(rg, bb, floats),
                                   interleaved_part<1>(rg, bb, floats),
                                   interleaved_part<2>(rg, bb, floats)};
        std::memcpy(px, run, sizeof run);
        return;
    }
    for (int k = 0; k < n; ++k, px += 3)
        px[0] = float(c.r[k]), px[1] = float(c.g[k]), px[2] = float(c.b[k]);
}

// Whether no primary ray of a tile can meet anything: every sphere's image rectangle lies
// outside it (TileCulling) and no plane is seen through it (plane_unseen()).
inline bool sky_only(const Scene &scene, const TileCulling &tile, const ImageSpan &span) {
    if (scene.spheres.size() > size_t(max_culled) || tile.seen.maybe != 0) return false;
    for (const Plane &pl : scene.planes)
        if (!plane_unseen(scene.camera, pl, span)) return false;
    return true;
}

// A tile whose rays all meet nothing (sky_only()), as trace() would colour it without tracing
// a ray: the background times the first level's coefficient 1, added to black, where a first
// level is traced; black where none is (max_depth 0, or a min_coefficient above 1). Counted as
// traced: each ray a primary ray, with a test of every object that found nothing. A 16 x 16
// tile of Ex 25's sky was 32 packets of primary rays, each a square root and a division, then
// the culling's bookkeeping, the background and the store (some 110 cycles a packet on the
// Xeon, by packet_model): 1,920 of Ex 25's 7,680 tiles see no floor, most of those no sphere.
// Ex 25 1.023x [0.993-1.044] on one Xeon thread, 1.038x [1.023-1.079] on two (7 rounds, the
// same bits; issue 12).
inline void fill_background(const Scene &scene, int x0, int y0, int x1, int y1, float *out,
                            RayCounts &counts) {
    const Settings &s = scene.settings;
    const double coef = 1.0;
    const bool traced = s.max_depth >= 1 && !(coef < s.min_coefficient);
    const Color c = traced ? Color{0.0 + s.background.r * coef, 0.0 + s.background.g * coef,
                                   0.0 + s.background.b * coef}
                           : Color{0.0, 0.0, 0.0};
    for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i) store_pixel(out, scene.camera.width, i, j, c);
    const uint64_t rays = uint64_t(x1 - x0) * uint64_t(y1 - y0);
    counts.primary += rays;
    if (traced) counts.primitive_tests += rays * (scene.spheres.size() + scene.planes.size());
}

// A tile of pixels, traced a packet at a time: the rays of 11_render.h for_each_sample(), in
// the same order, so each pixel's sum adds the same colours in the same order. `culling`: the
// render's rectangles (PacketCulling(scene)).
inline void render_tile_packets(const PacketCulling &culling, const Scene &scene, int x0,
                                int y0, int x1, int y1, float *out, RayCounts &counts) {
    const Camera &cam = scene.camera;
    if (scene.settings.spp == 1) { // one ray per pixel: whole packets along each row
        constexpr int most = tile_size / rays_per_packet; // packets across the widest tile
        Vec3L across[most];
        for (int p = 0, i = x0; i < x1 && p < most; ++p, i += rays_per_packet)
            across[p] = primary_across(cam, i);
        // The spheres some primary ray of this tile may meet (within the sphere's image
        // rectangle, sphere_rect()); the others' tests are skipped, and per
        // packet those of the rest it cannot meet (the first 32 spheres: a bit each). Ex 25's
        // sky and floor packets skip all three spheres: 1.03x to 1.07x on one thread, 1.03x to
        // 1.05x on two (paired A/B, issue 12). The same for the floor's reflections and shadow
        // rays (PacketCulling).
        const ImageSpan span = pixel_centres(x0, x1, y0, y1);
        const TileCulling tile(culling, span);
        if (sky_only(scene, tile, span)) {
            fill_background(scene, x0, y0, x1, y1, out, counts);
            return;
        }
        // A row's primary rays are made before any of them is traced. Each normalisation is a
        // square root and then a division, some 50 cycles of latency, and made one packet at
        // a time the trace waited for it (the instructions after it held 9% of Ex 25's time,
        // perf); made together, the packets' square roots and divisions overlap. Ex 25
        // 1.02x-1.04x on one thread, 1.01x on two (rounds of alternating builds, issue 12).
        RayL row[most];
        for (int j = y0; j < y1; ++j) {
            for (int p = 0, i = x0; i < x1 && p < most; ++p, i += rays_per_packet)
                row[p] = primary_rays(cam, across[p], j);
            for (int p = 0, i = x0; i < x1; ++p, i += rays_per_packet) {
                const int n = std::min(rays_per_packet, x1 - i);
                const LaneMask active = first_lanes(n);
                counts.primary += uint64_t(n);
                const PrimaryPixels pixels{tile, pixel_centres(i, i + n, j, j + 1)};
                const RayL rays = p < most ? row[p] : primary_rays(cam, i, j); // a wider tile
                const ColorL c = trace(scene, rays, active, counts, &culling, &pixels);
                store_pixels(out, cam.width, i, j, n, c);
            }
        }
        return;
    }
    // Several samples a pixel: packets of eight samples in order, each with the span of its
    // samples' image points (every sample of pixel (i, j) lies in [i, i + 1) x [j, j + 1)).
    const int tile_w = x1 - x0;
    std::vector<Color> sums(size_t(tile_w) * size_t(y1 - y0));
    const TileCulling tile(culling, ImageSpan{double(x0), double(x1), double(y0), double(y1)});
    RayL packet;
    int pixel[rays_per_packet], n = 0;
    ImageSpan span{};
    auto flush = [&] {
        const LaneMask active = first_lanes(n);
        for (int k = n; k < rays_per_packet; ++k) // idle lanes: any harmless ray, masked off
            packet.set(k, Ray{{0, 0, 0}, {0, 0, 1}});
        const PrimaryPixels samples{tile, span};
        ColorL c = trace(scene, packet, active, counts, &culling, &samples);
        for (int k = 0; k < n; ++k) sums[size_t(pixel[k])] += Color{c.r[k], c.g[k], c.b[k]};
        n = 0;
    };
    for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i)
            for_each_sample(scene, i, j, [&](double sx, double sy, Rng &) {
                Ray r = cam.primary_ray(sx, sy);
                ++counts.primary;
                packet.set(n, r);
                pixel[n] = (j - y0) * tile_w + (i - x0);
                if (n == 0) span = {sx, sx, sy, sy};
                else
                    span = {std::min(span.x0, sx), std::max(span.x1, sx), std::min(span.y0, sy),
                            std::max(span.y1, sy)};
                if (++n == rays_per_packet) flush();
            });
    if (n > 0) flush();
    for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i) {
            Color c = sums[size_t((j - y0) * tile_w + (i - x0))];
            if (scene.settings.spp > 1) c = c * (1.0 / scene.settings.spp);
            store_pixel(out, cam.width, i, j, c);
        }
}

} // namespace rt
