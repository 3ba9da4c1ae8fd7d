// Slide "How ray tracing works": for each pixel, shoot a ray from the pixel and find its colour;
// "calculate array of pixel values width x height" (slide "Implementation Notes").
//
// Pixels are rendered in tiles by a pool of threads. Each pixel's random numbers come from its
// own seed (scene seed, pixel index), never from a per-thread stream, so the image is the same
// whatever the number of threads and whichever thread takes a tile.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "10_classic.h"

namespace rt {

// SplitMix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number generators", 2014):
// a tiny generator whose consecutive states are well mixed, so seeding it with a pixel index
// gives independent-looking streams for neighbouring pixels.
struct Rng {
    uint64_t state;
    explicit Rng(uint64_t seed) : state(seed) {}
    uint64_t next() {
        uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; } // in [0, 1)
};

// The image-plane points (in pixel units) where pixel (i, j) is sampled, in order: its centre
// for spp = 1; otherwise spp samples in a rows x cols grid of strata (rows the largest divisor
// of spp not above its square root), one jittered sample in each: stratified sampling
// (Suffern ch. 5). Their average is the box-filtered pixel.
template <class Sample> inline void for_each_sample(const Scene &scene, int i, int j, Sample f) {
    int spp = scene.settings.spp;
    if (spp == 1) {
        f(i + 0.5, j + 0.5);
        return;
    }
    int rows = 1;
    for (int r = 1; r * r <= spp; ++r)
        if (spp % r == 0) rows = r;
    int cols = spp / rows;
    Rng rng(Rng(scene.settings.seed ^ 0x5bd1e995u).next() ^
            (uint64_t(j) * uint64_t(scene.camera.width) + uint64_t(i)));
    rng.next();
    for (int k = 0; k < spp; ++k) {
        double sx = i + (k % cols + rng.uniform()) / cols;
        double sy = j + (k / cols + rng.uniform()) / rows;
        f(sx, sy);
    }
}

// One pixel, one primary ray per sample, each traced on its own.
inline Color render_pixel(const Scene &scene, int i, int j, RayCounts &counts) {
    Color sum{0, 0, 0};
    for_each_sample(scene, i, j, [&](double sx, double sy) {
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

// A tile of pixels [x0, x1) x [y0, y1), one ray at a time (12_packet.h traces W at a time).
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

// Render into out (height x width x 3 floats, row 0 at the top) with `threads` workers. The
// calling thread only watches: every `poll_interval` it calls poll(tiles_done, tiles_total);
// when poll returns false the workers stop after their current tile.
inline RenderResult render(const Scene &scene, int threads, float *out,
                           const std::function<bool(int, int)> &poll,
                           const TileRenderer &render_tile = render_tile_rays,
                           std::chrono::milliseconds poll_interval = std::chrono::milliseconds(100)) {
    constexpr int tile = 16;
    const int W = scene.camera.width, H = scene.camera.height;
    const int tiles_x = (W + tile - 1) / tile, tiles_y = (H + tile - 1) / tile;
    const int total = tiles_x * tiles_y;
    threads = std::max(1, std::min(threads, total));

    std::atomic<int> next_tile{0}, tiles_done{0};
    std::atomic<bool> cancel{false};
    std::vector<RayCounts> counts(threads);
    std::mutex mutex;
    std::condition_variable finished;
    int workers_left = threads;

    auto worker = [&](int id) {
        RayCounts &c = counts[id];
        for (int t; !cancel.load(std::memory_order_relaxed) && (t = next_tile++) < total;) {
            int x0 = (t % tiles_x) * tile, y0 = (t / tiles_x) * tile;
            render_tile(scene, x0, y0, std::min(x0 + tile, W), std::min(y0 + tile, H), out, c);
            ++tiles_done;
        }
        std::lock_guard<std::mutex> lock(mutex);
        if (--workers_left == 0) finished.notify_all();
    };

    std::vector<std::thread> pool;
    for (int id = 0; id < threads; ++id) pool.emplace_back(worker, id);
    {
        std::unique_lock<std::mutex> lock(mutex);
        while (!finished.wait_for(lock, poll_interval, [&] { return workers_left == 0; })) {
            lock.unlock();
            if (poll && !poll(tiles_done.load(), total)) cancel = true;
            lock.lock();
        }
    }
    for (std::thread &t : pool) t.join();

    RenderResult result;
    result.cancelled = cancel.load();
    for (const RayCounts &c : counts) {
        result.counts.primary += c.primary;
        result.counts.secondary += c.secondary;
        result.counts.shadow += c.shadow;
        result.counts.box_tests += c.box_tests;
        result.counts.primitive_tests += c.primitive_tests;
    }
    return result;
}

} // namespace rt
