// Slide "Interaction between Lights and Objects": point and directional lights.
// In the classic model neither falls off with distance.
#pragma once

#include "01_vec3.h"

namespace rt {

struct Light {
    enum class Type { point, directional };
    Type type = Type::point;
    Vec3 position;  // point light
    Vec3 direction; // directional light: the unit direction the light travels
    Color color{1, 1, 1};
};

} // namespace rt
