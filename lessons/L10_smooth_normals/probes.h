// L10's probes (lessons/L10_smooth_normals/checks.py computes what they must return): the
// shading normal of a smooth mesh from the barycentric coordinates of a hit, the three vertex
// normals and the face's normal.
#include "16_mesh.h"

RT_PROBE(smooth_normal) {
    rt::TriangleHit th;
    th.t = 1;
    th.b0 = a.next();
    th.b1 = a.next();
    th.b2 = a.next();
    rt::Vec3 n0 = a.vec(), n1 = a.vec(), n2 = a.vec();
    return rt::probe::out(rt::smooth_normal(th, n0, n1, n2, a.vec()));
}
