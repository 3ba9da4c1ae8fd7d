// The probe program of the grader (lessons/grader.py): it calls a submission's functions on the
// inputs of a probe file and prints what they return, one probe at a time, so that the grader
// (which never loads student code) compares them with values it computed on its own.
//
//   probe PROBES.txt TOKEN FIRST
//
// Each line of PROBES.txt is "index function arg...", the arguments as hexadecimal floats
// (exact). Probes from index FIRST on are run; before each the program prints
// "TOKEN begin index" and after it "TOKEN result index value...", values as %a (exact), flushed
// at once, so that a crash or a hang names the probe that was running and the grader can go on
// from the next one. A stub (rt::NotImplemented) is caught and reported per probe.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "04_hit.h"
#include "05_sphere.h"
#include "06_plane.h"
#include "10_classic.h"
#include "not_implemented.h"

using namespace rt;

namespace {

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
};

std::string out(double x) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, " %a", x);
    return buffer;
}
std::string out(const Vec3 &v) { return out(v.x) + out(v.y) + out(v.z); }
std::string out(const Color &c) { return out(c.r) + out(c.g) + out(c.b); }

// One probe: the values the function returned, as text.
std::string run(const std::string &function, Args &a) {
    if (function == "sphere_roots" || function == "sphere_case" || function == "sphere_t") {
        Sphere s;
        s.center = a.vec();
        s.radius = a.next();
        Ray ray;
        ray.o = a.vec();
        ray.d = a.vec();
        if (function == "sphere_roots") {
            SphereRoots r = sphere_roots(s, ray);
            return out(r.real ? 1.0 : 0.0) + out(r.t0) + out(r.t1);
        }
        if (function == "sphere_case") return out(double(int(sphere_case(s, ray))));
        Interval range;
        range.min = a.next();
        range.max = a.next();
        return out(sphere_t(s, ray, range));
    }
    if (function == "plane_t" || function == "intersect_plane") {
        Plane pl;
        pl.point = a.vec();
        pl.normal = a.vec();
        Ray ray;
        ray.o = a.vec();
        ray.d = a.vec();
        if (function == "plane_t") return out(plane_t(pl, ray));
        Interval range;
        range.min = a.next();
        range.max = a.next();
        Hit hit;
        bool found = intersect_plane(pl, ray, range, hit);
        return out(found ? 1.0 : 0.0) + out(hit.t) + out(hit.p) + out(hit.N);
    }
    if (function == "ambient_term") {
        Material m;
        m.color = a.color();
        m.ambient = a.next();
        return out(ambient_term(m, a.color()));
    }
    if (function == "lambert_term") {
        Vec3 N = a.vec();
        return out(lambert_term(N, a.vec()));
    }
    if (function == "to_light") {
        Light light;
        light.type = a.next() != 0 ? Light::Type::directional : Light::Type::point;
        light.position = a.vec();
        light.direction = a.vec();
        return out(to_light(light, a.vec()));
    }
    if (function == "face_the_ray") {
        Hit hit;
        hit.N = a.vec();
        hit.Ng = a.vec();
        Facing f = face_the_ray(hit, a.vec());
        return out(f.N) + out(f.Ng);
    }
    if (function == "reflect") {
        Vec3 d = a.vec();
        return out(reflect(d, a.vec()));
    }
    if (function == "phong_term") {
        Vec3 R = a.vec(), L = a.vec();
        return out(phong_term(R, L, a.next()));
    }
    return " unknown";
}

} // namespace

int main(int argc, char **argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: probe PROBES.txt TOKEN FIRST\n");
        return 2;
    }
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    const std::string token = argv[2];
    const long first = std::strtol(argv[3], nullptr, 10);
    std::ifstream file(argv[1]);
    std::string line;
    while (std::getline(file, line)) {
        std::istringstream fields(line);
        long index = -1;
        std::string function, word;
        fields >> index >> function;
        if (index < first) continue;
        Args a;
        while (fields >> word) a.v.push_back(std::strtod(word.c_str(), nullptr));
        std::printf("\n%s begin %ld\n", token.c_str(), index);
        std::fflush(stdout);
        std::string result;
        try {
            result = run(function, a);
        } catch (const NotImplemented &error) {
            std::printf("\n%s not_implemented %ld %s\n", token.c_str(), index, error.what());
            std::fflush(stdout);
            continue;
        } catch (const std::exception &error) {
            std::printf("\n%s exception %ld %s\n", token.c_str(), index, error.what());
            std::fflush(stdout);
            continue;
        }
        std::printf("\n%s result %ld%s\n", token.c_str(), index, result.c_str());
        std::fflush(stdout);
    }
    return 0;
}
