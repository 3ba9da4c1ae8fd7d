// L03's probes (lessons/L03_plane/checks.py): a plane (a point on it, its normal), a ray and,
// for intersect_plane, the range [min, max].
#include "04_hit.h"
#include "06_plane.h"

namespace l03 {

rt::Plane read_plane(rt::probe::Args &a) {
    rt::Plane pl;
    pl.point = a.vec();
    pl.normal = a.vec();
    return pl;
}

} // namespace l03

RT_PROBE(plane_t) {
    rt::Plane pl = l03::read_plane(a);
    return rt::probe::out(rt::plane_t(pl, a.ray()));
}

RT_PROBE(intersect_plane) {
    using rt::probe::out;
    rt::Plane pl = l03::read_plane(a);
    rt::Ray ray = a.ray();
    rt::Interval range = a.range();
    rt::Hit hit;
    bool found = rt::intersect_plane(pl, ray, range, hit);
    return out(found) + out(hit.t) + out(hit.p) + out(hit.N);
}
