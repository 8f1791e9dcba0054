// Procedural meshes for the demo scene: outward-facing counter-clockwise triangles with normals
// and UVs, in object space so instances can place and scale them.
#pragma once

#include "wire/types.hpp"

namespace shadow::scenes {

// Square in the y = 0 plane, `extent` wide, centred on the origin, `cells`² quads, facing +y.
Mesh make_grid(float extent, int cells);

// Axis-aligned cube from -0.5 to 0.5 with a flat normal per face.
Mesh make_box();

// Sphere of radius 1 around the origin.
Mesh make_sphere(int slices, int stacks);

// Capped cylinder of radius 1 along +y from y = 0 to y = 1.
Mesh make_cylinder(int segments);

}  // namespace shadow::scenes
