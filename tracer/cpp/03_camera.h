// Slide "Perspective Ray Tracing" (Suffern fig. 8.14): the eye, and primary rays through pixel
// centres.
//
// Right-handed: image right = forward x up. Pixel (i, j), row 0 at the top, is sampled at
// x = (i + 0.5)/W - 0.5, y = 0.5 - (j + 0.5)/H on an image plane at distance 1 that is
// 2 tan(fov_y/2) high and W/H times that wide. (POV-Ray with -A and Mitsuba's stratified
// sampler without jitter sample exactly these points; converters/ rely on that.)
#pragma once

#include <cmath>

#include "01_vec3.h"
#include "02_ray.h"
#include "constants.h"

namespace rt {

// The defaults are the scene language's (the Python package tracer.scene sets every field).
struct Camera {
    Vec3 eye, look_at, up{0, 1, 0};
    double fov_y = 45; // vertical field of view, degrees
    int width = 320, height = 240;

    // Derived in initialize(): the orthonormal frame and the size of the image plane.
    Vec3 forward, right, true_up;
    double plane_height = 0, plane_width = 0;

    void initialize() {
        forward = normalize(look_at - eye);
        right = normalize(cross(forward, up));
        true_up = cross(right, forward);
        plane_height = 2 * std::tan(fov_y * pi / 360.0); // half the angle, in radians
        plane_width = plane_height * width / height;
    }

    // A primary ray through the image-plane point (sx, sy) given in pixel units, where
    // (i + 0.5, j + 0.5) is the centre of pixel (i, j).
    Ray primary_ray(double sx, double sy) const {
        double x = sx / width - 0.5;
        double y = 0.5 - sy / height;
        Vec3 d = forward + (x * plane_width) * right + (y * plane_height) * true_up;
        return {eye, normalize(d)};
    }
};

} // namespace rt
