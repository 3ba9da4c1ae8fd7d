// Slide "Intersecting a Complex Object" (intersections: generic triangle). A triangle lies in a
// plane ("Triangle: limit plane", slide "Implicit Surfaces"); the ray hits it when the point
// where it meets that plane is inside all three edges.
//
// Moeller-Trumbore, the usual test, decides "inside" for each triangle separately, so a ray
// through an edge shared by two triangles can be judged outside both and slip through a closed
// mesh. Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2(1), 2013) first
// move the ray to the origin and shear it onto the +z axis; then the three edge functions of
// every triangle are evaluated in the same coordinates, from the same vertex values, so two
// triangles sharing an edge compute the same value for it with opposite signs: a ray is inside
// at least one of them. An edge function that is exactly 0 counts as inside.
#pragma once

#include <cmath>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"

namespace rt {

// What the shear needs from the ray, computed once per ray (a mesh tests many triangles).
struct WatertightRay {
    Vec3 o, d;
    int kx, ky, kz; // the axis of d's largest component becomes z; x, y keep the winding
    double Sx, Sy, Sz;

    WatertightRay() = default; // filled in later (a packet's rays, 22_mesh_packets.h)
    explicit WatertightRay(const Ray &ray) : o(ray.o), d(ray.d) {
        shear(ray.d);
        Sz = 1 / ray.d[kz];
    }
    // The same, where the caller has 1/d per axis already (a mesh search's slab test,
    // 21_wide_bvh.h): Sz = 1 / d[kz] is one of those divisions, the same bits.
    WatertightRay(const Ray &ray, const Vec3 &inv_d) : o(ray.o), d(ray.d) {
        shear(ray.d);
        Sz = inv_d[kz];
    }

  private:
    // The axes and Sx, Sy, from the ray's direction as given: read back from the member d, the
    // Cornell box's path tracer ran 1.05x slower (Clang 19, build_ab; issue 12).
    void shear(const Vec3 &dir) {
        Vec3 a = abs(dir);
        kz = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
        kx = (kz + 1) % 3;
        ky = (kx + 1) % 3;
        Sx = -dir[kx] / dir[kz];
        Sy = -dir[ky] / dir[kz];
    }
};

struct TriangleHit {
    double t, b0, b1, b2; // ray parameter and barycentric coordinates
};

// The larger of two sizes (non-negative, or NaN from an overflowed product): std::fmax's answer,
// which for a NaN is the other value, but inline and without a branch. GCC makes std::fmax a
// call into the maths library through the PLT, and a call clobbers every vector register: the
// packet search (22_mesh_packets.h), which inlines this test, saved and restored its rays'
// lanes around each of the eight calls below; inline, the bunny's primary rays took 7-12% less
// time (paired A/B, issue 12). Equal sizes are the same value (no -0: they come from fabs).
inline double larger(double a, double b) {
    const double m = a > b ? a : b; // b where either is NaN (maxsd)
    return b != b ? a : m;
}

// pbrt-v4's conservative bound deltaT on the rounding error of t (6.8.3), from the errors of
// each step of the test below: a, b, c are the sheared vertices (x, y and the scaled z), e the
// edge functions. A hit closer than this to range.min may be the surface the ray starts on.
// Given to the student, not part of the exercise.
inline double triangle_t_error(const Vec3 &a, const Vec3 &b, const Vec3 &c, double e0, double e1,
                               double e2, double inv_det) {
    double max_z = larger(std::fabs(a.z), larger(std::fabs(b.z), std::fabs(c.z)));
    double max_x = larger(std::fabs(a.x), larger(std::fabs(b.x), std::fabs(c.x)));
    double max_y = larger(std::fabs(a.y), larger(std::fabs(b.y), std::fabs(c.y)));
    double delta_z = gamma(3) * max_z;
    double delta_x = gamma(5) * (max_x + max_z), delta_y = gamma(5) * (max_y + max_z);
    double delta_e = 2 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    double max_e = larger(std::fabs(e0), larger(std::fabs(e1), std::fabs(e2)));
    return 3 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) *
           std::fabs(inv_det);
}

// Whether the ray certainly starts off the triangle's plane and heads into it, decided in world
// coordinates, where the sheared test cannot decide. triangle_t_error() bounds t's error by the
// sheared edge functions' sizes over det; for a ray within ~1e-12 rad of the plane det is tiny
// and the bound exceeds t itself, so the guard would reject a hit the ray truly makes (the stiff
// study's triangles family found two). Here h = (o - p0).n and dn = d.n, n = (p1 - p0) x (p2 -
// p0): the line meets the plane at t = -h / dn, ahead when h and dn have opposite signs. Each
// is a sum of three products of differences and cross-product terms; their forward error
// bounds (Higham, "Accuracy and Stability of Numerical Algorithms", ch. 3): h's value has at
// most 8 roundings per term (v and e1, e2 one each, the cross term's products and difference,
// the product with v, the sum of three), dn's 7 (d is exact), so |error| <= gamma(8) or
// gamma(7) times the same sums of absolute values. A ray spawned from this triangle leaves it:
// h and dn have the same sign, and the guard still rejects its hit. Given to the student, not
// part of the exercise.
inline bool starts_off_the_plane_heading_in(const Vec3 &p0, const Vec3 &p1, const Vec3 &p2,
                                            const WatertightRay &r) {
    Vec3 v = r.o - p0, e1 = p1 - p0, e2 = p2 - p0;
    Vec3 n = cross(e1, e2);
    Vec3 size = {std::fabs(e1.y * e2.z) + std::fabs(e1.z * e2.y),
                 std::fabs(e1.z * e2.x) + std::fabs(e1.x * e2.z),
                 std::fabs(e1.x * e2.y) + std::fabs(e1.y * e2.x)};
    double h = dot(v, n), dn = dot(r.d, n);
    double h_error = gamma(8) * dot(abs(v), size), dn_error = gamma(7) * dot(abs(r.d), size);
    return std::fabs(h) > h_error && std::fabs(dn) > dn_error && (h > 0) != (dn > 0);
}

// a b - c d to within 1.5 ulps of the exact value, however close a b is to c d (Kahan's
// algorithm; Jeannerod, Louvet and Muller 2013 prove the bound; pbrt-v4's DifferenceOfProducts).
// The product c d is rounded, its rounding error recovered exactly by a fused multiply-add and
// added back. Plain a b - c d loses every digit the two products share: a sliver of aspect 1e-8
// has edge functions 1e-8 of its products, so t = t_scaled / det came out 1e8 ulps off while
// one ulp of the inputs moves the true t by a few (the stiff study's slivers family). The signs
// stay exact (zero when a b = c d exactly), which keeps the test watertight. Given to the
// student, not part of the exercise.
inline double difference_of_products(double a, double b, double c, double d) {
    double cd = c * d;
    double error = std::fma(-c, d, cd); // cd - c d, exactly
    return std::fma(a, b, -cd) + error;
}

// Watertight ray/triangle test (Woop et al. 2013, with pbrt-v4's conservative bound on t, 6.8.3).
// Two-sided: the edge functions all >= 0 or all <= 0 is a hit (the sign says which side the
// ray comes from; both sides are the surface).
inline bool intersect_triangle(const Vec3 &p0, const Vec3 &p1, const Vec3 &p2,
                               const WatertightRay &r, const Interval &range, TriangleHit &th) {
    // BEGIN SOLUTION L08
    // PROMPT: The generic triangle (slide "Intersecting a Complex Object"), watertight (Woop,
    // PROMPT: Benthin and Wald 2013): translate the vertices to the ray's origin r.o, permute and
    // PROMPT: shear them (r.kx, r.ky, r.kz, r.Sx, r.Sy, r.Sz) so that the ray runs along +z from
    // PROMPT: (0, 0, 0); the three edge functions at (0, 0) are twice the signed areas of the
    // PROMPT: sub-triangles (each a b - c d: difference_of_products(), given, keeps a sliver's
    // PROMPT: exact). Inside (edge functions all >= 0 or all <= 0: both sides of the
    // PROMPT: triangle) and t in (range.min, range.max]: fill th with t and the barycentric
    // PROMPT: coordinates (b0 + b1 + b2 = 1, p = b0 p0 + b1 p1 + b2 p2) and return true. Reject
    // PROMPT: a hit with t <= range.min + triangle_t_error(...) (the surface the ray starts on)
    // PROMPT: unless starts_off_the_plane_heading_in(...) says the ray certainly meets the plane.
    // Translate to the ray origin, permute so the ray runs along z, shear x and y.
    Vec3 a = p0 - r.o, b = p1 - r.o, c = p2 - r.o;
    double ax = a[r.kx] + r.Sx * a[r.kz], ay = a[r.ky] + r.Sy * a[r.kz];
    double bx = b[r.kx] + r.Sx * b[r.kz], by = b[r.ky] + r.Sy * b[r.kz];
    double cx = c[r.kx] + r.Sx * c[r.kz], cy = c[r.ky] + r.Sy * c[r.kz];
    // Edge functions: twice the signed areas of the sheared triangle's sub-triangles at the
    // ray's point (0, 0).
    double e0 = difference_of_products(bx, cy, by, cx);
    double e1 = difference_of_products(cx, ay, cy, ax);
    double e2 = difference_of_products(ax, by, ay, bx);
    if ((e0 < 0 || e1 < 0 || e2 < 0) && (e0 > 0 || e1 > 0 || e2 > 0)) return false;
    double det = e0 + e1 + e2;
    if (det == 0) return false; // the ray runs in the triangle's plane
    double az = r.Sz * a[r.kz], bz = r.Sz * b[r.kz], cz = r.Sz * c[r.kz];
    double t_scaled = e0 * az + e1 * bz + e2 * cz;
    // t = t_scaled / det must lie in range; compare before dividing.
    if (det < 0 && (t_scaled >= range.min * det || t_scaled < range.max * det)) return false;
    if (det > 0 && (t_scaled <= range.min * det || t_scaled > range.max * det)) return false;
    double inv_det = 1 / det;
    double t = t_scaled * inv_det;
    // t is a little uncertain; a hit closer than that uncertainty may be the surface the ray
    // starts on, unless the ray certainly starts off the plane and heads into it.
    if (t <= range.min + triangle_t_error({ax, ay, az}, {bx, by, bz}, {cx, cy, cz}, e0, e1, e2,
                                          inv_det) &&
        !starts_off_the_plane_heading_in(p0, p1, p2, r))
        return false;
    th = {t, e0 * inv_det, e1 * inv_det, e2 * inv_det};
    return true;
    // END SOLUTION
}

// The hit record: the point from the barycentric coordinates (not o + t d, whose error grows
// with t), its error bound (pbrt-v4 eq. 6.29), and the normal of the side from which the
// vertices run counter-clockwise (the front).
inline void triangle_hit(const Vec3 &p0, const Vec3 &p1, const Vec3 &p2, const TriangleHit &th,
                         Hit &hit) {
    // BEGIN SOLUTION L08
    // PROMPT: The hit record of a triangle hit: hit.t, the point p = b0 p0 + b1 p1 + b2 p2 (not o +
    // PROMPT: t d, whose rounding error grows with t), its error bound hit.p_error = gamma(7) (|b0
    // PROMPT: p0| + |b1 p1| + |b2 p2|), and the unit normal hit.N = hit.Ng of the side from which
    // PROMPT: p0, p1, p2 run counter-clockwise.
    hit.t = th.t;
    hit.p = th.b0 * p0 + th.b1 * p1 + th.b2 * p2;
    hit.p_error = gamma(7) * (abs(th.b0 * p0) + abs(th.b1 * p1) + abs(th.b2 * p2));
    hit.N = hit.Ng = normalize(cross(p1 - p0, p2 - p0));
    // END SOLUTION
}

} // namespace rt
