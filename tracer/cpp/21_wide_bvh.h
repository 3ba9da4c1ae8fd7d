// Slide "Efficiency and Complexity": "Efficiency is a HUGE deal". The mesh's hierarchy
// (16_mesh.h) searched faster, with the same answer: a wider tree whose boxes and triangles are
// tested four at a time in SIMD (GCC/Clang vector extensions: one AVX2 register of 4 doubles,
// two SSE2 ones where AVX2 is missing).
//
// - A 4-wide hierarchy collapsed from the binary SAH one (Wald, Benthin, Boulos, "Getting Rid of
//   Packets", 2008; the "BVH4" of Embree and tinybvh): each wide node takes the place of a
//   binary node and up to three levels below it, opening the child of largest surface area
//   until it has four children. A ray visits about half as many nodes, each a single 4-lane
//   slab test in double precision, the same arithmetic as slab_test() lane by lane (so just as
//   conservative: it never misses a box the ray touches).
// - The triangles of a leaf side by side in structure-of-arrays form (TriangleBlock), four at
//   a time through the first steps of intersect_triangle() (shear, edge functions, range), the
//   same operations in the same order lane by lane: the build forbids fused multiply-add
//   contraction, and difference_of_products() uses an explicit correctly rounded fma per lane,
//   so each lane computes bit for bit what the one-ray code computes. A lane that survives is
//   then tested by intersect_triangle() itself, in leaf order with the range shrunk by each hit,
//   as leaf_hit() does: a leaf gives exactly leaf_hit()'s answer, and the hit record is the
//   one-ray code's.
//
// - A mesh that is not flat (more than one wide node) is searched in an eight-wide tree
//   collapsed the same way instead (Search8 below: the eight boxes tested at once, in float
//   where that decides as the double test does, children ordered by a bitonic sort of integer
//   keys), its boxes stored in 8 bits a plane against a node's own frame (QNode8) and, where
//   every vertex is a float, its leaves as their few vertices in float and the numbers of
//   their corners among them (IndexBlock): boxes that contain the lecture's boxes, in a
//   shallower tree, and the same triangle tests, so the same answers, in fewer, cheaper steps
//   from less memory (issue 12).
//
// What may differ from Mesh::traverse() is only the order in which leaves are visited (nearest
// child box first, among four instead of two). Where two triangles are hit at the same t (an
// edge they share) a traversal keeps the one it visits last, so either may be kept; the test
// tests/tracer/test_wide_bvh.py renders the mesh scenes both ways and requires equal pixels
// except where such a tie is shown. Counts: every child box tested is one box test, every real
// triangle of a leaf one primitive test (the padding of a block is not counted).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <thread>
#include <type_traits>
#include <vector>

#include <cstdlib>
#include <new>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <immintrin.h>

#include "01_vec3.h"
#include "02_ray.h"
#include "04_hit.h"
#include "09_scene.h"
#include "14_box.h"
#include "15_triangle.h"
#include "16_mesh.h"
#include "constants.h"
#include "power.h"

namespace rt {

constexpr int bvh_width = 4; // children per wide node, triangles per block
typedef double D4 __attribute__((vector_size(bvh_width * sizeof(double))));
typedef int64_t M4 __attribute__((vector_size(bvh_width * sizeof(int64_t)))); // true: all ones

// a b + c, rounded once, lane by lane, for any vector of doubles or floats here (D4, F8, D8,
// power.h Lanes): one fused multiply-add instruction where the machine has one of the vector's
// width (AVX-512 for 8 doubles, FMA for 4 doubles or 8 floats), else the library's fma lane
// by lane, correctly rounded too, so the bits are the same on every machine. (A scalar has no
// lanes to subscript: this template is not a candidate for double.)
template <class V, class S = std::decay_t<decltype(std::declval<V>()[0])>,
          std::enable_if_t<std::is_floating_point_v<S>, int> = 0>
inline V fma(V a, V b, V c) {
#if defined(__AVX512F__)
    if constexpr (sizeof(V) == sizeof(__m512d) && std::is_same_v<S, double>)
        return bit_cast<V>(_mm512_fmadd_pd(bit_cast<__m512d>(a), bit_cast<__m512d>(b),
                                           bit_cast<__m512d>(c)));
#endif
#if defined(__FMA__)
    if constexpr (sizeof(V) == sizeof(__m256d) && std::is_same_v<S, double>)
        return bit_cast<V>(_mm256_fmadd_pd(bit_cast<__m256d>(a), bit_cast<__m256d>(b),
                                           bit_cast<__m256d>(c)));
    if constexpr (sizeof(V) == sizeof(__m256) && std::is_same_v<S, float>)
        return bit_cast<V>(_mm256_fmadd_ps(bit_cast<__m256>(a), bit_cast<__m256>(b),
                                           bit_cast<__m256>(c)));
#endif
    V r;
    for (size_t k = 0; k < sizeof(V) / sizeof(S); ++k) r[k] = std::fma(a[k], b[k], c[k]);
    return r;
}

// The lanes of a mask as bits (lane k: bit k), by one instruction where there is one (a true
// lane's sign bit is set); lane_bits8() below for eight lanes. From the loop, Clang 19 made a
// mask register, a vector of it and four lanes taken out one by one: with the instruction in
// candidates_hit(), the bunny's incoherent rays 1.025x (nine alternating rounds, one Zen 4
// thread), the Cornell box 1.031x; the same hits.
inline unsigned lane_bits4(M4 m) {
#if defined(__AVX__)
    return unsigned(_mm256_movemask_pd(bit_cast<__m256d>(m)));
#else
    unsigned b = 0;
    for (int k = 0; k < bvh_width; ++k) b |= unsigned(m[k] != 0) << k;
    return b;
#endif
}

// 15_triangle.h's difference_of_products(), lane by lane, for 4 lanes (D4) or a packet's
// (Lanes).
template <class V> inline V difference_of_products(V a, V b, V c, V d) {
    V cd = c * d;
    V error = fma(-c, d, cd);
    return fma(a, b, -cd) + error;
}

typedef float F4 __attribute__((vector_size(bvh_width * sizeof(float))));

// The largest float <= x and the smallest float >= x: a box stored in float rounded outward
// contains the double box it stands for.
inline float float_down(double x) {
    float f = float(x);
    return double(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}
inline float float_up(double x) {
    float f = float(x);
    return double(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

// Four children's boxes: planes[0] their min corners, planes[1] their max corners, per axis,
// lane c for child c (planes[1 - near] picks the far plane as slab_test() does). Stored in
// float, rounded outward (float_down() for min, float_up() for max), so a node is two cache
// lines (128 bytes) instead of four: the traversal of a 100,000-triangle mesh is bound by
// memory. The test converts them back to double (exactly) and runs slab_test()'s double
// arithmetic on them: each float box contains the binary hierarchy's double box, so a ray that
// meets the double box (which slab_test() never misses) meets the float one, and the wide
// search skips no box the lecture's search would visit; it only visits a few more.
// A lane without a child holds the empty box (min +infinity, max -infinity), which every ray
// misses: its near plane gives t = +infinity (infinity minus a finite origin, times a nonzero
// 1/d of the right sign), its far plane -infinity, with no 0 * infinity anywhere.
struct alignas(64) WideNode {
    F4 planes[2][3];
    int32_t child[bvh_width]; // an inner child: its WideNode; a leaf: -1 - its first block
    int32_t children = 0;     // lanes in use, from lane 0
};

// Four triangles of a leaf, vertex by vertex and axis by axis (p[vertex][axis], lane k for the
// k-th), and each one's index in leaf order (Mesh::leaf_vertices, Mesh::order); -1 pads a
// block with a triangle whose vertices are all 0, whose edge functions are exactly 0 (det = 0:
// no hit), and which the candidate loop skips besides. `more`: the leaf's next block follows.
// Aligned to a cache line, so that a block (320 bytes) is exactly five lines, the five that
// WideSearch::node() prefetches, and never straddles a sixth.
struct alignas(64) TriangleBlock {
    D4 p[3][3];
    int32_t leaf[bvh_width];
    int32_t more;
};
static_assert(sizeof(TriangleBlock) == 5 * 64, "a triangle block is five cache lines");

// slab_test() (14_box.h) for the four children of a node at once: the same operations, lane
// by lane, in the same order.
inline M4 slab_test(const WideNode &node, const SlabRay &r, const Interval &range, D4 &t_near) {
    // BEGIN SOLUTION L09
    // PROMPT: A copy, lane by lane, of slab_test() for the four children of a wide node.
    D4 near_planes[2][3];
    for (int side = 0; side < 2; ++side)
        for (int axis = 0; axis < 3; ++axis)
            near_planes[side][axis] = __builtin_convertvector(node.planes[side][axis], D4);
    D4 tx0 = (near_planes[r.near_x][0] - r.o.x) * r.inv_d.x;
    D4 tx1 = (near_planes[1 - r.near_x][0] - r.o.x) * r.inv_d_far.x;
    D4 ty0 = (near_planes[r.near_y][1] - r.o.y) * r.inv_d.y;
    D4 ty1 = (near_planes[1 - r.near_y][1] - r.o.y) * r.inv_d_far.y;
    D4 tz0 = (near_planes[r.near_z][2] - r.o.z) * r.inv_d.z;
    D4 tz1 = (near_planes[1 - r.near_z][2] - r.o.z) * r.inv_d_far.z;
    // (t_near is compared by value only (WideSearch), where -0 and +0 are equal: unlike
    // slab_test8()'s, its lo needs no +0.)
    D4 lo = broadcast<D4>(range.min), hi = broadcast<D4>(range.max);
    lo = tx0 > lo ? tx0 : lo, hi = tx1 < hi ? tx1 : hi;
    lo = ty0 > lo ? ty0 : lo, hi = ty1 < hi ? ty1 : hi;
    lo = tz0 > lo ? tz0 : lo, hi = tz1 < hi ? tz1 : hi;
    t_near = lo;
    return lo <= hi;
    // END SOLUTION
}

// What the first steps of intersect_triangle() compute, lane by lane: the sheared vertices
// (a, b, c: x, y and the scaled z), the edge functions, det and t_scaled, and `candidates`, the
// lanes that get past the inside test, det != 0 and the range test.
template <class V, class M> struct Sheared {
    V ax, ay, az, bx, by, bz, cx, cy, cz, e0, e1, e2, det, t_scaled;
    M candidates;
};

// The first steps of intersect_triangle() (15_triangle.h) lane by lane: shear, edge functions,
// the inside test, det != 0 and the range test, the same operations in the same order, so a
// lane is a candidate exactly where intersect_triangle() gets past them. Lanes are either four
// triangles and one ray (below: p0, p1, p2 vectors of lanes, o and S doubles), whose candidates
// go on to the rest of the test in intersect_triangle() itself, or one triangle and a packet of
// rays (22_mesh_packets.h: p0, p1, p2 doubles, o and S vectors of lanes), which carries the
// rest of the test over the lanes from these values.
// V and M, the value and mask types, are named by the caller: a student's tree replaces the
// body with a stub, from which no return type could be deduced.
template <class V, class M, class P, class O, class S, class R>
inline Sheared<V, M> sheared_candidates(const P &p0, const P &p1, const P &p2, const O &o,
                                        int kx, int ky, int kz, S Sx, S Sy, S Sz, R min,
                                        R max) {
    // BEGIN SOLUTION L08
    // PROMPT: A copy, lane by lane, of intersect_triangle()'s shear, edge functions and range
    // PROMPT: test, for the four triangles of a block or for a packet of rays.
    auto a_x = p0[kx] - o[kx], a_y = p0[ky] - o[ky], a_z = p0[kz] - o[kz];
    auto b_x = p1[kx] - o[kx], b_y = p1[ky] - o[ky], b_z = p1[kz] - o[kz];
    auto c_x = p2[kx] - o[kx], c_y = p2[ky] - o[ky], c_z = p2[kz] - o[kz];
    auto ax = a_x + Sx * a_z, ay = a_y + Sy * a_z;
    auto bx = b_x + Sx * b_z, by = b_y + Sy * b_z;
    auto cx = c_x + Sx * c_z, cy = c_y + Sy * c_z;
    auto e0 = difference_of_products(bx, cy, by, cx);
    auto e1 = difference_of_products(cx, ay, cy, ax);
    auto e2 = difference_of_products(ax, by, ay, bx);
    auto outside = ((e0 < 0) | (e1 < 0) | (e2 < 0)) & ((e0 > 0) | (e1 > 0) | (e2 > 0));
    auto det = e0 + e1 + e2;
    auto az = Sz * a_z, bz = Sz * b_z, cz = Sz * c_z;
    auto t_scaled = e0 * az + e1 * bz + e2 * cz;
    auto lo = min * det, hi = max * det;
    auto out_negative = (det < 0) & ((t_scaled >= lo) | (t_scaled < hi));
    auto out_positive = (det > 0) & ((t_scaled <= lo) | (t_scaled > hi));
    return {ax, ay, az, bx, by, bz, cx, cy, cz, e0, e1, e2, det, t_scaled,
            ~(outside | (det == 0) | out_negative | out_positive)};
    // END SOLUTION
}

// sheared_candidates() for a block's four triangles and one ray.
inline M4 triangle_candidates(const TriangleBlock &block, const WatertightRay &r,
                              const Interval &range) {
    return sheared_candidates<D4, M4>(block.p[0], block.p[1], block.p[2], r.o, r.kx, r.ky,
                                      r.kz, r.Sx, r.Sy, r.Sz, range.min, range.max)
        .candidates;
}

// -- The eight-wide hierarchy (issue 12) -------------------------------------------------------
// The same collapse with eight children a node (Embree's BVH8; Benthin, Woop, Wald and Afra,
// "Improved Two-Level BVHs using Partial Re-Braiding", use it on AVX-512 too): an incoherent ray
// through the bunny visited 12 four-wide nodes, each one step of fixed cost (the node's set-up,
// its children's order, a return to the scheduler), and was bound by that cost rather than by
// memory (the same rays took as long with every node already in cache). Eight children's boxes
// are one AVX-512 register of 8 doubles per slab plane (slab_test8()), or one AVX register of
// 8 floats (float_slab_test8()); on a machine without AVX-512 the compiler splits each vector
// of doubles in two (AVX2) or four (SSE2), the same arithmetic.
constexpr int bvh8_width = 8;
typedef double D8 __attribute__((vector_size(bvh8_width * sizeof(double))));
typedef float F8 __attribute__((vector_size(bvh8_width * sizeof(float))));
typedef int64_t M8 __attribute__((vector_size(bvh8_width * sizeof(int64_t))));
typedef uint64_t K8 __attribute__((vector_size(bvh8_width * sizeof(uint64_t))));
typedef uint32_t U8 __attribute__((vector_size(bvh8_width * sizeof(uint32_t))));

// A child's code: an inner child's Node8 index (never 0, the root's), or leaf_code | its first
// block. Never 0, so that a search key (below) of a child is never 0.
constexpr uint32_t leaf_code = 0x80000000u;

// Eight children's boxes as WideNode's four (float, rounded outward, empty boxes in unused
// lanes): 192 bytes of planes and 32 of codes, four cache lines. The form the build collapses
// into; the search reads each node quantised (QNode8, below), in half the memory.
struct alignas(64) Node8 {
    F8 planes[2][3];
    uint32_t child[bvh8_width];
};

// Eight floats to eight doubles (exactly), one AVX-512 instruction where there is one (the
// vector extension's conversion became two halves and a merge); four to four, one AVX one.
inline D8 to_double(const F8 &f) {
#if defined(__AVX512F__)
    return bit_cast<D8>(_mm512_maskz_cvtps_pd(0xff, bit_cast<__m256>(f)));
#else
    return __builtin_convertvector(f, D8);
#endif
}
inline D4 to_double(const F4 &f) {
#if defined(__AVX__)
    return bit_cast<D4>(_mm256_cvtps_pd(bit_cast<__m128>(f)));
#else
    return __builtin_convertvector(f, D4);
#endif
}

// Node8 in 8 bits a plane (Mahovsky and Wyvill, "Memory-Conserving Bounding Volume
// Hierarchies with Coherent Raytracing", 2006; Ylitie, Karras and Laine, "Efficient Incoherent
// Ray Traversal on GPUs Through Compressed Wide BVHs", 2017): per axis an origin and a power of
// two, and each child's plane as the whole number q of steps from the origin, read back as
// fma(q, scale, origin) in float (one rounding, the same in the build and in the search, on
// every machine: fma is correctly rounded). The build picks each lower q so that the plane read
// back is at or below the float box's, each upper q at or above it (quantize()): a child's box
// read back contains its float box, which contains the binary hierarchy's double box, so the
// search still misses no box the lecture's search meets; it meets a few more (on the bunny's
// incoherent rays, 2% more nodes and primitive tests).
// Why: an incoherent ray's nodes and leaves are cache misses, and the bunny's eight-wide tree
// (2.5 MB of Node8, 6.2 MB of leaves of four triangles in float, 192 bytes each) did not fit
// the part of this machine's 32 MB shared L3 that its neighbours leave: a chain of dependent
// loads through 4 MB took 26-52 ns a step, through 8 MB 134 ns, through 16 MB 150 ns (issue
// 12). 128 bytes a node instead of 256, and one line a leaf (its corners as places in a copy of
// the vertices) instead of three, took the bunny's tree from 8.7 MB to 4.0 MB and its incoherent
// rays 1.3x-1.8x faster; the leaves now hold their vertices in two lines (IndexBlock), 5.0 MB.
// `valid`: the lanes with a child (bit c: lane c); the others are masked out of the slab test.
struct alignas(64) QNode8 {
    float origin[3], scale[3];
    uint32_t valid;
    uint8_t q[2][3][bvh8_width]; // [lower, upper][axis][child]
    uint32_t child[bvh8_width];  // as Node8::child
};
static_assert(sizeof(QNode8) == 2 * 64, "a quantised node is two cache lines");

// A plane read back from its q (0 to 255), one rounding.
inline float dequantize(int q, float scale, float origin) {
    return std::fma(float(q), scale, origin);
}

// The quantised form of a node whose valid planes are all finite (false, and `out` unusable,
// for a node with an infinite plane, a vertex beyond float's range).
inline bool quantize(const Node8 &node, QNode8 &out) {
    out = QNode8{};
    for (int c = 0; c < bvh8_width; ++c) {
        out.child[c] = node.child[c];
        if (node.planes[0][0][c] <= node.planes[1][0][c]) out.valid |= 1u << c;
    }
    for (int axis = 0; axis < 3; ++axis) {
        float lo = std::numeric_limits<float>::infinity(), hi = -lo;
        for (int c = 0; c < bvh8_width; ++c)
            if (out.valid >> c & 1) {
                lo = std::min(lo, node.planes[0][axis][c]);
                hi = std::max(hi, node.planes[1][axis][c]);
            }
        if (!std::isfinite(lo) || !std::isfinite(hi)) return false;
        // The origin is the lowest plane (read back exactly: fma(0, scale, lo) = lo); the scale
        // the smallest power of two that might reach the highest plane in 255 steps, doubled
        // until every child's upper plane is reached (rounding can cost a step). Finite: the
        // extent is below 2^129, so a scale of 2^121 reaches it.
        const double extent = double(hi) - double(lo);
        float scale = std::numeric_limits<float>::min();
        if (extent > 0)
            scale = std::max(scale, std::ldexp(1.0f, int(std::ceil(std::log2(extent / 255)))));
        for (bool fits = false; !fits; scale *= 2) {
            fits = true;
            for (int c = 0; c < bvh8_width && fits; ++c) {
                if (!(out.valid >> c & 1)) { // inside out besides, should the mask be lost
                    out.q[0][axis][c] = 255, out.q[1][axis][c] = 0;
                    continue;
                }
                const float child_lo = node.planes[0][axis][c];
                const float child_hi = node.planes[1][axis][c];
                const auto steps = [&](double plane) { return (plane - double(lo)) / scale; };
                int q_lo = int(std::clamp(std::floor(steps(child_lo)), 0.0, 255.0));
                while (q_lo > 0 && dequantize(q_lo, scale, lo) > child_lo) --q_lo;
                int q_hi = int(std::clamp(std::ceil(steps(child_hi)), 0.0, 255.0));
                while (q_hi <= 255 && dequantize(q_hi, scale, lo) < child_hi) ++q_hi;
                fits = q_hi <= 255;
                out.q[0][axis][c] = uint8_t(q_lo);
                out.q[1][axis][c] = uint8_t(std::min(q_hi, 255));
            }
            if (fits) out.origin[axis] = lo, out.scale[axis] = scale;
        }
    }
    return true;
}

// Eight children's plane `side` (0: lower, 1: upper) on `axis`, read back and converted to
// double (exactly).
inline D8 node_plane(const QNode8 &node, int side, int axis) {
#if defined(__AVX2__) && defined(__FMA__)
    const __m128i q8 = _mm_loadl_epi64(reinterpret_cast<const __m128i *>(node.q[side][axis]));
    const __m256 q = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(q8));
    const F8 f = bit_cast<F8>(_mm256_fmadd_ps(q, _mm256_set1_ps(node.scale[axis]),
                                              _mm256_set1_ps(node.origin[axis])));
#else
    F8 f;
    for (int c = 0; c < bvh8_width; ++c)
        f[c] = dequantize(node.q[side][axis][c], node.scale[axis], node.origin[axis]);
#endif
    return to_double(f);
}

// The lanes of a node's valid bits as a mask.
inline M8 valid_lanes(const QNode8 &node) {
#if defined(__AVX512DQ__)
    return bit_cast<M8>(_mm512_movm_epi64(__mmask8(node.valid)));
#else
    M8 m;
    for (int c = 0; c < bvh8_width; ++c) m[c] = node.valid >> c & 1 ? -1 : 0;
    return m;
#endif
}

// Up to four triangles of a leaf, for a mesh whose vertices are all floats (a scanned mesh read
// from a PLY file of floats, like the bunny), with their vertices: up to eight of their own, in
// float, axis by axis (x[j], y[j], z[j]: vertex j), and each corner as the number of one of them
// (corner[k][l]: lane l's corner k). Each converts back to the very same double, so the block
// tested in double is TriangleBlock's test bit for bit. Lane l is the triangle `first` + l in
// leaf order (TriangleBlock's leaf[l]); `lanes_more`: the number of triangles (1 to 4) in bits
// 0-2, the leaf's next block follows if bit 3 is set. An empty lane's corners are vertex 0 three
// times: a triangle of no area, never a candidate.
// Why a block carries its vertices: a leaf of neighbouring triangles shares most of them (the
// bunny's leaves of up to four triangles have 4 to 8 vertices, 5 or 6 in most), so its
// vertices and corners fit two cache lines, both asked for from memory with the leaf (prefetch
// in Search8). Until then a block held its corners as places in one float copy of the mesh's
// vertices (one line a block, 16 bytes a vertex, 2.9 MB for the bunny's blocks and copy, 4.1
// MB now): a leaf's test waited on that copy's lines, which it could ask for only once the
// block had come, and the bunny's incoherent rays took 1.13x as long on one Zen 4 thread and
// 1.14x on two (seven and five alternating rounds; the same hits; issue 12).
struct alignas(64) IndexBlock {
    static constexpr int vertices = 8;
    float x[vertices], y[vertices], z[vertices];
    uint8_t corner[3][bvh_width];
    int32_t first;
    uint32_t lanes_more;
};
static_assert(sizeof(IndexBlock) == 2 * 64, "an index block is two cache lines");

// One corner of a block's four triangles, axis by axis, converted to double (exactly): with
// AVX2, each axis's eight vertices permuted into the corner's lanes by one instruction.
struct CornerLanes {
    D4 axis[3];
    CornerLanes(const IndexBlock &block, int k) {
#if defined(__AVX2__)
        int32_t bytes;
        __builtin_memcpy(&bytes, block.corner[k], sizeof(bytes));
        // The lanes' vertex numbers widened to 32 bits; lanes 4-7 (undefined) are not used.
        const __m256i lanes =
            _mm256_castsi128_si256(_mm_cvtepu8_epi32(_mm_cvtsi32_si128(bytes)));
        const float *from[3] = {block.x, block.y, block.z};
        for (int a = 0; a < 3; ++a) {
            const __m256 picked = _mm256_permutevar8x32_ps(_mm256_load_ps(from[a]), lanes);
            axis[a] = to_double(bit_cast<F4>(_mm256_castps256_ps128(picked)));
        }
#else
        for (int l = 0; l < bvh_width; ++l) {
            const int j = block.corner[k][l];
            axis[0][l] = block.x[j], axis[1][l] = block.y[j], axis[2][l] = block.z[j];
        }
#endif
    }
    D4 operator[](int a) const { return axis[a]; }
};

// The triangles of one block tested against one ray, in leaf order, as leaf_hit() tests them:
// the block's candidates (sheared_candidates(), all four lanes at once) re-tested by
// intersect_triangle() itself with the range shrunk by each hit. Counts each real triangle as
// one primitive test. Returns whether one was hit; with `any`, stops at the first. The loop
// runs over the candidates' bits only: a block's triangles (2 to 4) and its candidates (a tenth
// of a candidate a ray, over all its blocks) are counted and picked without a branch per lane,
// which the lanes' mix of outcomes made mispredict (a loop over the lanes that asked each lane
// took a fifth of the Cornell box's time in a flat mesh's search, perf, issue 12).
// `vertex(k, l)`: lane l's corner k; `triangle(l)`: the number lane l's triangle is reported by
// in best_triangle (the mesh's own, or its place in leaf order: see block_hits()).
template <class Vertex, class Triangle>
inline bool candidates_hit(M4 candidates, unsigned real, Vertex vertex, Triangle triangle,
                           const WatertightRay &wr, Interval &range, TriangleHit &best,
                           int &best_triangle, uint64_t &primitive_tests, bool any) {
    const unsigned picked = lane_bits4(candidates);
    primitive_tests += uint64_t(__builtin_popcount(real));
    bool found = false;
    for (unsigned bits = picked & real; bits != 0; bits &= bits - 1) {
        const int l = __builtin_ctz(bits);
        const Vec3 v[3] = {vertex(0, l), vertex(1, l), vertex(2, l)};
        TriangleHit th;
        if (intersect_triangle(v[0], v[1], v[2], wr, range, th)) {
            best = th;
            best_triangle = triangle(l);
            range.max = th.t;
            found = true;
            if (any) return true;
        }
    }
    return found;
}

// best_triangle is the mesh's number of the triangle hit, or with in_leaf_order its place in leaf
// order, mesh.order's index, for a batch to look up once its searches are over (the lookup is a
// miss in the cache for most hits: interleaved_searches()).
inline bool block_hits(const TriangleBlock &block, const Mesh &mesh, const WatertightRay &wr,
                       Interval &range, TriangleHit &best, int &best_triangle,
                       uint64_t &primitive_tests, bool any, bool in_leaf_order = false) {
    unsigned real = 0;
    for (int l = 0; l < bvh_width; ++l) real |= unsigned(block.leaf[l] >= 0) << l;
    return candidates_hit(
        triangle_candidates(block, wr, range), real,
        [&](int k, int l) -> Vec3 {
            return {block.p[k][0][l], block.p[k][1][l], block.p[k][2][l]};
        },
        [&](int l) { return in_leaf_order ? block.leaf[l] : mesh.order[size_t(block.leaf[l])]; },
        wr, range, best, best_triangle, primitive_tests, any);
}

// An IndexBlock's triangles.
inline bool block_hits(const IndexBlock &block, const Mesh &mesh, const WatertightRay &wr,
                       Interval &range, TriangleHit &best, int &best_triangle,
                       uint64_t &primitive_tests, bool any, bool in_leaf_order = false) {
    const CornerLanes p0(block, 0), p1(block, 1), p2(block, 2);
    const M4 candidates = sheared_candidates<D4, M4>(p0, p1, p2, wr.o, wr.kx, wr.ky, wr.kz,
                                                     wr.Sx, wr.Sy, wr.Sz, range.min, range.max)
                              .candidates;
    return candidates_hit(
        candidates, (1u << (block.lanes_more & 7u)) - 1,
        [&](int k, int l) -> Vec3 {
            const int j = block.corner[k][l];
            return {double(block.x[j]), double(block.y[j]), double(block.z[j])};
        },
        [&](int l) {
            return in_leaf_order ? block.first + l : mesh.order[size_t(block.first + l)];
        },
        wr, range, best, best_triangle, primitive_tests, any);
}

// slab_test() (14_box.h) for the eight children of a node: the same operations, lane by lane
// (a name of its own: a lesson's region is named by its file, lesson and function), on the
// planes read back from the quantised node (each exactly a double), lanes without a child
// masked out.
inline M8 slab_test8(const QNode8 &node, const SlabRay &r, const Interval &range, D8 &t_near) {
    // BEGIN SOLUTION L09
    // PROMPT: A copy, lane by lane, of slab_test() for the eight children of a wide node.
    // Only the six planes used are read back (node_plane()).
    D8 tx0 = (node_plane(node, r.near_x, 0) - r.o.x) * r.inv_d.x;
    D8 tx1 = (node_plane(node, 1 - r.near_x, 0) - r.o.x) * r.inv_d_far.x;
    D8 ty0 = (node_plane(node, r.near_y, 1) - r.o.y) * r.inv_d.y;
    D8 ty1 = (node_plane(node, 1 - r.near_y, 1) - r.o.y) * r.inv_d_far.y;
    D8 tz0 = (node_plane(node, r.near_z, 2) - r.o.z) * r.inv_d.z;
    D8 tz1 = (node_plane(node, 1 - r.near_z, 2) - r.o.z) * r.inv_d_far.z;
    // lo from range.min plus 0, which makes a -0 +0: t_near's bits order the children (keys).
    D8 lo = D8{} + range.min, hi = broadcast<D8>(range.max);
    lo = tx0 > lo ? tx0 : lo, hi = tx1 < hi ? tx1 : hi;
    lo = ty0 > lo ? ty0 : lo, hi = ty1 < hi ? ty1 : hi;
    lo = tz0 > lo ? tz0 : lo, hi = tz1 < hi ? tz1 : hi;
    t_near = lo;
    return (lo <= hi) & valid_lanes(node);
    // END SOLUTION
}

// The lanes of a mask as bits (lane k: bit k), of 8 doubles' lanes or 8 floats' (lane_bits4()
// above for four).
typedef int32_t M8F __attribute__((vector_size(bvh8_width * sizeof(int32_t))));
inline unsigned lane_bits8(M8F m) {
#if defined(__AVX__)
    return unsigned(_mm256_movemask_ps(bit_cast<__m256>(m)));
#else
    unsigned b = 0;
    for (int k = 0; k < bvh8_width; ++k) b |= unsigned(m[k] != 0) << k;
    return b;
#endif
}
inline unsigned lane_bits8(M8 m) {
#if defined(__AVX512DQ__)
    return _mm512_movepi64_mask(bit_cast<__m512i>(m));
#else
    unsigned b = 0;
    for (int k = 0; k < bvh8_width; ++k) b |= unsigned(m[k] != 0) << k;
    return b;
#endif
}

// Each lane's t (>= 0, as a slab test's entry is) as the bits of the largest float <= t. For
// non-negative floats the order of their bits is the order of their values, so a search key
// (t's bits above a child's code) orders children by entry distance in one integer compare;
// the float is at most t, so a child skipped for entering beyond a hit (t > range.max) is one
// the double t would skip too.
inline U8 float_bits_down(D8 t) {
#if defined(__AVX512F__)
    return bit_cast<U8>(
        _mm512_maskz_cvt_roundpd_ps(0xff, bit_cast<__m512d>(t),
                                    _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC));
#else
    const F8 f = __builtin_convertvector(t, F8); // to nearest, then one step down where above
    const M8 above = __builtin_convertvector(f, D8) > t;
    return bit_cast<U8>(f) + __builtin_convertvector(above, U8); // true is -1: one ulp down
#endif
}

// -- The eight children's slab test in float (issue 12) ----------------------------------
// slab_test8() converts each plane to double and runs slab_test()'s arithmetic on eight
// doubles: under AVX-512 that is 512-bit work, which Zen 4 does in two halves, and on every
// machine a chain of conversions before the children's order is known. float_slab_test8()
// tests the same boxes in float, a plane's t in one multiply-add from its 8-bit q: the plane
// read back is fma(q, scale, origin) (dequantize()), so t = (plane - o) / d = q A + B, with
// A = scale / d and B = (origin - o) / d two numbers per axis a node (Ylitie, Karras and Laine
// 2017 test their compressed nodes so). It decides exactly what slab_test8() decides (below),
// so the search visits the same nodes; only its keys (entry t in float, rounded down further)
// may order two children of nearly equal entry otherwise, and keep for a leaf on the stack a
// t a little lower (a leaf so kept whose triangle is then hit is one tied with the best hit
// to rounding, as between any two searches). The bunny's incoherent rays 1.075x faster on one
// thread and 1.064x on two (Zen 4, 2M rays, alternating builds, every hit the same).
//
// The bound. Let u = 2^-24 (float's unit roundoff), i = 1/d on one axis rounded to float, P
// the largest |plane| of the tree on that axis (WideBVH::plane_bound) and R = (P + |o|) |i|.
// A = fl(scale i), B = fl(fma(origin, i, c)) and t = fl(fma(q, A, B)) round once each; q
// scale is plane - origin (but for the plane's rounding), at most 2P, and origin i and c = -o i
// are at most R, so A's rounding adds at most 2 u R, B's u R, t's 3 u R, the plane's own
// rounding in dequantize() u R and i's u R: the computed t is within 8 u R of the exact
// (plane - o) / d. The near planes take c lowered by e = 16 u R (plus 2^-120: an underflow's
// error is absolute, below 2^-140 here) and rounded down, the far planes c raised by e and
// rounded up, the range's ends are rounded outward: each near t lies between the exact one
// and 2e below it, each far t between the exact one and 2e above. So the window [lo, hi]
// found contains the exact one, and so the double test's (which is within 2 gamma(3) of the
// exact one, far inside 7 u R): a child the float test misses, the double test misses. A child
// whose window is at least 5 max(e, range's rounding) wide has a non-empty exact window,
// which the double test never misses; the rare child met by a narrower window (a ray grazing
// its box, a box flat on one axis: 1% of the bunny's nodes) is asked of slab_test8().
// That needs every number finite and no float overflow, nor i lost to subnormals: a ray with
// 1/d beyond 2^100 or below 2^-100 on an axis (a zero component: 1/d infinite), or R above
// 2^64, is tested in double only.
constexpr float float_slab_margin = 0x1p-20f; // 16 u

// x rounded to float downward (mode _MM_FROUND_TO_NEG_INF) or upward (_MM_FROUND_TO_POS_INF):
// AVX-512's conversion with its rounding given, else float_down() and float_up().
template <int mode> inline float to_float_rounded(double x) {
#if defined(__AVX512F__)
    return _mm_cvtss_f32(
        _mm_cvt_roundsd_ss(_mm_setzero_ps(), _mm_set_sd(x), mode | _MM_FROUND_NO_EXC));
#else
    static_assert(mode == _MM_FROUND_TO_NEG_INF || mode == _MM_FROUND_TO_POS_INF);
    return mode == _MM_FROUND_TO_NEG_INF ? float_down(x) : float_up(x);
#endif
}

// Eight q (one plane of a node, 8 bits a child) as floats.
inline F8 q_lanes(const uint8_t *q) {
#if defined(__AVX2__)
    const __m128i q8 = _mm_loadl_epi64(reinterpret_cast<const __m128i *>(q));
    return bit_cast<F8>(_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(q8)));
#else
    F8 f;
    for (int c = 0; c < bvh8_width; ++c) f[c] = float(q[c]);
    return f;
#endif
}

// A ray's numbers for float_slab_test8(), per axis: i = 1/d in float, and c = -o i lowered
// (near) and raised (far) by the margin e; where each plane's q lies in QNode8::q (its byte
// offset, near and far side as slab_test() picks them); the range's start rounded down.
// `usable`: false where the bounds above do not hold (the ray is tested in double).
struct FloatSlabRay {
    float inv[3], near_c[3], far_c[3];
    int q_near[3], q_far[3];
    float min_t;   // range.min rounded down, +0 for a -0 (lo starts at it: its bits order keys)
    double margin; // the largest of the three axes' margins e (see above)
    bool usable = true;

    FloatSlabRay(const SlabRay &r, const float plane_bound[3], const Interval &range)
        : min_t(to_float_rounded<_MM_FROUND_TO_NEG_INF>(range.min) + 0.0f), margin(0) {
        const int near[3] = {r.near_x, r.near_y, r.near_z};
        for (int a = 0; a < 3; ++a) {
            const float i = float(r.inv_d[a]);
            const double reach = (double(plane_bound[a]) + std::fabs(r.o[a])) * std::fabs(i);
            // (false for NaN too)
            usable = usable && std::fabs(i) >= 0x1p-100f && std::fabs(i) <= 0x1p100f &&
                     reach <= 0x1p64;
            const double e = double(float_slab_margin) * reach + 0x1p-120;
            margin = std::max(margin, e);
            const double c = -r.o[a] * double(i);
            inv[a] = i;
            near_c[a] = to_float_rounded<_MM_FROUND_TO_NEG_INF>(c - e);
            far_c[a] = to_float_rounded<_MM_FROUND_TO_POS_INF>(c + e);
            constexpr int side = sizeof(QNode8::q[0]), axis = sizeof(QNode8::q[0][0]);
            q_near[a] = near[a] * side + a * axis;
            q_far[a] = (1 - near[a]) * side + a * axis;
        }
    }

    // The width from which a window found is surely not empty in exact arithmetic: the near
    // and far ends each move by at most 2 e, or by the range's rounding to float (2^-23 of it).
    float sure_width(const Interval &range) const {
        double m = std::max(margin, 0x1p-23 * range.min);
        if (std::isfinite(range.max)) m = std::max(m, 0x1p-23 * range.max);
        return to_float_rounded<_MM_FROUND_TO_POS_INF>(5 * m);
    }
};

// The children a ray meets within [min_t, max_t] (bit c for child c; max_t: range.max rounded
// up), each one's entry t (at or before the exact one) as its float's bits in t_near; `unsure`:
// those of them whose window is narrower than sure_width (for slab_test8() to decide).
inline unsigned float_slab_test8(const QNode8 &node, const FloatSlabRay &r, float max_t,
                                 float sure_width, U8 &t_near, unsigned &unsure) {
    F8 lo = broadcast<F8>(r.min_t), hi = broadcast<F8>(max_t);
    const uint8_t *q = &node.q[0][0][0];
    for (int a = 0; a < 3; ++a) {
        const F8 A = broadcast<F8>(node.scale[a] * r.inv[a]);
        const F8 low_b = broadcast<F8>(std::fma(node.origin[a], r.inv[a], r.near_c[a]));
        const F8 high_b = broadcast<F8>(std::fma(node.origin[a], r.inv[a], r.far_c[a]));
        const F8 q0 = q_lanes(q + r.q_near[a]), q1 = q_lanes(q + r.q_far[a]);
        const F8 t0 = fma(q0, A, low_b), t1 = fma(q1, A, high_b);
        lo = t0 > lo ? t0 : lo, hi = t1 < hi ? t1 : hi;
    }
    t_near = bit_cast<U8>(lo); // lo >= min_t >= 0: its bits order as its values
    const unsigned met = lane_bits8(lo <= hi) & node.valid;
    unsure = met & ~lane_bits8(hi - lo >= broadcast<F8>(sure_width));
    return met;
}

// A search key per child (t_near's bits above its code), 0 for a child not in `bits`.
// (Each step zeroes the lanes not in `bits`, by its mask: the unmasked intrinsics of GCC 12 merge
// into an "undefined" register that its -Wmaybe-uninitialized reports as read, GCC bug 105593.)
inline K8 search_keys(const U8 &t_near, const uint32_t child[bvh8_width], unsigned bits) {
#if defined(__AVX512F__)
    const __mmask8 in = __mmask8(bits);
    const __m512i t = _mm512_maskz_cvtepu32_epi64(in, bit_cast<__m256i>(t_near));
    const __m512i code = _mm512_maskz_cvtepu32_epi64(
        in, _mm256_loadu_si256(reinterpret_cast<const __m256i *>(child)));
    return bit_cast<K8>(_mm512_or_si512(_mm512_maskz_slli_epi64(in, t, 32), code));
#else
    K8 keys;
    for (int c = 0; c < bvh8_width; ++c)
        keys[c] = bits >> c & 1 ? uint64_t(t_near[c]) << 32 | child[c] : 0;
    return keys;
#endif
}

// The keys of the lowest and the highest lane of `bits`, which holds n = 1 or 2 lanes (for one,
// its key twice). AVX-512: the lanes met packed to the bottom of the register by one compress
// and taken from there, where Clang 19 had stored all eight keys to the stack to read two back:
// the bunny's incoherent rays 1.012x to 1.017x faster on one Zen 4 thread (four sets of five
// to seven alternating rounds, the same hits). The choice for one child is made by a mask, not
// by `b != 0 ? b : a`, which GCC 12 compiled as a branch, the one Search8::node() had shed
// (GCC's build 1.11x slower); with the mask GCC's build takes the time it took (0.984x to
// 1.001x, three sets).
inline void one_or_two_keys(const K8 &keys, unsigned bits, int n, uint64_t &a, uint64_t &b) {
#if defined(__AVX512F__)
    // (Lanes read from the vector, not by the cast intrinsic to 128 bits: GCC bug 105593 above.)
    const K8 packed =
        bit_cast<K8>(_mm512_maskz_compress_epi64(__mmask8(bits), bit_cast<__m512i>(keys)));
    const uint64_t two = 0 - uint64_t(n - 1); // all ones for two lanes, 0 for one
    a = packed[0];
    b = (packed[1] & two) | (a & ~two);
#else
    (void)n;
    a = keys[__builtin_ctz(bits)], b = keys[31 - __builtin_clz(bits)];
#endif
}

// Search keys in descending order (the farthest child first, keys of 0 last): AVX-512's
// bitonic network (Batcher 1968) of six compare-exchange layers, else an insertion sort.
template <int k, int j> inline K8 bitonic_layer(K8 v) {
    // Lane i's partner is i ^ j; in a block of k lanes that sorts descending (i & k == 0) the
    // lower lane takes the larger key, in one that sorts ascending the smaller.
    // (__builtin_shufflevector: GCC 12 and Clang both have it; GCC's __builtin_shuffle is
    // GCC's alone.)
    M8 larger;
    for (int i = 0; i < 8; ++i) larger[i] = ((i & j) == 0) == ((i & k) == 0) ? -1 : 0;
    const K8 p = __builtin_shufflevector(v, v, 0 ^ j, 1 ^ j, 2 ^ j, 3 ^ j, 4 ^ j, 5 ^ j, 6 ^ j,
                                         7 ^ j);
    const K8 hi = v > p ? v : p, lo = v > p ? p : v;
    return larger ? hi : lo;
}
inline K8 sort_descending(K8 keys) {
#if defined(__AVX512F__)
    keys = bitonic_layer<2, 1>(keys);
    keys = bitonic_layer<4, 2>(keys), keys = bitonic_layer<4, 1>(keys);
    keys = bitonic_layer<8, 4>(keys), keys = bitonic_layer<8, 2>(keys);
    return bitonic_layer<8, 1>(keys);
#else
    for (int i = 1; i < bvh8_width; ++i) {
        const uint64_t x = keys[i];
        int k = i;
        for (; k > 0 && keys[k - 1] < x; --k) keys[k] = keys[k - 1];
        keys[k] = x;
    }
    return keys;
#endif
}

// Memory for the eight-wide tree on 2 MiB pages where the system lends them (Linux's transparent
// huge pages, asked for with madvise): an incoherent ray's nodes and blocks lie on pages all
// over the tree's megabytes, and with 4 KiB pages nearly every one was also a miss in the
// address translation cache, whose page walk the prefetch must wait for.
template <class T> struct HugePageAllocator {
    typedef T value_type;
    static constexpr size_t huge = size_t(2) << 20;
    HugePageAllocator() = default;
    template <class U> HugePageAllocator(const HugePageAllocator<U> &) {}
    T *allocate(size_t n) {
        const size_t bytes = n * sizeof(T);
        if (bytes < huge / 2) return static_cast<T *>(::operator new(bytes, std::align_val_t(64)));
        const size_t rounded = (bytes + huge - 1) / huge * huge;
        void *p = std::aligned_alloc(huge, rounded);
        if (p == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
        madvise(p, rounded, MADV_HUGEPAGE); // a hint: without it, ordinary pages
#endif
        return static_cast<T *>(p);
    }
    void deallocate(T *p, size_t n) {
        if (n * sizeof(T) < huge / 2) ::operator delete(p, std::align_val_t(64));
        else std::free(p);
    }
    template <class U> bool operator==(const HugePageAllocator<U> &) const { return true; }
    template <class U> bool operator!=(const HugePageAllocator<U> &) const { return false; }
};
template <class T> using HugeVector = std::vector<T, HugePageAllocator<T>>;

struct WideBVH : MeshAccelerator {
    std::vector<WideNode> nodes; // nodes[0] is the root
    std::vector<TriangleBlock> blocks;
    // A small mesh (the Cornell box's room of 10 triangles, its light of 2) whose wide tree is
    // one node of leaves: searched by search_flat(), without WideSearch's stack and set-up.
    bool flat = false;

    // The deepest stack: a wide node lies at least one binary level below its parent, so at
    // most max_tree_depth + 1 levels; each visit takes one entry and leaves up to four.
    static constexpr int stack_size = 3 * (Mesh::max_tree_depth + 1) + 2;

    explicit WideBVH(const Mesh &mesh) {
        nodes.reserve(mesh.nodes.size() / 2 + 1);
        blocks.reserve(mesh.order.size() / 2 + 1);
        const BVHNode &root = mesh.nodes[0];
        if (root.count > 0) { // one leaf: a wide root with that one child
            nodes.emplace_back();
            set_child(mesh, 0, 0, 0);
        } else
            collapse(mesh, 0);
        flat = nodes.size() == 1;
        for (int c = 0; c < nodes[0].children; ++c) flat = flat && nodes[0].child[c] < 0;
        if (flat) return;
        // Any other mesh is searched in the eight-wide tree only (Search8), unless a box
        // reaches beyond float's range (a vertex of 1e300): its node cannot be quantised, and
        // the four-wide tree (infinite planes and all) is searched instead.
        if (build8(mesh)) nodes = {}, blocks = {};
    }

    // -- the eight-wide tree (Search8), for every mesh that is not flat --------------------
    HugeVector<QNode8> nodes8;               // nodes8[0] is the root
    HugeVector<TriangleBlock> double_blocks; // its leaves' blocks, for a mesh of doubles
    HugeVector<IndexBlock> index_blocks;     // or for a mesh of floats (float_vertices)
    bool float_vertices = false;
    float plane_bound[3] = {0, 0, 0}; // per axis: no plane read back lies farther from 0
    std::vector<Node8> build_nodes8;         // the tree as collapsed, before quantize()

    // The eight-wide tree; false (and no tree) where a node cannot be quantised.
    bool build8(const Mesh &mesh) {
        float_vertices = true;
        for (const Vec3 &v : mesh.leaf_vertices)
            for (int axis = 0; axis < 3; ++axis)
                float_vertices = float_vertices && double(float(v[axis])) == v[axis];
        build_nodes8.reserve(mesh.nodes.size() / 4 + 1);
        plan_collapse(mesh);
        if (mesh.nodes[0].count > 0) { // one leaf: a root with that one child
            build_nodes8.emplace_back();
            set_child8(mesh, 0, 0, 0);
        } else
            collapse8(mesh, 0);
        nodes8.resize(build_nodes8.size());
        bool quantised = true;
        for (size_t k = 0; k < build_nodes8.size() && quantised; ++k)
            quantised = quantize(build_nodes8[k], nodes8[k]);
        build_nodes8 = {}, plan = {};
        if (!quantised) nodes8 = {}, double_blocks = {}, index_blocks = {};
        for (const QNode8 &node : nodes8)
            for (int axis = 0; axis < 3; ++axis)
                plane_bound[axis] = std::max(
                    {plane_bound[axis], std::fabs(node.origin[axis]),
                     std::fabs(dequantize(255, node.scale[axis], node.origin[axis]))});
        return quantised;
    }

    static void set_box8(Node8 &w, int c, const AABB &box) {
        for (int axis = 0; axis < 3; ++axis) {
            if (c == 0)
                for (int l = 0; l < bvh8_width; ++l)
                    w.planes[0][axis][l] = std::numeric_limits<float>::infinity(),
                    w.planes[1][axis][l] = -std::numeric_limits<float>::infinity();
            w.planes[0][axis][c] = float_down(box.min[axis]);
            w.planes[1][axis][c] = float_up(box.max[axis]);
        }
        if (c == 0)
            for (int l = 0; l < bvh8_width; ++l) w.child[l] = leaf_code; // unused: never hit
    }

    // Which binary nodes become the eight-wide tree's nodes and which its leaves: the choice of
    // least cost by the surface area heuristic (Ylitie, Karras and Laine 2017, by dynamic
    // programming over the binary tree), where a binary subtree of up to four triangles may be
    // one leaf. Opening the child of largest area until a node has eight (wide_children(), as
    // the four-wide tree does) had left 4,243 of the bunny's 9,593 nodes with two children,
    // above two of the binary tree's leaves; the least-cost tree has 6,343 nodes (6.1 children
    // each on average) and the same 32,306 leaves, and an incoherent ray takes 8.05 steps
    // through nodes instead of 8.30: 1.022x on one Zen 4 thread, 1.021x on two (seven and five
    // alternating rounds; the same hits; issue 12). A node and a block cost one each, times its
    // box's area: a node at 0.6 or 1.7 of a block made no difference, and leaves of up to eight
    // triangles (two blocks; 5,469 nodes, 7.93 steps) were 1.01x slower. For binary node n,
    // cost[m - 1] is the least cost of its subtree as at most m children of a wide node, of
    // which `left[m - 1]` in its first child's subtree and `right[m - 1]` in its second's
    // (both 0: the subtree as one child, a leaf if `leaf`).
    struct Collapse {
        double cost[bvh8_width];
        int8_t left[bvh8_width], right[bvh8_width];
        int8_t node_left; // as a node: its children, node_left in its first child's subtree
        bool leaf;
        int first, count; // its triangles in leaf order
    };
    std::vector<Collapse> plan; // per binary node, during build8()

    void plan_collapse(const Mesh &mesh) {
        constexpr double node_cost = 1, block_cost = 1;
        constexpr int max_leaf = bvh_width; // triangles: one block
        constexpr double none = std::numeric_limits<double>::infinity();
        plan.assign(mesh.nodes.size(), Collapse{});
        // Children follow their parent in mesh.nodes: from the last node back, each node's
        // children are planned before it.
        for (size_t i = mesh.nodes.size(); i-- > 0;) {
            const BVHNode &node = mesh.nodes[i];
            Collapse &p = plan[i];
            const double area = node.bounds.area();
            if (node.count > 0) { // a binary leaf: one leaf, however many lanes it may take
                p.first = node.first, p.count = node.count, p.leaf = true;
                const double blocks = (node.count + bvh_width - 1) / bvh_width;
                std::fill(std::begin(p.cost), std::end(p.cost), area * block_cost * blocks);
                continue;
            }
            const Collapse &l = plan[i + 1], &r = plan[size_t(node.first)];
            p.first = l.first, p.count = l.count + r.count; // the two ranges are adjacent
            // split[m]: the least cost of m children at most, some of each side's.
            double split[bvh8_width + 1];
            int8_t split_left[bvh8_width + 1] = {};
            for (int m = 2; m <= bvh8_width; ++m) {
                split[m] = none;
                for (int a = 1; a < m; ++a) {
                    const double c = l.cost[a - 1] + r.cost[m - a - 1];
                    if (c < split[m]) split[m] = c, split_left[m] = int8_t(a);
                }
            }
            p.node_left = split_left[bvh8_width];
            const double as_node = area * node_cost + split[bvh8_width];
            const double as_leaf = p.count <= max_leaf ? area * block_cost : none;
            p.leaf = as_leaf <= as_node;
            p.cost[0] = std::min(as_leaf, as_node);
            for (int m = 2; m <= bvh8_width; ++m) {
                p.cost[m - 1] = p.cost[m - 2];
                p.left[m - 1] = p.left[m - 2], p.right[m - 1] = p.right[m - 2];
                if (split[m] < p.cost[m - 1])
                    p.cost[m - 1] = split[m], p.left[m - 1] = split_left[m],
                               p.right[m - 1] = int8_t(m - split_left[m]);
            }
        }
    }

    // The children that binary node `binary`'s subtree gives a wide node, `most` at most,
    // appended to kids (n of them so far).
    void planned_children(const Mesh &mesh, int binary, int most, int *kids, int &n) const {
        const Collapse &p = plan[size_t(binary)];
        if (p.left[most - 1] == 0) {
            kids[n++] = binary;
            return;
        }
        planned_children(mesh, binary + 1, p.left[most - 1], kids, n);
        planned_children(mesh, mesh.nodes[size_t(binary)].first, p.right[most - 1], kids, n);
    }

    // A wide node in place of the binary inner node `binary`, of the children plan_collapse()
    // chose for it. Returns the wide node's index.
    int collapse8(const Mesh &mesh, int binary) {
        const int index = int(build_nodes8.size());
        build_nodes8.emplace_back();
        int kids[bvh8_width], n = 0;
        const int a = plan[size_t(binary)].node_left;
        planned_children(mesh, binary + 1, a, kids, n);
        planned_children(mesh, mesh.nodes[size_t(binary)].first, bvh8_width - a, kids, n);
        for (int c = 0; c < n; ++c) set_child8(mesh, index, c, kids[c]);
        return index;
    }

    // Lane c of wide node `index`: binary node `binary`'s subtree, a node or a leaf as planned.
    void set_child8(const Mesh &mesh, int index, int c, int binary) {
        const Collapse &p = plan[size_t(binary)];
        set_box8(build_nodes8[size_t(index)], c, mesh.nodes[size_t(binary)].bounds);
        if (!p.leaf) {
            int child = collapse8(mesh, binary);
            build_nodes8[size_t(index)].child[c] = uint32_t(child);
            return;
        }
        const size_t first = float_vertices ? index_blocks.size() : double_blocks.size();
        build_nodes8[size_t(index)].child[c] = leaf_code | uint32_t(first);
        const int end = p.first + p.count;
        if (!float_vertices) {
            for (int f = p.first; f < end; f += bvh_width)
                double_blocks.push_back(make_block(mesh, f, end));
            return;
        }
        for (int f = p.first; f < end;) {
            const IndexBlock block = make_index_block(mesh, f, end);
            f += int(block.lanes_more & 7u);
            index_blocks.push_back(block);
        }
    }

    // The block of leaf-order triangles first, first + 1, ... before `end`: up to four, as
    // many as have no more than IndexBlock::vertices vertices among them (at least one).
    static IndexBlock make_index_block(const Mesh &mesh, int first, int end) {
        IndexBlock block{};
        int vertex[IndexBlock::vertices], vertices = 0, lanes = 0; // mesh vertex of each
        for (; lanes < bvh_width && first + lanes < end; ++lanes) {
            const auto &triangle = mesh.triangles[size_t(mesh.order[size_t(first + lanes)])];
            int corner[3], added = vertices;
            for (int k = 0; k < 3 && added <= IndexBlock::vertices; ++k) {
                corner[k] = 0;
                while (corner[k] < added && vertex[corner[k]] != triangle[size_t(k)]) ++corner[k];
                if (corner[k] == added && added++ < IndexBlock::vertices)
                    vertex[corner[k]] = triangle[size_t(k)];
            }
            if (added > IndexBlock::vertices) break; // this triangle begins the next block
            for (int k = 0; k < 3; ++k) {
                const int j = corner[k];
                block.corner[k][lanes] = uint8_t(j);
                if (j < vertices) continue; // an earlier triangle's vertex, already stored
                const Vec3 &v = mesh.leaf_vertices[3 * size_t(first + lanes) + size_t(k)];
                block.x[j] = float(v[0]), block.y[j] = float(v[1]), block.z[j] = float(v[2]);
            }
            vertices = added;
        }
        block.first = first;
        block.lanes_more = uint32_t(lanes) | (first + lanes < end ? 8u : 0u);
        return block;
    }

    // Lane c of a node's boxes: `box` rounded outward to float (lanes after c: empty boxes).
    static void set_box(WideNode &w, int c, const AABB &box) {
        for (int axis = 0; axis < 3; ++axis) {
            if (c == 0) // lanes without a child keep the empty box
                for (int l = 0; l < bvh_width; ++l)
                    w.planes[0][axis][l] = std::numeric_limits<float>::infinity(),
                    w.planes[1][axis][l] = -std::numeric_limits<float>::infinity();
            w.planes[0][axis][c] = float_down(box.min[axis]);
            w.planes[1][axis][c] = float_up(box.max[axis]);
        }
        w.children = c + 1;
    }

    // The block of leaf-order triangles first, first + 1, ... (up to four, before `end`),
    // padded with the all-zero triangle.
    static TriangleBlock make_block(const Mesh &mesh, int first, int end) {
        TriangleBlock b{};
        for (int l = 0; l < bvh_width; ++l) {
            const int i = first + l;
            b.leaf[l] = i < end ? i : -1;
            for (int v = 0; v < 3; ++v)
                for (int axis = 0; axis < 3; ++axis)
                    b.p[v][axis][l] =
                        b.leaf[l] < 0 ? 0.0 : mesh.leaf_vertices[3 * size_t(i) + v][axis];
        }
        b.more = first + bvh_width < end;
        return b;
    }

    // A flat mesh's answer, WideSearch's for a tree of one node, step by step: the node's four
    // boxes tested at once, the leaves hit taken nearest first (the same order: farthest first
    // into `next`, then from its end), each skipped if a hit has come nearer meanwhile. So the
    // same hits, bit for bit, counted alike. The ray's set-up (slab and watertight) comes from
    // the caller, made once for every mesh the ray meets (CulledQueries in 20_path.h).
    bool search_flat(const Mesh &mesh, const SlabRay &sr, const WatertightRay &wr,
                     Interval range, TriangleHit &best, int &best_triangle, RayCounts &counts,
                     bool any) const {
        const WideNode &node = nodes[0];
        counts.box_tests += uint64_t(node.children);
        D4 t_near;
        const M4 hit = slab_test(node, sr, range, t_near);
        struct Entry {
            int32_t child;
            double t_near;
        } next[bvh_width];
        int n = 0;
        for (int c = 0; c < node.children; ++c) {
            if (!hit[c]) continue;
            Entry x{node.child[c], t_near[c]};
            int k = n++;
            for (; k > 0 && next[k - 1].t_near < x.t_near; --k) next[k] = next[k - 1];
            next[k] = x;
        }
        bool found = false;
        for (int k = n - 1; k >= 0; --k) {
            if (next[k].t_near > range.max) continue;
            for (int b = -1 - next[k].child, more = 1; more; ++b) {
                const TriangleBlock &block = blocks[size_t(b)];
                more = block.more;
                if (block_hits(block, mesh, wr, range, best, best_triangle,
                               counts.primitive_tests, any)) {
                    found = true;
                    if (any) return true;
                }
            }
        }
        return found;
    }

    // The children of a wide node in place of the binary inner node `binary`, written to kids
    // (room for `width`): its two children, then the child of largest surface area among the
    // inner ones opened in place (its two children take its lane and the next), until there
    // are `width` or only leaves. Returns how many. (The eight-wide tree is planned instead:
    // plan_collapse().)
    static int wide_children(const Mesh &mesh, int binary, int width, int *kids) {
        kids[0] = binary + 1, kids[1] = mesh.nodes[size_t(binary)].first;
        int n = 2;
        while (n < width) {
            int open = -1;
            double largest = -1;
            for (int c = 0; c < n; ++c) {
                const BVHNode &k = mesh.nodes[size_t(kids[c])];
                if (k.count == 0 && k.bounds.area() > largest) largest = k.bounds.area(), open = c;
            }
            if (open < 0) break;
            const int opened = kids[open];
            for (int c = n; c > open + 1; --c) kids[c] = kids[c - 1];
            kids[open] = opened + 1;
            kids[open + 1] = mesh.nodes[size_t(opened)].first;
            ++n;
        }
        return n;
    }

    // A wide node in place of the binary inner node `binary`, of wide_children()'s four
    // children. Returns the wide node's index.
    int collapse(const Mesh &mesh, int binary) {
        const int index = int(nodes.size());
        nodes.emplace_back();
        int kids[bvh_width];
        const int n = wide_children(mesh, binary, bvh_width, kids);
        for (int c = 0; c < n; ++c) set_child(mesh, index, c, kids[c]);
        return index;
    }

    void set_child(const Mesh &mesh, int index, int c, int binary) {
        const BVHNode &k = mesh.nodes[size_t(binary)];
        set_box(nodes[size_t(index)], c, k.bounds);
        if (k.count == 0) { // an inner child (collapse() may move `nodes`: index, not reference)
            int child = collapse(mesh, binary);
            nodes[size_t(index)].child[c] = child;
            return;
        }
        nodes[size_t(index)].child[c] = -1 - int(blocks.size());
        for (int first = k.first; first < k.first + k.count; first += bvh_width)
            blocks.push_back(make_block(mesh, first, k.first + k.count));
    }

    // Mesh::traverse()'s answer (see the top of this file), nearest child first.
    bool traverse(const Mesh &mesh, const Ray &ray, Interval range, TriangleHit &best,
                  int &best_triangle, RayCounts &counts, bool any) const override;
};

// Every cache line of an object of `bytes` bytes at `p` asked for at once: a wide node is two
// lines, a triangle block five. Asking for the first line only left the others to be fetched
// when the test reached them, one miss after another; asking for all of them took a third off
// the time of incoherent rays through the bunny (issue 12).
inline void prefetch_lines(const void *p, size_t bytes) {
    const char *c = static_cast<const char *>(p);
    for (size_t k = 0; k < bytes; k += 64) __builtin_prefetch(c + k);
}

// One ray's search of a wide hierarchy, a step (a node or a leaf) at a time, so that a batch
// of rays can take turns (closest_mesh_hits()): while one ray waits for its next node to come
// from memory, the others work.
struct WideSearch {
    static constexpr bool in_leaf_order = false; // what block_hits() reports (see Search8)
    struct Entry {
        int32_t child; // as WideNode::child
        double t_near;
    };
    const WideBVH &bvh;
    const Mesh &mesh;
    const WatertightRay wr;
    const SlabRay sr;
    Interval range;
    const bool any;
    Entry stack[WideBVH::stack_size];
    int top = 0;
    TriangleHit best{};
    int best_triangle = -1;
    bool found = false;
    uint64_t box_tests = 0, primitive_tests = 0;

    WideSearch(const WideBVH &bvh, const Mesh &mesh, const Ray &ray, Interval range, bool any)
        : bvh(bvh), mesh(mesh), wr(ray), sr(ray), range(range), any(any) {
        if (!bvh.nodes.empty()) stack[top++] = {0, range.min};
    }

    // One node or leaf; false when the search is over (found and best say what it found).
    bool step() {
        while (top > 0) {
            const Entry e = stack[--top];
            if (e.t_near > range.max) continue; // a hit has come nearer meanwhile
            if (e.child < 0) return leaf(-1 - e.child);
            node(e.child);
            return top > 0;
        }
        return false;
    }

    bool leaf(int first_block) {
        for (int b = first_block, more = 1; more; ++b) {
            const TriangleBlock &block = bvh.blocks[size_t(b)];
            more = block.more;
            if (block_hits(block, mesh, wr, range, best, best_triangle, primitive_tests, any,
                           in_leaf_order)) {
                found = true;
                if (any) return top = 0, false;
            }
        }
        return top > 0;
    }

    void node(int index) {
        const WideNode &node = bvh.nodes[size_t(index)];
        box_tests += uint64_t(node.children);
        D4 t_near;
        const M4 hit = slab_test(node, sr, range, t_near);
        // The children hit, pushed farthest first so that the nearest is taken next.
        Entry next[bvh_width];
        int n = 0;
        for (int c = 0; c < node.children; ++c) {
            if (!hit[c]) continue;
            Entry x{node.child[c], t_near[c]};
            // Ask memory for every child hit now, so that their cache misses overlap (the
            // search is bound by memory, not arithmetic).
            if (x.child >= 0) prefetch_lines(&bvh.nodes[size_t(x.child)], sizeof(WideNode));
            else prefetch_lines(&bvh.blocks[size_t(-1 - x.child)], sizeof(TriangleBlock));
            int k = n++;
            for (; k > 0 && next[k - 1].t_near < x.t_near; --k) next[k] = next[k - 1];
            next[k] = x;
        }
        for (int k = 0; k < n; ++k) stack[top++] = next[k];
    }
};

// One ray's search of the eight-wide tree, as WideSearch: the children a node's ray meets
// ordered by entry distance (search keys, sort_descending()), the nearest taken next without
// going through the stack, the others pushed farthest first. A step ends only where the next
// node or leaf was asked for from memory just now (a node's nearest child met); the stack's
// entries were asked for when they were pushed, a turn or more before, so a leaf, or a node
// that met no child, goes on to the entry below at once (see step()).
// With by_leaf, best_triangle is the hit's place in leaf order (block_hits()), for a batch to map.
template <class Block, bool by_leaf = false> struct Search8 {
    static constexpr bool in_leaf_order = by_leaf;
    const WideBVH &bvh;
    const Block *blocks;
    const Mesh &mesh;
    // sr before wr, which takes its Sz = 1/d[kz] from sr's 1/d: one division fewer in a ray's
    // set-up, which lies on its first step's path; the bunny's 2M incoherent rays ran 1.017x
    // faster on one Xeon thread, 1.016x on two (build_ab, 7 rounds, the same hits; doing the
    // other five divisions as one 256-bit division made them 1.06x slower; issue 12).
    const SlabRay sr;
    const WatertightRay wr;
    Interval range;
    const bool any;
    const FloatSlabRay fr;
    float max_t = 0, sure_width = 0; // set_range_max(): range.max rounded up to float, and
                                     // float_slab_test8()'s width of a sure window
    uint64_t key_limit = 0; // the largest search key whose entry t is at most max_t (step())
    uint32_t next = 0; // the child to visit next (0: pop one from the stack)
    int top = 0;
    TriangleHit best{};
    int best_triangle = -1;
    bool found = false;
    uint64_t box_tests = 0, primitive_tests = 0;
    // A node leaves up to 7 children on the stack and stores 8 keys: one per level of the
    // binary tree below it at most (a wide node is one level or more below its parent).
    uint64_t stack[(bvh8_width - 1) * (Mesh::max_tree_depth + 1) + bvh8_width];

    Search8(const WideBVH &bvh, const Block *blocks, const Mesh &mesh, const Ray &ray,
            Interval range, bool any)
        : bvh(bvh), blocks(blocks), mesh(mesh), sr(ray), wr(ray, sr.inv_d),
          range(range), any(any), fr(sr, bvh.plane_bound, range) {
        set_range_max();
        stack[top++] = 0; // the root, entered at t >= 0
    }

    // The float test's numbers that follow range.max (at the start, and as hits shrink it).
    void set_range_max() {
        max_t = to_float_rounded<_MM_FROUND_TO_POS_INF>(range.max);
        sure_width = fr.sure_width(range);
        key_limit = uint64_t(bit_cast<uint32_t>(max_t)) << 32 | 0xffffffffu;
    }

    // Every line of the block or node a code names, without a branch on which: a node's
    // children mix the two unpredictably, and the rays taking turns overlap only where
    // their branches are foreseen. The address is chosen by masks, not by `leaf ? a : b`, which
    // GCC 12 compiled as a jump on the code's sign bit for every child asked for (Clang as a
    // conditional move): the bunny's incoherent rays took 1.10x as long (issue 12). A line that
    // only a TriangleBlock has is asked for in a node as a repeat of its first. An IndexBlock
    // is two lines, as a node (a leaf's next block, if it has one, is not asked for: the
    // bunny's leaves of up to four triangles are one block each).
    void prefetch(uint32_t code) const {
        static_assert(sizeof(QNode8) == 2 * 64 &&
                      (sizeof(Block) == 2 * 64 || sizeof(Block) == 5 * 64));
        const uintptr_t leaf = 0 - uintptr_t(code >> 31); // all ones for a leaf, else 0
        static_assert(leaf_code == 1u << 31);
        const uintptr_t index = code & ~leaf_code;
        const uintptr_t nodes = uintptr_t(bvh.nodes8.data());
        // Unsigned differences wrap around, so the sums below are exact modulo 2^64.
        const uintptr_t base = nodes + ((uintptr_t(blocks) - nodes) & leaf);
        const uintptr_t size = sizeof(QNode8) + ((sizeof(Block) - sizeof(QNode8)) & leaf);
        const uintptr_t p = base + index * size;
        auto line = [p](uintptr_t at) { __builtin_prefetch(reinterpret_cast<void *>(p + at)); };
        line(0), line(64);
        if constexpr (sizeof(Block) > 2 * 64)
            for (uintptr_t at = 2 * 64; at < sizeof(Block); at += 64) line(at & leaf);
    }

    // Nodes and leaves up to the next one just asked for from memory; false when the search is
    // over. Going on from a leaf or a node without a child met to the stack's next entry, in
    // place of a turn each, took the bunny's incoherent rays 1.05x less time on 1 thread and
    // 1.03x on 2 (2M rays, issue 12): a turn given back to the batch (interleaved_searches())
    // costs its bookkeeping and a branch on whether the search is over, and the next turn one on
    // whether to pop, neither of which the rays taking turns let the processor foresee.
    bool step() {
        for (;;) {
            uint32_t code = next;
            next = 0;
            if (code == 0) {
                for (;;) {
                    if (top == 0) return false;
                    // An entry whose entry t (its key's float, at or below the exact one) lies
                    // past range.max rounded up to float holds nothing nearer than the hit
                    // found. Compared as the key itself, one integer comparison (non-negative
                    // floats order as their bits), not as a float widened to double against
                    // range.max: the bunny's incoherent rays 1.011x to 1.019x faster on one Zen 4
                    // thread, 1.015x on two, GCC's build 1.011x (alternating rounds). Entries
                    // in (range.max, max_t] are visited now where they were not; every triangle
                    // in them lies beyond range.max, so no answer changes (the same hits).
                    const uint64_t key = stack[--top];
                    if (key <= key_limit) {
                        code = uint32_t(key);
                        break;
                    }
                }
            }
            if (code & leaf_code) {
                if (!leaf(code & ~leaf_code)) return false;
                continue;
            }
            node(code);
            if (next != 0) return true;
        }
    }

    bool leaf(uint32_t first_block) {
        for (uint32_t b = first_block, more = 1; more; ++b) {
            const Block &block = blocks[b];
            if constexpr (std::is_same_v<Block, IndexBlock>)
                more = block.lanes_more >> 3;
            else
                more = uint32_t(block.more);
            if (block_hits(block, mesh, wr, range, best, best_triangle, primitive_tests, any,
                           in_leaf_order)) {
                found = true;
                set_range_max();
                if (any) return top = 0, false;
            }
        }
        return top > 0;
    }

    // slab_test8()'s answer, for the few children float_slab_test8() leaves unsure: out of
    // line, so that the search's loop keeps its registers for the usual case.
    [[gnu::noinline, gnu::cold]] unsigned double_test(const QNode8 &node) const {
        D8 t;
        return lane_bits8(slab_test8(node, sr, range, t));
    }

    // The children met, as slab_test8() decides, in float where the ray allows it
    // (float_slab_test8()), with their entry t's float bits (at or below the entry t).
    unsigned children_met(const QNode8 &node, U8 &t_near) const {
        if (fr.usable) {
            unsigned unsure;
            const unsigned met = float_slab_test8(node, fr, max_t, sure_width, t_near, unsure);
            if (__builtin_expect(unsure == 0, 1)) return met;
            return (met & ~unsure) | (double_test(node) & unsure);
        }
        D8 t;
        const unsigned met = lane_bits8(slab_test8(node, sr, range, t));
        t_near = float_bits_down(t);
        return met;
    }

    void node(uint32_t index) {
        const QNode8 &node = bvh.nodes8[index];
        U8 t_near;
        const unsigned bits = children_met(node, t_near);
        box_tests += bvh8_width; // (lanes without a child count too: the same instruction)
        if (bits == 0) return;
        const int n = __builtin_popcount(bits);
        const K8 keys = search_keys(t_near, node.child, bits);
        // One child or two, by the same instructions: the lowest and highest lanes met (one lane
        // twice for one child), the nearer next, the farther pushed, and the stack's top moved
        // only for two (for one, the entry written is left above the top, unused). One child
        // had had a path of its own, without keys: which of the two a node takes, the rays
        // taking turns do not let the processor foresee (2.7 mispredictions a ray at that branch,
        // cachegrind's model, AVX2 build), and one path for both took the bunny's incoherent
        // rays 1.059x faster on one Zen 4 thread (nine alternating rounds; GCC's build 1.064x,
        // five) and 1.029x on two; the same hits. Three or more: the six layers of the sort.
        if (n <= 2) {
            uint64_t a, b;
            one_or_two_keys(keys, bits, n, a, b);
            const uint64_t far = a > b ? a : b, near = a > b ? b : a;
            prefetch(uint32_t(far)), prefetch(uint32_t(near));
            stack[top] = far;
            top += n - 1;
            next = uint32_t(near);
            return;
        }
        const K8 sorted = sort_descending(keys);
        for (int k = 0; k < n; ++k) prefetch(uint32_t(sorted[k]));
        __builtin_memcpy(&stack[top], &sorted, sizeof(sorted));
        top += n - 1;
        next = uint32_t(sorted[n - 1]);
    }
};

// A search (WideSearch, Search8) run to its end, its counts and answer handed over.
template <class Search>
inline bool finish(Search &search, TriangleHit &best, int &best_triangle, RayCounts &counts) {
    while (search.step()) {
    }
    counts.box_tests += search.box_tests;
    counts.primitive_tests += search.primitive_tests;
    if (!search.found) return false;
    best = search.best, best_triangle = search.best_triangle;
    return true;
}

inline bool WideBVH::traverse(const Mesh &mesh, const Ray &ray, Interval range, TriangleHit &best,
                              int &best_triangle, RayCounts &counts, bool any) const {
    if (nodes8.empty()) {
        WideSearch search(*this, mesh, ray, range, any);
        return finish(search, best, best_triangle, counts);
    }
    if (float_vertices) {
        Search8<IndexBlock> search(*this, index_blocks.data(), mesh, ray, range, any);
        return finish(search, best, best_triangle, counts);
    }
    Search8<TriangleBlock> search(*this, double_blocks.data(), mesh, ray, range, any);
    return finish(search, best, best_triangle, counts);
}

// Rays start to end of a batch (closest_mesh_hits()) searched in_flight at a time, a step each
// in turn, so that each ray's next node, asked for when it was pushed, has come from memory by
// the time its turn comes again. `make` starts a ray's search in a slot.
template <class Search, class Make>
inline void interleaved_searches(const Mesh &mesh, size_t start, size_t end, Make make,
                                 double *t_out, int32_t *object_out, int32_t *triangle_out,
                                 RayCounts &counts) {
    // 12: enough rays taking turns to cover a memory latency. With leaves whose corners lay in
    // a copy of the vertices, 8 rays were 7% slower than 16, 24 and 32 no faster; since the
    // leaves carry their vertices (IndexBlock) a leaf waits on memory no more than a node, and
    // 8, 10 and 12 are alike and 1.012x to 1.019x faster than 16 on one Zen 4 thread, 1.020x
    // on two (24: 0.972x; five to seven alternating rounds; issue 12).
    constexpr int in_flight = 12;
    std::optional<Search> slot[in_flight];
    size_t ray_of[in_flight] = {}, i = start;
    int live = 0;
    auto begin = [&](int k) {
        if (i >= end) return;
        make(slot[k], i);
        ray_of[k] = i++;
        ++live;
    };
    for (int k = 0; k < in_flight; ++k) begin(k);
    auto retire = [&](int k) { // the search in slot k is over: its answer written out
        const Search &done = *slot[k];
        const size_t r = ray_of[k];
        const int t = done.best_triangle;
        t_out[r] = done.found ? done.best.t : infinity;
        triangle_out[r] = done.found ? t : -1; // object_out: below
        counts.box_tests += done.box_tests;
        counts.primitive_tests += done.primitive_tests;
        slot[k].reset();
        --live;
    };
    // A ray that takes the place of one that is over takes its first step (the root, always in
    // the cache) in the same turn: 1.01x to 1.03x on 1 thread, 1.03x to 1.06x on 2 (the bunny's
    // 2M incoherent rays, medians of 4 to 11 alternating rounds, near the machine's noise;
    // issue 12): one turn fewer a ray.
    while (live > 0)
        for (int k = 0; k < in_flight; ++k)
            while (slot[k] && !slot[k]->step()) {
                retire(k);
                begin(k);
            }
    // Each hit's triangle number (for a search in leaf order) and its object, looked up once
    // the searches are over rather than as each hit is found or its search retires:
    // mesh.order[] and mesh.triangle_object[] are misses in the cache for most hits, and a
    // search's store of what it read held back every instruction after it (7% of the time of
    // the bunny's incoherent rays, perf), where here the misses of many rays overlap. The 2M
    // rays 1.046x [1.010-1.052] faster on one Xeon thread, 1.033x on two (build_ab, 7 rounds,
    // the same hits; the object alone 1.020x; issue 12).
    for (size_t r = start; r < end; ++r) {
        const int32_t found = triangle_out[r];
        if (found < 0) {
            object_out[r] = -1;
            continue;
        }
        const int32_t t = Search::in_leaf_order ? mesh.order[size_t(found)] : found;
        triangle_out[r] = t;
        object_out[r] = mesh.object_of(t);
    }
}

// The wide hierarchy of a mesh built with Acceleration::bvh (none for the other kinds, which
// exist to count what a hierarchy saves and keep the lecture's search).
inline void build_accelerator(Mesh &mesh) {
    mesh.accelerator.reset();
    if (mesh.acceleration == Acceleration::bvh && !mesh.nodes.empty() && !mesh.order.empty())
        mesh.accelerator = std::make_shared<const WideBVH>(mesh);
}

// render_with_stats(packets=...) for every mesh of the scene, set before a render starts (never
// during one). The scene holds its objects as const so that tracing cannot change them; every
// mesh in it was made non-const by the bindings' add_mesh, so the cast is well defined.
inline void set_mesh_packets(const Scene &scene, bool packets) {
    for (const auto &object : scene.objects)
        if (const auto *mesh = dynamic_cast<const Mesh *>(object.get()))
            const_cast<Mesh *>(mesh)->packets = packets;
}

// The closest hit of each of n rays (origins and directions: n x 3 doubles, row-major) with the
// scene's meshes (spheres, planes and other objects are not searched), t in (0, infinity), with
// `threads` threads taking chunks of rays in turn: t (infinity on a miss), the object (-1) and
// the triangle's index in its mesh (-1). What `rtlab bench geometry` times against Embree.
inline void closest_mesh_hits(const Scene &scene, const double *origins,
                              const double *directions, size_t n, int threads, double *t_out,
                              int32_t *object_out, int32_t *triangle_out) {
    std::vector<const Mesh *> meshes;
    for (const auto &object : scene.objects)
        if (const auto *mesh = dynamic_cast<const Mesh *>(object.get())) meshes.push_back(mesh);
    constexpr size_t chunk = 4096; // rays per turn: one atomic increment per 4096 rays
    std::atomic<size_t> next{0};
    // One mesh with a wide hierarchy: in_flight rays take turns, a step each (Search8, or
    // WideSearch for a flat mesh), so that each ray's next node, asked for when it was pushed,
    // has come from memory by the time its turn comes again. Incoherent rays wait on memory: 12
    // wide nodes and 8 triangles a ray on the bunny took 1.2 us, a main-memory latency for each;
    // one ray at a time through the eight-wide tree was still 1.6x slower than 16 taking turns.
    // Each search is the one traverse() makes, so the answers are the same.
    const WideBVH *wide =
        meshes.size() == 1 && meshes[0]->packets
            ? dynamic_cast<const WideBVH *>(meshes[0]->accelerator.get())
            : nullptr;
    auto ray_at = [&](size_t i) {
        const double *o = origins + 3 * i, *d = directions + 3 * i;
        // The rays 64 on, asked for now: the batch's 48 bytes a ray come from main memory,
        // and a ray's set-up waited for them (1.02x).
        if (i + 64 < n) __builtin_prefetch(o + 3 * 64), __builtin_prefetch(d + 3 * 64);
        return Ray{{o[0], o[1], o[2]}, {d[0], d[1], d[2]}};
    };
    auto interleaved = [&](size_t start, size_t end, RayCounts &counts) {
        const Mesh &mesh = *meshes[0];
        const Interval all{0, infinity};
        if (wide->nodes8.empty()) {
            interleaved_searches<WideSearch>(
                mesh, start, end,
                [&](std::optional<WideSearch> &s, size_t i) {
                    s.emplace(*wide, mesh, ray_at(i), all, false);
                },
                t_out, object_out, triangle_out, counts);
        } else if (wide->float_vertices) {
            interleaved_searches<Search8<IndexBlock, true>>(
                mesh, start, end,
                [&](std::optional<Search8<IndexBlock, true>> &s, size_t i) {
                    s.emplace(*wide, wide->index_blocks.data(), mesh, ray_at(i), all, false);
                },
                t_out, object_out, triangle_out, counts);
        } else {
            interleaved_searches<Search8<TriangleBlock, true>>(
                mesh, start, end,
                [&](std::optional<Search8<TriangleBlock, true>> &s, size_t i) {
                    s.emplace(*wide, wide->double_blocks.data(), mesh, ray_at(i), all, false);
                },
                t_out, object_out, triangle_out, counts);
        }
    };
    auto work = [&] {
        RayCounts counts;
        for (size_t start; (start = next.fetch_add(chunk)) < n;) {
            if (wide != nullptr) {
                interleaved(start, std::min(n, start + chunk), counts);
                continue;
            }
            for (size_t i = start; i < std::min(n, start + chunk); ++i) {
                const Ray ray = ray_at(i);
                Interval range{0, infinity};
                int object = -1, triangle = -1;
                for (const Mesh *mesh : meshes) {
                    TriangleHit th;
                    int t = -1;
                    if (mesh->search(ray, range, th, t, counts, false)) {
                        range.max = th.t, triangle = t;
                        object = mesh->object_of(t);
                    }
                }
                t_out[i] = object >= 0 ? range.max : infinity;
                object_out[i] = object;
                triangle_out[i] = triangle;
            }
        }
    };
    threads = std::max(1, threads);
    std::vector<std::thread> pool;
    for (int k = 1; k < threads; ++k) pool.emplace_back(work);
    work();
    for (std::thread &t : pool) t.join();
}

} // namespace rt
