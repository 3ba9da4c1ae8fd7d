// Slide "Intersecting a Sphere": centre, radius, smooth normal, and five cases - none, once
// (from inside), tangent, internal, twice (Suffern figs. 3.7 and 3.8).
//
// Implicit surface (slide "Implicit Surfaces"): (p - c).(p - c) - r^2 = 0. With p = o + t d and
// f = o - c this is the quadratic  a t^2 + 2 b t + c0 = 0,  a = d.d, b = f.d, c0 = f.f - r^2.
//
// Precision (lesson L13, slide "Efficiency and Complexity": "pushing the envelope of hardware"):
// the textbook discriminant b^2 - a c0 subtracts two huge, nearly equal numbers when the sphere
// is small or far away, and loses every digit. Haines, Guenther and Akenine-Moeller, "Precision
// Improvements for Ray/Sphere Intersection" (Ray Tracing Gems, ch. 7, 2019) compute it instead
// from the vector l from the centre to the point of the line closest to it:
//     b^2 - a c0 = a (r^2 - |f - (b/a) d|^2),
// and take the roots in the stable form q = -(b + sign(b) sqrt(D)), t0 = c0/q, t1 = q/a, so
// that neither root is the difference of two nearly equal numbers (sphere_discriminant() and
// quadratic_roots() below; sphere_roots() and sphere_t() call them).
#pragma once

#include <cmath>
#include <utility>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"
#include "constants.h"

namespace rt {

struct Sphere {
    Vec3 center;
    double radius = 1;
    int object = -1, material = -1;
};

// The two roots t0 <= t1 of the ray's line with the sphere; real == false when it misses.
struct SphereRoots {
    bool real = false;
    double t0 = 0, t1 = 0;
};

// Lesson L13: the discriminant D = b^2 - a c0 of the quadratic, for f = o - c, the direction d,
// a = d.d, inv_a = 1/a (sphere_t() has it already), b = f.d and r2 = r^2, without the
// cancellation of b^2 - a c0: as a (r^2 - |l|^2) with l = f - (b/a) d, the vector from the
// centre to the point of the line closest to it (Haines et al. 2019, eq. 7.5). Its error grows
// with |f| / r, where the textbook form's grows with (|f| / r)^2.
inline double sphere_discriminant(const Vec3 &f, const Vec3 &d, double a, double inv_a, double b,
                                  double r2) {
    // BEGIN SOLUTION L13
    // PROMPT: The discriminant b^2 - a c0 (c0 = f.f - r2) of the ray's quadratic, computed so that
    // PROMPT: it keeps its digits for a sphere far away or tiny (|f| >> r), where b^2 and a c0
    // PROMPT: are huge and nearly equal: use the centre's distance to the ray's line (Ray
    // PROMPT: Tracing Gems ch. 7, eq. 7.5).
    // GIVEN: (void)d, (void)inv_a; // the robust form needs them
    // GIVEN: return b * b - a * (dot(f, f) - r2); // the textbook form, until lesson L13
    Vec3 l = f - (b * inv_a) * d; // centre -> closest point of the line (Haines eq. 7.5)
    return a * (r2 - dot(l, l));
    // END SOLUTION
}

// Lesson L13: both roots t0 <= t1 of a t^2 + 2 b t + c0 = 0 from its discriminant D >= 0 and
// inv_a = 1/a. The textbook (-b -+ sqrt(D)) / a subtracts two nearly equal numbers, -b and
// sqrt(D), for the root nearer zero when |a c0| << b^2 (a ray that starts just off a sphere, or a
// sphere far away seen from a point near another): that root loses its digits. The stable form
// adds only numbers of one sign: q = -(b + sign(b) sqrt(D)), t1 = q / a, and t0 = c0 / q from
// Vieta's t0 t1 = c0 / a (Press et al., Numerical Recipes, section 5.6; Haines et al. 2019, eq.
// 7.7).
inline SphereRoots quadratic_roots(double b, double c0, double D, double inv_a) {
    // BEGIN SOLUTION L13
    // PROMPT: Both roots t0 <= t1 of a t^2 + 2 b t + c0 = 0, given D = b^2 - a c0 >= 0 and
    // PROMPT: inv_a = 1/a, such that neither root is the difference of two nearly equal numbers
    // PROMPT: (the small root of t^2 - 2e8 t + 1 = 0 is 5e-9, not 0). real = true.
    // GIVEN: (void)c0; // the stable form needs it (Vieta)
    // GIVEN: double root = std::sqrt(D); // the textbook form, until lesson L13
    // GIVEN: return {true, (-b - root) * inv_a, (-b + root) * inv_a};
    double q = -(b + std::copysign(std::sqrt(D), b));
    if (q == 0) return {true, 0, 0}; // b = D = 0: the double root t = 0
    double t0 = c0 / q, t1 = q * inv_a;
    if (t0 > t1) std::swap(t0, t1);
    return {true, t0, t1};
    // END SOLUTION
}

inline SphereRoots sphere_roots(const Sphere &s, const Ray &ray) {
    // BEGIN SOLUTION L02
    // PROMPT: Solve a t^2 + 2 b t + c0 = 0 for the ray's line, with f = o - c, a = d.d,
    // PROMPT: b = f.d, c0 = f.f - r^2. Return real = false when the line misses; otherwise both
    // PROMPT: roots, t0 <= t1. The textbook formula will do here (lesson L13 returns to it:
    // PROMPT: until then sphere_discriminant() and quadratic_roots() hold the textbook one).
    Vec3 f = ray.o - s.center;
    double a = dot(ray.d, ray.d);
    double b = dot(f, ray.d);
    double r2 = s.radius * s.radius;
    double inv_a = 1 / a;
    double D = sphere_discriminant(f, ray.d, a, inv_a, b, r2);
    if (D < 0) return {};
    return quadratic_roots(b, dot(f, f) - r2, D, inv_a);
    // END SOLUTION
}

// The five cases, for a ray whose parameters t count in `range` (t > 0 for a ray's forward half):
enum class SphereCase {
    none,             // the line misses the sphere, or the sphere lies behind the ray
    once_from_inside, // the origin is inside: the ray leaves through the far side (t0 < 0 < t1)
    tangent,          // the ray grazes the sphere: one double root (D = 0)
    internal,         // the ray starts on the surface and runs inside it, as a reflection
                      // inside a mirror sphere does: the root at its own start (t = 0) is the
                      // surface it leaves, not a hit; the far side t1 is
    twice,            // the origin is outside and the ray enters and leaves: the hit is t0
};

// Which of the five cases the ray meets. Only for teaching and tests: intersect_sphere() below
// needs no case analysis, it takes the nearest root in range.
inline SphereCase sphere_case(const Sphere &s, const Ray &ray) {
    // BEGIN SOLUTION L02
    // PROMPT: Name which of the slide's five cases the ray meets: none, once (from inside),
    // PROMPT: tangent, internal (the ray starts on the surface and runs inside), twice.
    SphereRoots roots = sphere_roots(s, ray);
    if (!roots.real) return SphereCase::none;
    Vec3 f = ray.o - s.center;
    double r2 = s.radius * s.radius;
    // The origin is "on" the surface when f.f - r^2 is within the rounding error of its terms.
    bool on_surface = std::fabs(dot(f, f) - r2) <= gamma(8) * (dot(f, f) + r2);
    if (on_surface) {
        if (dot(f, ray.d) < 0 && roots.t1 > 0) return SphereCase::internal;
        if (roots.t0 == roots.t1) return SphereCase::tangent;
        return SphereCase::none;
    }
    if (roots.t1 <= 0) return SphereCase::none;
    if (roots.t0 == roots.t1) return SphereCase::tangent;
    if (roots.t0 <= 0) return SphereCase::once_from_inside;
    return SphereCase::twice;
    // END SOLUTION
}

// The nearest root within `range`, or infinity. (Finding the closest object needs only t;
// the hit record is filled once, for the winner, by sphere_hit().)
inline double sphere_t(const Sphere &s, const Ray &ray, const Interval &range) {
    // BEGIN SOLUTION L02
    // PROMPT: The nearest root t with range.min < t < range.max, or infinity when there is none. A
    // PROMPT: root behind the ray, or at its own start, is not a hit.
    Vec3 f = ray.o - s.center;
    double b = dot(f, ray.d);
    double r2 = s.radius * s.radius;
    double c0 = dot(f, f) - r2;
    if (c0 > 0 && b > 0) return infinity; // outside and moving away: both roots negative
    double a = dot(ray.d, ray.d);
    double inv_a = 1 / a; // 1/a depends on the ray only: the packet tracer computes it once
    double D = sphere_discriminant(f, ray.d, a, inv_a, b, r2);
    if (D < 0) return infinity;
    // (A tangent ray whose origin is the touching point itself has the double root t = 0,
    // which the open range leaves out.)
    SphereRoots roots = quadratic_roots(b, c0, D, inv_a);
    double t0 = roots.t0, t1 = roots.t1;
    if (range.surrounds(t0)) return t0;
    if (range.surrounds(t1)) return t1;
    return infinity;
    // END SOLUTION
}

// The hit record at parameter t, with the point moved exactly onto the sphere.
inline void sphere_hit(const Sphere &s, const Ray &ray, double t, Hit &hit) {
    // Refine the hit point by projecting it onto the sphere (pbrt-v4 6.8.5): whatever error t
    // carries, p is then within a few ulps of the true surface.
    Vec3 local = ray.at(t) - s.center;
    double len = length(local);
    // A sphere smaller than the spacing of doubles at its centre (radius 1e-300 at 1e-207):
    // the computed point may fall on the centre itself, or so near it that its squared length
    // underflows; there is no direction left to project along, so take the side facing the ray.
    if (!(len > 0)) local = -ray.d, len = length(local);
    local = local * (s.radius / len);
    hit.t = t;
    hit.p = s.center + local;
    // Error of the projected point, to the nearest point of the sphere in the direction the
    // scaling kept: the scaling costs gamma(5) of |local| (pbrt-v4 eq. 6.39), the addition of
    // the centre one rounding of |c + local| <= |c| + |local|. The subtraction of the centre
    // before costs nothing: its rounding turns the direction, and whatever the direction, the
    // scaled vector ends on the sphere. (Once gamma(7) (|c| + |local|): 5 to 7 times wider for a
    // sphere away from the origin, wider than the gap between nearly touching spheres that a
    // mirror chain crosses: the stiff study's mirror-chains family.)
    hit.p_error = gamma(5) * abs(local) + gamma(1) * (abs(s.center) + abs(local));
    hit.N = hit.Ng = local / s.radius;
    hit.object = s.object;
    hit.material = s.material;
}

// The closest root within `range`, with its hit record.
inline bool intersect_sphere(const Sphere &s, const Ray &ray, const Interval &range, Hit &hit) {
    double t = sphere_t(s, ray, range);
    if (t == infinity) return false;
    sphere_hit(s, ray, t, hit);
    return true;
}

// Shadow rays only need to know whether something lies in range, not what is closest.
inline bool sphere_blocks(const Sphere &s, const Ray &ray, const Interval &range) {
    return sphere_t(s, ray, range) != infinity;
}

} // namespace rt
