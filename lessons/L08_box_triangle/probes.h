// L08's probes (lessons/L08_box_triangle/checks.py computes what they must return): the slab
// test of a box (min, max) and a ray (origin, direction); the box's hit from given slab
// intervals and a range; the ray/triangle test (three vertices, a ray, a range); the hit record
// of a triangle hit (three vertices, t and the barycentric coordinates).
#include "14_box.h"
#include "15_triangle.h"

RT_PROBE(slab_interval) {
    using rt::probe::out;
    rt::AABB box;
    box.min = a.vec();
    box.max = a.vec();
    rt::Slabs s = rt::slab_interval(box, a.ray());
    // "inside" as the box's hit reads it: an overlap that is not empty (a NaN is no overlap).
    return out(s.t_enter <= s.t_leave) + out(s.t_enter) + out(s.t_leave) +
           out(double(s.enter_axis)) + out(double(s.leave_axis));
}

RT_PROBE(box_crossing) {
    using rt::probe::out;
    rt::Slabs s;
    s.t_enter = a.next();
    s.t_leave = a.next();
    s.enter_axis = int(a.next());
    s.leave_axis = int(a.next());
    rt::BoxCrossing c = rt::box_crossing(s, a.range());
    return out(c.found) + out(c.t) + out(double(c.axis)) + out(c.entering);
}

RT_PROBE(intersect_triangle) {
    using rt::probe::out;
    rt::Vec3 p0 = a.vec(), p1 = a.vec(), p2 = a.vec();
    rt::Ray ray = a.ray();
    rt::Interval range = a.range();
    rt::TriangleHit th{rt::infinity, 0, 0, 0};
    bool found = rt::intersect_triangle(p0, p1, p2, rt::WatertightRay(ray), range, th);
    return out(found) + out(th.t) + out(th.b0) + out(th.b1) + out(th.b2);
}

RT_PROBE(triangle_hit) {
    using rt::probe::out;
    rt::Vec3 p0 = a.vec(), p1 = a.vec(), p2 = a.vec();
    rt::TriangleHit th;
    th.t = a.next();
    th.b0 = a.next();
    th.b1 = a.next();
    th.b2 = a.next();
    rt::Hit hit;
    rt::triangle_hit(p0, p1, p2, th, hit);
    return out(hit.t) + out(hit.p) + out(hit.N) + out(hit.Ng);
}
