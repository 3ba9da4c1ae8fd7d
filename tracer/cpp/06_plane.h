// Slide "Implicit Surfaces": the plane through point a with normal n, (p - a).n = 0.
// With p = o + t d:  t = (a - o).n / (d.n).
#pragma once

#include <cmath>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"
#include "constants.h"

namespace rt {

struct Plane {
    Vec3 point;
    Vec3 normal{0, 1, 0}; // unit length (the scene loader normalises it)
    int object = -1, material = -1;
    // For the packet tracer only (12_packet.h unit_axis(), set where the scene is made): k where
    // the normal is the unit vector of axis k, as the floor's (0, 1, 0) is of y; -1 where it is
    // not, or where nobody looked.
    int axis = -1;
};

inline double plane_t(const Plane &pl, const Ray &ray) {
    // BEGIN SOLUTION L03
    // PROMPT: Solve (o + t d - a).n = 0 for t. A ray parallel to the plane never meets it:
    // PROMPT: infinity.
    double denom = dot(ray.d, pl.normal);
    if (denom == 0) return infinity; // the ray runs parallel to the plane
    return dot(pl.point - ray.o, pl.normal) / denom;
    // END SOLUTION
}

// The hit record at parameter t.
inline void plane_hit(const Plane &pl, const Ray &ray, double t, Hit &hit) {
    // Refine: project o + t d back onto the plane, removing the error that t carries.
    Vec3 p = ray.at(t);
    p = p - dot(p - pl.point, pl.normal) * pl.normal;
    // The projection's residual comes from a dot product and a subtraction over |p| and |a|:
    // a handful of roundings of the largest magnitudes involved; gamma(8) bounds them.
    double e = gamma(8) * (std::fabs(p.x) + std::fabs(p.y) + std::fabs(p.z) +
                           std::fabs(pl.point.x) + std::fabs(pl.point.y) + std::fabs(pl.point.z));
    hit.t = t;
    hit.p = p;
    hit.p_error = {e, e, e};
    hit.N = hit.Ng = pl.normal;
    hit.object = pl.object;
    hit.material = pl.material;
}

inline bool intersect_plane(const Plane &pl, const Ray &ray, const Interval &range, Hit &hit) {
    // BEGIN SOLUTION L03
    // PROMPT: Fill the hit record (plane_hit) and return true only when the plane's t lies in
    // PROMPT: range.
    double t = plane_t(pl, ray);
    if (!range.surrounds(t)) return false;
    plane_hit(pl, ray, t, hit);
    return true;
    // END SOLUTION
}

inline bool plane_blocks(const Plane &pl, const Ray &ray, const Interval &range) {
    return range.surrounds(plane_t(pl, ray));
}

} // namespace rt
