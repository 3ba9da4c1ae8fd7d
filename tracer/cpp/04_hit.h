// Slide "Intersections" (Suffern fig. 3.4): what a ray learns where it meets an object.
#pragma once

#include "02_ray.h"

namespace rt {

struct Hit {
    double t = infinity; // ray parameter of the closest hit; infinity: no hit
    Vec3 p;              // the point of intersection, refined onto the surface
    Vec3 p_error;        // bound on the absolute rounding error of p, per component
    Vec3 N;              // unit normal, facing out of the object (turned toward the ray later)
    int object = -1;     // index into the scene's [[objects]]
    int material = -1;   // index into the scene's materials

    bool found() const { return object >= 0; }
};

} // namespace rt
