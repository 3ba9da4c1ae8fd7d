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
#include "13_transform.h"
#include "14_box.h"
#include "15_triangle.h"
#include "16_mesh.h"
#include "21_wide_bvh.h"
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
// wasted on the grazing directions that contribute little. Malley's method (pbrt-v4 section
// A.5.3, "Cosine-Weighted Hemisphere Sampling"): a point uniform on the unit disk, r = sqrt(u1),
// phi = 2 pi u2, projected up onto the hemisphere, z = sqrt(1 - r^2), is distributed as cos / pi.
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
    std::vector<double> cdf;   // mesh: cumulative triangle areas
    std::vector<Vec3> normals; // mesh: each triangle's unit normal, once (not per sample)
    double area = 0;
    Color emission;
    int object = -1;
    // Constants of every sample, divided once (PathContext): 1 / area, and the density per
    // unit area with which next-event estimation picks a point of this light, pick / area.
    double pdf_area = 0, pick_per_area = 0;
};

// A point on an area light, chosen uniformly by area.
struct LightPoint {
    Vec3 p, p_error, Ng;
    double pdf_area;
};

inline LightPoint sample_area_light(const AreaLight &light, double u1, double u2) {
    LightPoint lp;
    if (light.sphere) {
        const Sphere &s = *light.sphere;
        Vec3 n = sample_sphere(u1, u2);
        lp.p = s.center + s.radius * n;
        lp.p_error = gamma(7) * (abs(s.center) + abs(s.radius * n));
        lp.Ng = n;
    } else {
        const Mesh &m = *light.mesh;
        // The triangle by u1, which is then stretched back over [0, 1) within the triangle's
        // share of the area (sample reuse, pbrt-v4 SampleDiscrete()): the pair (u1, u2) picks
        // both the triangle and the point in it, so a pair spread evenly over the unit square
        // (11_render.h SobolStream) is spread evenly over the whole light, a quad's two
        // triangles included.
        double at = u1 * light.area;
        size_t t = size_t(std::upper_bound(light.cdf.begin(), light.cdf.end(), at) -
                          light.cdf.begin());
        t = std::min(t, m.triangles.size() - 1);
        double below = t == 0 ? 0 : light.cdf[t - 1], share = light.cdf[t] - below;
        u1 = std::clamp((at - below) / share, 0.0, 0x1.fffffffffffffp-1); // in [0, 1)
        const auto &tri = m.triangles[t];
        Vec3 a = m.vertices[size_t(tri[0])], b = m.vertices[size_t(tri[1])],
             c = m.vertices[size_t(tri[2])];
        double su = std::sqrt(u1), b0 = 1 - su, b1 = u2 * su, b2 = 1 - b0 - b1;
        lp.p = b0 * a + b1 * b + b2 * c;
        lp.p_error = gamma(7) * (abs(b0 * a) + abs(b1 * b) + abs(b2 * c));
        lp.Ng = light.normals[t];
    }
    lp.pdf_area = light.pdf_area; // 1 / light.area
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
    double pick = 0; // 1 / n_sampled: the chance of each
    std::vector<BSDF> bsdfs; // each material's lobes (BSDF's constructor), for any normal

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
                l.normals.push_back(normalize(cross(b - a, c - a)));
            }
            l.area = acc;
            l.emission = m.emission;
            l.object = o->object;
            add(l);
        }
        n_sampled = int(area_lights.size()) + (environment ? 1 : 0);
        pick = 1.0 / n_sampled;
        for (AreaLight &l : area_lights) l.pdf_area = 1 / l.area, l.pick_per_area = pick / l.area;
        for (const Material &m : s.materials) bsdfs.emplace_back(m, Vec3{0, 0, 1});
    }
    // The scattering of material `material` at a point whose normal (facing the ray) is N.
    BSDF bsdf(int material, const Vec3 &N) const {
        BSDF b = bsdfs[size_t(material)];
        b.N = N;
        return b;
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
        return area_lights[size_t(index)].pick_per_area * d2 / cos_l; // (1 / n) / area ...
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

// The two questions a path asks the scene (slide "How is it Done?"), as the lecture's code asks
// them: closest_hit() (09_scene.h) and in_shadow() (10_classic.h), every object tested in turn.
// The student's build renders with these (packets=False).
struct SceneQueries {
    const Scene &scene;
    Hit closest(const Ray &ray, RayCounts &counts) const { return closest_hit(scene, ray, counts); }
    bool blocked(const ShadowRay &shadow, RayCounts &counts) const {
        return in_shadow(scene, shadow, counts);
    }
};

// -- Speed beside the lesson code (packets=True): the same two answers, fewer tests -------------
//
// A ray of the Cornell box meets the room's mesh, the light's mesh and two boxes; the lecture's
// closest_hit() asks each in turn, and each builds its own per-ray set-up (a box transforms the
// ray and takes three reciprocals; a mesh takes six divisions before its first box test). Here
// every ray takes its slab set-up (SlabRay, 14_box.h) once, and an object whose box in world
// coordinates the ray misses within the current range is skipped: the test a top-level
// hierarchy makes over its objects (pbrt-v4 7.3, "Bounding Volume Hierarchies"). Skipping is
// exact only if an object the ray could hit is never skipped; why it is not, per kind of
// object, is argued at WorldBounds::around(). The answers are then the lecture's, bit for bit
// (tests/tracer/test_path.py): the same objects, in the same order, give the same hits.

inline double max_abs(const Vec3 &v) {
    return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z)));
}

// An object's box in world coordinates, and the margin by which a ray must miss it to be
// skipped: margin = absolute + per_reach |o| (|o| the largest coordinate of the ray's origin).
struct WorldBounds {
    AABB box;
    double absolute = 0, per_reach = 0;

    // A mesh: the root of its hierarchy, which is already in world coordinates, with no margin:
    // Mesh::traverse() begins with slab_test() of this box, this ray (the same SlabRay, made
    // from the same ray) and this range, so a ray skipped here is one it would reject at once.
    static WorldBounds around(const Mesh &mesh) {
        WorldBounds b;
        if (!mesh.nodes.empty()) b.box = mesh.nodes[0].bounds;
        return b;
    }

    // A box placed by a transform p -> A p + b: the hull of its eight corners placed in the
    // world, widened by a bound on how far outside the placed box a hit that Box::hit() accepts
    // can lie. Box::hit() tests o'' = inv o + c, d'' = inv d (inv ~ A^-1 and c ~ -inv b as
    // Transform::from_matrix() computed them), rounded by at most e1 = gamma(4) (|inv| |o| +
    // |c|) and e2 = gamma(3) |inv| |d| (sums of four products, Higham ch. 3), and its slab t
    // carry a relative error of gamma(3) (a difference, a reciprocal, a product): at an accepted
    // t the computed ray is within gamma(3) t |d''| of a point q of the box. Then (infinity
    // norms, rho = ||I - A inv||, taken from the computed product plus its own rounding)
    //   o + t d - (A q + b) = (I - A inv)(o + t d - b) - A (c + inv b) - A (e1 + t e2) + A (...)
    // is at most rho (|o| + t|d| + |b|) + ||A|| (gamma(3) ||inv|| |b| + e1 + 2 gamma(4) ||inv||
    // t|d|), and t|d| <= |o| + R at a point near the box (R its largest placed coordinate). The
    // world slab test's own near t may come out a relative gamma(3) late: gamma(3) (|o| + R)
    // more. The sum is absolute + per_reach |o|; both are taken 16 times over (a margin near
    // 1e-14 of the scene's size skips the same rays; the factor covers second-order terms).
    static WorldBounds around(const Box &box) {
        const Transform &T = box.transform;
        WorldBounds b;
        double R = 0;
        for (int k = 0; k < 8; ++k) {
            Vec3 corner{k & 1 ? box.box.max.x : box.box.min.x,
                        k & 2 ? box.box.max.y : box.box.min.y,
                        k & 4 ? box.box.max.z : box.box.min.z};
            Vec3 p = T.point(corner);
            b.box.extend(p);
            R = std::max(R, max_abs(p));
        }
        double norm_A = 0, norm_inv = 0, c = 0, t = 0, rho = 0, abs_product = 0;
        for (int i = 0; i < 3; ++i) {
            norm_A = std::max(norm_A, std::fabs(T.m[i][0]) + std::fabs(T.m[i][1]) +
                                          std::fabs(T.m[i][2]));
            norm_inv = std::max(norm_inv, std::fabs(T.inv[i][0]) + std::fabs(T.inv[i][1]) +
                                              std::fabs(T.inv[i][2]));
            c = std::max(c, std::fabs(T.inv[i][3]));
            t = std::max(t, std::fabs(T.m[i][3]));
            double row = 0, abs_row = 0;
            for (int j = 0; j < 3; ++j) {
                double e = -(i == j ? 1.0 : 0.0);
                for (int k = 0; k < 3; ++k) {
                    e += T.m[i][k] * T.inv[k][j];
                    abs_row += std::fabs(T.m[i][k] * T.inv[k][j]);
                }
                row += std::fabs(e);
            }
            rho = std::max(rho, row);
            abs_product = std::max(abs_product, abs_row);
        }
        rho += gamma(4) * (abs_product + 3); // the computed residual's own rounding
        constexpr double safety = 16;
        b.absolute = safety * (rho * (R + t) +
                               norm_A * gamma(4) * (norm_inv * t + c + 2 * norm_inv * R) +
                               gamma(3) * R);
        b.per_reach = safety * (2 * rho + 3 * gamma(4) * norm_A * norm_inv + gamma(3));
        // A margin that is not finite (a degenerate transform) skips nothing.
        if (!(b.absolute < infinity && b.per_reach < infinity)) b = everywhere();
        return b;
    }

    // Everything else (cylinders, tori): all of space, so nothing is skipped.
    static WorldBounds everywhere() {
        WorldBounds b;
        b.box = AABB{{-infinity, -infinity, -infinity}, {infinity, infinity, infinity}};
        return b;
    }

    bool may_hit(const SlabRay &r, double reach, const Interval &range, RayCounts &counts) const {
        ++counts.box_tests;
        if (absolute == 0 && per_reach == 0) {
            double t_near;
            return slab_test(box, r, range, t_near);
        }
        double m = absolute + per_reach * reach;
        AABB wide{{box.min.x - m, box.min.y - m, box.min.z - m},
                  {box.max.x + m, box.max.y + m, box.max.z + m}};
        double t_near;
        return slab_test(wide, r, range, t_near);
    }
};

// closest_hit() and in_shadow() as the lecture writes them (09_scene.h, 10_classic.h), with each
// object behind its world bounds. Shadow rays ask the boxes before the meshes: any blocker
// answers, and a box is the cheaper test. A mesh whose wide tree is one node (WideBVH::flat,
// 21_wide_bvh.h) is searched here directly, with the ray's slab and watertight set-up made once
// for all of them: the hit Mesh::hit() would give (the same search, the same record()).
struct CulledQueries {
    const Scene &scene;
    struct Bounded {
        const Object *object;
        WorldBounds bounds;
        const Mesh *mesh = nullptr;   // a flat mesh (flat_bvh its search), else null
        const WideBVH *flat_bvh = nullptr;
    };
    std::vector<Bounded> objects; // in the scene's order (ties between equal t go as there)
    std::vector<Bounded> blockers; // the same, boxes first
    bool any_flat = false;

    explicit CulledQueries(const Scene &s) : scene(s) {
        for (const auto &o : s.objects) {
            if (const auto *mesh = dynamic_cast<const Mesh *>(o.get())) {
                Bounded b{o.get(), WorldBounds::around(*mesh)};
                // Mesh::search()'s choice: the faster search only with packets on.
                const auto *wide = mesh->packets
                                       ? dynamic_cast<const WideBVH *>(mesh->accelerator.get())
                                       : nullptr;
                if (wide && wide->flat) b.mesh = mesh, b.flat_bvh = wide, any_flat = true;
                objects.push_back(b);
            } else if (const auto *box = dynamic_cast<const Box *>(o.get()))
                objects.push_back({o.get(), WorldBounds::around(*box)});
            else
                objects.push_back({o.get(), WorldBounds::everywhere()});
        }
        for (const Bounded &b : objects)
            if (dynamic_cast<const Box *>(b.object)) blockers.push_back(b);
        for (const Bounded &b : objects)
            if (!dynamic_cast<const Box *>(b.object)) blockers.push_back(b);
    }

    Hit closest(const Ray &ray, RayCounts &counts) const {
        Interval range{0, infinity};
        Nearest nearest = nearest_sphere_or_plane(scene, ray, range, counts);
        Hit hit;
        if (!objects.empty()) {
            const SlabRay sr(ray);
            const double reach = max_abs(ray.o);
            // The ray's watertight set-up (15_triangle.h: a permutation and three divisions),
            // once for every flat mesh.
            WatertightRay wr;
            if (any_flat) wr = WatertightRay(ray);
            for (const Bounded &b : objects) {
                if (!b.bounds.may_hit(sr, reach, range, counts)) continue;
                if (b.flat_bvh) { // Mesh::hit(), its root box tested above
                    TriangleHit th;
                    int t = -1;
                    if (b.flat_bvh->search_flat(*b.mesh, sr, wr, range, th, t, counts, false)) {
                        b.mesh->record(th, t, hit);
                        range.max = hit.t, nearest = Nearest{};
                    }
                    continue;
                }
                if (b.object->hit(ray, range, hit, counts)) range.max = hit.t, nearest = Nearest{};
            }
        }
        nearest.record(ray, range.max, hit);
        return hit;
    }

    bool blocked(const ShadowRay &shadow, RayCounts &counts) const {
        ++counts.shadow;
        const Ray &ray = shadow.ray;
        const Interval range{0, shadow.max_t};
        if (sphere_or_plane_blocks(scene, ray, range, counts)) return true;
        if (blockers.empty()) return false;
        const SlabRay sr(ray);
        const double reach = max_abs(ray.o);
        WatertightRay wr;
        bool wr_made = false; // when the first flat mesh is asked (a box may answer first)
        for (const Bounded &b : blockers) {
            if (!b.bounds.may_hit(sr, reach, range, counts)) continue;
            if (b.flat_bvh) { // Mesh::blocks(), its root box tested above
                if (!wr_made) wr = WatertightRay(ray), wr_made = true;
                TriangleHit th;
                int t = -1;
                if (b.flat_bvh->search_flat(*b.mesh, sr, wr, range, th, t, counts, true))
                    return true;
                continue;
            }
            if (b.object->blocks(ray, range, counts)) return true;
        }
        return false;
    }
};

// One path from the camera: the radiance it carries back along `ray`, the scene asked through
// `queries` (SceneQueries: the lecture's; CulledQueries: the same answers, sooner).
// `rng`: the sample's random numbers (11_render.h: an Rng, or a SobolStream that stratifies
// the first vertices' numbers across the pixel's samples); uniform2() takes the two numbers of
// one two-dimensional choice.
template <class Queries, class Random>
inline Color trace_path(const PathContext &ctx, const Queries &queries, Ray ray, Random &rng,
                        RayCounts &counts) {
    const Scene &scene = ctx.scene;
    const Settings &s = scene.settings;
    Color L{0, 0, 0}, beta{1, 1, 1}; // the radiance so far; the path's throughput
    bool prev_delta = true;           // the camera ray and mirror bounces: no MIS
    double prev_pdf = 0;
    Vec3 prev_x;
    for (int level = 1;; ++level) {
        Hit hit = queries.closest(ray, counts);
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
        BSDF bsdf = ctx.bsdf(hit.material, N); // BSDF(m, N), its lobes weighed once
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
                if (!queries.blocked(shadow_ray(hit, Ng, light), counts))
                    L += beta * bsdf.eval(wo, wi) * Li * cos_i;
            }
            if (ctx.n_sampled > 0) {
                int k = std::min(int(rng.uniform() * ctx.n_sampled), ctx.n_sampled - 1);
                auto [u1, u2] = rng.uniform2();
                if (k < int(ctx.area_lights.size())) {
                    const AreaLight &al = ctx.area_lights[size_t(k)];
                    LightPoint lp = sample_area_light(al, u1, u2);
                    LightConnection c = connect_to_light(hit.p, N, lp, ctx.pick);
                    const Vec3 &wi = c.wi;
                    if (c.cos_l > 0 && c.cos_i > 0 && dot(wi, Ng) > 0) {
                        // The light's point, moved off the light's own surface towards the hit
                        // (pbrt-v4 SpawnRayTo between two surfaces), so the light cannot block
                        // the ray that reaches it.
                        Vec3 target = offset_ray_origin(lp.p, lp.p_error, lp.Ng, -wi);
                        if (!queries.blocked(shadow_ray_to(hit, Ng, target), counts)) {
                            double w = mis_weights(c.pdf, bsdf.pdf(wo, wi)).light;
                            L += light_estimate(beta, bsdf.eval(wo, wi), al.emission, c.cos_i, w,
                                                c.pdf);
                        }
                    }
                } else { // the environment, uniformly over the sphere
                    Vec3 wi = sample_sphere(u1, u2);
                    double cos_i = dot(wi, N);
                    if (cos_i > 0 && dot(wi, Ng) > 0 &&
                        !queries.blocked(shadow_ray_towards(hit, Ng, wi), counts)) {
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
        double u0 = rng.uniform();
        auto [u1, u2] = rng.uniform2();
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
template <class Queries>
inline void render_tile_path(const PathContext &ctx, const Queries &queries, int x0, int y0,
                             int x1, int y1, float *out, RayCounts &counts) {
    const Scene &scene = ctx.scene;
    const Camera &cam = scene.camera;
    // The tile's counts on this thread's stack, added to the thread's own at the end: the
    // threads' counters lie side by side in memory (11_render.h), and counting every test there
    // makes the two threads' caches pass one line back and forth.
    RayCounts tile;
    for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i) {
            Color sum{0, 0, 0};
            for_each_sample(scene, i, j, [&](double sx, double sy, auto &rng) {
                ++tile.primary;
                sum += trace_path(ctx, queries, cam.primary_ray(sx, sy), rng, tile);
            });
            store_pixel(out, cam.width, i, j, sum * (1.0 / scene.settings.spp));
        }
    counts.primary += tile.primary;
    counts.secondary += tile.secondary;
    counts.shadow += tile.shadow;
    counts.box_tests += tile.box_tests;
    counts.primitive_tests += tile.primitive_tests;
}

} // namespace rt
