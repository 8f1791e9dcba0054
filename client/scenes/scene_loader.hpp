// Loads a scene file into the engine's vocabulary types. Throws std::runtime_error naming the
// file and what is wrong with it.
#pragma once

#include <filesystem>

#include "engine/types.hpp"

namespace shadow::scenes {

// Dispatches on the extension: .obj, .gltf or .glb (case-insensitive).
Scene load_scene(const std::filesystem::path& path);

// One mesh per OBJ shape, triangulated, with one identity instance each. Positions, normals and
// UVs are re-indexed into a single index stream; a mesh keeps normals/UVs only if every corner
// has them.
Scene load_obj(const std::filesystem::path& path);

// Every triangle primitive (lists, strips, fans) of every mesh reachable from the default scene
// becomes one engine mesh; each node that uses it becomes an instance with the node's world
// transform. Meshes used by several nodes are shared.
Scene load_gltf(const std::filesystem::path& path);

}  // namespace shadow::scenes
