// Slide "True Global Ray Tracing": light can bounce many times, colour changes at each bounce,
// each bounce attenuates light, objects block light. The classic tracer follows one mirror ray;
// here each bounce is sampled at random, and the average of many such paths converges to the
// solution of the rendering equation (Kajiya 1986): unbiased Monte Carlo path tracing.
//
// Physical units: an emitting material gives radiance `emission` from its front side only (as
// Mitsuba's area emitter does); a point light's colour is its intensity (radiance falls off as
// 1/r^2); a directional light's colour is its irradiance; the background is a uniform
// environment radiance. A material scatters as a mix of three lobes:
//   Lambert:  f = albedo / pi, albedo = diffuse * color;
//   glossy:   f = specular (n + 2) / (2 pi) max(cos a, 0)^n, a from the mirror direction (the
//             normalised Phong lobe of Lafortune and Willems 1994), n = shininess;
//   mirror:   a perfect reflection carrying `reflectivity`.
// Next-event estimation samples lights at every vertex; emitters that can also be hit by the
// scattered ray (area lights, the environment) are weighted by multiple importance sampling
// (the power heuristic, Veach and Guibas 1995) so neither strategy counts them twice. Russian
// roulette ends long paths without bias. max_depth counts as Mitsuba counts: 1 sees emitters
// directly, 2 adds direct lighting, and so on (the primary ray is level 1, as in the classic
// model). The steps shared with the classic tracer keep its names: face_the_ray(),
// secondary_ray(), shadow_ray() and in_shadow() (04_hit.h, 10_classic.h), and each sample's
// random numbers come from pixel_rng() (11_render.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "01_vec3.h"
#include "02_ray.h"
#include "03_camera.h"
#include "04_hit.h"
#include "05_sphere.h"
#include "06_plane.h"
#include "07_material.h"
#include "08_light.h"
#include "09_scene.h"
#include "10_classic.h"
#include "11_render.h"
#include "16_mesh.h"
#include "constants.h"

namespace rt {

// An orthonormal basis around a unit normal (Duff et al., "Building an Orthonormal Basis,
// Revisited", JCGT 2017): no branch on which axis to cross with.
struct Frame {
    Vec3 s, t, n;
    explicit Frame(const Vec3 &normal) : n(normal) {
        double sign = std::copysign(1.0, n.z);
        double a = -1 / (sign + n.z), b = n.x * n.y * a;
        s = {1 + sign * n.x * n.x * a, sign * b, -sign * n.x};
        t = {b, sign + n.y * n.y * a, -n.y};
    }
    Vec3 to_world(const Vec3 &v) const { return v.x * s + v.y * t + v.z * n; }
};

// Slide "True Global Ray Tracing": "light can bounce many times", "light scatters in complex
// way". A Lambertian surface sends towards the eye f cos(theta) of the radiance arriving from a
// direction at angle theta from its normal, f = albedo / pi; a bounce sampled with density
// proportional to the cosine carries f cos / pdf = albedo, whatever the direction: no sample is
// wasted on the grazing directions that contribute little. Malley's method (pbrt-v4 section A.5.3, "Cosine-
// Weighted Hemisphere Sampling"): a point uniform on the unit disk, r = sqrt(u1), phi = 2 pi u2,
// projected up onto the hemisphere, z = sqrt(1 - r^2), is distributed as cos / pi.
inline Vec3 sample_cosine(double u1, double u2) {
    // BEGIN SOLUTION L12
    // PROMPT: A direction about +z whose density is cos(theta) / pi (Malley's method): a point
    // PROMPT: uniform on the unit disk (radius sqrt(u1), angle 2 pi u2), lifted onto the
    // PROMPT: hemisphere. u1 and u2 are uniform in [0, 1).
    double r = std::sqrt(u1), phi = 2 * pi * u2;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1 - u1))};
    // END SOLUTION
}

// The solid-angle density of sample_cosine() at a direction whose cosine with +z (the normal) is
// cos_theta: cos / pi, which integrates to one over the hemisphere (the integral of cos over
// the hemisphere is pi).
inline double cosine_pdf(double cos_theta) {
    // BEGIN SOLUTION L12
    // PROMPT: The density, per unit solid angle, with which sample_cosine() picks a direction at
    // PROMPT: angle theta from the normal (cos_theta = cos(theta) > 0).
    return cos_theta / pi;
    // END SOLUTION
}

// Direction about +z distributed as cos^n: pdf = (n + 1) / (2 pi) cos^n.
inline Vec3 sample_phong_lobe(double u1, double u2, double n) {
    double c = std::pow(u1, 1 / (n + 1)), s = std::sqrt(std::max(0.0, 1 - c * c));
    double phi = 2 * pi * u2;
    return {s * std::cos(phi), s * std::sin(phi), c};
}

inline Vec3 sample_sphere(double u1, double u2) { // uniform: pdf = 1 / (4 pi)
    double z = 1 - 2 * u1, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * pi * u2;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

inline double max_component(const Color &c) { return std::max(c.r, std::max(c.g, c.b)); }
inline bool is_black(const Color &c) { return c.r == 0 && c.g == 0 && c.b == 0; }

// The scattering of one material at one point: lobe weights and the normal facing the viewer.
struct BSDF {
    Color albedo;           // diffuse * color
    double specular, shininess, reflectivity;
    double p_diffuse, p_glossy, p_mirror; // the chance of sampling each lobe
    Vec3 N;                 // shading normal, on the side of the incoming ray

    BSDF(const Material &m, const Vec3 &N_)
        : albedo(m.diffuse * m.color), specular(m.specular), shininess(m.shininess),
          reflectivity(m.reflectivity), N(N_) {
        double wd = max_component(albedo), wg = specular, wm = reflectivity;
        double sum = wd + wg + wm;
        p_diffuse = sum > 0 ? wd / sum : 0;
        p_glossy = sum > 0 ? wg / sum : 0;
        p_mirror = sum > 0 ? wm / sum : 0;
    }
    bool black() const { return p_diffuse + p_glossy + p_mirror == 0; }
    bool smooth_only() const { return p_diffuse + p_glossy == 0; } // nothing for lights to see

    // f for the non-delta lobes; wo towards the viewer, wi towards the light, both unit.
    Color eval(const Vec3 &wo, const Vec3 &wi) const {
        if (dot(wi, N) <= 0 || dot(wo, N) <= 0) return {0, 0, 0};
        Color f = albedo * (1 / pi);
        if (specular > 0) {
            double cos_a = dot(reflect(-wo, N), wi);
            if (cos_a > 0) {
                double g = specular * (shininess + 2) / (2 * pi) * std::pow(cos_a, shininess);
                f += Color{g, g, g};
            }
        }
        return f;
    }
    // The solid-angle density of sample_bsdf() choosing wi, for the non-delta lobes.
    double pdf(const Vec3 &wo, const Vec3 &wi) const {
        double cos_i = dot(wi, N);
        if (cos_i <= 0 || dot(wo, N) <= 0) return 0;
        double p = p_diffuse * cosine_pdf(cos_i);
        if (p_glossy > 0) {
            double cos_a = dot(reflect(-wo, N), wi);
            if (cos_a > 0) p += p_glossy * (shininess + 1) / (2 * pi) * std::pow(cos_a, shininess);
        }
        return p;
    }
};

struct BSDFSample {
    Vec3 wi;
    Color weight;  // f cos / pdf, or for the mirror reflectivity / p_mirror
    double pdf;    // solid-angle pdf of the non-delta lobes (0 for the mirror)
    bool delta;
};

inline bool sample_bsdf(const BSDF &b, const Vec3 &wo, double u0, double u1, double u2,
                        BSDFSample &out) {
    if (dot(wo, b.N) <= 0) return false;
    Vec3 mirror = reflect(-wo, b.N);
    if (u0 < b.p_mirror) {
        out = {mirror, Color{1, 1, 1} * (b.reflectivity / b.p_mirror), 0, true};
        return true;
    }
    Vec3 wi = u0 < b.p_mirror + b.p_glossy
                  ? Frame(mirror).to_world(sample_phong_lobe(u1, u2, b.shininess))
                  : Frame(b.N).to_world(sample_cosine(u1, u2));
    double p = b.pdf(wo, wi);
    if (p <= 0) return false;
    Color f = b.eval(wo, wi);
    out = {wi, f * (dot(wi, b.N) / p), p, false};
    return true;
}

// Multiple importance sampling (Veach and Guibas 1995; Veach's thesis 1997, section 9.2): an
// area light can be found by two strategies, next-event estimation (a point sampled on the light,
// density pdf_light) and the scattered ray that happens to hit it (density pdf_bsdf). Counting
// both in full counts the light twice; weighting each sample by w = pdf_s^2 / (pdf_light^2 +
// pdf_bsdf^2), the power heuristic (eq. 9.13), keeps the estimate unbiased (the two weights of a
// direction sum to one) and lets the strategy that samples it better dominate.
inline double power_heuristic(double f, double g) {
    // BEGIN SOLUTION L12
    // PROMPT: The power heuristic's weight f^2 / (f^2 + g^2) of a sample drawn with density f, when
    // PROMPT: the other strategy would have drawn it with density g (0 when both are 0). Keep it
    // PROMPT: finite where f^2 overflows (f = 1e200).
    double f2 = f * f, g2 = g * g;
    if (f2 + g2 < infinity) return f2 + g2 > 0 ? f2 / (f2 + g2) : 0;
    // A density whose square overflows (a light of area 1e-150 seen edge on): the same weight,
    // from the ratio of the two, where inf / inf would give NaN.
    if (f >= g) {
        double r = g / f;
        return 1 / (1 + r * r);
    }
    double r = f / g;
    return r * r / (1 + r * r);
    // END SOLUTION
}

// Both strategies' weights for one direction: next-event estimation's sample (light) and the
// scattered ray's (bsdf). The path tracer uses the first at the vertex that samples the light,
// the second when the scattered ray hits the light at the next vertex.
struct MISWeights {
    double light, bsdf;
};

inline MISWeights mis_weights(double pdf_light, double pdf_bsdf) {
    // BEGIN SOLUTION L12
    // PROMPT: The power heuristic's weights of the two strategies that can find an area light, for
    // PROMPT: a direction that next-event estimation picks with density pdf_light and the
    // PROMPT: scattered ray with density pdf_bsdf: light + bsdf must be one.
    return {power_heuristic(pdf_light, pdf_bsdf), power_heuristic(pdf_bsdf, pdf_light)};
    // END SOLUTION
}

// Emitting objects that next-event estimation can sample a point on: spheres and triangle
// meshes (triangles, quads, meshes). Others (planes, boxes, cylinders, tori) still emit when a
// path hits them; for them the scattered ray is the only strategy, and MIS gives it full weight.
struct AreaLight {
    const Sphere *sphere = nullptr;
    const Mesh *mesh = nullptr;
    std::vector<double> cdf; // mesh: cumulative triangle areas
    double area = 0;
    Color emission;
    int object = -1;
};

// A point on an area light, chosen uniformly by area.
struct LightPoint {
    Vec3 p, p_error, Ng;
    double pdf_area;
};

inline LightPoint sample_area_light(const AreaLight &light, double u0, double u1, double u2) {
    LightPoint lp;
    if (light.sphere) {
        const Sphere &s = *light.sphere;
        Vec3 n = sample_sphere(u1, u2);
        lp.p = s.center + s.radius * n;
        lp.p_error = gamma(7) * (abs(s.center) + abs(s.radius * n));
        lp.Ng = n;
    } else {
        const Mesh &m = *light.mesh;
        size_t t = size_t(std::upper_bound(light.cdf.begin(), light.cdf.end(), u0 * light.area) -
                          light.cdf.begin());
        t = std::min(t, m.triangles.size() - 1);
        const auto &tri = m.triangles[t];
        Vec3 a = m.vertices[size_t(tri[0])], b = m.vertices[size_t(tri[1])],
             c = m.vertices[size_t(tri[2])];
        double su = std::sqrt(u1), b0 = 1 - su, b1 = u2 * su, b2 = 1 - b0 - b1;
        lp.p = b0 * a + b1 * b + b2 * c;
        lp.p_error = gamma(7) * (abs(b0 * a) + abs(b1 * b) + abs(b2 * c));
        lp.Ng = normalize(cross(b - a, c - a));
    }
    lp.pdf_area = 1 / light.area;
    return lp;
}

// Next-event estimation (slide "True Global Ray Tracing": "area light"): at every vertex x a
// point y on a light is chosen (by area, with probability `pick` for this light) and joined to x
// by a shadow ray. An estimate of the light's radiance in solid angle needs the density of wi in
// solid angle: a patch dA at distance r whose normal makes the angle theta_l with the ray fills
// d omega = cos(theta_l) dA / r^2, so pdf_omega = pick * pdf_area * r^2 / cos(theta_l) (pbrt-v4
// section 12.2.2; Veach's thesis eq. 8.10). The estimate f Le cos(theta_i) / pdf_omega is then
// f Le G / (pick pdf_area) with the geometry term G = cos(theta_i) cos(theta_l) / r^2.
struct LightConnection {
    Vec3 wi;      // unit direction from x towards y
    double cos_i; // at x: wi.N
    double cos_l; // at y: the cosine between the light's normal and the direction back to x
    double pdf;   // the solid-angle density of wi; 0 when the light turns its back to x
};

inline LightConnection connect_to_light(const Vec3 &x, const Vec3 &N, const LightPoint &lp,
                                        double pick) {
    // BEGIN SOLUTION L12
    // PROMPT: Join the point x (shading normal N) to the light's point lp (lp.p, normal lp.Ng,
    // PROMPT: density per unit area lp.pdf_area) chosen with probability `pick`: the unit direction
    // PROMPT: wi to it, the cosines at both ends, and the density of wi per unit solid angle (0
    // PROMPT: when the light faces away from x).
    Vec3 v = lp.p - x;
    double d2 = dot(v, v), d = std::sqrt(d2);
    Vec3 wi = v / d;
    double cos_l = -dot(lp.Ng, wi), cos_i = dot(wi, N);
    double pdf = cos_l > 0 ? pick * lp.pdf_area * d2 / cos_l : 0;
    return {wi, cos_i, cos_l, pdf};
    // END SOLUTION
}

// What one unblocked light sample adds to the pixel: the path's throughput beta times the
// estimate f Le cos(theta_i) / pdf, weighted by its MIS weight w (the Monte Carlo estimator of
// the rendering equation's direct part, Kajiya 1986).
inline Color light_estimate(const Color &beta, const Color &f, const Color &Le, double cos_i,
                            double w, double pdf) {
    // BEGIN SOLUTION L12
    // PROMPT: The contribution of one unblocked light sample: throughput beta, BSDF value f, the
    // PROMPT: light's radiance Le, the cosine at the surface cos_i, its MIS weight w and its
    // PROMPT: solid-angle density pdf (beta f Le cos_i w / pdf, channel by channel).
    return beta * f * Le * (cos_i * w / pdf);
    // END SOLUTION
}

struct PathContext {
    const Scene &scene;
    std::vector<AreaLight> area_lights;
    std::vector<int> area_light_of_object; // object index -> area light index, or -1
    bool environment;                      // a non-black background: a light to sample
    int n_sampled; // area lights + the environment: one of them is sampled per vertex

    explicit PathContext(const Scene &s) : scene(s), environment(!is_black(s.settings.background)) {
        int n_objects = 0;
        for (const Sphere &sp : s.spheres) n_objects = std::max(n_objects, sp.object + 1);
        for (const Plane &pl : s.planes) n_objects = std::max(n_objects, pl.object + 1);
        for (const auto &o : s.objects) {
            n_objects = std::max(n_objects, o->object + 1);
            if (const auto *mesh = dynamic_cast<const Mesh *>(o.get())) // a joined mesh
                for (int k : mesh->triangle_object) n_objects = std::max(n_objects, k + 1);
        }
        area_light_of_object.assign(size_t(n_objects), -1);
        for (const Sphere &sp : s.spheres) {
            const Material &m = s.materials[size_t(sp.material)];
            if (is_black(m.emission)) continue;
            AreaLight l;
            l.sphere = &sp;
            l.area = 4 * pi * sp.radius * sp.radius;
            l.emission = m.emission;
            l.object = sp.object;
            add(l);
        }
        for (const auto &o : s.objects) {
            const auto *mesh = dynamic_cast<const Mesh *>(o.get());
            const Material &m = s.materials[size_t(o->material)];
            if (!mesh || is_black(m.emission)) continue;
            AreaLight l;
            l.mesh = mesh;
            double acc = 0;
            for (const auto &tri : mesh->triangles) {
                Vec3 a = mesh->vertices[size_t(tri[0])], b = mesh->vertices[size_t(tri[1])],
                     c = mesh->vertices[size_t(tri[2])];
                acc += 0.5 * length(cross(b - a, c - a));
                l.cdf.push_back(acc);
            }
            l.area = acc;
            l.emission = m.emission;
            l.object = o->object;
            add(l);
        }
        n_sampled = int(area_lights.size()) + (environment ? 1 : 0);
    }
    // A light whose area is 0 (a sphere of radius 1e-300), below 1e-308 (so that 1 / area
    // overflows) or infinite (radius 1e200) has no finite density 1 / area to sample its
    // points by; it still emits when a path hits it, with the scattered ray as the only
    // strategy (as planes and boxes do).
    void add(const AreaLight &l) {
        if (!(l.area < infinity && 1 / l.area < infinity)) return;
        area_light_of_object[size_t(l.object)] = int(area_lights.size());
        area_lights.push_back(l);
    }
    // The solid-angle density with which next-event estimation picks the point y (normal Ng,
    // on area light `index`) seen from x.
    double light_pdf(int index, const Vec3 &x, const Vec3 &y, const Vec3 &Ng) const {
        Vec3 v = y - x;
        double d2 = dot(v, v), cos_l = std::fabs(dot(Ng, v)) / std::sqrt(d2);
        if (cos_l == 0) return 0;
        return (1.0 / n_sampled) / area_lights[size_t(index)].area * d2 / cos_l;
    }
};

constexpr int roulette_from_level = 5;         // Mitsuba's rr_depth
constexpr double roulette_max_survival = 0.95; // Mitsuba's cap on the survival chance

// Slide "True Global Ray Tracing": "each bounce attenuates light". Russian roulette (Arvo and
// Kirk 1990; pbrt-v4 section 13.1.1) ends a path whose throughput beta has dropped, without
// bias: it survives with probability q and then carries 1/q more, so the expectation is
// unchanged. q follows the brightest channel of beta, capped at roulette_max_survival (as
// Mitsuba's): even a bright path ends with a chance of 5 %, so none runs on for ever.
// Returns whether the path goes on (beta reweighted), given u uniform in [0, 1).
inline bool russian_roulette(Color &beta, double u) {
    // BEGIN SOLUTION L12
    // PROMPT: Survive with probability q = min(brightest channel of beta, roulette_max_survival)
    // PROMPT: (u < q), and then divide beta by q so the estimate stays unbiased; return whether the
    // PROMPT: path goes on.
    double q = std::min(max_component(beta), roulette_max_survival);
    if (!(u < q)) return false;
    beta = beta * (1 / q);
    return true;
    // END SOLUTION
}

// One path from the camera: the radiance it carries back along `ray`.
inline Color trace_path(const PathContext &ctx, Ray ray, Rng &rng, RayCounts &counts) {
    const Scene &scene = ctx.scene;
    const Settings &s = scene.settings;
    Color L{0, 0, 0}, beta{1, 1, 1}; // the radiance so far; the path's throughput
    bool prev_delta = true;           // the camera ray and mirror bounces: no MIS
    double prev_pdf = 0;
    Vec3 prev_x;
    for (int level = 1;; ++level) {
        Hit hit = closest_hit(scene, ray, counts);
        if (!hit.found()) { // the environment
            if (ctx.environment) {
                double w = prev_delta
                               ? 1
                               : mis_weights((1.0 / ctx.n_sampled) / (4 * pi), prev_pdf).bsdf;
                L += beta * s.background * w;
            }
            break;
        }
        const Material &m = scene.materials[size_t(hit.material)];
        Vec3 wo = -ray.d;
        const Facing f = face_the_ray(hit, ray.d);
        const Vec3 &N = f.N, &Ng = f.Ng;
        bool front = dot(hit.Ng, ray.d) < 0; // the ray meets the surface's own front side
        if (front && !is_black(m.emission)) { // emission leaves the front side only
            double w = 1;
            int light = ctx.area_light_of_object[size_t(hit.object)];
            if (!prev_delta && light >= 0)
                w = mis_weights(ctx.light_pdf(light, prev_x, hit.p, hit.Ng), prev_pdf).bsdf;
            L += beta * m.emission * w;
        }
        if (level >= s.max_depth) break;
        BSDF bsdf(m, N);
        if (bsdf.black()) break;

        // Next-event estimation: every point and directional light, and one of the others.
        if (!bsdf.smooth_only()) {
            for (const Light &light : scene.lights) {
                Vec3 wi;
                Color Li;
                if (light.type == Light::Type::point) {
                    Vec3 v = light.position - hit.p;
                    double d2 = dot(v, v);
                    wi = v / std::sqrt(d2);
                    Li = light.color * (1 / d2); // intensity / r^2
                } else {
                    wi = -light.direction;
                    Li = light.color; // irradiance
                }
                double cos_i = dot(wi, N);
                // Behind the surface, or a point light on the hit point itself (wi = 0 / 0).
                if (!(cos_i > 0 && dot(wi, Ng) > 0)) continue;
                if (!in_shadow(scene, shadow_ray(hit, Ng, light), counts))
                    L += beta * bsdf.eval(wo, wi) * Li * cos_i;
            }
            if (ctx.n_sampled > 0) {
                int k = std::min(int(rng.uniform() * ctx.n_sampled), ctx.n_sampled - 1);
                double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                if (k < int(ctx.area_lights.size())) {
                    const AreaLight &al = ctx.area_lights[size_t(k)];
                    LightPoint lp = sample_area_light(al, u0, u1, u2);
                    LightConnection c = connect_to_light(hit.p, N, lp, 1.0 / ctx.n_sampled);
                    const Vec3 &wi = c.wi;
                    if (c.cos_l > 0 && c.cos_i > 0 && dot(wi, Ng) > 0) {
                        // The light's point, moved off the light's own surface towards the hit
                        // (pbrt-v4 SpawnRayTo between two surfaces), so the light cannot block
                        // the ray that reaches it.
                        Vec3 target = offset_ray_origin(lp.p, lp.p_error, lp.Ng, -wi);
                        if (!in_shadow(scene, shadow_ray_to(hit, Ng, target), counts)) {
                            double w = mis_weights(c.pdf, bsdf.pdf(wo, wi)).light;
                            L += light_estimate(beta, bsdf.eval(wo, wi), al.emission, c.cos_i, w,
                                                c.pdf);
                        }
                    }
                } else { // the environment, uniformly over the sphere
                    Vec3 wi = sample_sphere(u1, u2);
                    double cos_i = dot(wi, N);
                    if (cos_i > 0 && dot(wi, Ng) > 0 &&
                        !in_shadow(scene, shadow_ray_towards(hit, Ng, wi), counts)) {
                        double pdf_l = (1.0 / ctx.n_sampled) / (4 * pi);
                        double w = mis_weights(pdf_l, bsdf.pdf(wo, wi)).light;
                        L += light_estimate(beta, bsdf.eval(wo, wi), s.background, cos_i, w,
                                            pdf_l);
                    }
                }
            }
        }

        // Scatter: choose a lobe, a direction, and carry f cos / pdf along.
        BSDFSample bs;
        double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        if (!sample_bsdf(bsdf, wo, u0, u1, u2, bs)) break;
        if (dot(bs.wi, Ng) <= 0) break; // a smooth normal sent it into the surface
        beta = beta * bs.weight;
        prev_delta = bs.delta, prev_pdf = bs.pdf, prev_x = hit.p;
        // Russian roulette from rr_depth 5 on (as Mitsuba): the first bounces always survive
        // (they carry most of the light).
        if (level >= roulette_from_level && !russian_roulette(beta, rng.uniform())) break;
        ray = secondary_ray(hit, Ng, bs.wi);
        ++counts.secondary;
    }
    return L;
}

// A tile of pixels: spp paths per pixel through the strata of for_each_sample(), each path
// drawing on its sample's own random stream (pixel_rng()), box-filtered.
inline void render_tile_path(const PathContext &ctx, int x0, int y0, int x1, int y1, float *out,
                             RayCounts &counts) {
    const Scene &scene = ctx.scene;
    const Camera &cam = scene.camera;
    for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i) {
            Color sum{0, 0, 0};
            for_each_sample(scene, i, j, [&](double sx, double sy, Rng &rng) {
                ++counts.primary;
                sum += trace_path(ctx, cam.primary_ray(sx, sy), rng, counts);
            });
            store_pixel(out, cam.width, i, j, sum * (1.0 / scene.settings.spp));
        }
}

} // namespace rt
