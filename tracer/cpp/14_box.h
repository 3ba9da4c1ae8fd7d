// Slides "Building a real Ray Tracer in C++" (derived class Cube) and "Intersecting a Complex
// Object" (intersections: axis-aligned box): the slab test of Kay and Kajiya (1986). A box is
// the intersection of three slabs min.x <= x <= max.x, ...; the ray is inside the box for the
// t where it is inside all three, the overlap of three intervals.
//
// The same test bounds the triangles of a mesh (16_mesh.h). For that use it must never miss a
// box the ray touches: computed t values carry rounding error, so the far end of the overlap is
// widened by 1 + 2 gamma(3) (pbrt-v4 6.8.2, "Robust Bounding Box Intersection").
#pragma once

#include <algorithm>
#include <utility>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"
#include "13_transform.h"
#include "constants.h"

namespace rt {

struct AABB {
    Vec3 min{infinity, infinity, infinity}, max{-infinity, -infinity, -infinity}; // adjacent

    void extend(const Vec3 &p) {
        min = {std::min(min.x, p.x), std::min(min.y, p.y), std::min(min.z, p.z)};
        max = {std::max(max.x, p.x), std::max(max.y, p.y), std::max(max.z, p.z)};
    }
    void extend(const AABB &b) {
        if (b.min.x > b.max.x) return; // an empty box adds nothing (its corners are infinite)
        extend(b.min);
        extend(b.max);
    }
    Vec3 centre() const { return (min + max) * 0.5; }
    double area() const { // surface area, for the surface-area heuristic
        Vec3 e = max - min;
        return e.x < 0 ? 0 : 2 * (e.x * e.y + e.y * e.z + e.z * e.x);
    }
};

inline Vec3 reciprocal(const Vec3 &d) { return {1 / d.x, 1 / d.y, 1 / d.z}; }

// The ray as the slab test needs it, computed once for the many boxes it meets: 1/d per
// component (infinite for a zero component: IEEE division then gives +-infinity slabs, the
// right limit), and the signs of 1/d, which pick the near and far plane of each slab directly
// instead of swapping (Williams, Barrus, Morley and Shirley, "An Efficient and Robust Ray-Box
// Intersection Algorithm", 2005).
struct SlabRay {
    Vec3 o, inv_d, inv_d_far; // inv_d_far = inv_d (1 + 2 gamma(3)): the far end's widening,
                              // applied once per ray (one more rounding, inside the margin)
    int near_x, near_y, near_z; // 0: min is the near plane, 1: max is
    explicit SlabRay(const Ray &ray)
        : o(ray.o), inv_d(reciprocal(ray.d)), inv_d_far(inv_d * (1 + 2 * gamma(3))),
          near_x(inv_d.x < 0), near_y(inv_d.y < 0), near_z(inv_d.z < 0) {}
};

// Whether the ray overlaps the box's three slabs within range; t_near is where it enters.
inline bool slab_test(const AABB &box, const SlabRay &r, const Interval &range, double &t_near) {
    const Vec3 *planes = &box.min; // planes[0] = min, planes[1] = max
    double tx0 = (planes[r.near_x].x - r.o.x) * r.inv_d.x;
    double tx1 = (planes[1 - r.near_x].x - r.o.x) * r.inv_d_far.x;
    double ty0 = (planes[r.near_y].y - r.o.y) * r.inv_d.y;
    double ty1 = (planes[1 - r.near_y].y - r.o.y) * r.inv_d_far.y;
    double tz0 = (planes[r.near_z].z - r.o.z) * r.inv_d.z;
    double tz1 = (planes[1 - r.near_z].z - r.o.z) * r.inv_d_far.z;
    // Comparisons written so that a NaN slab (0 * infinity, a ray in a slab's plane) leaves the
    // interval unchanged.
    double lo = range.min, hi = range.max;
    lo = tx0 > lo ? tx0 : lo, hi = tx1 < hi ? tx1 : hi;
    lo = ty0 > lo ? ty0 : lo, hi = ty1 < hi ? ty1 : hi;
    lo = tz0 > lo ? tz0 : lo, hi = tz1 < hi ? tz1 : hi;
    t_near = lo;
    return lo <= hi;
}

// The box as an object: axis-aligned in its own coordinates, placed by a transform.
struct Box : Object {
    AABB box;
    Transform transform;

    bool hit(const Ray &world_ray, const Interval &range, Hit &hit,
             RayCounts &counts) const override {
        ++counts.primitive_tests;
        Ray ray = transform.to_object(world_ray);
        Vec3 inv_d = reciprocal(ray.d);
        // Entering and leaving t of each slab; the hit is where the ray enters the box, or
        // leaves it when it starts inside.
        double t_enter = -infinity, t_leave = infinity;
        int enter_axis = 0, leave_axis = 0;
        for (int axis = 0; axis < 3; ++axis) {
            double t0 = (box.min[axis] - ray.o[axis]) * inv_d[axis];
            double t1 = (box.max[axis] - ray.o[axis]) * inv_d[axis];
            if (t0 > t1) std::swap(t0, t1);
            if (t0 > t_enter) t_enter = t0, enter_axis = axis;
            if (t1 < t_leave) t_leave = t1, leave_axis = axis;
        }
        if (t_enter > t_leave) return false;
        double t;
        int axis;
        bool entering = range.surrounds(t_enter);
        if (entering) t = t_enter, axis = enter_axis;
        else if (range.surrounds(t_leave)) t = t_leave, axis = leave_axis;
        else return false;
        Vec3 p = ray.at(t);
        // The face is known exactly: put the point on it. The other two coordinates carry the
        // error of o + t d, with t from one subtraction, one multiplication: gamma(5) of their size.
        double d_axis = ray.d[axis];
        // Entering along +d crosses the min face; leaving along +d, the max face.
        double face = entering == (d_axis > 0) ? box.min[axis] : box.max[axis];
        Vec3 e = gamma(5) * (abs(ray.o) + abs(t * ray.d));
        Vec3 N{0, 0, 0};
        if (axis == 0) p.x = face, e.x = 0, N.x = face == box.min.x ? -1 : 1;
        else if (axis == 1) p.y = face, e.y = 0, N.y = face == box.min.y ? -1 : 1;
        else p.z = face, e.z = 0, N.z = face == box.min.z ? -1 : 1;
        transform.place(*this, t, p, e, N, hit);
        return true;
    }
};

} // namespace rt
