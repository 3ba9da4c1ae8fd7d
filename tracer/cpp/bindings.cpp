// tracer._core: the C++ core as a Python extension (nanobind). The Python side (tracer/render.py
// to_core()) fills a core Scene from the validated scene model through these calls; nothing here
// parses TOML.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdlib>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "01_vec3.h"
#include "02_ray.h"
#include "03_camera.h"
#include "04_hit.h"
#include "05_sphere.h"
#include "06_plane.h"
#include "08_light.h"
#include "09_scene.h"
#include "10_classic.h"
#include "11_render.h"
#include "12_packet.h"
#include "13_transform.h"
#include "14_box.h"
#include "16_mesh.h"
#include "17_cylinder.h"
#include "18_torus.h"
#include "19_aov.h"
#include "20_path.h"
#include "21_wide_bvh.h"
#include "22_mesh_packets.h"
#include "constants.h"
#include "power.h"

namespace nb = nanobind;
using namespace nb::literals;
using rt::Color;
using rt::Vec3;

using Triple = std::array<double, 3>;
static Vec3 vec(const Triple &a) { return {a[0], a[1], a[2]}; }
static Color col(const Triple &a) { return {a[0], a[1], a[2]}; }
static Triple triple(const Vec3 &v) { return {v.x, v.y, v.z}; }
static Triple triple(const Color &c) { return {c.r, c.g, c.b}; }

static const char *case_name(rt::SphereCase c) {
    switch (c) {
    case rt::SphereCase::none: return "none";
    case rt::SphereCase::once_from_inside: return "once_from_inside";
    case rt::SphereCase::tangent: return "tangent";
    case rt::SphereCase::internal: return "internal";
    case rt::SphereCase::twice: return "twice";
    }
    return "?";
}

static nb::dict hit_dict(const rt::Hit &hit) {
    nb::dict d;
    d["t"] = hit.t;
    d["point"] = triple(hit.p);
    d["error"] = triple(hit.p_error);
    d["normal"] = triple(hit.N);
    d["object"] = hit.object;
    return d;
}

static nb::dict counts_dict(const rt::RayCounts &c) {
    nb::dict d;
    d["primary"] = c.primary;
    d["secondary"] = c.secondary;
    d["shadow"] = c.shadow;
    d["box_tests"] = c.box_tests;
    d["primitive_tests"] = c.primitive_tests;
    return d;
}

using Image = nb::ndarray<nb::numpy, float, nb::shape<-1, -1, -1>>;
using Matrix34 = std::array<std::array<double, 4>, 3>;

static rt::Transform transform_from(const std::optional<Matrix34> &m) {
    if (!m) return {};
    double a[3][4];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) a[i][j] = (*m)[size_t(i)][size_t(j)];
    return rt::Transform::from_matrix(a);
}

// What a render traces (Suffern's tracers, chosen per scene): the classic model one ray at a
// time (10_classic.h, the lecture's code as written) or a packet of rays at a time
// (12_packet.h; the same image), the arbitrary output variables (19_aov.h), or paths
// (20_path.h), with the lecture's scene queries or with culled ones (the same image).
enum class Integrator { classic, classic_packets, aov, path, path_culled, aov_packets };

using Vertices = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig>;
using Faces = nb::ndarray<const int32_t, nb::shape<-1, 3>, nb::c_contig>;

// A mesh's vertices and triangles from (n, 3) arrays, every face checked to name a vertex.
static void fill_mesh(rt::Mesh &mesh, const Vertices &vertices, const Faces &faces) {
    const size_t nv = vertices.shape(0), nf = faces.shape(0);
    mesh.vertices.resize(nv);
    for (size_t i = 0; i < nv; ++i)
        mesh.vertices[i] = {vertices(i, 0), vertices(i, 1), vertices(i, 2)};
    mesh.triangles.resize(nf);
    for (size_t i = 0; i < nf; ++i)
        for (size_t k = 0; k < 3; ++k) {
            int v = faces(i, k);
            if (v < 0 || size_t(v) >= nv)
                throw std::out_of_range("mesh face refers to a missing vertex");
            mesh.triangles[i][k] = v;
        }
}

// The image's memory. The kernel maps a fresh page only when it is first written and zeroes it
// first: 24 MB for Ex 25 at 1920 x 1024, a tenth of its render's time, and a 1920 x 1024 aov
// image (5 floats a pixel, 39 MB) took 9,600 faults, the render threads queueing on the lock of
// the process's memory map (perf, issue 12). So the last image freed is kept, one block, and
// the next render of the same size (a benchmark's repeats, a progressive render's passes, a
// viewer's frames) writes into it instead: every pixel is written, so what it held does not
// matter. A render of another size frees it. At most one image's memory stays held.
// closest_mesh_hits() takes its answer's three columns from the same cache, for the same reason
// (a 2M-ray batch faulted in 32 MB each time): a batch and a render of different sizes take
// turns freeing each other's block, and the block held may be a batch's.
//
// The block is aligned to 2 MiB, so that where transparent huge pages are on for every mapping
// the kernel can map it in 2 MiB pages if it has them free, but it is not marked MADV_HUGEPAGE:
// with the kernel's usual defrag setting ("madvise") a marked region's faults wait while the
// kernel compacts memory to make huge pages, and on a machine whose memory was in use (after
// the test suite, say) that added 30 to 100 ms of system time to the first render in a process,
// which is the only render of `rtlab render` (Ex 25 at 1920 x 1024: 70 to 140 ms marked, 72 to
// 77 ms unmarked, one thread; the aov bunny 46 to 79 ms against 37 to 44 ms, two threads).
// The renders that reuse the block are as fast either way (its pages are written in order, one
// translation serving many pixels). The mesh hierarchy's nodes, read all over, keep the mark
// (21_wide_bvh.h HugePageAllocator).
namespace {
struct ImageCache {
    std::mutex mutex;
    void *spare = nullptr; // the last image freed, of spare_bytes
    size_t spare_bytes = 0;
    std::unordered_map<void *, size_t> live; // images handed out: their sizes
};
ImageCache &image_cache() {
    static ImageCache *cache = new ImageCache; // never destroyed: capsules may outlive statics
    return *cache;
}
} // namespace

static float *allocate_image(size_t floats) {
    constexpr size_t huge_page = size_t(2) << 20;
    const size_t bytes =
        std::max<size_t>(1, (floats * sizeof(float) + huge_page - 1) / huge_page) * huge_page;
    ImageCache &cache = image_cache();
    void *p = nullptr, *stale = nullptr;
    {
        std::lock_guard<std::mutex> lock(cache.mutex);
        if (cache.spare != nullptr && cache.spare_bytes == bytes) p = cache.spare;
        else stale = cache.spare;
        cache.spare = nullptr;
    }
    std::free(stale); // free(nullptr) does nothing
    if (p == nullptr) {
        p = std::aligned_alloc(huge_page, bytes);
        if (p == nullptr) throw std::bad_alloc();
    }
    std::lock_guard<std::mutex> lock(image_cache().mutex);
    cache.live[p] = bytes;
    return static_cast<float *>(p);
}

// The capsule's deleter: keep the image as the spare, freeing the one it replaces.
static void release_image(void *p) noexcept {
    ImageCache &cache = image_cache();
    void *stale = nullptr;
    {
        std::lock_guard<std::mutex> lock(cache.mutex);
        auto it = cache.live.find(p);
        stale = cache.spare;
        cache.spare = p;
        cache.spare_bytes = it->second;
        cache.live.erase(it);
    }
    std::free(stale);
}

// Render with the GIL released. Every poll interval (11_render.h) the watching thread takes the
// GIL to check for Ctrl-C and to report progress; an exception from either cancels the render
// and is re-raised. Returns the image, the ray counts and the integrator that ran: packets
// asked of a scene they do not serve (packets_serve(), 12_packet.h) fall back to one ray at a
// time, and the caller learns so.
static std::tuple<Image, nb::dict, Integrator> render(const rt::Scene &scene, int threads,
                                                      nb::object progress,
                                                      Integrator integrator, bool packets) {
    // packets: also the meshes' faster search (21_wide_bvh.h), under every integrator.
    rt::set_mesh_packets(scene, packets);
    if (integrator == Integrator::classic_packets && !rt::packets_serve(scene))
        integrator = Integrator::classic;
    if (integrator == Integrator::aov && packets && rt::mesh_packets_serve(scene))
        integrator = Integrator::aov_packets; // 22_mesh_packets.h: scenes of meshes
    const int width = scene.camera.width, height = scene.camera.height;
    const bool aov = integrator == Integrator::aov || integrator == Integrator::aov_packets;
    const size_t channels = aov ? rt::aov_channels : 3;
    // Not zeroed: every pixel is written (a cancelled render raises instead of returning).
    float *data = allocate_image(size_t(width) * size_t(height) * channels);
    nb::capsule owner(data, release_image);
    bool failed = false;
    rt::RenderResult result;
    {
        nb::gil_scoped_release release;
        auto poll = [&](int done, int total) {
            nb::gil_scoped_acquire acquire;
            if (PyErr_CheckSignals() != 0) {
                failed = true; // the KeyboardInterrupt stays set for the re-raise below
                return false;
            }
            if (!progress.is_none()) {
                try {
                    progress(done, total);
                } catch (nb::python_error &e) {
                    e.restore();
                    failed = true;
                    return false;
                }
            }
            return true;
        };
        std::unique_ptr<rt::PathContext> context;
        std::unique_ptr<rt::CulledQueries> culled;
        std::unique_ptr<rt::PacketCulling> packet_culling;
        rt::TileRenderer tiles;
        switch (integrator) {
        case Integrator::classic: tiles = rt::render_tile_rays; break;
        case Integrator::classic_packets:
            packet_culling = std::make_unique<rt::PacketCulling>(scene);
            tiles = [&](const rt::Scene &, int x0, int y0, int x1, int y1, float *out,
                        rt::RayCounts &c) {
                rt::render_tile_packets(*packet_culling, scene, x0, y0, x1, y1, out, c);
            };
            break;
        case Integrator::aov: tiles = rt::render_tile_aov; break;
        case Integrator::aov_packets: tiles = rt::render_tile_aov_packets; break;
        case Integrator::path:
            context = std::make_unique<rt::PathContext>(scene);
            tiles = [&](const rt::Scene &, int x0, int y0, int x1, int y1, float *out,
                        rt::RayCounts &c) {
                rt::render_tile_path(*context, rt::SceneQueries{scene}, x0, y0, x1, y1, out, c);
            };
            break;
        case Integrator::path_culled:
            context = std::make_unique<rt::PathContext>(scene);
            culled = std::make_unique<rt::CulledQueries>(scene);
            tiles = [&](const rt::Scene &, int x0, int y0, int x1, int y1, float *out,
                        rt::RayCounts &c) {
                rt::render_tile_path(*context, *culled, x0, y0, x1, y1, out, c);
            };
            break;
        }
        result = rt::render(scene, threads, data, poll, tiles);
    }
    if (failed) throw nb::python_error();
    if (!progress.is_none()) progress(1, 1);
    Image image(data, {size_t(height), size_t(width), channels}, owner);
    return {image, counts_dict(result.counts), integrator};
}

NB_MODULE(_core, m) {
    m.doc() = "The rtlab ray tracer's C++ core: the lecture's classic algorithm.";
    // The rays a packet traces at once: 8 with AVX-512, 4 with AVX or AVX2, 2 with SSE2 (power.h).
    m.attr("rays_per_packet") = rt::rays_per_packet;

    nb::class_<rt::Scene>(m, "Scene")
        .def(nb::init<>())
        .def(
            "set_camera",
            [](rt::Scene &s, Triple eye, Triple look_at, Triple up, double fov_y, int width,
               int height, int stereo_side, double eye_separation, double convergence) {
                s.camera = rt::Camera{};
                s.camera.eye = vec(eye);
                s.camera.look_at = vec(look_at);
                s.camera.up = vec(up);
                s.camera.fov_y = fov_y;
                s.camera.width = width;
                s.camera.height = height;
                s.camera.initialize();
                if (stereo_side != 0) // 03_camera.h: one eye of a stereo pair
                    s.camera = rt::stereo_eye(s.camera, eye_separation, convergence, stereo_side);
            },
            "eye"_a, "look_at"_a, "up"_a, "fov_y"_a, "width"_a, "height"_a, "stereo_side"_a = 0,
            "eye_separation"_a = 0.0, "convergence"_a = 1.0,
            "stereo_side: 0 a single camera, -1 the left eye, +1 the right eye of a stereo pair "
            "(eye_separation, convergence).")
        .def(
            "set_render",
            [](rt::Scene &s, int max_depth, double min_coefficient, int spp, uint64_t seed,
               Triple background, Triple ambient_light, const std::string &sampler) {
                if (sampler != "stratified" && sampler != "sobol")
                    throw std::invalid_argument("sampler: expected 'stratified' or 'sobol', got '" +
                                                sampler + "'");
                s.settings.sampler =
                    sampler == "sobol" ? rt::Sampler::sobol : rt::Sampler::stratified;
                s.settings.max_depth = max_depth;
                s.settings.min_coefficient = min_coefficient;
                s.settings.spp = spp;
                s.settings.seed = seed;
                s.settings.background = col(background);
                s.settings.ambient_light = col(ambient_light);
            },
            "max_depth"_a, "min_coefficient"_a, "spp"_a, "seed"_a, "background"_a,
            "ambient_light"_a, "sampler"_a = "stratified")
        .def(
            "add_material",
            [](rt::Scene &s, Triple color, double ambient, double diffuse, double specular,
               double shininess, double reflectivity, Triple emission) {
                s.materials.push_back({col(color), ambient, diffuse, specular, shininess,
                                       reflectivity, col(emission)});
                return int(s.materials.size()) - 1;
            },
            "color"_a, "ambient"_a, "diffuse"_a, "specular"_a, "shininess"_a, "reflectivity"_a,
            "emission"_a = Triple{0, 0, 0})
        .def(
            "add_point_light",
            [](rt::Scene &s, Triple position, Triple color) {
                rt::Light l;
                l.type = rt::Light::Type::point;
                l.position = vec(position);
                l.color = col(color);
                s.lights.push_back(l);
            },
            "position"_a, "color"_a)
        .def(
            "add_directional_light",
            [](rt::Scene &s, Triple direction, Triple color) {
                rt::Light l;
                l.type = rt::Light::Type::directional;
                l.direction = rt::normalize(vec(direction));
                l.color = col(color);
                s.lights.push_back(l);
            },
            "direction"_a, "color"_a)
        .def(
            "add_sphere",
            [](rt::Scene &s, Triple center, double radius, int object, int material) {
                s.spheres.push_back({vec(center), radius, object, material});
            },
            "center"_a, "radius"_a, "object"_a, "material"_a)
        .def(
            "add_plane",
            [](rt::Scene &s, Triple point, Triple normal, int object, int material) {
                rt::Plane pl{vec(point), rt::normalize(vec(normal)), object, material};
                pl.axis = rt::unit_axis(pl.normal);
                s.planes.push_back(pl);
            },
            "point"_a, "normal"_a, "object"_a, "material"_a)
        .def(
            "add_box",
            [](rt::Scene &s, Triple min, Triple max, std::optional<Matrix34> to_world, int object,
               int material) {
                auto box = std::make_shared<rt::Box>();
                box->box.min = vec(min);
                box->box.max = vec(max);
                box->transform = transform_from(to_world);
                box->object = object, box->material = material;
                s.objects.push_back(box);
            },
            "min"_a, "max"_a, "to_world"_a.none(), "object"_a, "material"_a)
        .def(
            "add_cylinder",
            [](rt::Scene &s, double radius, double height, bool capped, Matrix34 to_world,
               int object, int material) {
                auto c = std::make_shared<rt::Cylinder>();
                c->radius = radius, c->height = height, c->capped = capped;
                c->transform = transform_from(to_world);
                c->object = object, c->material = material;
                s.objects.push_back(c);
            },
            "radius"_a, "height"_a, "capped"_a, "to_world"_a, "object"_a, "material"_a)
        .def(
            "add_torus",
            [](rt::Scene &s, double major_radius, double minor_radius, Matrix34 to_world,
               int object, int material) {
                auto t = std::make_shared<rt::Torus>();
                t->major_radius = major_radius, t->minor_radius = minor_radius;
                t->transform = transform_from(to_world);
                t->object = object, t->material = material;
                s.objects.push_back(t);
            },
            "major_radius"_a, "minor_radius"_a, "to_world"_a, "object"_a, "material"_a)
        .def(
            "add_mesh",
            [](rt::Scene &s, Vertices vertices, Faces faces,
               std::optional<nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig>> normals,
               const std::string &acceleration, int object, int material,
               std::optional<nb::ndarray<const int32_t, nb::shape<-1>, nb::c_contig>> objects,
               std::optional<nb::ndarray<const int32_t, nb::shape<-1>, nb::c_contig>> materials) {
                auto mesh = std::make_shared<rt::Mesh>();
                fill_mesh(*mesh, vertices, faces);
                const size_t nv = vertices.shape(0), nf = faces.shape(0);
                if (normals) {
                    if (normals->shape(0) != nv)
                        throw std::invalid_argument("one normal per vertex expected");
                    mesh->normals.resize(nv);
                    for (size_t i = 0; i < nv; ++i)
                        mesh->normals[i] = {(*normals)(i, 0), (*normals)(i, 1), (*normals)(i, 2)};
                }
                if (objects && materials) { // one mesh standing for several objects
                    if (objects->shape(0) != nf || materials->shape(0) != nf)
                        throw std::invalid_argument("one object and material per face expected");
                    mesh->triangle_object.assign(objects->data(), objects->data() + nf);
                    mesh->triangle_material.assign(materials->data(), materials->data() + nf);
                }
                mesh->acceleration = acceleration == "none" ? rt::Acceleration::none
                                     : acceleration == "bounding_box"
                                         ? rt::Acceleration::bounding_box
                                         : rt::Acceleration::bvh;
                {
                    nb::gil_scoped_release release;
                    mesh->build();
                    rt::build_accelerator(*mesh); // 21_wide_bvh.h, for packets=True
                }
                mesh->object = object, mesh->material = material;
                s.objects.push_back(mesh);
                return mesh->nodes.size();
            },
            "vertices"_a, "faces"_a, "normals"_a.none(), "acceleration"_a, "object"_a,
            "material"_a, "objects"_a.none() = nb::none(), "materials"_a.none() = nb::none(),
            "Add a triangle mesh (with per-face objects and materials where it joins several); "
            "returns the number of hierarchy nodes.")
        .def(
            "primary_ray",
            [](const rt::Scene &s, double sx, double sy) {
                rt::Ray r = s.camera.primary_ray(sx, sy);
                return std::make_tuple(triple(r.o), triple(r.d));
            },
            "sx"_a, "sy"_a, "The primary ray through image point (sx, sy) in pixel units.")
        .def(
            "closest_hit",
            [](const rt::Scene &s, Triple origin, Triple direction) -> std::optional<nb::dict> {
                rt::RayCounts counts;
                rt::Hit hit = rt::closest_hit(s, {vec(origin), vec(direction)}, counts);
                if (!hit.found()) return std::nullopt;
                return hit_dict(hit);
            },
            "origin"_a, "direction"_a)
        .def(
            "trace",
            [](const rt::Scene &s, Triple origin, Triple direction) {
                rt::RayCounts counts;
                Color c = rt::trace(s, {vec(origin), rt::normalize(vec(direction))}, counts);
                return std::make_tuple(triple(c), counts_dict(counts));
            },
            "origin"_a, "direction"_a, "The classic colour seen along one ray.")
        .def(
            "trace_packet",
            [](const rt::Scene &s, std::vector<Triple> origins, std::vector<Triple> directions) {
                const size_t n = origins.size();
                if (n == 0 || n > size_t(rt::rays_per_packet) || directions.size() != n)
                    throw std::invalid_argument("1 to " + std::to_string(rt::rays_per_packet) +
                                                " origins and as many directions expected");
                if (!rt::packets_serve(s))
                    throw std::invalid_argument("packets serve scenes of spheres and planes only");
                rt::RayL rays{};
                for (size_t k = 0; k < n; ++k)
                    rays.set(int(k), {vec(origins[k]), rt::normalize(vec(directions[k]))});
                rt::RayCounts counts;
                const rt::ColorL c =
                    rt::trace(s, rays, rt::first_lanes(int(n)), counts, nullptr, nullptr);
                std::vector<Triple> out(n);
                for (size_t k = 0; k < n; ++k) out[k] = {c.r[k], c.g[k], c.b[k]};
                return std::make_tuple(out, counts_dict(counts));
            },
            "origins"_a, "directions"_a,
            "The classic colours seen along up to rays_per_packet rays traced as one packet "
            "(12_packet.h trace(), without the render's culling), in double precision: each "
            "lane's is trace()'s for its ray, bit for bit.");

    nb::enum_<Integrator>(m, "Integrator", "What a render traces.")
        .value("classic", Integrator::classic, "the classic model, one ray at a time")
        .value("classic_packets", Integrator::classic_packets,
               "the classic model, a packet of rays at a time where the scene allows (spheres "
               "and planes only), else one ray at a time; the same image")
        .value("aov", Integrator::aov, "depth, object index and normal of the primary hits")
        .value("path", Integrator::path, "Monte Carlo path tracing")
        .value("path_culled", Integrator::path_culled,
               "Monte Carlo path tracing, objects culled by their world bounds (the same image)")
        .value("aov_packets", Integrator::aov_packets,
               "aov, packets of primary rays through the meshes' hierarchies (scenes of meshes)");

    m.def("render", &render, "scene"_a, "threads"_a, "progress"_a = nb::none(),
          "integrator"_a = Integrator::classic_packets, "packets"_a = true,
          "Render to a float32 (height, width, channels) array: 3 channels, or 5 for aov. "
          "packets=False: meshes searched by the lecture's one-ray traversal, not the wide "
          "hierarchy (21_wide_bvh.h). Returns (image, ray counts, the integrator that ran).");
    // Whether this build checks memory and undefined behaviour (CMake's RTLAB_SANITIZE; `make
    // sanitize` checks it is testing such a build).
#if defined(__SANITIZE_ADDRESS__)
    m.attr("sanitized") = true;
#else
    m.attr("sanitized") = false;
#endif
    // The compiler that built this core, as it names itself (GCC: "12.2.0", Clang: "Debian
    // Clang 19.1.7 (3~deb12u1)"), and which one it is, from its own macros rather than that text:
    // tests/test_second_compiler.py builds with the other one, tests/with_core.py checks it has
    // the build it was asked for, and `rtlab bench` writes it beside the CPU (the same source
    // runs at different speeds).
    m.attr("compiler") = __VERSION__;
#if defined(__clang__)
    m.attr("compiler_family") = "clang";
#elif defined(__GNUC__)
    m.attr("compiler_family") = "gcc";
#else
    m.attr("compiler_family") = "other";
#endif

    m.def(
        "intersect_sphere",
        [](Triple center, double radius, Triple origin, Triple direction)
            -> std::tuple<std::string, std::optional<nb::dict>> {
            rt::Sphere s{vec(center), radius, 0, 0};
            rt::Ray ray{vec(origin), vec(direction)};
            rt::Hit hit;
            std::optional<nb::dict> found;
            if (rt::intersect_sphere(s, ray, {0, rt::infinity}, hit)) found = hit_dict(hit);
            return {case_name(rt::sphere_case(s, ray)), found};
        },
        "center"_a, "radius"_a, "origin"_a, "direction"_a,
        "The sphere case (one of the five) and the closest hit with t > 0, or None.");

    m.def("power", [](double x, double n) { return rt::power(x, n); }, "x"_a, "n"_a,
          "x^n as the Phong term computes it (power.h), for 0 < x <= 1 and n > 0.");
    m.def(
        "power_lanes",
        [](std::array<double, rt::rays_per_packet> x, std::array<double, rt::rays_per_packet> n) {
            rt::Lanes xl, nl;
            for (int k = 0; k < rt::rays_per_packet; ++k)
                xl[k] = x[size_t(k)], nl[k] = n[size_t(k)];
            const rt::Lanes r = rt::power(xl, nl);
            std::array<double, rt::rays_per_packet> out;
            for (int k = 0; k < rt::rays_per_packet; ++k) out[size_t(k)] = r[k];
            return out;
        },
        "x"_a, "n"_a,
        "power() for a packet's 8 lanes at once, as the packet tracer computes it (12_packet.h).");
    m.def(
        "power_whole_lanes",
        [](std::array<double, rt::rays_per_packet> x, int n) {
            if (n < 1 || n > int(rt::max_whole_exponent))
                throw nb::value_error("n: expected a whole exponent from 1 to 1024");
            rt::Lanes xl;
            for (int k = 0; k < rt::rays_per_packet; ++k) xl[k] = x[size_t(k)];
            const rt::Lanes r = rt::power_whole(xl, n);
            std::array<double, rt::rays_per_packet> out;
            for (int k = 0; k < rt::rays_per_packet; ++k) out[size_t(k)] = r[k];
            return out;
        },
        "x"_a, "n"_a,
        "power_whole() for a packet's lanes, which share the whole exponent n (power.h): what the "
        "packet tracer computes for a material's whole shininess.");

    m.def(
        "leaving_origins",
        [](std::array<Triple, rt::rays_per_packet> p,
           std::array<Triple, rt::rays_per_packet> p_error,
           std::array<Triple, rt::rays_per_packet> normal,
           std::array<Triple, rt::rays_per_packet> toward) {
            auto lanes = [](const std::array<Triple, rt::rays_per_packet> &v) {
                rt::Vec3L l;
                for (int k = 0; k < rt::rays_per_packet; ++k) l.set(k, vec(v[size_t(k)]));
                return l;
            };
            const rt::Vec3L pl = lanes(p), el = lanes(p_error), nl = lanes(normal);
            // Lanes whose normals are one axis's unit vector take its shortcuts (rt::dot_unit()),
            // as a packet whose rays all met one such plane does.
            rt::FacingL f{nl, nl};
            const int axis = rt::unit_axis(vec(normal[0]));
            if (std::all_of(normal.begin(), normal.end(),
                            [&](const Triple &t) { return rt::unit_axis(vec(t)) == axis; }))
                f.axis = axis;
            const rt::Vec3L o = rt::leaving_origin(pl, el, f, rt::away_origin(pl, el, f),
                                                   lanes(toward), rt::mask_all(true));
            std::array<Triple, rt::rays_per_packet> out;
            for (int k = 0; k < rt::rays_per_packet; ++k)
                out[size_t(k)] = {o.x[k], o.y[k], o.z[k]};
            return out;
        },
        "p"_a, "p_error"_a, "normal"_a, "toward"_a,
        "The origins of a packet's rays leaving points p (error bounds p_error) on the side of "
        "`toward`, as the packet tracer computes them (12_packet.h leaving_origin()).");
    m.def(
        "offset_ray_origin",
        [](Triple p, Triple p_error, Triple normal, Triple toward) {
            return triple(rt::offset_ray_origin(vec(p), vec(p_error), vec(normal), vec(toward)));
        },
        "p"_a, "p_error"_a, "normal"_a, "toward"_a);
    m.def(
        "plane_unseen",
        [](const rt::Scene &scene, size_t plane, double x0, double x1, double y0, double y1) {
            if (plane >= scene.planes.size())
                throw nb::index_error("no plane of that number in the scene");
            return rt::plane_unseen(scene.camera, scene.planes[plane], {x0, x1, y0, y1});
        },
        "scene"_a, "plane"_a, "x0"_a, "x1"_a, "y0"_a, "y1"_a,
        "Whether no primary ray through an image point of [x0, x1] x [y0, y1] (pixel units) can "
        "meet the scene's plane number `plane` (12_packet.h plane_unseen()): a tile for which "
        "this holds of every plane, and whose pixels no sphere's rectangle reaches, is filled "
        "with the background without tracing a ray.");
    m.def(
        "tile_filled",
        [](const rt::Scene &scene, int x0, int y0, int x1, int y1) {
            if (!rt::packets_serve(scene) || scene.settings.spp != 1) return false;
            const rt::PacketCulling culling(scene);
            const rt::ImageSpan span = rt::pixel_centres(x0, x1, y0, y1);
            return rt::sky_only(scene, rt::TileCulling(culling, span), span);
        },
        "scene"_a, "x0"_a, "y0"_a, "x1"_a, "y1"_a,
        "Whether the packet tracer fills the tile of columns [x0, x1) and rows [y0, y1) with the "
        "background without tracing a ray (12_packet.h sky_only(), one sample a pixel).");

    // Issue 11's study (study/): many rays at once through the scene's own closest_hit() and
    // any_hit(), the functions the renderer runs, so that what the study measures is what a
    // render does, not a re-implementation. One call per batch: a Python loop over single rays
    // would make the timings measure the binding, not the intersection. closest_hit() searches
    // t in (0, infinity), as every ray of the renderer does; a closest hit beyond tmax is
    // therefore exactly "no hit in (0, tmax)".
    using Rays = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig>;
    // Row i of the origins and directions as a ray (the one conversion both batch calls make).
    auto ray_at = [](const Rays &origins, const Rays &directions, size_t i) {
        return rt::Ray{{origins(i, 0), origins(i, 1), origins(i, 2)},
                       {directions(i, 0), directions(i, 1), directions(i, 2)}};
    };
    using Column = nb::ndarray<nb::numpy, double, nb::shape<-1>>;
    using Columns = nb::ndarray<nb::numpy, double, nb::shape<-1, 3>>;
    m.def(
        "intersect",
        [ray_at](const rt::Scene &s, Rays origins, Rays directions, double tmax) {
            const size_t n = origins.shape(0);
            if (directions.shape(0) != n)
                throw std::invalid_argument("one direction per origin expected");
            // One owned block for the five outputs (t, p, p_error, Ng as doubles; the object
            // index and the hit flag as doubles too, converted by the Python side): a capsule
            // per array would cost five allocations and five owners for no gain.
            double *out = new double[n * 12];
            nb::capsule owner(out, [](void *p) noexcept { delete[] static_cast<double *>(p); });
            {
                nb::gil_scoped_release release;
                rt::RayCounts counts;
                for (size_t i = 0; i < n; ++i) {
                    rt::Ray ray = ray_at(origins, directions, i);
                    rt::Hit hit = rt::closest_hit(s, ray, counts);
                    bool found = hit.found() && hit.t < tmax;
                    double *row = out + i * 12;
                    row[0] = found ? hit.t : rt::infinity;
                    const Vec3 v[3] = {hit.p, hit.p_error, hit.Ng};
                    for (int k = 0; k < 3; ++k)
                        row[1 + 3 * k] = v[k].x, row[2 + 3 * k] = v[k].y, row[3 + 3 * k] = v[k].z;
                    row[10] = found ? hit.object : -1;
                    row[11] = found ? 1 : 0;
                }
            }
            // Strides in elements (nanobind's convention): row i of each output starts at 12 i.
            Column t(out, {n}, owner, {12});
            Columns p(out + 1, {n, 3}, owner, {12, 1}), e(out + 4, {n, 3}, owner, {12, 1}),
                ng(out + 7, {n, 3}, owner, {12, 1});
            Column object(out + 10, {n}, owner, {12}), hit(out + 11, {n}, owner, {12});
            return std::make_tuple(hit, t, p, e, ng, object);
        },
        "scene"_a, "origins"_a, "directions"_a, "tmax"_a = rt::infinity,
        "For each ray (origins, directions: (N, 3) float64) the closest hit with t in (0, tmax), "
        "as the renderer finds it (closest_hit): (hit, t, p, p_error, Ng, object), each a view "
        "of one (N, 12) block; hit and object as float64 (1/0, index or -1), t infinity on a "
        "miss.");
    m.def(
        "closest_mesh_hits",
        [](const rt::Scene &s, Rays origins, Rays directions, int threads, bool packets) {
            const size_t n = origins.shape(0);
            if (directions.shape(0) != n)
                throw std::invalid_argument("one direction per origin expected");
            if (threads < 1) throw std::invalid_argument("threads must be at least 1");
            // One block for the three columns (t, then objects, then triangles), from the
            // images' cache (allocate_image()): every entry is written.
            static_assert(sizeof(double) == 2 * sizeof(float) && sizeof(int32_t) == sizeof(float));
            float *block = allocate_image(4 * n);
            nb::capsule owner(block, release_image);
            double *t = reinterpret_cast<double *>(block);
            int32_t *ids = reinterpret_cast<int32_t *>(block + 2 * n); // objects, then triangles
            {
                nb::gil_scoped_release release;
                rt::set_mesh_packets(s, packets);
                rt::closest_mesh_hits(s, origins.data(), directions.data(), n, threads, t, ids,
                                      ids + n);
            }
            using Ids = nb::ndarray<nb::numpy, int32_t, nb::shape<-1>>;
            return std::make_tuple(Column(t, {n}, owner), Ids(ids, {n}, owner),
                                   Ids(ids + n, {n}, owner));
        },
        "scene"_a, "origins"_a, "directions"_a, "threads"_a = 1, "packets"_a = true,
        "For each ray (origins, directions: (N, 3) float64) the closest hit with the scene's "
        "meshes only, t in (0, infinity), on `threads` threads: (t, object, triangle), t "
        "infinity and -1 on a miss; triangle is the face's index in its mesh. packets=False: "
        "the lecture's one-ray traversal, else the wide hierarchy (21_wide_bvh.h).");
    m.def(
        "mesh_hierarchy",
        [](Vertices vertices, Faces faces, int threads) {
            rt::Mesh mesh;
            fill_mesh(mesh, vertices, faces);
            mesh.build_threads = threads;
            {
                nb::gil_scoped_release release;
                mesh.build();
            }
            std::vector<double> bounds;
            std::vector<int> first, count;
            for (const rt::BVHNode &node : mesh.nodes) {
                for (int k = 0; k < 3; ++k) bounds.push_back(node.bounds.min[k]);
                for (int k = 0; k < 3; ++k) bounds.push_back(node.bounds.max[k]);
                first.push_back(node.first), count.push_back(node.count);
            }
            return std::make_tuple(bounds, first, count, mesh.order);
        },
        "vertices"_a, "faces"_a, "threads"_a = 1,
        "The bounding volume hierarchy 16_mesh.h builds for a mesh with `threads` build "
        "threads: (bounds: min and max corner per node, flattened; first; count; order).");
    m.def(
        "occluded",
        [ray_at](const rt::Scene &s, Rays origins, Rays directions,
                 nb::ndarray<const double, nb::shape<-1>, nb::c_contig> tmax) {
            const size_t n = origins.shape(0);
            if (directions.shape(0) != n || tmax.shape(0) != n)
                throw std::invalid_argument("one direction and one tmax per origin expected");
            double *out = new double[n];
            nb::capsule owner(out, [](void *p) noexcept { delete[] static_cast<double *>(p); });
            {
                nb::gil_scoped_release release;
                rt::RayCounts counts;
                for (size_t i = 0; i < n; ++i) {
                    rt::Ray ray = ray_at(origins, directions, i);
                    // The range a shadow ray asks about (shadow_ray_to(), 04_hit.h): (0, tmax).
                    out[i] = rt::any_hit(s, ray, {0, tmax(i)}, counts) ? 1 : 0;
                }
            }
            return Column(out, {n}, owner);
        },
        "scene"_a, "origins"_a, "directions"_a, "tmax"_a,
        "For each ray whether anything lies at t in (0, tmax[i]), as a shadow ray asks "
        "(any_hit): float64 1/0.");
}
