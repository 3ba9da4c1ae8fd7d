// Slide "Simple Ray Tracing Algorithm", step by step. Each step a student writes is a function
// of its own, so a lesson can hand it out as an exercise:
//
//   Initialize ray (O, d); color = black; coef = 1
//   Find closest intersection P
//     color += coef * ambient * material                       ambient_term()
//     if not in shadow color += coef * N.L * diffuse * material  shadow_ray(), lambert_term()
//                      (and the Phong highlight)                 phong_term()
//     coef *= reflectivity                                       the chain, trace()
//     redirect ray from P to d - 2 (d.N) N                       reflect(), secondary_ray()
//   Stop when no intersection, or coef << 1, or maximum number of bounces
#pragma once

#include <cmath>

#include "09_scene.h"
#include "power.h"

namespace rt {

// Ambient: light that arrives from everywhere, unshadowed.
inline Color ambient_term(const Material &m, const Color &ambient_light) {
    return m.color * (m.ambient * ambient_light);
}

// Lambert (slide "Light Reflection", Suffern fig. 13.6): a perfectly diffuse surface returns
// light in proportion to the cosine N.L between its normal and the direction to the light.
inline double lambert_term(const Vec3 &N, const Vec3 &L) { return dot(N, L); }

// Mirror direction: "redirect ray from P to d - 2(d.N)N".
inline Vec3 reflect(const Vec3 &d, const Vec3 &N) { return d - 2 * dot(d, N) * N; }

// Phong (slide "Specular reflection"): the highlight peaks where the mirror direction R of the
// incoming ray points at the light, and narrows as the exponent grows. R.L equals V.R' with
// R' = 2(N.L)N - L, the slide's form, by the symmetry of reflection. (power() is pow(); see
// power.h for why it is our own.)
inline double phong_term(const Vec3 &R, const Vec3 &L, double shininess) {
    double cos_alpha = dot(R, L);
    return cos_alpha > 0 ? power(cos_alpha, shininess) : 0.0;
}

// L: the unit direction from the hit towards a light.
inline Vec3 to_light(const Light &light, const Vec3 &p) {
    if (light.type == Light::Type::directional) return -light.direction;
    return normalize(light.position - p);
}

// Shadow ray: from the hit towards the light; any object strictly between blocks it. The origin
// is moved off the surface by the hit's error bound (02_ray.h), so the surface the ray leaves
// cannot block it. Towards a point light the direction is left unnormalised, light - origin, so
// that the light itself sits at t = 1 and the blocking range is exactly (0, 1).
inline Ray shadow_ray(const Hit &hit, const Vec3 &Ng, const Light &light, const Vec3 &L) {
    Vec3 o = offset_ray_origin(hit.p, hit.p_error, Ng, L);
    if (light.type == Light::Type::directional) return {o, L};
    return {o, light.position - o};
}

inline bool in_shadow(const Scene &scene, const Ray &shadow, const Light &light,
                      RayCounts &counts) {
    double max_t = light.type == Light::Type::directional ? infinity : 1.0;
    return any_hit(scene, shadow, {0, max_t}, counts);
}

// Secondary (reflected) ray: starts just off the surface on the side it leaves to (measured
// along the geometric normal Ng, the surface's own).
inline Ray secondary_ray(const Hit &hit, const Vec3 &Ng, const Vec3 &R) {
    return {offset_ray_origin(hit.p, hit.p_error, Ng, R), R};
}

// The light one hit returns without its reflection: C_k of the slide's chain
// alpha1 (C1 + alpha2 (C2 + ...)).
inline Color local_color(const Scene &scene, const Material &m, const Hit &hit, const Vec3 &N,
                         const Vec3 &Ng, const Vec3 &R, RayCounts &counts) {
    Color color = ambient_term(m, scene.settings.ambient_light);
    if (m.diffuse == 0 && m.specular == 0) return color; // no light term: no shadow rays
    for (const Light &light : scene.lights) {
        Vec3 L = to_light(light, hit.p);
        double NL = lambert_term(N, L);
        if (NL <= 0) continue; // the light is behind the surface
        ++counts.shadow;
        if (in_shadow(scene, shadow_ray(hit, Ng, light, L), light, counts)) continue;
        color += (m.diffuse * NL) * (m.color * light.color);
        if (m.specular != 0) color += (m.specular * phong_term(R, L, m.shininess)) * light.color;
    }
    return color;
}

// The reflection-coefficient chain (slide "Specular Reflected Light"): rather than recursing,
// keep the running product coef = alpha1 alpha2 ... and add coef * C_k at each level, since
// light is linearly additive: alpha1 C1 + alpha1 alpha2 C2 + alpha1 alpha2 alpha3 C3 + ...
// (Here the primary hit is weighted 1, so the chain reads C1 + alpha1 C2 + alpha1 alpha2 C3 ...)
inline Color trace(const Scene &scene, Ray ray, RayCounts &counts) {
    const Settings &s = scene.settings;
    Color color{0, 0, 0};
    double coef = 1;
    for (int level = 1;; ++level) {
        if (level > s.max_depth) break;      // past the last level: black
        if (coef < s.min_coefficient) break; // "coef << 1": black
        if (level > 1) ++counts.secondary;
        Hit hit = closest_hit(scene, ray, counts);
        if (!hit.found()) {
            color += coef * s.background;
            break;
        }
        const Material &m = scene.materials[hit.material];
        // Turn N to face the incoming ray: the side we see is the side we shade. (The shading
        // normal N of a smooth mesh follows its geometric normal Ng to that side.)
        Vec3 Ng = dot(hit.Ng, ray.d) > 0 ? -hit.Ng : hit.Ng;
        Vec3 N = dot(hit.N, Ng) < 0 ? -hit.N : hit.N;
        Vec3 R = reflect(ray.d, N);
        color += coef * local_color(scene, m, hit, N, Ng, R, counts);
        if (m.reflectivity == 0) break; // a feature not used costs nothing: no reflected ray
        coef *= m.reflectivity;
        ray = secondary_ray(hit, Ng, R);
    }
    return color;
}

} // namespace rt
