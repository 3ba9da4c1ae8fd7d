// Slide "Light Reflection": what an object is made of, in the classic model's terms.
#pragma once

#include "01_vec3.h"

namespace rt {

// The defaults are the scene language's (the Python package tracer.scene sets every field).
struct Material {
    Color color{1, 1, 1};
    double ambient = 0.1;      // share of the ambient light it returns
    double diffuse = 0.6;      // Lambert coefficient, times N.L
    double specular = 0;       // Phong coefficient; the highlight is the light's colour
    double shininess = 40;     // Phong exponent
    double reflectivity = 0;   // alpha, the mirror coefficient in the chain
    Color emission{0, 0, 0};   // radiance from the front side (the path tracer's area lights)
};

} // namespace rt
