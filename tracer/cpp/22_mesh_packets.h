// Slide "Efficiency and Complexity": the mesh's hierarchy (16_mesh.h) searched by a packet of
// rays_per_packet neighbouring primary rays at once (Wald, Slusallek, Benthin and Wagner,
// "Interactive Rendering with Coherent Ray Tracing", 2001). Rays through neighbouring pixels
// cross nearly the same boxes, so the packet fetches each box once for all of them and tests
// it against all of them in one vector instruction per step; one ray's search fetches and
// tests it alone. The packet visits a box when any of its rays meets it, and each ray keeps its
// own range, so a ray sees a few boxes more than its own search would, never fewer.
//
// Each ray's answer is its own search's: the box test is slab_test()'s arithmetic lane by lane
// (a lane's decision is the one-ray decision), and a triangle is accepted by
// intersect_triangle()'s arithmetic lane by lane too, for each ray with that ray's range, in
// leaf order (or by intersect_triangle() itself, a ray at a time, where the rays' sheared axes
// differ). What may differ is the order in which leaves are reached, and so which of two
// triangles hit at exactly the same t (an edge they share) is kept, as with the wide hierarchy
// (21_wide_bvh.h);
// tests/tracer/test_mesh_packets.py renders every mesh scene both ways.
//
// It serves the aov integrator's primary rays in scenes of meshes only (mesh_packets_serve());
// other scenes, and packets=False, trace one ray at a time (19_aov.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "01_vec3.h"
#include "02_ray.h"
#include "03_camera.h"
#include "04_hit.h"
#include "09_scene.h"
#include "11_render.h"
#include "12_packet.h"
#include "14_box.h"
#include "15_triangle.h"
#include "16_mesh.h"
#include "19_aov.h"
#include "21_wide_bvh.h"
#include "constants.h"
#include "power.h"

namespace rt {

// Whether every object is a mesh with a hierarchy and the packets flag is on: the scenes this
// file serves.
inline bool mesh_packets_serve(const Scene &scene) {
    if (!scene.spheres.empty() || !scene.planes.empty() || scene.objects.empty()) return false;
    for (const auto &object : scene.objects) {
        const auto *mesh = dynamic_cast<const Mesh *>(object.get());
        if (mesh == nullptr || !mesh->packets || mesh->acceleration != Acceleration::bvh ||
            mesh->nodes.empty())
            return false;
    }
    return true;
}

// The packet's rays as the box and triangle tests need them (SlabRay and WatertightRay per
// lane), and each ray's own WatertightRay for the exact test. Lane masks are LaneMasks, one bit
// a lane in a mask register with AVX-512 (12_packet.h): the bunny's primary rays 1.038x
// [1.025-1.082] and 1.056x on the Xeon's one and two threads (9 rounds, the same hits).
struct MeshRaysL {
    Vec3L o, inv_d, inv_d_far;
    LaneMask near_x, near_y, near_z; // as SlabRay::near_x, ... (true: the max plane is near)
    int near[3]; // per axis: 1 (every lane's max plane is near), 0 (every lane's min), -1 mixed
    Vec3L d;
    bool shared_axes; // every lane's WatertightRay has the same kx, ky, kz
    Lanes Sx, Sy, Sz;
    int kx, ky, kz;
    WatertightRay each[rays_per_packet]; // where the axes are not shared
    // Whether the watertight set-up below has been made: only for a packet that meets a
    // mesh's root box (watertight()), so that a packet that misses every mesh (a sky's worth
    // of them: 81% of the bunny's 1920 x 1024 rays) spares its three divisions.
    bool watertight_made = false;

    // Lane k's WatertightRay, as WatertightRay(ray) makes it.
    WatertightRay lane(int k) const {
        if (!shared_axes) return each[k];
        WatertightRay w;
        w.o = {o.x[k], o.y[k], o.z[k]}, w.d = {d.x[k], d.y[k], d.z[k]};
        w.kx = kx, w.ky = ky, w.kz = kz;
        w.Sx = Sx[k], w.Sy = Sy[k], w.Sz = Sz[k];
        return w;
    }
};

// SlabRay's set-up for every lane at once: the same divisions and comparisons, one vector
// instruction each (a ray's six divisions were a tenth of its search). WatertightRay's follows
// in watertight(), when a packet first meets a mesh.
inline MeshRaysL mesh_rays(const RayL &ray) {
    MeshRaysL r;
    r.o = ray.o;
    r.d = ray.d;
    r.inv_d = {1 / ray.d.x, 1 / ray.d.y, 1 / ray.d.z}; // 14_box.h reciprocal()
    r.inv_d_far = r.inv_d * splat(1 + 2 * gamma(3));
    r.near_x = r.inv_d.x < 0, r.near_y = r.inv_d.y < 0, r.near_z = r.inv_d.z < 0;
    const LaneMask *nears[3] = {&r.near_x, &r.near_y, &r.near_z};
    for (int axis = 0; axis < 3; ++axis) {
        const unsigned bits = lane_bits(*nears[axis]);
        r.near[axis] = bits == (1u << rays_per_packet) - 1 ? 1 : bits == 0 ? 0 : -1;
    }
    return r;
}

// WatertightRay's set-up for every lane (once a packet: later calls return at once): the axis
// of d's largest component becomes z, for all lanes at once where they agree.
inline void watertight(MeshRaysL &r) {
    if (r.watertight_made) return;
    r.watertight_made = true;
    const Vec3L a = abs(r.d);
    const Mask x_biggest = (a.x > a.y) & (a.x > a.z), y_biggest = ~(a.x > a.y) & (a.y > a.z);
    const Mask z_biggest = ~x_biggest & ~y_biggest;
    const unsigned all = (1u << rays_per_packet) - 1;
    const unsigned zx = lane_bits(x_biggest), zy = lane_bits(y_biggest), zz = lane_bits(z_biggest);
    r.shared_axes = zx == all || zy == all || zz == all;
    if (!r.shared_axes) { // each lane its own axes, one lane at a time
        for (int k = 0; k < rays_per_packet; ++k)
            r.each[k] = WatertightRay(Ray{{r.o.x[k], r.o.y[k], r.o.z[k]},
                                          {r.d.x[k], r.d.y[k], r.d.z[k]}});
        return;
    }
    r.kz = zx == all ? 0 : zy == all ? 1 : 2;
    r.kx = (r.kz + 1) % 3;
    r.ky = (r.kx + 1) % 3;
    const Lanes *d[3] = {&r.d.x, &r.d.y, &r.d.z};
    r.Sx = -*d[r.kx] / *d[r.kz];
    r.Sy = -*d[r.ky] / *d[r.kz];
    r.Sz = 1 / *d[r.kz];
}

// 14_box.h slab_test(), per lane: the same operations in the same order (the near plane chosen
// per lane by the sign of its 1/d, as planes[r.near_x] chooses it).
// Always inlined, as mesh_closest_hits() below: called out of line, each call passed its
// vectors of lanes through memory, and the search took a fifth longer (perf, issue 12).
[[gnu::always_inline]] inline LaneMask slab_test(const AABB &box, const MeshRaysL &r, Lanes min,
                                             Lanes max, Lanes &t_near) {
    // BEGIN SOLUTION L09
    // PROMPT: A copy, lane by lane, of slab_test() for a packet of rays.
    const Vec3 *planes = &box.min; // planes[0] = min, planes[1] = max
    // Each lane's near and far plane per axis: one value for all lanes where they agree (rays
    // through neighbouring pixels nearly always do), else chosen lane by lane.
    auto plane = [&](int axis, LaneMask near, bool far) {
        if (r.near[axis] >= 0) return splat(planes[r.near[axis] ^ int(far)][axis]);
        return far ? select(near, splat(box.min[axis]), splat(box.max[axis]))
                   : select(near, splat(box.max[axis]), splat(box.min[axis]));
    };
    Lanes tx0 = (plane(0, r.near_x, false) - r.o.x) * r.inv_d.x;
    Lanes tx1 = (plane(0, r.near_x, true) - r.o.x) * r.inv_d_far.x;
    Lanes ty0 = (plane(1, r.near_y, false) - r.o.y) * r.inv_d.y;
    Lanes ty1 = (plane(1, r.near_y, true) - r.o.y) * r.inv_d_far.y;
    Lanes tz0 = (plane(2, r.near_z, false) - r.o.z) * r.inv_d.z;
    Lanes tz1 = (plane(2, r.near_z, true) - r.o.z) * r.inv_d_far.z;
    Lanes lo = min, hi = max;
    lo = select(tx0 > lo, tx0, lo), hi = select(tx1 < hi, tx1, hi);
    lo = select(ty0 > lo, ty0, lo), hi = select(ty1 < hi, ty1, hi);
    lo = select(tz0 > lo, tz0, lo), hi = select(tz1 < hi, tz1, hi);
    t_near = lo;
    return lo <= hi;
    // END SOLUTION
}

// 15_triangle.h larger() and triangle_t_error(), lane by lane: the same operations in the same
// order, so each lane's bound is the one-ray bound's bits.
inline Lanes larger(Lanes a, Lanes b) { return select(b != b, a, select(a > b, a, b)); }
inline Lanes triangle_t_error(const Vec3L &a, const Vec3L &b, const Vec3L &c, Lanes e0, Lanes e1,
                              Lanes e2, Lanes inv_det) {
    Lanes max_z = larger(fabs(a.z), larger(fabs(b.z), fabs(c.z)));
    Lanes max_x = larger(fabs(a.x), larger(fabs(b.x), fabs(c.x)));
    Lanes max_y = larger(fabs(a.y), larger(fabs(b.y), fabs(c.y)));
    Lanes delta_z = gamma(3) * max_z;
    Lanes delta_x = gamma(5) * (max_x + max_z), delta_y = gamma(5) * (max_y + max_z);
    Lanes delta_e = 2 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    Lanes max_e = larger(fabs(e0), larger(fabs(e1), fabs(e2)));
    return 3 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * fabs(inv_det);
}

// intersect_triangle()'s answer for a packet's rays: t and the barycentric coordinates per lane.
struct TriangleHitL {
    Lanes t, b0, b1, b2;
};

// 15_triangle.h intersect_triangle() for one triangle and the rays of `lanes` (which share kx,
// ky, kz: MeshRaysL::shared_axes), all lanes at once: its first steps are 21_wide_bvh.h
// sheared_candidates(), the rest the same operations in the same order, so a lane is true
// exactly where intersect_triangle() returns true for that ray and range, and there th's lanes
// are its t and barycentric coordinates (elsewhere they mean nothing). The rare lane whose hit
// is within the error of t of range.min asks starts_off_the_plane_heading_in() on its own. A
// primary ray meets a bunny's triangle in a few lanes of eight: one call per such lane, each
// shearing the triangle again, cost more than this test in all eight (perf, issue 12).
// Always inlined into the leaf loop (GCC kept it out of line, a fifth of the bunny's primary
// rays' time in it): 1.02x on one thread and on two (Zen 4, five alternating rounds).
[[gnu::always_inline]] inline LaneMask intersect_triangle(const Vec3 &p0, const Vec3 &p1,
                                                      const Vec3 &p2, const MeshRaysL &r,
                                                      LaneMask lanes, Lanes min, Lanes max,
                                                      TriangleHitL &th) {
    // BEGIN SOLUTION L08
    // PROMPT: A copy, lane by lane, of intersect_triangle() for a packet of rays.
    const Lanes o[3] = {r.o.x, r.o.y, r.o.z};
    const Sheared<Lanes, LaneMask> s = sheared_candidates<Lanes, LaneMask>(
        p0, p1, p2, o, r.kx, r.ky, r.kz, r.Sx, r.Sy, r.Sz, min, max);
    LaneMask hit = lanes & s.candidates;
    if (!any(hit)) return hit;
    const Lanes inv_det = 1 / s.det;
    const Lanes t = s.t_scaled * inv_det;
    const LaneMask doubtful =
        hit & (t <= min + triangle_t_error({s.ax, s.ay, s.az}, {s.bx, s.by, s.bz},
                                           {s.cx, s.cy, s.cz}, s.e0, s.e1, s.e2, inv_det));
    for (unsigned bits = lane_bits(doubtful); bits != 0; bits &= bits - 1) {
        const int k = __builtin_ctz(bits);
        if (!starts_off_the_plane_heading_in(p0, p1, p2, r.lane(k))) hit.set(k, false);
    }
    th = {t, s.e0 * inv_det, s.e1 * inv_det, s.e2 * inv_det};
    return hit;
    // END SOLUTION
}

// Each ray's closest hit in `mesh` within (min, max] (max shrinks to it): for the lanes of
// `active`, th[k] and triangle[k] where found[k]. Boxes and triangles are counted once per ray
// that takes part in the test, as the one-ray search counts them.
[[gnu::always_inline]] inline LaneMask mesh_closest_hits(const Mesh &mesh, MeshRaysL &r,
                                                   LaneMask active, Lanes min, Lanes &max,
                                                   TriangleHit (&th)[rays_per_packet],
                                                   int (&triangle)[rays_per_packet],
                                                   RayCounts &counts) {
    LaneMask found = mask_all(false);
    struct Pending {
        int node;
        LaneMask lanes;
        Lanes t_near;
    } stack[Mesh::max_tree_depth + 1];
    Lanes t_root;
    counts.box_tests += uint64_t(count(active));
    LaneMask lanes = active & slab_test(mesh.nodes[0].bounds, r, min, max, t_root);
    if (!any(lanes)) return found;
    watertight(r);
    int top = 0, index = 0;
    for (;;) {
        const BVHNode &node = mesh.nodes[size_t(index)];
        if (node.count > 0) { // a leaf: its triangles in leaf order, each for the rays in it
            counts.primitive_tests += uint64_t(count(lanes)) * uint64_t(node.count);
            for (int i = node.first; i < node.first + node.count; ++i) {
                const Vec3 *v = &mesh.leaf_vertices[3 * size_t(i)];
                if (r.shared_axes) { // all lanes at once
                    TriangleHitL hit;
                    const LaneMask hits =
                        intersect_triangle(v[0], v[1], v[2], r, lanes, min, max, hit);
                    if (!any(hits)) continue;
                    max = select(hits, hit.t, max);
                    found |= hits;
                    for (unsigned bits = lane_bits(hits); bits != 0; bits &= bits - 1) {
                        const int k = __builtin_ctz(bits);
                        th[k] = {hit.t[k], hit.b0[k], hit.b1[k], hit.b2[k]};
                        triangle[k] = mesh.order[size_t(i)];
                    }
                    continue;
                }
                for (unsigned bits = lane_bits(lanes); bits != 0; bits &= bits - 1) {
                    const int k = __builtin_ctz(bits);
                    TriangleHit hit;
                    if (intersect_triangle(v[0], v[1], v[2], r.lane(k), {min[k], max[k]}, hit)) {
                        th[k] = hit, triangle[k] = mesh.order[size_t(i)];
                        max[k] = hit.t;
                        found.set(k, true);
                    }
                }
            }
        } else {
            const int left = index + 1, right = node.first;
            Lanes t_left, t_right;
            counts.box_tests += 2 * uint64_t(count(lanes));
            LaneMask in_left =
                lanes & slab_test(mesh.nodes[size_t(left)].bounds, r, min, max, t_left);
            LaneMask in_right =
                lanes & slab_test(mesh.nodes[size_t(right)].bounds, r, min, max, t_right);
            const bool l = any(in_left), rr = any(in_right);
            if (l && rr) { // the child the first of the rays enters first, then the other
                // (The lanes read as bits and the t's compared as vectors, the pending child
                // stored field by field: Clang 19 read in_left[k] by storing the vector and
                // loading one lane back, and built the pushed Pending in a temporary, padding
                // and all. The bunny's primary rays 0.969x the time with Clang, GCC's 1.004x;
                // five and three alternating rounds, Zen 4, issue 12.)
                const unsigned lb = lane_bits(in_left), rb = lane_bits(in_right);
                const int k = __builtin_ctz(lb | rb);
                const bool left_first =
                    (lb >> k & 1) &&
                    (!(rb >> k & 1) || (lane_bits(Mask(t_left <= t_right)) >> k & 1));
                Pending &later = stack[top++];
                later.node = left_first ? right : left;
                later.lanes = left_first ? in_right : in_left;
                later.t_near = left_first ? t_right : t_left;
                index = left_first ? left : right;
                lanes = left_first ? in_left : in_right;
                continue;
            }
            if (l || rr) {
                index = l ? left : right;
                lanes = l ? in_left : in_right;
                continue;
            }
        }
        // Next: the nearest waiting node that some of its rays still reach before their hit.
        for (;;) {
            if (top == 0) return found;
            const Pending &p = stack[--top];
            lanes = p.lanes & (p.t_near <= max);
            if (any(lanes)) {
                index = p.node;
                break;
            }
        }
    }
}

// A packet's pixels: a block of packet_columns x packet_rows, lane k at column k %
// packet_columns, row k / packet_columns. A compact block is more coherent than a row of 8: its
// rays lie closer together, so fewer boxes are met by only some of them. (4 x 2 with AVX-512's
// 8 lanes; a row of 4 or of 2 where a packet has fewer, power.h.)
constexpr int packet_columns = std::min(4, rays_per_packet),
              packet_rows = rays_per_packet / packet_columns;

// 03_camera.h primary_ray() through the centres of a block of pixels from (i0, j0), one per
// lane: 12_packet.h primary_rays() with a row per lane (y times true_up lane by lane is the
// same product as primary_ray()'s), each lane bit for bit the one-ray code's.
inline RayL primary_rays_block(const Camera &cam, int i0, int j0) {
    // BEGIN SOLUTION L01
    // PROMPT: A copy of 03_camera.h primary_ray() for a block of pixels, one ray per lane.
    Lanes sx, sy;
    for (int k = 0; k < rays_per_packet; ++k)
        sx[k] = (i0 + k % packet_columns) + 0.5, sy[k] = (j0 + k / packet_columns) + 0.5;
    Lanes x = sx / double(cam.width) - 0.5;
    Lanes y = 0.5 - sy / double(cam.height);
    Vec3L d = splat(cam.forward) + splat(cam.right) * (x * cam.plane_width + cam.window_shift) +
              splat(cam.true_up) * (y * cam.plane_height);
    return {splat(cam.eye), normalize(d)};
    // END SOLUTION
}

// primary_rays_block() in two steps, as 12_packet.h primary_across() splits primary_rays():
// the direction's part that depends on the column only, forward + right (x plane_width +
// window_shift), once per column of blocks in a tile, and the part that depends on the row
// only, true_up (y plane_height), once per row of blocks; a block adds them and normalises.
// The same operations in the same order as primary_rays_block(), so the same bits, for two
// divisions a packet fewer (the divisions were a fifth of a missing packet's time, perf).
inline Vec3L block_across(const Camera &cam, int i0) {
    Lanes sx;
    for (int k = 0; k < rays_per_packet; ++k) sx[k] = (i0 + k % packet_columns) + 0.5;
    Lanes x = sx / double(cam.width) - 0.5;
    return splat(cam.forward) + splat(cam.right) * (x * cam.plane_width + cam.window_shift);
}
inline Vec3L block_up(const Camera &cam, int j0) {
    Lanes sy;
    for (int k = 0; k < rays_per_packet; ++k) sy[k] = (j0 + k / packet_columns) + 0.5;
    Lanes y = 0.5 - sy / double(cam.height);
    return splat(cam.true_up) * (y * cam.plane_height);
}

// A packet's pixels where its rays meet nothing. Not inlined: inlined, it made the tile's loop
// too large for GCC to inline the search (mesh_closest_hits(), slab_test()) into it, which
// cost more than the rays it spares.
[[gnu::noinline]] inline void store_misses(float *out, int width, int i0, int j0, LaneMask active) {
    for (unsigned bits = lane_bits(active); bits != 0; bits &= bits - 1) {
        const int k = __builtin_ctz(bits);
        store_aov(out, width, i0 + k % packet_columns, j0 + k / packet_columns, Hit{});
    }
}

// 19_aov.h render_tile_aov() for scenes of meshes (mesh_packets_serve()), a packet of
// neighbouring pixels of a row at a time: each pixel's channels as the one-ray code gives them.
inline void render_tile_aov_packets(const Scene &scene, int x0, int y0, int x1, int y1,
                                    float *out, RayCounts &counts) {
    const Camera &cam = scene.camera;
    constexpr int most = tile_size / packet_columns; // block columns across the widest tile
    Vec3L across[most];
    for (int c = 0, i0 = x0; i0 < x1 && c < most; ++c, i0 += packet_columns)
        across[c] = block_across(cam, i0);
    // The pixels of this tile whose rays may meet some mesh's root box: the others miss every
    // mesh, and their packets are only counted and stored.
    PixelRect seen{infinity, -infinity, infinity, -infinity};
    for (const auto &object : scene.objects) {
        const PixelRect r = pixel_rect(cam, static_cast<const Mesh &>(*object).nodes[0].bounds);
        seen = {std::min(seen.i_min, r.i_min), std::max(seen.i_max, r.i_max),
                std::min(seen.j_min, r.j_min), std::max(seen.j_max, r.j_max)};
    }
    for (int j0 = y0; j0 < y1; j0 += packet_rows) {
        const Vec3L up = block_up(cam, j0);
        for (int c = 0, i0 = x0; i0 < x1; ++c, i0 += packet_columns) {
            // Lanes past the tile's edge are rays through pixels beyond it, masked off.
            LaneMask active = mask_all(false);
            for (int k = 0; k < rays_per_packet; ++k)
                if (i0 + k % packet_columns < x1 && j0 + k / packet_columns < y1)
                    active.set(k, true);
            counts.primary += uint64_t(count(active));
            if (!seen.may_meet(i0, i0 + packet_columns, j0, j0 + packet_rows)) {
                // Every ray misses every root box, as each mesh's slab test would find: counted
                // as those tests, stored as misses.
                counts.box_tests += uint64_t(count(active)) * scene.objects.size();
                store_misses(out, cam.width, i0, j0, active);
                continue;
            }
            const RayL rays = c < most ? RayL{splat(cam.eye), normalize(across[c] + up)}
                                       : primary_rays_block(cam, i0, j0); // a wider tile
            MeshRaysL r = mesh_rays(rays);
            Lanes max = splat(infinity);
            const Mesh *owner[rays_per_packet] = {};
            TriangleHit th[rays_per_packet];
            int triangle[rays_per_packet];
            for (const auto &object : scene.objects) { // in order, as closest_hit() asks them
                const Mesh &mesh = static_cast<const Mesh &>(*object);
                TriangleHit here[rays_per_packet];
                int t[rays_per_packet];
                LaneMask found =
                    mesh_closest_hits(mesh, r, active, splat(0.0), max, here, t, counts);
                for (unsigned bits = lane_bits(found); bits != 0; bits &= bits - 1) {
                    const int k = __builtin_ctz(bits);
                    owner[k] = &mesh, th[k] = here[k], triangle[k] = t[k];
                }
            }
            for (unsigned bits = lane_bits(active); bits != 0; bits &= bits - 1) {
                const int k = __builtin_ctz(bits);
                Hit hit;
                if (owner[k] != nullptr) owner[k]->record(th[k], triangle[k], hit);
                store_aov(out, cam.width, i0 + k % packet_columns, j0 + k / packet_columns, hit);
            }
        }
    }
}

} // namespace rt
