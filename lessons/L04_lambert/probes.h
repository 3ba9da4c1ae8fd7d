// L04's probes (lessons/L04_lambert/checks.py): the ambient term, Lambert's N.L, the direction
// to the light, the normal facing the ray.
#include "04_hit.h"
#include "10_classic.h"

RT_PROBE(ambient_term) {
    rt::Material m;
    m.color = a.color();
    m.ambient = a.next();
    return rt::probe::out(rt::ambient_term(m, a.color()));
}

RT_PROBE(lambert_term) {
    rt::Vec3 N = a.vec();
    return rt::probe::out(rt::lambert_term(N, a.vec()));
}

RT_PROBE(to_light) {
    rt::Light light;
    light.type = a.next() != 0 ? rt::Light::Type::directional : rt::Light::Type::point;
    light.position = a.vec();
    light.direction = a.vec();
    return rt::probe::out(rt::to_light(light, a.vec()));
}

RT_PROBE(face_the_ray) {
    rt::Hit hit;
    hit.N = a.vec();
    hit.Ng = a.vec();
    rt::Facing f = rt::face_the_ray(hit, a.vec());
    return rt::probe::out(f.N) + rt::probe::out(f.Ng);
}
