// Slide "Intersections" (Suffern fig. 3.4): what a ray learns where it meets an object.
#pragma once

#include <cstdint>

#include "02_ray.h"

namespace rt {

struct Hit {
    double t = infinity; // ray parameter of the closest hit; infinity: no hit
    Vec3 p;              // the point of intersection, refined onto the surface
    Vec3 p_error;        // bound on the absolute rounding error of p, per component
    Vec3 N;              // unit shading normal, on the front side (turned toward the ray later)
    Vec3 Ng;             // unit geometric normal: the surface's own; new rays start off it
    int object = -1;     // index into the scene's [[objects]]
    int material = -1;   // index into the scene's materials

    bool found() const { return object >= 0; }
};

// Counts of the three kinds of rays (slide "What is a Ray?") and of the tests they cost: how
// many ray/box tests (bounding volumes) and ray/primitive tests (spheres, planes, triangles,
// the other shapes) a render made. Kept per thread, summed at the end.
struct RayCounts {
    uint64_t primary = 0, secondary = 0, shadow = 0;
    uint64_t box_tests = 0, primitive_tests = 0;
};

// Slides "Object Class" and "Virtual Methods": every kind of object answers the same question
// - where does this ray hit you - by overriding hit(). (Spheres and planes, the objects of
// Ex 25, are also kept in lists of their own that the tracer tests without a virtual call.)
struct Object {
    int object = -1, material = -1;
    virtual ~Object() = default;
    // The closest hit with t in range: fills the whole hit record and returns true.
    virtual bool hit(const Ray &ray, const Interval &range, Hit &hit, RayCounts &counts) const = 0;
    // Whether any hit lies within range (shadow rays need no more).
    virtual bool blocks(const Ray &ray, const Interval &range, RayCounts &counts) const {
        Hit h;
        return hit(ray, range, h, counts);
    }
};

} // namespace rt
