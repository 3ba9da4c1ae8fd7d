// L13's probes (lessons/L13_precision/checks.py computes what they must return): the
// discriminant and the roots of the ray/sphere quadratic without cancellation, the whole
// intersection on stiff spheres (far, tiny, grazed), and the offset of a new ray's origin.
#include "02_ray.h"
#include "05_sphere.h"

// The discriminant as sphere_t() computes its arguments: a sphere (centre, radius), a ray
// (origin, direction).
RT_PROBE(sphere_discriminant) {
    rt::Vec3 c = a.vec();
    double r = a.next();
    rt::Vec3 o = a.vec(), d = a.vec();
    rt::Vec3 f = o - c;
    double aa = dot(d, d), b = dot(f, d);
    return rt::probe::out(rt::sphere_discriminant(f, d, aa, 1 / aa, b, r * r));
}

RT_PROBE(quadratic_roots) {
    using rt::probe::out;
    double b = a.next(), c0 = a.next(), D = a.next();
    rt::SphereRoots roots = rt::quadratic_roots(b, c0, D, a.next());
    return out(roots.real) + out(roots.t0) + out(roots.t1);
}

// The stiff spheres go through L02's sphere_t() and sphere_roots() (the course's own, calling
// yours), read as L02's probes read them; where both lessons' probes are built into one program
// L02's definitions serve both.
#ifndef RT_PROBES_L02
RT_PROBE(sphere_roots) {
    using rt::probe::out;
    rt::Sphere s;
    s.center = a.vec();
    s.radius = a.next();
    rt::Ray ray = a.ray();
    rt::SphereRoots r = rt::sphere_roots(s, ray);
    return out(r.real) + out(r.t0) + out(r.t1);
}

RT_PROBE(sphere_t) {
    rt::Sphere s;
    s.center = a.vec();
    s.radius = a.next();
    rt::Ray ray = a.ray();
    rt::Interval range = a.range();
    return rt::probe::out(rt::sphere_t(s, ray, range));
}
#endif

// The offset the new origin moved by, po - p: exact, since po and p agree in sign and lie
// within a factor of two of each other (Sterbenz's lemma) unless p is 0, where po - p = po.
RT_PROBE(offset_ray_origin) {
    rt::Vec3 p = a.vec(), p_error = a.vec(), N = a.vec(), toward = a.vec();
    rt::Vec3 po = rt::offset_ray_origin(p, p_error, N, toward);
    return rt::probe::out(po - p);
}
