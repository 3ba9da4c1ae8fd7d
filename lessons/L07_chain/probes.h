// L07's probes (lessons/L07_chain/checks.py): the colour one hit returns (local_color()) and
// the chain of reflections (trace()), each in a tiny scene built from the probe's inputs.
#include "04_hit.h"
#include "06_plane.h"
#include "09_scene.h"
#include "10_classic.h"

namespace l07 {

rt::Material read_material(rt::probe::Args &a) {
    rt::Material m;
    m.color = a.color();
    m.ambient = a.next();
    m.diffuse = a.next();
    m.specular = a.next();
    m.shininess = a.next();
    m.reflectivity = a.next();
    return m;
}

} // namespace l07

// The material (colour, ambient, diffuse, specular, shininess, reflectivity), the ambient
// light, the hit (p, its normal N = Ng; p exact: p_error 0), the mirror direction R, then the
// lights (count; each: directional 0/1, position, direction, colour) and sphere blockers
// (count; each: centre, radius) -> the colour C_k.
RT_PROBE(local_color) {
    rt::Scene scene;
    rt::Material m = l07::read_material(a);
    scene.materials.push_back(m);
    scene.settings.ambient_light = a.color();
    rt::Hit hit;
    hit.p = a.vec();
    hit.N = hit.Ng = a.vec();
    hit.object = hit.material = 0;
    rt::Vec3 R = a.vec();
    int lights = int(a.next());
    for (int k = 0; k < lights; ++k) {
        rt::Light light;
        light.type = a.next() != 0 ? rt::Light::Type::directional : rt::Light::Type::point;
        light.position = a.vec();
        light.direction = a.vec();
        light.color = a.color();
        scene.lights.push_back(light);
    }
    int spheres = int(a.next());
    for (int k = 0; k < spheres; ++k) {
        rt::Sphere s;
        s.center = a.vec();
        s.radius = a.next();
        s.object = k + 1;
        s.material = 0;
        scene.spheres.push_back(s);
    }
    rt::RayCounts counts;
    return rt::probe::out(rt::local_color(scene, m, hit, hit.N, hit.Ng, R, counts));
}

// max_depth, min_coefficient, background, then the mirrors (count; each a plane: point,
// normal, colour, ambient, reflectivity; no diffuse or specular term: C_k is the ambient term
// alone), then the ray (o, d) -> the colour and counts.secondary.
RT_PROBE(trace) {
    using rt::probe::out;
    rt::Scene scene;
    scene.settings.max_depth = int(a.next());
    scene.settings.min_coefficient = a.next();
    scene.settings.background = a.color();
    scene.settings.ambient_light = {1, 1, 1};
    int planes = int(a.next());
    for (int k = 0; k < planes; ++k) {
        rt::Plane pl;
        pl.point = a.vec();
        pl.normal = a.vec();
        rt::Material m;
        m.color = a.color();
        m.ambient = a.next();
        m.diffuse = m.specular = 0;
        m.reflectivity = a.next();
        pl.object = pl.material = k;
        scene.planes.push_back(pl);
        scene.materials.push_back(m);
    }
    rt::Ray ray = a.ray();
    rt::RayCounts counts;
    rt::Color c = rt::trace(scene, ray, counts);
    return out(c) + out(double(counts.secondary));
}
