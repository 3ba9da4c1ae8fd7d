// L11's probes (lessons/L11_stereo/checks.py): one eye of a stereo pair, stereo_eye() of
// 03_camera.h, made from an initialized centre camera. The first input is the mode, then the
// centre camera (eye, look_at, up, fov_y, width, height), eye_separation, convergence and, for
// modes 0 and 1, the side (-1 left, +1 right).
//   0: the eye's position.
//   1: its frame (forward, right, true_up), its axis unit(look_at - eye) and window_shift.
//   2: then (sx, sy): where both eyes' rays through that image point meet the plane at
//      distance `convergence` along the centre's forward (left's point, then right's).
//   3: then a point P: the image point (sx, sy) at which each eye sees P (left's, then right's).
// The eyes are used as stereo_eye() returns them, without initialize(): so does the renderer
// (bindings.cpp set_camera()).
#include "03_camera.h"

namespace l11 {

rt::Camera read_centre(rt::probe::Args &a) {
    rt::Camera cam = a.camera();
    cam.initialize();
    return cam;
}

// Where an eye's ray through (sx, sy) meets the plane at distance `convergence` in front of
// the centre eye, perpendicular to the centre's axis.
rt::Vec3 on_convergence_plane(const rt::Camera &centre, const rt::Camera &eye,
                              double convergence, double sx, double sy) {
    rt::Ray ray = eye.primary_ray(sx, sy);
    double t = (convergence - rt::dot(ray.o - centre.eye, centre.forward)) /
               rt::dot(ray.d, centre.forward);
    return ray.at(t);
}

// primary_ray() inverted: the image point (sx, sy), in pixel units, whose ray passes through P.
std::string image_point(const rt::Camera &eye, const rt::Vec3 &P) {
    rt::Vec3 v = P - eye.eye;
    double z = rt::dot(v, eye.forward);
    double x = rt::dot(v, eye.right) / z, y = rt::dot(v, eye.true_up) / z;
    double sx = ((x - eye.window_shift) / eye.plane_width + 0.5) * eye.width;
    double sy = (0.5 - y / eye.plane_height) * eye.height;
    return rt::probe::out(sx) + rt::probe::out(sy);
}

} // namespace l11

RT_PROBE(stereo_eye) {
    using rt::probe::out;
    int mode = int(a.next());
    rt::Camera centre = l11::read_centre(a);
    double separation = a.next(), convergence = a.next();
    if (mode <= 1) {
        int side = int(a.next());
        rt::Camera eye = rt::stereo_eye(centre, separation, convergence, side);
        if (mode == 0) return out(eye.eye);
        return out(eye.forward) + out(eye.right) + out(eye.true_up) +
               out(rt::normalize(eye.look_at - eye.eye)) + out(eye.window_shift);
    }
    rt::Camera left = rt::stereo_eye(centre, separation, convergence, -1);
    rt::Camera right = rt::stereo_eye(centre, separation, convergence, +1);
    if (mode == 2) {
        double sx = a.next(), sy = a.next();
        return out(l11::on_convergence_plane(centre, left, convergence, sx, sy)) +
               out(l11::on_convergence_plane(centre, right, convergence, sx, sy));
    }
    rt::Vec3 P = a.vec();
    return l11::image_point(left, P) + l11::image_point(right, P);
}
