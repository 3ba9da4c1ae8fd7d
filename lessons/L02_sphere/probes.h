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

} // namespace l02

RT_PROBE(sphere_roots) {
    using rt::probe::out;
    rt::Sphere s = l02::read_sphere(a);
    rt::SphereRoots r = rt::sphere_roots(s, a.ray());
    return out(r.real) + out(r.t0) + out(r.t1);
}

RT_PROBE(sphere_case) {
    rt::Sphere s = l02::read_sphere(a);
    return rt::probe::out(double(int(rt::sphere_case(s, a.ray()))));
}

RT_PROBE(sphere_t) {
    rt::Sphere s = l02::read_sphere(a);
    rt::Ray ray = a.ray();
    return rt::probe::out(rt::sphere_t(s, ray, a.range()));
}
