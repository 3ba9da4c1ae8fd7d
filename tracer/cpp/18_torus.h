// Slide "Object Class" (implicit surfaces: torus). In its own coordinates the torus lies around
// the z axis: the points at distance r (minor radius) from the circle of radius R (major radius)
// in the plane z = 0,
//     (x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4 R^2 (x^2 + y^2) = 0,
// a quartic in t along a ray. Closed-form quartic solutions (Ferrari) lose every digit for thin
// tori and grazing rays. Instead (after moving the ray's origin to the point nearest the centre,
// which keeps the coefficients small): the quartic's real roots are isolated between the roots
// of its derivative (a cubic), whose own roots lie between the roots of its derivative (a
// quadratic, solved in closed form); on each interval where the function is monotone, a sign
// change brackets exactly one root, found by bisection to the last bit. Slow next to a formula,
// but it cannot miss a root that changes sign, nor report one that does not exist.
//
// The signs are not taken from the quartic itself. Its constant term A^2 - 4 R^2 (x^2 + y^2)
// is the difference of two numbers near 4 R^4 whose true difference is about 4 R^2 (r^2 - m^2)
// (m: how far the ray passes from the tube's circle): below r / R ~ 1e-6 it is all rounding,
// and the quartic's signs decide nothing (the stiff study measured it: study/, torus-tube).
// The quartic factors, (x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4 R^2 (x^2 + y^2) =
//     ((rho - R)^2 + z^2 - r^2) ((rho + R)^2 + z^2 - r^2),   rho = sqrt(x^2 + y^2),
// and the second factor is positive for r <= R: the quartic has the sign of the tube distance
// hypot(rho - R, z) - r, which double precision evaluates to a few ulps of R for any r. So the
// quartic's derivative (its coefficients carry no such cancellation) cuts the chord into pieces
// where the quartic is monotone, and the tube distance's signs bracket and bisect the roots.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"
#include "13_transform.h"

namespace rt {

// p(x) = c[0] + c[1] x + ... + c[n] x^n by Horner's rule.
inline double polynomial(const double *c, int n, double x) {
    double v = c[n];
    for (int i = n - 1; i >= 0; --i) v = v * x + c[i];
    return v;
}

// The root of f in [lo, hi] where f(lo) and f(hi) differ in sign, to the last bit. Each step
// halves the interval, and a double interval of one sign shrinks to adjacent doubles in at most
// 64 halvings once it is narrower than its magnitude (more while it straddles zero or starts
// wide): 200 steps is a cap that a working bisection never reaches, there against a loop that
// would never end.
template <class F> double bisect(F f, double lo, double hi) {
    double f_lo = f(lo);
    for (int i = 0; i < 200; ++i) {
        double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break; // adjacent doubles: done
        double f_mid = f(mid);
        if ((f_mid < 0) == (f_lo < 0)) lo = mid, f_lo = f_mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

inline double bisect(const double *c, int n, double lo, double hi) {
    return bisect([c, n](double x) { return polynomial(c, n, x); }, lo, hi);
}

// The real roots of p (degree n <= 4) in [lo, hi], in increasing order, isolated between the
// roots of p' (found the same way, recursively).
inline void real_roots(const double *c, int n, double lo, double hi, std::vector<double> &out) {
    out.clear();
    if (n == 1) {
        if (c[1] != 0) {
            double x = -c[0] / c[1];
            if (lo <= x && x <= hi) out.push_back(x);
        }
        return;
    }
    double d[4];
    for (int i = 1; i <= n; ++i) d[i - 1] = i * c[i];
    std::vector<double> critical;
    real_roots(d, n - 1, lo, hi, critical);
    std::vector<double> edges{lo};
    edges.insert(edges.end(), critical.begin(), critical.end());
    edges.push_back(hi);
    for (size_t i = 0; i + 1 < edges.size(); ++i) {
        double a = edges[i], b = edges[i + 1];
        double fa = polynomial(c, n, a), fb = polynomial(c, n, b);
        if (fa == 0) {
            if (out.empty() || out.back() != a) out.push_back(a);
        } else if ((fa < 0) != (fb < 0) && fb != 0) {
            out.push_back(bisect(c, n, a, b));
        }
    }
    if (polynomial(c, n, hi) == 0 && (out.empty() || out.back() != hi)) out.push_back(hi);
}

struct Torus : Object {
    double major_radius = 1, minor_radius = 0.25;
    Transform transform; // object -> world: centre at the origin, axis along +z

    bool hit(const Ray &world_ray, const Interval &range, Hit &hit,
             RayCounts &counts) const override {
        ++counts.primitive_tests;
        Ray ray = transform.to_object(world_ray);
        const double R = major_radius, r = minor_radius;
        // Work along the unit direction u, from the point o' of the line nearest the centre:
        // p = o' + s u, with t = (s0 + s) / |d|.
        double len = length(ray.d);
        Vec3 u = ray.d / len;
        double s0 = -dot(ray.o, u);
        Vec3 o = ray.o + s0 * u;
        // The bounding sphere, widened relatively by 1e-9 (far above the rounding of o2): the
        // outer equator touches it, and rays grazing the equator must reach the test below.
        double reach = (R + r) * (1 + 1e-9);
        double o2 = dot(o, o);
        if (o2 > reach * reach) return false;
        double A = o2 + R * R - r * r;
        double ou = o.x * u.x + o.y * u.y, uu = u.x * u.x + u.y * u.y;
        // The quartic's derivative, 4 s^3 + 2 c2 s + c1 (the quartic is c0 + c1 s + c2 s^2 + s^4;
        // c0, the cancelling one, is not needed).
        const double dc[4] = {-8 * R * R * ou, 2 * (2 * A - 4 * R * R * uu), 0, 4};
        double half = std::sqrt(reach * reach - o2); // the chord inside the bounding sphere
        // The chord, widened by 1e-300 so that a zero chord, a ray grazing the bounding sphere,
        // is an interval; its ends lie outside the torus.
        double lo = -half - 1e-300, hi = half + 1e-300;
        auto tube = [&](double s) { // the tube distance at o + s u: the quartic's sign
            Vec3 p = o + s * u;
            return std::hypot(std::hypot(p.x, p.y) - R, p.z) - r;
        };
        std::vector<double> critical, roots;
        real_roots(dc, 3, lo, hi, critical);
        std::vector<double> edges{lo};
        edges.insert(edges.end(), critical.begin(), critical.end());
        edges.push_back(hi);
        for (size_t i = 0; i + 1 < edges.size(); ++i) { // the quartic is monotone on each piece
            double a = edges[i], b = edges[i + 1];
            double fa = tube(a), fb = tube(b);
            if (fa == 0) roots.push_back(a);
            else if ((fa < 0) != (fb < 0) && fb != 0) roots.push_back(bisect(tube, a, b));
        }
        for (double s : roots) {
            double t = (s0 + s) / len;
            if (!range.surrounds(t)) continue;
            // A root is known only to within the tube distance's rounding (a few ulps of the
            // point's coordinates, hypot's and the subtractions': gamma(8) of R + |p|) over its
            // slope along the ray, |N . u| (Higham 5.1); one nearer the origin than that may be
            // the surface a new ray starts on.
            Vec3 q = o + s * u;
            double rho_q = std::hypot(q.x, q.y);
            Vec3 n_q = rho_q > 0 ? Vec3{q.x - R * q.x / rho_q, q.y - R * q.y / rho_q, q.z} : q;
            double slope = std::fabs(dot(n_q, u)) / std::max(length(n_q), 1e-300);
            double uncertainty = gamma(8) * (R + length(q)) / slope;
            if (!(s0 + s > uncertainty)) continue;
            // Refine: move the point onto the tube, along the normal of the tube's circle.
            Vec3 p = o + s * u;
            double rho = std::sqrt(p.x * p.x + p.y * p.y);
            Vec3 ring = rho > 0 ? Vec3{R * p.x / rho, R * p.y / rho, 0} : Vec3{R, 0, 0};
            // normalize(p - ring); for a tube thinner than the spacing of doubles on the ring
            // there is no direction left (as in 05_sphere.h sphere_hit()): face the ray.
            Vec3 v = p - ring;
            double len = length(v);
            Vec3 N = len > 0 ? v / len : -u;
            p = ring + r * N;
            transform.place(*this, t, p, gamma(8) * (abs(ring) + abs(r * N)), N, hit);
            return true;
        }
        return false;
    }
};

} // namespace rt
