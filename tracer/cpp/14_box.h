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

// Whether the ray overlaps the box's three slabs within range; t_near is where it enters. The
// test a bounding volume needs (16_mesh.h): the ray's 1/d and signs come precomputed, and the
// range shrinks to the closest hit found so far, so a box beyond it is skipped.
inline bool slab_test(const AABB &box, const SlabRay &r, const Interval &range, double &t_near) {
    // BEGIN SOLUTION L09
    // PROMPT: Slide "Intersecting a Complex Object" ("test bounding box of entire object"): does
    // PROMPT: the ray overlap the box's three slabs for some t within range? r.inv_d is 1/d per
    // PROMPT: component (infinite for a zero one), r.near_x is 1 when max.x is the slab's near
    // PROMPT: plane (d.x < 0), and r.inv_d_far is inv_d widened for the far planes (so rounding
    // PROMPT: never misses a box the ray touches). Set t_near to where the ray enters (no earlier
    // PROMPT: than range.min). A ray lying in a slab's plane gives 0 * infinity = NaN there: it
    // PROMPT: must not decide the answer.
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
    // END SOLUTION
}

// Where a ray is inside the box: the overlap [t_enter, t_leave] of its three slabs' intervals
// (empty when t_enter > t_leave), and the axes whose planes bound it (the faces it enters and
// leaves by, for the normal).
struct Slabs {
    double t_enter, t_leave;
    int enter_axis, leave_axis;
};

// Slide "Intersecting a Complex Object" (intersections: axis-aligned box), the slab test in its
// plain form, for the Box object: each slab's two planes give two t, the nearer is where the ray
// enters that slab; the ray is inside the box from the last entry to the first exit.
inline Slabs slab_interval(const AABB &box, const Ray &ray) {
    // BEGIN SOLUTION L08
    // PROMPT: The slab test (slide "Intersecting a Complex Object": axis-aligned box). For each
    // PROMPT: axis, the t where the ray crosses the box's min and max planes; the smaller is where
    // PROMPT: it enters that slab (d's component may be negative). Return the overlap of the three
    // PROMPT: intervals, [t_enter, t_leave] (the latest entry, the earliest exit), and the axis of
    // PROMPT: each. A zero component of d: IEEE 1/0 = infinity gives the right limit, but a ray in
    // PROMPT: the plane of a face gives 0 * infinity = NaN, which must change nothing.
    Vec3 inv_d = reciprocal(ray.d);
    double t_enter = -infinity, t_leave = infinity;
    int enter_axis = 0, leave_axis = 0;
    for (int axis = 0; axis < 3; ++axis) {
        double t0 = (box.min[axis] - ray.o[axis]) * inv_d[axis];
        double t1 = (box.max[axis] - ray.o[axis]) * inv_d[axis];
        if (t0 > t1) std::swap(t0, t1);
        // Strict comparisons: a NaN t (0 * infinity) fails both and changes nothing.
        if (t0 > t_enter) t_enter = t0, enter_axis = axis;
        if (t1 < t_leave) t_leave = t1, leave_axis = axis;
    }
    return {t_enter, t_leave, enter_axis, leave_axis};
    // END SOLUTION
}

// Where the ray meets the box within range: t, the axis of the face, and whether it enters
// there (found = false: it does not meet the box within range).
struct BoxCrossing {
    bool found;
    double t;
    int axis;
    bool entering;
};

// The hit is where the ray enters the box, or where it leaves when it starts inside (the
// entry lies before range.min), as the sphere's nearest root in range (slide "Intersecting a
// Sphere": "internal").
inline BoxCrossing box_crossing(const Slabs &slabs, const Interval &range) {
    // BEGIN SOLUTION L08
    // PROMPT: From the slab test's [t_enter, t_leave]: where the ray meets the box within the open
    // PROMPT: range (range.surrounds(t)), and whether it enters there. An empty overlap is no hit;
    // PROMPT: the entry when it is in range, else the exit (the ray starts inside), else no hit.
    if (slabs.t_enter > slabs.t_leave) return {false, infinity, 0, false};
    if (range.surrounds(slabs.t_enter)) return {true, slabs.t_enter, slabs.enter_axis, true};
    if (range.surrounds(slabs.t_leave)) return {true, slabs.t_leave, slabs.leave_axis, false};
    return {false, infinity, 0, false};
    // END SOLUTION
}

// The box as an object: axis-aligned in its own coordinates, placed by a transform.
struct Box : Object {
    AABB box;
    Transform transform;

    bool hit(const Ray &world_ray, const Interval &range, Hit &hit,
             RayCounts &counts) const override {
        ++counts.primitive_tests;
        Ray ray = transform.to_object(world_ray);
        BoxCrossing c = box_crossing(slab_interval(box, ray), range);
        if (!c.found) return false;
        double t = c.t;
        int axis = c.axis;
        bool entering = c.entering;
        Vec3 p = ray.at(t);
        // The face is known exactly: put the point on it. The other two coordinates carry the
        // error of o + t d, with t from one subtraction, one multiplication: gamma(5) of their
        // size.
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

    // A shadow ray needs only whether the box lies within range (slide "How is it Done?": "is
    // anything in the way"): the same test as hit(), without the hit record (the point, its
    // error bound, the normal taken back to the world), so the same answer.
    bool blocks(const Ray &world_ray, const Interval &range, RayCounts &counts) const override {
        ++counts.primitive_tests;
        return box_crossing(slab_interval(box, transform.to_object(world_ray)), range).found;
    }
};

} // namespace rt
