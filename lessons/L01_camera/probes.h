// L01's probes (lessons/L01_camera/checks.py): the point p = o + t d of a ray, the camera's
// frame (initialize()) and a primary ray through an image-plane point (primary_ray()).
#include "03_camera.h"

RT_PROBE(at) {
    rt::Ray ray = a.ray();
    return rt::probe::out(ray.at(a.next()));
}

RT_PROBE(initialize) {
    using rt::probe::out;
    rt::Camera cam = a.camera();
    cam.initialize();
    return out(cam.forward) + out(cam.right) + out(cam.true_up) + out(cam.plane_height) +
           out(cam.plane_width);
}

// The frame is given, not derived, so that primary_ray() is checked on its own: eye, forward,
// right, true_up, plane_width, plane_height, width, height, window_shift, then (sx, sy).
RT_PROBE(primary_ray) {
    using rt::probe::out;
    rt::Camera cam;
    cam.eye = a.vec();
    cam.forward = a.vec();
    cam.right = a.vec();
    cam.true_up = a.vec();
    cam.plane_width = a.next();
    cam.plane_height = a.next();
    cam.width = int(a.next());
    cam.height = int(a.next());
    cam.window_shift = a.next();
    double sx = a.next();
    rt::Ray ray = cam.primary_ray(sx, a.next());
    return out(ray.o) + out(ray.d);
}
