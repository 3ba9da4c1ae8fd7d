// Slide "Object Class" (implicit surfaces: cylinder). In its own coordinates the cylinder's
// axis is z, from z = 0 to z = height: the side x^2 + y^2 = r^2 is the sphere's quadratic in two
// dimensions, solved the same robust way (05_sphere.h); the caps are discs z = 0, z = height.
#pragma once

#include <cmath>
#include <initializer_list>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"
#include "13_transform.h"
#include "constants.h"

namespace rt {

struct Cylinder : Object {
    double radius = 1, height = 1;
    bool capped = true;
    Transform transform; // object -> world: the base at the origin, the axis along +z

    // Candidates in the cylinder's coordinates: the nearest t in range and its normal.
    bool nearest(const Ray &ray, const Interval &range, double &t_best, Vec3 &N) const {
        bool found = false;
        t_best = range.max;
        // The side: a t^2 + 2 b t + c = 0 in x and y only (Haines et al.'s form, as the sphere).
        double a = ray.d.x * ray.d.x + ray.d.y * ray.d.y;
        if (a > 0) {
            double b = ray.o.x * ray.d.x + ray.o.y * ray.d.y;
            double r2 = radius * radius;
            double lx = ray.o.x - (b / a) * ray.d.x, ly = ray.o.y - (b / a) * ray.d.y;
            double D = a * (r2 - (lx * lx + ly * ly));
            if (D >= 0) {
                double q = -(b + std::copysign(std::sqrt(D), b));
                double c = ray.o.x * ray.o.x + ray.o.y * ray.o.y - r2;
                double roots[2] = {q != 0 ? c / q : infinity, q / a};
                for (double t : roots) {
                    if (!(range.min < t && t < t_best)) continue;
                    double z = ray.o.z + t * ray.d.z;
                    if (z < 0 || z > height) continue;
                    double x = ray.o.x + t * ray.d.x, y = ray.o.y + t * ray.d.y;
                    t_best = t, N = {x, y, 0}, found = true;
                }
            }
        }
        if (capped && ray.d.z != 0) {
            for (double zc : {0.0, height}) {
                double t = (zc - ray.o.z) / ray.d.z;
                if (!(range.min < t && t < t_best)) continue;
                double x = ray.o.x + t * ray.d.x, y = ray.o.y + t * ray.d.y;
                if (x * x + y * y > radius * radius) continue;
                t_best = t, N = {0, 0, zc == 0 ? -1.0 : 1.0}, found = true;
            }
        }
        return found;
    }

    bool hit(const Ray &world_ray, const Interval &range, Hit &hit,
             RayCounts &counts) const override {
        ++counts.primitive_tests;
        Ray ray = transform.to_object(world_ray);
        double t;
        Vec3 N;
        if (!nearest(ray, range, t, N)) return false;
        Vec3 p = ray.at(t);
        Vec3 e = gamma(5) * (abs(ray.o) + abs(t * ray.d));
        if (N.z == 0) { // on the side: move (x, y) onto the circle, as the sphere's point
            double rho = std::sqrt(p.x * p.x + p.y * p.y);
            // A radius below the spacing of doubles on the axis: no direction left (as in
            // 05_sphere.h sphere_hit()); the side facing the ray (d.xy != 0 on a side hit).
            if (!(rho > 0)) p.x = -ray.d.x, p.y = -ray.d.y, rho = std::sqrt(p.x * p.x + p.y * p.y);
            double s = radius / rho;
            p.x *= s, p.y *= s;
            e.x = gamma(5) * std::fabs(p.x), e.y = gamma(5) * std::fabs(p.y);
            N = {p.x / radius, p.y / radius, 0};
        } else { // on a cap: z is exact
            p.z = N.z < 0 ? 0 : height;
            e.z = 0;
        }
        transform.place(*this, t, p, e, N, hit);
        return true;
    }
};

} // namespace rt
