// Slide "How is it Done?": the scene - objects, lights, the eye - and the two questions a ray
// asks of it: what is the closest hit (primary and secondary rays), and is anything in the way
// (shadow rays).
//
// As in the course's Ex 25 ("no object abstraction, STL vector<> for lists"), spheres and planes
// have lists of their own; every other kind of object (boxes, triangles, meshes, cylinders, tori:
// "Building a real Ray Tracer in C++") is an Object with a virtual hit(). Every object keeps its
// index into the scene file's [[objects]].
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "01_vec3.h"
#include "02_ray.h"
#include "03_camera.h"
#include "04_hit.h"
#include "05_sphere.h"
#include "06_plane.h"
#include "07_material.h"
#include "08_light.h"
#include "constants.h"

namespace rt {

// Where a pixel's samples lie when spp > 1 (11_render.h for_each_sample()).
enum class Sampler {
    stratified, // a rows x cols grid of strata, one jittered sample in each
    sobol,      // Sobol's (0,2)-sequence, Owen-scrambled per pixel
};

// The defaults are the scene language's (the Python package tracer.scene sets every field).
struct Settings {
    int max_depth = 5;            // the primary ray is level 1
    double min_coefficient = 0;   // a level whose chain coefficient is below this is black
    int spp = 1;                  // samples per pixel
    uint64_t seed = 0;
    Sampler sampler = Sampler::stratified;
    Color background{0, 0, 0};    // what a ray that hits nothing returns
    Color ambient_light{1, 1, 1};
};

struct Scene {
    Camera camera;
    Settings settings;
    std::vector<Material> materials;
    std::vector<Light> lights;
    std::vector<Sphere> spheres;
    std::vector<Plane> planes;
    std::vector<std::shared_ptr<const Object>> objects;
};

// The closest sphere or plane, spheres first; range.max shrinks to it. A later hit by another
// object forgets it (Nearest{}); record() fills the hit record of whichever is left.
struct Nearest {
    const Sphere *sphere = nullptr;
    const Plane *plane = nullptr;
    void record(const Ray &ray, double t, Hit &hit) const {
        if (plane) plane_hit(*plane, ray, t, hit);
        else if (sphere) sphere_hit(*sphere, ray, t, hit);
    }
};

inline Nearest nearest_sphere_or_plane(const Scene &scene, const Ray &ray, Interval &range,
                                       RayCounts &counts) {
    Nearest nearest;
    counts.primitive_tests += scene.spheres.size() + scene.planes.size();
    for (const Sphere &s : scene.spheres) {
        double t = sphere_t(s, ray, range);
        if (t < range.max) range.max = t, nearest.sphere = &s;
    }
    for (const Plane &pl : scene.planes) {
        double t = plane_t(pl, ray);
        if (range.surrounds(t)) range.max = t, nearest = {nullptr, &pl};
    }
    return nearest;
}

// "Find nearest hit" (slide "How ray tracing works"). The search needs only each object's t;
// the hit record (point, error bound, normal) is computed once, for the closest.
inline Hit closest_hit(const Scene &scene, const Ray &ray, RayCounts &counts) {
    Interval range{0, infinity};
    Nearest nearest = nearest_sphere_or_plane(scene, ray, range, counts);
    Hit hit;
    for (const auto &object : scene.objects)
        if (object->hit(ray, range, hit, counts)) range.max = hit.t, nearest = Nearest{};
    nearest.record(ray, range.max, hit);
    return hit;
}

// Whether a sphere or a plane lies within the range: any_hit()'s first question.
inline bool sphere_or_plane_blocks(const Scene &scene, const Ray &ray, const Interval &range,
                                   RayCounts &counts) {
    for (const Sphere &s : scene.spheres) {
        ++counts.primitive_tests;
        if (sphere_blocks(s, ray, range)) return true;
    }
    for (const Plane &pl : scene.planes) {
        ++counts.primitive_tests;
        if (plane_blocks(pl, ray, range)) return true;
    }
    return false;
}

// "Objects block light": true as soon as any object lies within the range; no need to sort.
inline bool any_hit(const Scene &scene, const Ray &ray, const Interval &range,
                    RayCounts &counts) {
    if (sphere_or_plane_blocks(scene, ray, range, counts)) return true;
    for (const auto &object : scene.objects)
        if (object->blocks(ray, range, counts)) return true;
    return false;
}

} // namespace rt
