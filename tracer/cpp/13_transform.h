// Slide "Object Class": implicit surfaces such as a torus, a cylinder or a cube are simplest in
// their own coordinates (a torus around the z axis, a box with faces on the axes). An affine
// transform places them in the world; a ray is taken into the object's coordinates, tested
// there, and the hit is brought back.
//
// The ray's direction is transformed but not normalised, so t is the same parameter in both
// spaces: o + t d in the world is M (o' + t d') + m exactly in real arithmetic.
#pragma once

#include <cmath>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"

namespace rt {

struct Transform {
    double m[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}; // object -> world
    double inv[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}; // world -> object

    // From a 3x4 matrix [A | b]: p_world = A p + b. The inverse is (A^-1, -A^-1 b), A^-1 by the
    // adjugate; the caller guarantees det A != 0.
    static Transform from_matrix(const double a[3][4]) {
        Transform t;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 4; ++j) t.m[i][j] = a[i][j];
        const double(&A)[3][4] = t.m;
        double c00 = A[1][1] * A[2][2] - A[1][2] * A[2][1];
        double c01 = A[1][2] * A[2][0] - A[1][0] * A[2][2];
        double c02 = A[1][0] * A[2][1] - A[1][1] * A[2][0];
        double det = A[0][0] * c00 + A[0][1] * c01 + A[0][2] * c02;
        double inv_det = 1 / det;
        double B[3][3] = {
            {c00, A[0][2] * A[2][1] - A[0][1] * A[2][2], A[0][1] * A[1][2] - A[0][2] * A[1][1]},
            {c01, A[0][0] * A[2][2] - A[0][2] * A[2][0], A[0][2] * A[1][0] - A[0][0] * A[1][2]},
            {c02, A[0][1] * A[2][0] - A[0][0] * A[2][1], A[0][0] * A[1][1] - A[0][1] * A[1][0]},
        };
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) t.inv[i][j] = B[i][j] * inv_det;
            t.inv[i][3] = -(t.inv[i][0] * A[0][3] + t.inv[i][1] * A[1][3] + t.inv[i][2] * A[2][3]);
        }
        return t;
    }

    static Vec3 apply(const double M[3][4], const Vec3 &v, double w) {
        return {M[0][0] * v.x + M[0][1] * v.y + M[0][2] * v.z + M[0][3] * w,
                M[1][0] * v.x + M[1][1] * v.y + M[1][2] * v.z + M[1][3] * w,
                M[2][0] * v.x + M[2][1] * v.y + M[2][2] * v.z + M[2][3] * w};
    }
    Vec3 point(const Vec3 &p) const { return apply(m, p, 1); }
    Vec3 vector(const Vec3 &v) const { return apply(m, v, 0); }
    Vec3 to_object_point(const Vec3 &p) const { return apply(inv, p, 1); }
    Vec3 to_object_vector(const Vec3 &v) const { return apply(inv, v, 0); }
    // Normals transform with the inverse transpose, so they stay perpendicular to the surface.
    Vec3 normal(const Vec3 &n) const {
        return normalize(Vec3{inv[0][0] * n.x + inv[1][0] * n.y + inv[2][0] * n.z,
                              inv[0][1] * n.x + inv[1][1] * n.y + inv[2][1] * n.z,
                              inv[0][2] * n.x + inv[1][2] * n.y + inv[2][2] * n.z});
    }
    Ray to_object(const Ray &r) const { return {to_object_point(r.o), to_object_vector(r.d)}; }

    // Error bound of point(p) for a p that carries error e (pbrt-v4 6.8.4): the error carried
    // through |A|, plus the rounding of the sums of four products.
    Vec3 point_error(const Vec3 &p, const Vec3 &e) const {
        Vec3 r;
        for (int i = 0; i < 3; ++i) {
            double carried = std::fabs(m[i][0]) * e.x + std::fabs(m[i][1]) * e.y +
                             std::fabs(m[i][2]) * e.z;
            double sum = std::fabs(m[i][0] * p.x) + std::fabs(m[i][1] * p.y) +
                         std::fabs(m[i][2] * p.z) + std::fabs(m[i][3]);
            (i == 0 ? r.x : i == 1 ? r.y : r.z) = (1 + gamma(3)) * carried + gamma(3) * sum;
        }
        return r;
    }

    // Fill a world hit from an object-space hit (t is shared; see above).
    void to_world(Hit &hit) const {
        hit.p_error = point_error(hit.p, hit.p_error);
        hit.p = point(hit.p);
        hit.N = normal(hit.N);
        hit.Ng = normal(hit.Ng);
    }

    // The hit record of `object` from its own coordinates: the point p with error bound e and
    // the (geometric = shading) normal N there, at ray parameter t.
    void place(const Object &object, double t, const Vec3 &p, const Vec3 &e, const Vec3 &N,
               Hit &hit) const {
        hit.t = t;
        hit.p = p;
        hit.p_error = e;
        hit.N = hit.Ng = N;
        to_world(hit);
        hit.object = object.object;
        hit.material = object.material;
    }
};

} // namespace rt
