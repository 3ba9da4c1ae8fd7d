// L05's probes (lessons/L05_shadows/checks.py): the shadow rays of 04_hit.h (where they start,
// their direction and reach), the ray for one light (10_classic.h shadow_ray()), and whether
// an object blocks it (in_shadow()). Each probe's first input is its mode.
#include "04_hit.h"
#include "05_sphere.h"
#include "10_classic.h"

namespace l05 {

// A hit record at p with error bound p_error and geometric normal Ng (the ray's side).
rt::Hit read_hit(rt::probe::Args &a) {
    rt::Hit hit;
    hit.p = a.vec();
    hit.p_error = a.vec();
    hit.N = hit.Ng = a.vec();
    hit.object = 0;
    return hit;
}

// The far end of a shadow ray's reach, o + max_t d: the light itself for a point light.
rt::Vec3 reach_end(const rt::ShadowRay &s) { return s.ray.o + s.max_t * s.ray.d; }

// Shadow acne: rays from `eye` through an n x n grid of points across the sphere's disc; at
// every hit the light clearly lights (N.L > 0.05: away from the terminator, where a shadow ray
// runs tangent to the surface), the shadow ray towards the light (a point, or a direction) is
// traced against the sphere itself, which, being convex, cannot lie between. Returns how many
// are blocked (acne) and, in `lit`, how many were tested.
int self_shadowed(rt::probe::Args &a, bool directional, int &lit) {
    rt::Sphere s;
    s.center = a.vec();
    s.radius = a.next();
    rt::Vec3 eye = a.vec();
    rt::Vec3 light = a.vec(); // a point, or the unit direction towards a directional light
    int n = int(a.next());
    rt::Vec3 w = rt::normalize(s.center - eye);
    rt::Vec3 u = rt::normalize(rt::cross(w, std::fabs(w.y) < 0.9 ? rt::Vec3{0, 1, 0}
                                                                   : rt::Vec3{1, 0, 0}));
    rt::Vec3 v = rt::cross(u, w);
    int blocked = 0;
    lit = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            double x = (2 * (i + 0.5) / n - 1) * 0.95, y = (2 * (j + 0.5) / n - 1) * 0.95;
            rt::Vec3 target = s.center + s.radius * (x * u + y * v);
            rt::Ray ray{eye, rt::normalize(target - eye)};
            double t = rt::sphere_t(s, ray, {0, rt::infinity});
            if (t == rt::infinity) continue;
            rt::Hit hit;
            rt::sphere_hit(s, ray, t, hit);
            rt::Vec3 L = directional ? light : rt::normalize(light - hit.p);
            if (!(rt::dot(hit.Ng, L) > 0.05)) continue;
            ++lit;
            rt::ShadowRay sr = directional ? rt::shadow_ray_towards(hit, hit.Ng, light)
                                           : rt::shadow_ray_to(hit, hit.Ng, light);
            if (rt::sphere_blocks(s, sr.ray, {0, sr.max_t})) ++blocked;
        }
    return blocked;
}

// Whether a sphere (centre, radius) blocks the shadow ray.
bool sphere_in_the_way(rt::probe::Args &a, const rt::ShadowRay &sr) {
    rt::Sphere s;
    s.center = a.vec();
    s.radius = a.next();
    return rt::sphere_blocks(s, sr.ray, {0, sr.max_t});
}

} // namespace l05

// Mode 0: p, p_error, Ng, the light's position -> unit(d), o + max_t d.
// Mode 1: acne on a sphere (self_shadowed) -> blocked, lit.
// Mode 2: p, p_error, Ng, the light's position, a sphere -> whether it blocks the shadow ray.
RT_PROBE(shadow_ray_to) {
    using rt::probe::out;
    int mode = int(a.next());
    if (mode == 1) {
        int lit = 0;
        int blocked = l05::self_shadowed(a, false, lit);
        return out(double(blocked)) + out(double(lit));
    }
    rt::Hit hit = l05::read_hit(a);
    rt::ShadowRay sr = rt::shadow_ray_to(hit, hit.Ng, a.vec());
    if (mode == 2) return out(l05::sphere_in_the_way(a, sr));
    return out(rt::normalize(sr.ray.d)) + out(l05::reach_end(sr));
}

// Mode 0: p, p_error, Ng, the unit direction towards the light -> unit(d), max_t.
// Mode 1: acne on a sphere, the light a direction -> blocked, lit.
// Mode 2: p, p_error, Ng, the direction, a sphere -> whether it blocks the shadow ray.
RT_PROBE(shadow_ray_towards) {
    using rt::probe::out;
    int mode = int(a.next());
    if (mode == 1) {
        int lit = 0;
        int blocked = l05::self_shadowed(a, true, lit);
        return out(double(blocked)) + out(double(lit));
    }
    rt::Hit hit = l05::read_hit(a);
    rt::ShadowRay sr = rt::shadow_ray_towards(hit, hit.Ng, a.vec());
    if (mode == 2) return out(l05::sphere_in_the_way(a, sr));
    return out(rt::normalize(sr.ray.d)) + out(sr.max_t);
}

// directional (0 or 1), position, direction, p, Ng (an exact hit: p_error 0) -> unit(d),
// whether the reach is bounded, and o + max_t d when it is (else 0, 0, 0).
RT_PROBE(shadow_ray) {
    using rt::probe::out;
    rt::Light light;
    light.type = a.next() != 0 ? rt::Light::Type::directional : rt::Light::Type::point;
    light.position = a.vec();
    light.direction = a.vec();
    rt::Hit hit;
    hit.p = a.vec();
    hit.N = hit.Ng = a.vec();
    hit.object = 0;
    rt::ShadowRay sr = rt::shadow_ray(hit, hit.Ng, light);
    bool bounded = sr.max_t < rt::infinity;
    return out(rt::normalize(sr.ray.d)) + out(bounded) +
           out(bounded ? l05::reach_end(sr) : rt::Vec3{0, 0, 0});
}

// The shadow ray (o, d, max_t), then the number of spheres and each (centre, radius) ->
// whether it is in shadow, and how many shadow rays were counted.
RT_PROBE(in_shadow) {
    using rt::probe::out;
    rt::ShadowRay sr;
    sr.ray = a.ray();
    sr.max_t = a.next();
    rt::Scene scene;
    int n = int(a.next());
    for (int k = 0; k < n; ++k) {
        rt::Sphere s;
        s.center = a.vec();
        s.radius = a.next();
        s.object = k;
        s.material = 0;
        scene.spheres.push_back(s);
    }
    rt::RayCounts counts;
    bool shadowed = rt::in_shadow(scene, sr, counts);
    return out(shadowed) + out(double(counts.shadow));
}
