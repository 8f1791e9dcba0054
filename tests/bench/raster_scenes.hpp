// Large depth-only scenes for the rasterizer bench, as one world-space mesh each so that the
// engine and the llvmpipe peer draw exactly the same triangles, and the orthographic
// light-space matrix (texture NDC) that frames them.
#pragma once

#include <cstddef>

#include <glm/glm.hpp>

#include "wire/types.hpp"

namespace shadow::bench {

struct RasterScene {
  Mesh mesh;               // world space; one instance with the identity transform
  glm::mat4 world_to_ndc;  // orthographic, the mesh's light-space bounds, x, y, z in 0..1
};

// A 200 m ground (two triangles, drawn first) and 2500 spheres of 400 triangles each
// (0.4-1.4 m radius, on or floating over a 50 x 50 grid): 10^6 + 2 triangles.
RasterScene sphere_crowd();

// scenes::random_triangles (a 100 m ground, then `count` triangles of ~0.15 m edges at heights
// 0.5-3 m), flattened.
RasterScene random_field(size_t count);

// The engine scene that draws `mesh` once.
Scene one_instance(const Mesh& mesh);

}  // namespace shadow::bench
