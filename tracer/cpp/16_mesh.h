// Slide "Intersecting a Complex Object": a triangle mesh on vertices, with Gouraud shading, is
// "expensive to ray trace" if every ray is tested against every triangle. The slide's first
// remedy: test the bounding box of the entire object first. The full remedy: a bounding volume
// hierarchy (Kay and Kajiya 1986; Goldsmith and Salmon 1987), boxes within boxes, built with the
// surface-area heuristic (MacDonald and Booth 1990; the binned build of Wald 2007): a ray
// that misses a box skips every triangle inside it.
//
// Mesh::acceleration picks the remedy so a lesson can count what each saves (RayCounts).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"
#include "14_box.h"
#include "15_triangle.h"
#include "constants.h"

namespace rt {

enum class Acceleration { none, bounding_box, bvh };

struct BVHNode {
    AABB bounds;
    int first = 0;  // leaf: first triangle (in Mesh::order); inner: index of the second child
    int count = 0;  // triangles in a leaf; 0 for an inner node, whose first child follows it
};

// Slide "Intersecting a Complex Object" ("triangle mesh on vertexes, Gouraud shading"): a mesh
// that stands for a smooth surface carries a normal per vertex; across a triangle the shading
// normal is those three blended by the hit's barycentric coordinates (b0 weighs p0's normal,
// ...), then made unit length again, since a blend of unit vectors is shorter than one. Gouraud
// (1971) blended the colours computed at the vertices; blending the normals and shading each
// point (Phong 1975) keeps highlights inside a triangle; either way the facets disappear. A
// blend that vanishes (opposite normals) keeps the face's own normal Ng.
inline Vec3 smooth_normal(const TriangleHit &th, const Vec3 &n0, const Vec3 &n1, const Vec3 &n2,
                          const Vec3 &Ng) {
    // BEGIN SOLUTION L10
    // PROMPT: Gouraud shading (slide "Intersecting a Complex Object"): the shading normal at the
    // PROMPT: hit, the vertex normals n0, n1, n2 (of p0, p1, p2) blended by the barycentric
    // PROMPT: coordinates th.b0, th.b1, th.b2, as a unit vector; Ng (the face's unit normal) where
    // PROMPT: the blend has zero length.
    Vec3 n = th.b0 * n0 + th.b1 * n1 + th.b2 * n2;
    double len = length(n);
    return len > 0 ? n / len : Ng;
    // END SOLUTION
}

struct Mesh;

// A faster search of a built mesh (21_wide_bvh.h), beside the lecture's traverse(): the same
// closest hit (or any hit) from a hierarchy of its own. Mesh::hit() and blocks() use it when
// `packets` is set (render_with_stats(packets=True), the default); packets=False keeps the
// lecture's one-ray code below, as student builds run it.
struct MeshAccelerator {
    virtual ~MeshAccelerator() = default;
    virtual bool traverse(const Mesh &mesh, const Ray &ray, Interval range, TriangleHit &best,
                          int &best_triangle, RayCounts &counts, bool any) const = 0;
};

struct Mesh : Object {
    // The deepest a leaf may lie. The traversal keeps at most one waiting node per level on its
    // stack, so a stack of max_tree_depth + 1 entries cannot overflow; 60 levels of a tree that
    // halves its triangles at each level would hold 2^60 of them, more than any mesh here.
    static constexpr int max_tree_depth = 60;

    std::vector<Vec3> vertices;
    std::vector<Vec3> normals; // per vertex, for smooth (Gouraud-style) shading; empty: flat
    std::vector<std::array<int, 3>> triangles;
    Acceleration acceleration = Acceleration::bvh;
    std::vector<BVHNode> nodes; // nodes[0] is the root; its box bounds the whole mesh
    std::vector<int> order;     // triangle indices in leaf order
    std::vector<Vec3> leaf_vertices; // each triangle's three vertices, in leaf order
    // Where one mesh holds the flat triangles of several scene objects: each face's object and
    // material (empty: all are this mesh's own).
    std::vector<int> triangle_object, triangle_material;
    int object_of(int t) const { // triangle t's object
        return triangle_object.empty() ? object : triangle_object[size_t(t)];
    }
    // The faster search (none until one is built for this mesh), and whether to use it.
    std::shared_ptr<const MeshAccelerator> accelerator;
    bool packets = true;

    // -- building -------------------------------------------------------------------------
    AABB triangle_box(int t) const {
        AABB b;
        for (int v : triangles[size_t(t)]) b.extend(vertices[size_t(v)]);
        return b;
    }

    void build() {
        order.resize(triangles.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = int(i);
        nodes.clear();
        std::vector<AABB> boxes(triangles.size());
        std::vector<Vec3> centres(triangles.size());
        for (size_t i = 0; i < triangles.size(); ++i) {
            boxes[i] = triangle_box(int(i));
            centres[i] = boxes[i].centre();
        }
        nodes.reserve(2 * triangles.size() + 1);
        nodes.emplace_back();
        if (acceleration == Acceleration::bvh)
            build_node(0, 0, int(order.size()), 0, boxes, centres);
        else { // one leaf of all triangles
            if (acceleration == Acceleration::bounding_box) // in one box around everything
                for (const AABB &b : boxes) nodes[0].bounds.extend(b);
            else // none: in a box that is all of space, so the root's one slab test passes
                 // for every ray (no 0 * infinity: no plane is finite) and every ray tests
                 // every triangle, the slide's starting point before any bounding volume
                nodes[0].bounds = AABB{{-infinity, -infinity, -infinity},
                                       {infinity, infinity, infinity}};
            nodes[0].first = 0;
            nodes[0].count = int(order.size());
        }
        // The vertices each leaf tests, side by side in memory, in the order they are tested.
        leaf_vertices.resize(3 * order.size());
        for (size_t i = 0; i < order.size(); ++i)
            for (size_t k = 0; k < 3; ++k)
                leaf_vertices[3 * i + k] = vertices[size_t(triangles[size_t(order[i])][k])];
    }

    // Surface-area heuristic: the chance that a ray through a box also passes through a box
    // inside it is the ratio of their surface areas, so a split of n triangles into (L, R)
    // costs about area(L) nL + area(R) nR (relative to area(parent)), against n for a leaf.
    // Candidate splits: 16 bins of the triangles' centres along each axis.
    //
    // The root's two halves are built side by side when build_threads is 2 or more and the mesh
    // has at least parallel_build_triangles: the right half by a second thread into a list of
    // its own, appended after the left half with its child indices moved by the left half's
    // size, which is where the one-thread build puts it; the tree is the same node for node.
    static constexpr int parallel_build_triangles = 4096;
    int build_threads = 2;

    void build_node(int index, int first, int count, int depth, const std::vector<AABB> &boxes,
                    const std::vector<Vec3> &centres) {
        build_node(nodes, index, first, count, depth, boxes, centres);
    }

    void build_node(std::vector<BVHNode> &out, int index, int first, int count, int depth,
                    const std::vector<AABB> &boxes, const std::vector<Vec3> &centres) {
        AABB bounds, centre_bounds;
        for (int i = first; i < first + count; ++i) {
            bounds.extend(boxes[size_t(order[size_t(i)])]);
            centre_bounds.extend(centres[size_t(order[size_t(i)])]);
        }
        out[size_t(index)].bounds = bounds;
        // 16 bins find a split within a few per cent of the best of all (Wald 2007) at a
        // fraction of the cost; leaves of at most 4 triangles, as pbrt-v4's default; a depth of
        // at most max_tree_depth keeps the traversal stack from overflowing on any input.
        constexpr int bins = 16, max_leaf = 4, max_depth = max_tree_depth;
        double best_cost = infinity;
        int best_axis = -1, best_bin = 0;
        if (count > max_leaf && depth < max_depth) {
            for (int axis = 0; axis < 3; ++axis) {
                double lo = centre_bounds.min[axis], hi = centre_bounds.max[axis];
                if (!(hi > lo)) continue;
                AABB bin_box[bins];
                int bin_count[bins] = {};
                double scale = bins / (hi - lo);
                for (int i = first; i < first + count; ++i) {
                    int t = order[size_t(i)];
                    int b = std::min(bins - 1, int((centres[size_t(t)][axis] - lo) * scale));
                    bin_box[b].extend(boxes[size_t(t)]);
                    ++bin_count[b];
                }
                // Sweep: areas and counts left of each boundary, then right of it.
                double left_area[bins - 1];
                int left_count[bins - 1];
                AABB acc;
                int n = 0;
                for (int b = 0; b < bins - 1; ++b) {
                    acc.extend(bin_box[b]);
                    n += bin_count[b];
                    left_area[b] = acc.area();
                    left_count[b] = n;
                }
                acc = AABB();
                n = 0;
                for (int b = bins - 1; b >= 1; --b) {
                    acc.extend(bin_box[b]);
                    n += bin_count[b];
                    if (left_count[b - 1] == 0 || n == 0) continue;
                    double cost = left_area[b - 1] * left_count[b - 1] + acc.area() * n;
                    if (cost < best_cost) best_cost = cost, best_axis = axis, best_bin = b;
                }
            }
        }
        // Costs in units of one ray/triangle test; a ray/box test (two per inner node visited)
        // costs about half of one, so an inner node adds bounds.area() * traversal_cost.
        constexpr double traversal_cost = 1.0;
        double leaf_cost = bounds.area() * count;
        if (best_axis < 0 || leaf_cost <= best_cost + bounds.area() * traversal_cost) {
            out[size_t(index)].first = first;
            out[size_t(index)].count = count;
            return;
        }
        double lo = centre_bounds.min[best_axis], hi = centre_bounds.max[best_axis];
        double scale = bins / (hi - lo);
        auto middle = std::partition(
            order.begin() + first, order.begin() + first + count, [&](int t) {
                return std::min(bins - 1, int((centres[size_t(t)][best_axis] - lo) * scale)) <
                       best_bin;
            });
        int left = int(middle - order.begin()) - first;
        if (depth == 0 && build_threads > 1 && count >= parallel_build_triangles) {
            // The two halves own disjoint ranges of `order` and their own node lists.
            std::vector<BVHNode> right_nodes(1);
            right_nodes.reserve(2 * size_t(count - left) + 1);
            std::thread right([&] {
                build_node(right_nodes, 0, first + left, count - left, depth + 1, boxes, centres);
            });
            out.emplace_back();
            build_node(out, index + 1, first, left, depth + 1, boxes, centres);
            right.join();
            const int offset = int(out.size());
            out[size_t(index)].first = offset;
            for (BVHNode node : right_nodes) {
                if (node.count == 0) node.first += offset; // an inner node's second child
                out.push_back(node);
            }
            return;
        }
        int left_index = int(out.size());
        out.emplace_back();
        build_node(out, left_index, first, left, depth + 1, boxes, centres);
        int right_index = int(out.size());
        out.emplace_back();
        out[size_t(index)].first = right_index;
        build_node(out, right_index, first + left, count - left, depth + 1, boxes, centres);
    }

    // -- tracing --------------------------------------------------------------------------
    // The closest of a leaf's triangles within range. Each hit shrinks range.max to it, so a
    // later triangle counts only if it is nearer, and the traversal skips the boxes beyond it;
    // `any` stops at the first hit (a shadow ray needs no more).
    bool leaf_hit(const BVHNode &node, const WatertightRay &wr, Interval &range,
                  TriangleHit &best, int &best_triangle, bool any) const {
        // BEGIN SOLUTION L09
        // PROMPT: Test the leaf's node.count triangles, from index node.first on: triangle i has
        // PROMPT: its vertices at leaf_vertices[3 i], [3 i + 1], [3 i + 2] and its index in the
        // PROMPT: mesh is order[i]. Keep the closest hit in (range.min, range.max] (best,
        // PROMPT: best_triangle) and shrink range.max to it; with `any`, return at the first hit.
        bool found = false;
        for (int i = node.first; i < node.first + node.count; ++i) {
            const Vec3 *v = &leaf_vertices[3 * size_t(i)];
            TriangleHit th;
            if (intersect_triangle(v[0], v[1], v[2], wr, range, th)) {
                best = th;
                best_triangle = order[size_t(i)];
                range.max = th.t;
                found = true;
                if (any) return true;
            }
        }
        return found;
        // END SOLUTION
    }

    // Walk the hierarchy front to back; `any` stops at the first hit (shadow rays).
    bool traverse(const Ray &ray, Interval range, TriangleHit &best, int &best_triangle,
                  RayCounts &counts, bool any) const {
        // BEGIN SOLUTION L09
        // PROMPT: The closest hit in the hierarchy (slide "Intersecting a Complex Object": "test
        // PROMPT: bounding box of entire object", then boxes within boxes). nodes[0] is the root;
        // PROMPT: an inner node (count == 0) has its children at index + 1 and at node.first; a
        // PROMPT: leaf holds triangles (leaf_hit()). Test a box with slab_test() within the current
        // PROMPT: range and skip what it misses; visit the nearer child first, keep the farther on
        // PROMPT: a stack of at most max_tree_depth + 1 entries with its entry t, and skip it if a
        // PROMPT: hit has come nearer meanwhile. Count each box test in counts.box_tests and each
        // PROMPT: triangle a leaf tests in counts.primitive_tests.
        if (nodes.empty()) return false;
        const WatertightRay wr(ray);
        const SlabRay sr(ray);
        double t_near;
        ++counts.box_tests;
        if (!slab_test(nodes[0].bounds, sr, range, t_near)) return false;
        // Children are tested in pairs; the nearer is visited first, the farther waits on the
        // stack with its entry distance, and is skipped if a hit has come nearer meanwhile.
        struct Pending {
            int node;
            double t_near;
        } stack[max_tree_depth + 1];
        int top = 0, index = 0;
        bool found = false;
        for (;;) {
            const BVHNode &node = nodes[size_t(index)];
            if (node.count > 0) { // a leaf: its triangles, stored in leaf order
                counts.primitive_tests += uint64_t(node.count);
                if (leaf_hit(node, wr, range, best, best_triangle, any)) {
                    found = true;
                    if (any) return true;
                }
            } else {
                const int left = index + 1, right = node.first;
                double t_left, t_right;
                counts.box_tests += 2;
                bool hit_left = slab_test(nodes[size_t(left)].bounds, sr, range, t_left);
                bool hit_right = slab_test(nodes[size_t(right)].bounds, sr, range, t_right);
                if (hit_left && hit_right) {
                    bool left_first = t_left <= t_right;
                    stack[top++] = {left_first ? right : left, left_first ? t_right : t_left};
                    index = left_first ? left : right;
                    continue;
                }
                if (hit_left || hit_right) {
                    index = hit_left ? left : right;
                    continue;
                }
            }
            // Next: the nearest waiting node that still lies before the closest hit.
            while (top > 0 && stack[top - 1].t_near > range.max) --top;
            if (top == 0) break;
            index = stack[--top].node;
        }
        return found;
        // END SOLUTION
    }

    // The lecture's traverse(), or the faster search where one is built and packets are on.
    bool search(const Ray &ray, const Interval &range, TriangleHit &th, int &t,
                RayCounts &counts, bool any) const {
        if (packets && accelerator)
            return accelerator->traverse(*this, ray, range, th, t, counts, any);
        return traverse(ray, range, th, t, counts, any);
    }

    bool hit(const Ray &ray, const Interval &range, Hit &hit, RayCounts &counts) const override {
        TriangleHit th;
        int t = -1;
        if (!search(ray, range, th, t, counts, false)) return false;
        record(th, t, hit);
        return true;
    }

    // The hit record of triangle t hit at th: the point, its error bound and the normals
    // (triangle_hit()), the shading normal where the mesh is smooth, the object and material.
    void record(const TriangleHit &th, int t, Hit &hit) const {
        const std::array<int, 3> &tri = triangles[size_t(t)];
        triangle_hit(vertices[size_t(tri[0])], vertices[size_t(tri[1])], vertices[size_t(tri[2])],
                     th, hit);
        if (!normals.empty()) // Gouraud-style: the vertex normals, interpolated
            hit.N = smooth_normal(th, normals[size_t(tri[0])], normals[size_t(tri[1])],
                                  normals[size_t(tri[2])], hit.Ng);
        hit.object = object_of(t);
        hit.material = triangle_material.empty() ? material : triangle_material[size_t(t)];
    }

    bool blocks(const Ray &ray, const Interval &range, RayCounts &counts) const override {
        TriangleHit th;
        int t = -1;
        return search(ray, range, th, t, counts, true);
    }
};

} // namespace rt
