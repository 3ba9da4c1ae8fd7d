// L02's probes (lessons/L02_sphere/checks.py computes what they must return): a sphere
// (centre, radius), a ray (origin, direction) and, for sphere_t, the range [min, max].
#include "05_sphere.h"

// L13 probes these functions too (its stiff spheres): built together, these definitions serve.
#define RT_PROBES_L02

namespace l02 {

rt::Sphere read_sphere(rt::probe::Args &a) {
    rt::Sphere s;
    s.center = a.vec();
    s.radius = a.next();
    return s;
}

rt::Ray read_ray(rt::probe::Args &a) {
    rt::Ray ray;
    ray.o = a.vec();
    ray.d = a.vec();
    return ray;
}

rt::Interval read_range(rt::probe::Args &a) {
    rt::Interval range;
    range.min = a.next();
    range.max = a.next();
    return range;
}

} // namespace l02

RT_PROBE(sphere_roots) {
    using rt::probe::out;
    rt::Sphere s = l02::read_sphere(a);
    rt::SphereRoots r = rt::sphere_roots(s, l02::read_ray(a));
    return out(r.real) + out(r.t0) + out(r.t1);
}

RT_PROBE(sphere_case) {
    rt::Sphere s = l02::read_sphere(a);
    return rt::probe::out(double(int(rt::sphere_case(s, l02::read_ray(a)))));
}

RT_PROBE(sphere_t) {
    rt::Sphere s = l02::read_sphere(a);
    rt::Ray ray = l02::read_ray(a);
    return rt::probe::out(rt::sphere_t(s, ray, l02::read_range(a)));
}
