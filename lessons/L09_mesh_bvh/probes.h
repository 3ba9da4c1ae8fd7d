// L09's probes (lessons/L09_mesh_bvh/checks.py computes what they must return): the slab test
// of a bounding box within a range, and the closest hit of a ray in a small mesh (its triangles
// given one by one, three vertices each), with the number of box and triangle tests it cost.
#include "14_box.h"
#include "16_mesh.h"

RT_PROBE(slab_test) {
    using rt::probe::out;
    rt::AABB box;
    box.min = a.vec();
    box.max = a.vec();
    rt::SlabRay r(a.ray());
    rt::Interval range = a.range();
    double t_near = rt::infinity;
    bool hit = rt::slab_test(box, r, range, t_near);
    return out(hit) + out(t_near);
}

// Inputs: the acceleration (1: one bounding box, 2: the hierarchy), the number of triangles n,
// their 9 n vertex coordinates, the ray and the range. The mesh is built by the solution's
// build() (the hierarchy is not the student's: only the traversal is).
RT_PROBE(traverse) {
    using rt::probe::out;
    rt::Mesh mesh;
    mesh.acceleration = a.next() == 1 ? rt::Acceleration::bounding_box : rt::Acceleration::bvh;
    int n = int(a.next());
    for (int i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) mesh.vertices.push_back(a.vec());
        mesh.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
    }
    mesh.build();
    rt::Ray ray = a.ray();
    rt::Interval range = a.range();
    rt::TriangleHit th{rt::infinity, 0, 0, 0};
    int triangle = -1;
    rt::RayCounts counts;
    bool found = mesh.traverse(ray, range, th, triangle, counts, false);
    return out(found) + out(th.t) + out(double(triangle)) + out(th.b0) + out(th.b1) +
           out(th.b2) + out(double(counts.box_tests)) + out(double(counts.primitive_tests));
}
