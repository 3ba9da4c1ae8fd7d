// Arbitrary output variables: instead of a colour, what the primary ray through each pixel
// centre found - the distance to the hit (infinity on a miss), the index of the object in the
// scene's [[objects]] (-1 on a miss), and the shading normal (on the object's front side, not
// turned toward the ray; 0 on a miss). The geometry that rasterisers (pyrender) and Mitsuba's
// `aov` integrator can check without any shading model.
#pragma once

#include <algorithm>
#include <cfloat>
#include <cstddef>

#include "02_ray.h"
#include "03_camera.h"
#include "04_hit.h"
#include "09_scene.h"
#include "constants.h"

namespace rt {

constexpr int aov_channels = 5; // depth, object_id, N.X, N.Y, N.Z

// A pixel's channels from the primary ray's closest hit.
inline void store_aov(float *out, int width, int i, int j, const Hit &hit) {
    float *px = out + (size_t(j) * width + i) * aov_channels;
    bool found = hit.found();
    // A hit farther than float32 can say (3.4e38, a ray grazing a plane) keeps the largest
    // float: infinity means a miss, and only a miss.
    px[0] = found ? float(std::min(hit.t, double(FLT_MAX))) : float(infinity);
    px[1] = float(hit.object);
    px[2] = found ? float(hit.N.x) : 0.0f;
    px[3] = found ? float(hit.N.y) : 0.0f;
    px[4] = found ? float(hit.N.z) : 0.0f;
}

inline void render_tile_aov(const Scene &scene, int x0, int y0, int x1, int y1, float *out,
                            RayCounts &counts) {
    const Camera &cam = scene.camera;
    for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i) {
            Ray ray = cam.primary_ray(i + 0.5, j + 0.5); // unit direction: t is the distance
            ++counts.primary;
            store_aov(out, cam.width, i, j, closest_hit(scene, ray, counts));
        }
}

} // namespace rt
