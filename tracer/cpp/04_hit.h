// Slide "Intersections" (Suffern fig. 3.4): what a ray learns where it meets an object.
#pragma once

#include <cstdint>

#include "01_vec3.h"
#include "02_ray.h"
#include "constants.h"

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

// The normals a hit is shaded with, turned to face the ray: the side we see is the side we shade.
struct Facing {
    Vec3 N;  // shading normal, on Ng's side
    Vec3 Ng; // geometric normal, on the side the ray comes from: new rays start off it
};

// Ng turned against the incoming direction d, and N turned to Ng's side (a smooth mesh's
// interpolated normal may point away from the face it shades). RTIOW's set_face_normal, for a
// shading normal and a geometric one (pbrt-v4's FaceForward of the shading frame).
inline Facing face_the_ray(const Hit &hit, const Vec3 &d) {
    // BEGIN SOLUTION L04
    // PROMPT: Turn the geometric normal Ng against the incoming direction d (the side we see is the
    // PROMPT: side we shade), then turn the shading normal N to Ng's side.
    Vec3 Ng = dot(hit.Ng, d) > 0 ? -hit.Ng : hit.Ng;
    Vec3 N = dot(hit.N, Ng) < 0 ? -hit.N : hit.N;
    return {N, Ng};
    // END SOLUTION
}

// The rays that leave a hit (slide "What is a Ray?": secondary and shadow rays) all start just
// outside the hit's error bound, on the side they leave to (offset_ray_origin(), 02_ray.h),
// measured along Ng, the surface's own normal; pbrt-v4's SpawnRay and SpawnRayTo (6.8.6).

// A secondary ray: from the surface towards a unit `direction` (a mirror reflection, a
// scattered path).
inline Ray secondary_ray(const Hit &hit, const Vec3 &Ng, const Vec3 &direction) {
    return {offset_ray_origin(hit.p, hit.p_error, Ng, direction), direction};
}

// A shadow ray and its reach: anything it meets with t in (0, max_t) blocks the light.
struct ShadowRay {
    Ray ray;
    double max_t;
};

// Towards a point: the direction is left unnormalised, point - origin, so that the point sits
// at t = 1 and what lies in (0, 1) is between (no square root, no division by the distance).
inline ShadowRay shadow_ray_to(const Hit &hit, const Vec3 &Ng, const Vec3 &point) {
    // BEGIN SOLUTION L05
    // PROMPT: A shadow ray from the hit towards `point`: start it off the surface
    // PROMPT: (offset_ray_origin), on the side it leaves to, and choose its direction and reach so
    // PROMPT: that only what lies strictly between the surface and the point blocks the light.
    Vec3 o = offset_ray_origin(hit.p, hit.p_error, Ng, point - hit.p);
    return {{o, point - o}, 1.0};
    // END SOLUTION
}

// Towards a light infinitely far along the unit `direction`: everything ahead is between.
inline ShadowRay shadow_ray_towards(const Hit &hit, const Vec3 &Ng, const Vec3 &direction) {
    // BEGIN SOLUTION L05
    // PROMPT: A shadow ray towards a light infinitely far along the unit `direction`: where does it
    // PROMPT: start, and how far does it reach?
    return {{offset_ray_origin(hit.p, hit.p_error, Ng, direction), direction}, infinity};
    // END SOLUTION
}

// Counts of the three kinds of rays (slide "What is a Ray?") and of the tests they cost: how
// many ray/box tests (bounding volumes) and ray/primitive tests (spheres, planes, triangles,
// the other shapes) a render made. Kept per thread, summed at the end.
struct RayCounts {
    uint64_t primary = 0, secondary = 0, shadow = 0;
    uint64_t box_tests = 0, primitive_tests = 0;
    RayCounts &operator+=(const RayCounts &c) {
        primary += c.primary, secondary += c.secondary, shadow += c.shadow;
        box_tests += c.box_tests, primitive_tests += c.primitive_tests;
        return *this;
    }
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
