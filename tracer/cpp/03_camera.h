// Slide "Perspective Ray Tracing" (Suffern fig. 8.14): the eye, and primary rays through pixel
// centres.
//
// Right-handed: image right = forward x up. Pixel (i, j), row 0 at the top, is sampled at
// x = (i + 0.5)/W - 0.5, y = 0.5 - (j + 0.5)/H on an image plane at distance 1 that is
// 2 tan(fov_y/2) high and W/H times that wide. (POV-Ray with -A and Mitsuba's stratified
// sampler without jitter sample exactly these points; converters/ rely on that.)
//
// Slide "Stereoscopy": one eye of a stereo pair is this camera too, moved sideways and with its
// image window shifted sideways on the image plane (stereo_eye() below).
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
    // The image window's centre, moved this far along `right` on the image plane (in its units,
    // the plane at distance 1): 0 for a single camera, nonzero for an eye of a stereo pair.
    double window_shift = 0;

    // Derived in initialize(): the orthonormal frame and the size of the image plane.
    Vec3 forward, right, true_up;
    double plane_height = 0, plane_width = 0;

    void initialize() {
        // BEGIN SOLUTION L01
        // PROMPT: The camera's frame: the unit vectors forward (towards look_at), right
        // PROMPT: (forward x up: right-handed) and true_up (perpendicular to both), and the
        // PROMPT: image plane's height and width at distance 1 for the vertical field of view
        // PROMPT: fov_y (in degrees) and the image's aspect width / height.
        forward = normalize(look_at - eye);
        right = normalize(cross(forward, up));
        true_up = cross(right, forward);
        plane_height = 2 * std::tan(fov_y * pi / 360.0); // half the angle, in radians
        plane_width = plane_height * width / height;
        // END SOLUTION
    }

    // A primary ray through the image-plane point (sx, sy) given in pixel units, where
    // (i + 0.5, j + 0.5) is the centre of pixel (i, j).
    Ray primary_ray(double sx, double sy) const {
        // BEGIN SOLUTION L01
        // PROMPT: The unit-direction ray from the eye through the image-plane point (sx, sy),
        // PROMPT: in pixel units with row 0 at the top: x = sx / width - 0.5 and
        // PROMPT: y = 0.5 - sy / height, scaled to the plane's size, along right and true_up;
        // PROMPT: the window moves by window_shift along right (0 but for a stereo eye).
        double x = sx / width - 0.5;
        double y = 0.5 - sy / height;
        // x * plane_width + 0 is x * plane_width exactly (x is never -0), so a single camera's
        // rays are what they were before stereo pairs existed, bit for bit.
        Vec3 d = forward + (x * plane_width + window_shift) * right + (y * plane_height) * true_up;
        return {eye, normalize(d)};
        // END SOLUTION
    }
};

// Slide "Stereoscopy": one eye of a stereo pair seen through `centre` (initialized), side = -1
// for the left eye and +1 for the right. The parallel-axis asymmetric frustum ("off-axis"):
// the eye moves eye_separation/2 along `right` and keeps the centre's frame, so both eyes look
// along the same forward; its window moves the other way by (eye_separation/2)/convergence on
// the image plane, so that on the plane at distance `convergence` the two frusta coincide (a
// point there lands on the same pixel in both eyes, and nothing has vertical parallax).
// Rotating the eyes towards the convergence point instead ("toe-in") tilts their image planes
// against each other: points away from the centre get vertical parallax, which the eyes cannot
// fuse (P. Bourke, "Calculating stereo pairs", 1999; A. Woods, T. Docherty, R. Koch, "Image
// distortions in stereoscopic video systems", Proc. SPIE 1915, 1993).
inline Camera stereo_eye(const Camera &centre, double eye_separation, double convergence,
                         int side) {
    // BEGIN SOLUTION L11
    // PROMPT: One eye of a stereo pair (side -1 left, +1 right) seen through the initialized
    // PROMPT: camera `centre`: move the eye half the eye separation along `right`, keep the
    // PROMPT: centre's frame (parallel axes: no toe-in), and shift its image window sideways on
    // PROMPT: the image plane (window_shift, in the plane's units at distance 1) so that both
    // PROMPT: eyes' windows coincide on the plane at distance `convergence`.
    Camera view = centre; // the same frame: forward, right and true_up are the centre's
    const double half = side * eye_separation / 2;
    view.eye = centre.eye + half * centre.right;
    view.look_at = centre.look_at + half * centre.right; // parallel axes
    view.window_shift = centre.window_shift - half / convergence;
    return view;
    // END SOLUTION
}

} // namespace rt
