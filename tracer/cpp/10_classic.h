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
//
// The steps the tracers share (turning the normals to the ray, starting the next ray off the
// surface) are in 04_hit.h: face_the_ray(), secondary_ray(), shadow_ray_to(),
// shadow_ray_towards(). The packet tracer (12_packet.h) and the path tracer (20_path.h) call
// the same functions.
#pragma once

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"
#include "07_material.h"
#include "08_light.h"
#include "09_scene.h"
#include "power.h"

namespace rt {

// Ambient: light that arrives from everywhere, unshadowed.
inline Color ambient_term(const Material &m, const Color &ambient_light) {
    // BEGIN SOLUTION L04
    // PROMPT: The ambient light the material returns: its colour, its ambient coefficient and the
    // PROMPT: scene's (coloured) ambient light.
    return m.color * (m.ambient * ambient_light);
    // END SOLUTION
}

// Lambert (slide "Light Reflection", Suffern fig. 13.6): a perfectly diffuse surface returns
// light in proportion to the cosine N.L between its normal and the direction to the light.
inline double lambert_term(const Vec3 &N, const Vec3 &L) {
    // BEGIN SOLUTION L04
    // PROMPT: The slide's intensity factor N.L for a unit normal N and unit direction L to the
    // PROMPT: light.
    return dot(N, L);
    // END SOLUTION
}

// Mirror direction: "redirect ray from P to d - 2(d.N)N".
inline Vec3 reflect(const Vec3 &d, const Vec3 &N) {
    // BEGIN SOLUTION L06
    // PROMPT: The mirror direction of d about the unit normal N: d - 2(d.N)N.
    return d - 2 * dot(d, N) * N;
    // END SOLUTION
}

// Phong (slide "Specular reflection"): the highlight peaks where the mirror direction R of the
// incoming ray points at the light, and narrows as the exponent grows. R.L equals V.R' with
// R' = 2(N.L)N - L, the slide's form, by the symmetry of reflection. (power() is pow(); see
// power.h for why it is our own.)
inline double phong_term(const Vec3 &R, const Vec3 &L, double shininess) {
    // BEGIN SOLUTION L06
    // PROMPT: The Phong highlight for the mirror direction R and the direction L to the light: the
    // PROMPT: cosine between them raised to `shininess` (use power), and no highlight when it is
    // PROMPT: negative.
    double cos_alpha = dot(R, L);
    return cos_alpha > 0 ? power(cos_alpha, shininess) : 0.0;
    // END SOLUTION
}

// L: the unit direction from the hit towards a light.
inline Vec3 to_light(const Light &light, const Vec3 &p) {
    // BEGIN SOLUTION L04
    // PROMPT: The unit direction L from the point p towards the light (a point light or a
    // PROMPT: directional one).
    if (light.type == Light::Type::directional) return -light.direction;
    return normalize(light.position - p);
    // END SOLUTION
}

// Shadow ray (slide "Interaction between Lights and Objects"): from the hit to a point light,
// or towards a directional light; any object strictly between blocks it. It starts off the
// surface by the hit's error bound (04_hit.h), so the surface it leaves cannot block it.
inline ShadowRay shadow_ray(const Hit &hit, const Vec3 &Ng, const Light &light) {
    // BEGIN SOLUTION L05
    // PROMPT: The shadow ray from the hit to this light (point or directional).
    if (light.type == Light::Type::directional)
        return shadow_ray_towards(hit, Ng, -light.direction);
    return shadow_ray_to(hit, Ng, light.position);
    // END SOLUTION
}

// "Objects block light": whether anything lies on the shadow ray within its reach.
inline bool in_shadow(const Scene &scene, const ShadowRay &shadow, RayCounts &counts) {
    // BEGIN SOLUTION L05
    // PROMPT: Count the shadow ray, then ask whether anything lies on it within its reach
    // PROMPT: (any_hit).
    ++counts.shadow;
    return any_hit(scene, shadow.ray, {0, shadow.max_t}, counts);
    // END SOLUTION
}

// The light one hit returns without its reflection: C_k of the slide's chain
// alpha1 (C1 + alpha2 (C2 + ...)).
inline Color local_color(const Scene &scene, const Material &m, const Hit &hit, const Vec3 &N,
                         const Vec3 &Ng, const Vec3 &R, RayCounts &counts) {
    // BEGIN SOLUTION L07
    // PROMPT: C_k of the chain: the ambient term, then for each light not in shadow and in front of
    // PROMPT: the surface the diffuse term N.L and the Phong highlight (slide "Simple Ray Tracing
    // PROMPT: Algorithm").
    Color color = ambient_term(m, scene.settings.ambient_light);
    if (m.diffuse == 0 && m.specular == 0) return color; // no light term: no shadow rays
    for (const Light &light : scene.lights) {
        Vec3 L = to_light(light, hit.p);
        double NL = lambert_term(N, L);
        // The light is behind the surface, or sits on the hit point itself, where L = 0 / 0 has
        // no direction (NaN fails every comparison; 12_packet.h tests NL > 0 the same way).
        if (!(NL > 0)) continue;
        if (in_shadow(scene, shadow_ray(hit, Ng, light), counts)) continue;
        color += (m.diffuse * NL) * (m.color * light.color);
        if (m.specular != 0) color += (m.specular * phong_term(R, L, m.shininess)) * light.color;
    }
    return color;
    // END SOLUTION
}

// The reflection-coefficient chain (slide "Specular Reflected Light"): rather than recursing,
// keep the running product coef = alpha1 alpha2 ... and add coef * C_k at each level, since
// light is linearly additive: alpha1 C1 + alpha1 alpha2 C2 + alpha1 alpha2 alpha3 C3 + ...
// (Here the primary hit is weighted 1, so the chain reads C1 + alpha1 C2 + alpha1 alpha2 C3 ...)
inline Color trace(const Scene &scene, Ray ray, RayCounts &counts) {
    // BEGIN SOLUTION L07
    // PROMPT: The slide's loop: color = black, coef = 1; at each hit add coef * local colour,
    // PROMPT: multiply coef by the reflectivity and redirect the ray; stop when nothing is hit (the
    // PROMPT: background), when coef falls below min_coefficient, or past max_depth levels.
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
        const Facing f = face_the_ray(hit, ray.d); // the side we see is the side we shade
        Vec3 R = reflect(ray.d, f.N);
        color += coef * local_color(scene, m, hit, f.N, f.Ng, R, counts);
        if (m.reflectivity == 0) break; // a feature not used costs nothing: no reflected ray
        coef *= m.reflectivity;
        ray = secondary_ray(hit, f.Ng, R);
    }
    return color;
    // END SOLUTION
}

} // namespace rt
