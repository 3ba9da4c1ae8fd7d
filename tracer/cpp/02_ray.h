// Slide "What is a Ray?": p = o + t d, and the types of rays - primary, secondary, shadow.
//
// Also here: where a secondary or shadow ray may start. A hit point computed in floating point
// lies a little off the true surface, on either side; a ray started there can hit the surface it
// leaves ("shadow acne"). A fixed epsilon is wrong at some scale (too small for a huge sphere,
// too large for a tiny one). Instead every hit carries a bound on its own rounding error and the
// new ray starts just outside that bound, on the side it leaves to: the method of pbrt-v4
// (Pharr, Jakob, Humphreys, "Physically Based Rendering", 4th ed., sections 6.8.4-6.8.6).
#pragma once

#include <cfloat>
#include <cstdint>
#include <cstring>

#include "01_vec3.h"
#include "constants.h"

namespace rt {

struct Ray {
    Vec3 o; // origin
    Vec3 d; // direction: unit length for primary and secondary rays
    Vec3 at(double t) const {
        // BEGIN SOLUTION L01
        // PROMPT: The point p = o + t d at parameter t along the ray.
        return o + t * d;
        // END SOLUTION
    }
};

// The open interval (min, max) of ray parameters t that count as a hit.
struct Interval {
    double min = 0, max = infinity;
    bool surrounds(double t) const { return min < t && t < max; }
};

// gamma(n) = n u / (1 - n u), with u = 2^-53 the unit roundoff of double: the relative error
// bound of n chained floating-point operations (Higham, "Accuracy and Stability of Numerical
// Algorithms", section 3.1; pbrt-v4 section 6.8.1).
constexpr double gamma(int n) {
    constexpr double u = DBL_EPSILON * 0.5;
    return (n * u) / (1 - n * u);
}

// The next double after v in the direction of off's sign (v itself when off is 0): what
// std::nextafter(v, +-infinity) gives for finite v, without a library call on the hot path.
inline double next_away(double v, double off) {
    if (off == 0) return v;
    if (v == 0) return off > 0 ? DBL_TRUE_MIN : -DBL_TRUE_MIN;
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    // Moving away from zero adds one to the magnitude's bit pattern; towards zero subtracts one.
    bits += ((v > 0) == (off > 0)) ? 1 : uint64_t(-1);
    std::memcpy(&v, &bits, sizeof v);
    return v;
}

// Lesson L13 (self-intersection offsets): move a hit point p, whose absolute error is at most
// p_error per component, along the unit normal N far enough that it lies certainly on the side
// `toward` points to (pbrt-v4 6.8.6, OffsetRayOrigin). The offset d = |N|.p_error is the largest
// distance the error box reaches along N; the result is then rounded one ulp further away so the
// addition cannot fall back. Along N, not along the ray: a grazing ray would need to travel far
// to leave the error box, and the offset would then reach past nearby surfaces. Towards the side
// `toward` points to: a reflected ray leaves on N's side, a refracted ray or a ray from inside a
// sphere on the other.
inline Vec3 offset_ray_origin(const Vec3 &p, const Vec3 &p_error, const Vec3 &N,
                              const Vec3 &toward) {
    // BEGIN SOLUTION L13
    // PROMPT: A new ray's origin near the hit point p (absolute error at most p_error per
    // PROMPT: component, unit geometric normal N): p moved along N, to the side `toward` points to,
    // PROMPT: by the distance the error box reaches along N, then one ulp further (next_away()),
    // PROMPT: so the ray cannot hit the surface it leaves. No fixed epsilon: the error bound
    // PROMPT: scales with p.
    // GIVEN: (void)p_error; // lesson L13 offsets by it
    // GIVEN: return p + (dot(toward, N) < 0 ? -1e-4 : 1e-4) * N; // a fixed epsilon, until L13
    double d = dot(abs(N), p_error);
    Vec3 offset = d * N;
    if (dot(toward, N) < 0) offset = -offset;
    Vec3 po = p + offset;
    return {next_away(po.x, offset.x), next_away(po.y, offset.y), next_away(po.z, offset.z)};
    // END SOLUTION
}

} // namespace rt
