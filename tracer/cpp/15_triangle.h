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
    Vec3 o;
    int kx, ky, kz; // the axis of d's largest component becomes z; x, y keep the winding
    double Sx, Sy, Sz;

    explicit WatertightRay(const Ray &ray) : o(ray.o) {
        Vec3 a = abs(ray.d);
        kz = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
        kx = (kz + 1) % 3;
        ky = (kx + 1) % 3;
        Sx = -ray.d[kx] / ray.d[kz];
        Sy = -ray.d[ky] / ray.d[kz];
        Sz = 1 / ray.d[kz];
    }
};

struct TriangleHit {
    double t, b0, b1, b2; // ray parameter and barycentric coordinates
};

// Watertight ray/triangle test (Woop et al. 2013, with pbrt-v4's conservative bound on t, 6.8.3).
inline bool intersect_triangle(const Vec3 &p0, const Vec3 &p1, const Vec3 &p2,
                               const WatertightRay &r, const Interval &range, TriangleHit &th) {
    // Translate to the ray origin, permute so the ray runs along z, shear x and y.
    Vec3 a = p0 - r.o, b = p1 - r.o, c = p2 - r.o;
    double ax = a[r.kx] + r.Sx * a[r.kz], ay = a[r.ky] + r.Sy * a[r.kz];
    double bx = b[r.kx] + r.Sx * b[r.kz], by = b[r.ky] + r.Sy * b[r.kz];
    double cx = c[r.kx] + r.Sx * c[r.kz], cy = c[r.ky] + r.Sy * c[r.kz];
    // Edge functions: twice the signed areas of the sheared triangle's sub-triangles at the
    // ray's point (0, 0).
    double e0 = bx * cy - by * cx;
    double e1 = cx * ay - cy * ax;
    double e2 = ax * by - ay * bx;
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
    // starts on. pbrt-v4's bound deltaT on t's error, from the errors of each step above.
    double max_z = std::fmax(std::fabs(az), std::fmax(std::fabs(bz), std::fabs(cz)));
    double max_x = std::fmax(std::fabs(ax), std::fmax(std::fabs(bx), std::fabs(cx)));
    double max_y = std::fmax(std::fabs(ay), std::fmax(std::fabs(by), std::fabs(cy)));
    double delta_z = gamma(3) * max_z;
    double delta_x = gamma(5) * (max_x + max_z), delta_y = gamma(5) * (max_y + max_z);
    double delta_e = 2 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    double max_e = std::fmax(std::fabs(e0), std::fmax(std::fabs(e1), std::fabs(e2)));
    double delta_t = 3 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) *
                     std::fabs(inv_det);
    if (t <= range.min + delta_t) return false;
    th = {t, e0 * inv_det, e1 * inv_det, e2 * inv_det};
    return true;
}

// The hit record: the point from the barycentric coordinates (not o + t d, whose error grows
// with t), its error bound (pbrt-v4 eq. 6.29), and the normal of the side from which the
// vertices run counter-clockwise (the front).
inline void triangle_hit(const Vec3 &p0, const Vec3 &p1, const Vec3 &p2, const TriangleHit &th,
                         Hit &hit) {
    hit.t = th.t;
    hit.p = th.b0 * p0 + th.b1 * p1 + th.b2 * p2;
    hit.p_error = gamma(7) * (abs(th.b0 * p0) + abs(th.b1 * p1) + abs(th.b2 * p2));
    hit.N = hit.Ng = normalize(cross(p1 - p0, p2 - p0));
}

} // namespace rt
