// Slide "How ray tracing works": for each pixel, shoot a ray from the pixel and find its colour;
// "calculate array of pixel values width x height" (slide "Implementation Notes").
//
// Pixels are rendered in tiles by a pool of threads. Each sample's random numbers come from its
// own stream, seeded from (scene seed, pixel, sample) by pixel_rng(), never from a per-thread
// stream, so the image is the same whatever the number of threads and whichever thread takes a
// tile.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

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

// The image-plane points (in pixel units) where pixel (i, j) is sampled, in order, each with
// its sample's random stream (pixel_rng()): the pixel's centre for spp = 1; otherwise spp
// samples in a rows x cols grid of strata (rows the largest divisor of spp not above its square
// root), one jittered sample in each: stratified sampling (Suffern ch. 5). Their average is the
// box-filtered pixel. The jitter takes a sample's first two numbers; a path tracer goes on
// drawing from the same stream.
template <class Sample> inline void for_each_sample(const Scene &scene, int i, int j, Sample f) {
    const int spp = scene.settings.spp;
    const uint64_t pixel = uint64_t(j) * uint64_t(scene.camera.width) + uint64_t(i);
    if (spp == 1) {
        Rng rng = pixel_rng(scene.settings.seed, pixel, 0);
        f(i + 0.5, j + 0.5, rng);
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
// pixels) that taking the next tile, one atomic increment, costs nothing beside tracing it; a
// tile's rows hold whole packets (16 = 2 x 8 rays).
constexpr int tile_size = 16;

// A small image, where tiles of 16 x 16 would give each thread fewer than tiles_per_thread, is
// cut finer, into tiles of 8 x 8 (a packet per row still): tiles differ in cost (a tile of sky against one of
// mirrors), and with few of them per thread one thread is left tracing the last while the
// others wait. A 64 x 64 image had 16 tiles of 16 x 16 for 2 threads (issue 12); it gets 64.
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
        RayCounts c;
        for (int t; !cancel.load(std::memory_order_relaxed) && (t = next_tile++) < total;) {
            int x0 = (t % tiles_x) * tile, y0 = (t / tiles_x) * tile;
            render_tile(scene, x0, y0, std::min(x0 + tile, width), std::min(y0 + tile, height),
                        out, c);
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
