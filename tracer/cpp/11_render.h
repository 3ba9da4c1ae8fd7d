// Slide "How ray tracing works": for each pixel, shoot a ray from the pixel and find its colour;
// "calculate array of pixel values width x height" (slide "Implementation Notes").
//
// Pixels are rendered in tiles by a pool of threads. Each sample's random numbers come from its
// own stream, seeded from (scene seed, pixel, sample) by pixel_rng(), never from a per-thread
// stream, so the image is the same whatever the number of threads and whichever thread takes a
// tile.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#if defined(__GFNI__)
#include <immintrin.h>
#endif

#include "01_vec3.h"
#include "04_hit.h"
#include "09_scene.h"
#include "10_classic.h"

namespace rt {

// SplitMix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number generators", 2014): the
// state advances by the odd constant 2^64 / golden ratio, and next() passes it through a
// mixing function (two xor-shift-multiply rounds, the constants of Stafford's "Mix13") whose
// output looks random even for consecutive states. (The constants are the generator's own.)
struct Rng {
    uint64_t state;
    explicit Rng(uint64_t seed) : state(seed) {}
    uint64_t next() {
        uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    // The top 53 bits as a double in [0, 1): every value is a multiple of 2^-53, exactly.
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    // Two numbers for one two-dimensional choice (a point on a light, a direction): here the
    // next two of the stream; a SobolStream stratifies them as a pair.
    std::pair<double, double> uniform2() {
        double u1 = uniform();
        return {u1, uniform()};
    }
};

// The random stream of sample `sample` of pixel `pixel` (row-major index j * width + i): the
// one place where a stream is seeded from the scene seed. Each number is hashed into the state
// in turn by the generator's own mixing (a generator seeded with x gives next() = mix(x +
// constant)), so streams of neighbouring pixels and samples, and of seeds 0, 1, 2, ..., start
// from unrelated 64-bit states; two streams overlap only if their states land within a few
// hundred steps of each other on a cycle of 2^64.
inline Rng pixel_rng(uint64_t seed, uint64_t pixel, uint64_t sample) {
    return Rng(Rng(Rng(seed).next() ^ pixel).next() ^ sample);
}

// --- Sobol's (0,2)-sequence, Owen-scrambled: the sampler "sobol" ---
//
// Jittered strata put one sample in each cell of one grid. The first 2^m points of the first
// two dimensions of Sobol's sequence (Sobol 1967) are a (0,m,2)-net in base 2: every box of
// the unit square 2^-a wide and 2^-b high (a + b = m) that starts at a multiple of its size
// holds exactly one point, for all m + 1 shapes at once, from 1 x 2^m columns to 2^m x 1 rows.
// A pixel cut by an edge is where stratification matters (the Cornell box's light: three
// quarters of the squared error at 128 spp); with strata, every stratum the edge crosses adds
// a coin toss, with the net an edge along either axis crosses only one of 2^m thin columns or
// rows, and a slanted one is no worse off than with a square grid.

// Dimension 0 is van der Corput's sequence: the bits of k, mirrored about the binary point.
// Where the machine has GFNI (Galois field instructions: AMD Zen 4, Intel Ice Lake and later),
// one affine transform over GF(2) mirrors each byte (the matrix with ones on the antidiagonal,
// 0x8040201008040201) and a byte swap mirrors their order: three instructions for the five
// swap steps below, which the "sobol" sampler takes three or four times a number (perf, issue
// 12). Both give the same bits (tests/tracer/test_sampling.py's nets, and the renders).
inline uint32_t sobol_0(uint32_t k) {
#if defined(__GFNI__)
    const __m128i bytes = _mm_gf2p8affine_epi64_epi8(_mm_cvtsi32_si128(int(k)),
                                                     _mm_set1_epi64x(0x8040201008040201), 0);
    return __builtin_bswap32(uint32_t(_mm_cvtsi128_si32(bytes)));
#else
    k = (k << 16) | (k >> 16);
    k = ((k & 0x00ff00ffu) << 8) | ((k & 0xff00ff00u) >> 8);
    k = ((k & 0x0f0f0f0fu) << 4) | ((k & 0xf0f0f0f0u) >> 4);
    k = ((k & 0x33333333u) << 2) | ((k & 0xccccccccu) >> 2);
    return ((k & 0x55555555u) << 1) | ((k & 0xaaaaaaaau) >> 1);
#endif
}

// Dimension 1: bit b of k adds (xor) the direction number v_b, of the primitive polynomial
// x + 1, whose recurrence is v_b = v_(b-1) xor (v_(b-1) >> 1) from v_0 = 1/2 (Joe and Kuo's
// table, dimension 2): Pascal's triangle mod 2 as the generator matrix. Computed mirrored
// (v_0 = 1, each next v_(b-1) xor (v_(b-1) << 1): bit i of v_b is C(b, i) mod 2), as
// SobolStream scrambles it, and mirrored back by sobol_0() for the pixel. By Lucas' theorem
// C(b, i) is odd exactly where the bits of i are among the bits of b, so bit i of the sum is
// the xor of k's bits b over every b that holds i's bits: a sum over supersets, one step per
// bit of the bit position (i without bit s takes bit i + 2^s), five steps without a branch
// where adding the v_b one set bit of k at a time took a loop of up to 32 turns.
inline uint32_t sobol_1_mirrored(uint32_t k) {
    k ^= (k >> 1) & 0x55555555u;
    k ^= (k >> 2) & 0x33333333u;
    k ^= (k >> 4) & 0x0f0f0f0fu;
    k ^= (k >> 8) & 0x00ff00ffu;
    k ^= (k >> 16) & 0x0000ffffu;
    return k;
}
inline uint32_t sobol_1(uint32_t k) { return sobol_0(sobol_1_mirrored(k)); }

// Owen's nested uniform scrambling (Owen, "Randomly permuted (t,m,s)-nets and (t,s)-sequences",
// 1995) of the top `bits` bits of x: bit d (from the top) is flipped by a coin tossed for the
// d bits above it, so numbers that agree on those bits, one cell of width 2^-d, are flipped
// alike: cells are swapped whole at every scale and every net property survives, while each
// point becomes uniform. `key`: the scramble (a pixel's and dimension's). The coins are
// independent of each other (each is hashed from x's own prefix), so they are tossed at once.
inline uint32_t owen_bits(uint32_t x, uint64_t key, int bits) {
    uint32_t flips = 0;
    for (int d = 0; d < bits; ++d) {
        uint64_t prefix = d == 0 ? 0 : x >> (32 - d); // the d bits above bit d
        flips |= uint32_t(Rng(key ^ (uint64_t(d) << 32 | prefix)).next() >> 63) << (31 - d);
    }
    return x ^ flips;
}

// x scrambled as a number in [0, 1): its top `bits` bits (2^bits >= the points, which they
// tell apart) by owen_bits(); below them each point's digits are its own independent coin
// tosses, the rest of a 53-bit double drawn from its whole prefix.
inline double owen_scrambled(uint32_t x, uint64_t key, int bits) {
    uint32_t top = owen_bits(x, key, bits) >> (32 - bits);
    // A 53-bit integer, so the double is exact and below 1 (top + a uniform double could
    // round up to 2^bits).
    uint64_t below = Rng(key ^ (uint64_t(bits) << 32 | (x >> (32 - bits)))).next() >> (11 + bits);
    return double(uint64_t(top) << (53 - bits) | below) * 0x1.0p-53;
}

// A nested scramble at the cost of a hash: Laine and Karras ("Stratified sampling for
// stochastic transparency", 2011) observed that on the bits of x mirrored (sobol_0() mirrors),
// multiplying by an odd number, adding, and x ^= x * (an even number) each change a bit only by
// the bits below it, which are the bits above it in x: whatever such a chain does, it is a
// nested scramble (owen_bits()'s structure, though not all of Owen's random choices). The
// chain and its constants are Burley's ("Practical Hash-based Owen Scrambling", JCGT 9(4),
// 2020), chosen by him to pass tests of Owen scrambling's statistics. `seed`: the scramble.
inline uint32_t fast_owen_mirrored(uint32_t v, uint32_t seed) {
    v ^= v * 0x3d20adeau;
    v += seed;
    v *= (seed >> 16) | 1u;
    v ^= v * 0x05526c56u;
    v ^= v * 0x53a22864u;
    return v;
}

// A sample's random numbers with the sampler "sobol": its first `sobol_draws` numbers are, one
// dimension each (uniform()) or two (uniform2()), stratified across the pixel's spp samples as
// the image-plane point is: padded Sobol (as pbrt-v4's PaddedSobolSampler): each dimension (or
// pair) takes the (0,2)-sequence's first dimension (or two) at the sample's index permuted for
// this pixel and dimension, so that no two dimensions are the same sequence, and scrambles it
// (fast_owen_mirrored(): these are many numbers a sample, the image-plane point two). Six
// numbers are a path vertex's (20_path.h trace_path(): which light, where on it (a pair),
// which lobe, which direction (a pair)): the first two vertices, where most of the light is
// gathered, are stratified; the rest come from the sample's stream, as with the strata. Each
// number is uniform and independent of the sample's others, as a stream's: the estimate is
// unbiased. A number is a multiple of 2^-32 (a stream's, of 2^-53): finer than any light or
// lobe needs.
struct SobolStream : Rng {
    static constexpr int sobol_draws = 12;
    // Per dimension a 64-bit key, the same for every sample of the pixel, drawn once for it
    // (make_keys()): its low half seeds the index's permutation, its high half the scramble
    // (a pair's second dimension is scrambled by the next key's low half).
    using Keys = std::array<uint64_t, sobol_draws>;
    const Keys *keys;
    uint32_t k_mirrored; // the sample's index in the pixel, its `bits` bits mirrored
    int bits;            // 2^bits >= spp
    int dim = 0;         // the draws so far

    SobolStream(Rng stream, const Keys &pixel_keys, uint32_t index, int b)
        : Rng(stream), keys(&pixel_keys), k_mirrored(sobol_0(index << (32 - b))), bits(b) {}

    static Keys make_keys(Rng &pixel_stream) {
        Keys out;
        for (uint64_t &key : out) key = pixel_stream.next();
        return out;
    }
    // The sample's index permuted for one dimension: a nested scramble of its `bits` bits, the
    // highest first (fast_owen_mirrored() of them mirrored), is a permutation of 0 .. 2^bits
    // - 1. (Scrambling the index unmirrored, lowest bit first, keeps which half of the indices
    // a sample is in, and with it the coarse strata of dimension 0: the pairs' strata stay
    // correlated, and the error was 20% higher.)
    uint32_t index(uint32_t seed) const {
        return sobol_0(fast_owen_mirrored(k_mirrored, seed)) >> (32 - bits);
    }
    static double unit(uint32_t mirrored) { return sobol_0(mirrored) * 0x1.0p-32; }
    double uniform() {
        if (dim >= sobol_draws) return Rng::uniform();
        uint64_t key = (*keys)[size_t(dim++)];
        // Dimension 0 mirrored is the index itself: scramble it, then mirror it.
        return unit(fast_owen_mirrored(index(uint32_t(key)), uint32_t(key >> 32)));
    }
    std::pair<double, double> uniform2() {
        if (dim + 2 > sobol_draws) return Rng::uniform2();
        uint64_t a = (*keys)[size_t(dim)], b = (*keys)[size_t(dim + 1)];
        dim += 2;
        uint32_t i = index(uint32_t(a));
        return {unit(fast_owen_mirrored(i, uint32_t(a >> 32))),
                unit(fast_owen_mirrored(sobol_1_mirrored(i), uint32_t(b)))};
    }
};

// The image-plane points (in pixel units) where pixel (i, j) is sampled, in order, each with
// its sample's random stream (pixel_rng()): the pixel's centre for spp = 1; otherwise, with
// Sampler::stratified, spp samples in a rows x cols grid of strata (rows the largest divisor
// of spp not above its square root), one jittered sample in each: stratified sampling
// (Suffern ch. 5), the jitter taking a sample's first two numbers; with Sampler::sobol, the
// first spp points of the (0,2)-sequence, scrambled for this pixel (its keys drawn from the
// pixel's stream for the sample index 2^64 - 1, which no sample has). Their average is the
// box-filtered pixel; a path tracer goes on drawing from the sample's stream.
template <class Sample> inline void for_each_sample(const Scene &scene, int i, int j, Sample f) {
    const int spp = scene.settings.spp;
    const uint64_t pixel = uint64_t(j) * uint64_t(scene.camera.width) + uint64_t(i);
    if (spp == 1) {
        Rng rng = pixel_rng(scene.settings.seed, pixel, 0);
        f(i + 0.5, j + 0.5, rng);
        return;
    }
    if (scene.settings.sampler == Sampler::sobol) {
        Rng keys = pixel_rng(scene.settings.seed, pixel, ~uint64_t(0));
        const uint64_t key_x = keys.next(), key_y = keys.next();
        const SobolStream::Keys path_keys = SobolStream::make_keys(keys);
        int bits = 0; // the smallest m with 2^m >= spp
        while ((int64_t(1) << bits) < spp) ++bits;
        for (int k = 0; k < spp; ++k) {
            SobolStream rng(pixel_rng(scene.settings.seed, pixel, uint64_t(k)), path_keys,
                            uint32_t(k), bits);
            double sx = i + owen_scrambled(sobol_0(uint32_t(k)), key_x, bits);
            double sy = j + owen_scrambled(sobol_1(uint32_t(k)), key_y, bits);
            f(sx, sy, rng);
        }
        return;
    }
    int rows = 1;
    for (int r = 1; r * r <= spp; ++r)
        if (spp % r == 0) rows = r;
    int cols = spp / rows;
    for (int k = 0; k < spp; ++k) {
        Rng rng = pixel_rng(scene.settings.seed, pixel, uint64_t(k));
        double sx = i + (k % cols + rng.uniform()) / cols;
        double sy = j + (k / cols + rng.uniform()) / rows;
        f(sx, sy, rng);
    }
}

// One pixel, one primary ray per sample, each traced on its own.
inline Color render_pixel(const Scene &scene, int i, int j, RayCounts &counts) {
    Color sum{0, 0, 0};
    for_each_sample(scene, i, j, [&](double sx, double sy, Rng &) {
        ++counts.primary;
        sum += trace(scene, scene.camera.primary_ray(sx, sy), counts);
    });
    return scene.settings.spp == 1 ? sum : sum * (1.0 / scene.settings.spp);
}

inline void store_pixel(float *out, int width, int i, int j, const Color &color) {
    float *px = out + (size_t(j) * width + i) * 3;
    px[0] = float(color.r);
    px[1] = float(color.g);
    px[2] = float(color.b);
}

// A tile of pixels [x0, x1) x [y0, y1), one ray at a time (12_packet.h traces a packet at a
// time).
inline void render_tile_rays(const Scene &scene, int x0, int y0, int x1, int y1, float *out,
                             RayCounts &counts) {
    for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i)
            store_pixel(out, scene.camera.width, i, j, render_pixel(scene, i, j, counts));
}

using TileRenderer =
    std::function<void(const Scene &, int, int, int, int, float *, RayCounts &)>;

struct RenderResult {
    RayCounts counts;
    bool cancelled = false;
};

// Tiles of 16 x 16 pixels: small enough that a cancelled render stops soon, large enough (256
// pixels) that a tile's set-up costs nothing beside tracing it; a tile's rows hold whole packets
// (16 = 2 x 8 rays).
constexpr int tile_size = 16;

// A small image, where tiles of 16 x 16 would give each thread fewer than tiles_per_thread, is
// cut finer, into tiles of 8 x 8 (a packet per row still): tiles differ in cost (a tile of sky
// against one of mirrors), and with few of them per thread one thread is left tracing the last
// while the others wait. A 64 x 64 image had 16 tiles of 16 x 16 for 2 threads (issue 12); it
// gets 64.
constexpr int tiles_per_thread = 16;
inline int tile_side(int width, int height, int threads) {
    auto tiles = [&](int side) {
        return int64_t((width + side - 1) / side) * ((height + side - 1) / side);
    };
    return tiles(tile_size) >= int64_t(tiles_per_thread) * threads ? tile_size : tile_size / 2;
}

// Every 100 ms the watching thread reports progress and checks for Ctrl-C: ten times a second
// is smooth for a progress bar and quick for an interrupt, and rare enough to cost nothing.
constexpr std::chrono::milliseconds default_poll_interval{100};

// Render into out (height x width x 3 floats, row 0 at the top) with `threads` workers. The
// calling thread only watches: every `poll_interval` it calls poll(tiles_done, tiles_total);
// when poll returns false the workers stop after their current tile.
inline RenderResult render(const Scene &scene, int threads, float *out,
                           const std::function<bool(int, int)> &poll,
                           const TileRenderer &render_tile = render_tile_rays,
                           std::chrono::milliseconds poll_interval = default_poll_interval) {
    const int width = scene.camera.width, height = scene.camera.height;
    const int tile = tile_side(width, height, threads);
    const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
    const int total = tiles_x * tiles_y;
    threads = std::max(1, std::min(threads, total));

    std::atomic<int> next_tile{0}, tiles_done{0};
    std::atomic<bool> cancel{false};
    std::mutex mutex;
    std::condition_variable finished;
    int workers_left = threads;
    RenderResult result;

    auto worker = [&]() {
        // Each worker counts on its own stack and adds its counts to the total once, at the
        // end. Counters side by side in one shared array would put both threads' counts in one
        // cache line, which the cores would pass back and forth on every increment (false
        // sharing: issue 12 measured 1.5x from a second thread where Embree gains 2.0x).
        // Tiles are taken a run at a time, consecutive tiles of a row (guided scheduling, as
        // OpenMP's): each run an eighth of the tiles left per thread, so runs shrink to one tile
        // as the image nears its end and the threads finish together. Taking one tile at a
        // time, the two threads took turns along each row and each thread's tiles cost 5% to 8%
        // more CPU time than one thread's did on Ex 25 and the bunny's primary rays (two 1-thread
        // renders side by side in one process lost nothing): the gain from the second thread
        // was 1.79x-1.90x, with runs 1.89x-1.99x (process CPU time against wall time, issue 12).
        // The next run, tiles [first, end); false when none is left.
        auto take_run = [&](int &first, int &end) {
            first = next_tile.load(std::memory_order_relaxed);
            do {
                if (first >= total) return false;
                end = first + std::max(1, (total - first) / (8 * threads));
            } while (!next_tile.compare_exchange_weak(first, end));
            return true;
        };
        auto cancelled = [&] { return cancel.load(std::memory_order_relaxed); };
        RayCounts c;
        for (int first, end; !cancelled() && take_run(first, end);)
            for (int t = first; t < end && !cancelled(); ++t) {
                int x0 = (t % tiles_x) * tile, y0 = (t / tiles_x) * tile;
                render_tile(scene, x0, y0, std::min(x0 + tile, width),
                            std::min(y0 + tile, height), out, c);
                ++tiles_done;
            }
        std::lock_guard<std::mutex> lock(mutex);
        result.counts += c;
        if (--workers_left == 0) finished.notify_all();
    };

    std::vector<std::thread> pool;
    for (int id = 0; id < threads; ++id) pool.emplace_back(worker);
    {
        std::unique_lock<std::mutex> lock(mutex);
        while (!finished.wait_for(lock, poll_interval, [&] { return workers_left == 0; })) {
            lock.unlock();
            if (poll && !poll(tiles_done.load(), total)) cancel = true;
            lock.lock();
        }
    }
    for (std::thread &t : pool) t.join();

    result.cancelled = cancel.load();
    return result;
}

} // namespace rt
