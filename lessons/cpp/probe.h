// What every lesson's probes (each lesson folder's probes.h) share: the arguments of a probe as
// exact doubles, the values it returns printed exactly (%a), and the table of probes by function
// name. The grader (lessons/grader.py) builds one program from this file, the probes.h of the
// lessons it grades and probe_main.cpp, concatenated in that order.
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "01_vec3.h"
#include "02_ray.h"
#include "03_camera.h"
#include "07_material.h"

namespace rt::probe {

struct Args {
    std::vector<double> v;
    size_t i = 0;
    double next() { return i < v.size() ? v[i++] : 0.0; }
    Vec3 vec() {
        double x = next(), y = next(), z = next();
        return {x, y, z};
    }
    Color color() {
        double r = next(), g = next(), b = next();
        return {r, g, b};
    }
    Ray ray() { // origin, then direction
        Ray r;
        r.o = vec();
        r.d = vec();
        return r;
    }
    Interval range() { // min, then max
        Interval i;
        i.min = next();
        i.max = next();
        return i;
    }
    Camera camera() { // as the scene gives it: eye, look_at, up, fov_y (degrees), width, height
        Camera cam;
        cam.eye = vec();
        cam.look_at = vec();
        cam.up = vec();
        cam.fov_y = next();
        cam.width = int(next());
        cam.height = int(next());
        return cam;
    }
};

inline std::string out(double x) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, " %a", x);
    return buffer;
}
inline std::string out(const Vec3 &v) { return out(v.x) + out(v.y) + out(v.z); }
inline std::string out(const Color &c) { return out(c.r) + out(c.g) + out(c.b); }
inline std::string out(bool b) { return out(b ? 1.0 : 0.0); }

// A probe: reads its inputs from Args (in the order the lesson's checks.py writes them) and
// returns what the student's function gave, as text.
using Function = std::string (*)(Args &);

inline std::map<std::string, Function> &table() {
    static std::map<std::string, Function> functions;
    return functions;
}

struct Register {
    Register(const char *name, Function f) { table()[name] = f; }
};

} // namespace rt::probe

// RT_PROBE(sphere_t) { ... return out(...); } defines the probe of the function sphere_t and
// enters it in the table; its body reads its inputs from `a`.
#define RT_PROBE(name)                                                                         \
    static std::string probe_##name(rt::probe::Args &a);                                      \
    static const rt::probe::Register register_##name(#name, probe_##name);                    \
    static std::string probe_##name([[maybe_unused]] rt::probe::Args &a)
