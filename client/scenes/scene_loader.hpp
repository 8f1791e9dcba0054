// Loads a scene file into the engine's vocabulary types. Throws std::runtime_error (and nothing
// else) naming the file and what is wrong with it.
//
// Scene files are untrusted input: a render farm takes them from anywhere. The loaders read only
// the file they are given and, for glTF, buffer files inside that file's own folder; every size
// and offset is checked with overflow-safe arithmetic before it is used, and everything they
// allocate is charged against a budget proportional to the bytes actually read (LoadLimits).
#pragma once

#include <cstdint>
#include <filesystem>

#include "wire/types.hpp"

namespace shadow::scenes {

struct LoadLimits {
  // Largest single file read: the scene file itself, or one external glTF buffer.
  uint64_t max_file_bytes = uint64_t{2} << 30;
  // All files read for one scene together.
  uint64_t max_total_input_bytes = uint64_t{4} << 30;
  // Budget for everything the loader builds (tinygltf's parsed model, as estimated from the
  // JSON, temporaries and the Scene): bytes_per_input_byte * (bytes read) + slack_bytes. Type
  // widening costs at most 12x (a uint8 index strip becomes uint32 triangles) and tinygltf's
  // model of ordinary JSON ~50-80x; what can go past it is a file that reuses its data many
  // times over (many primitives sharing one vertex accessor, a node reached through many
  // parents, a sparse accessor of zeros), or JSON made of thousands of empty objects.
  uint64_t bytes_per_input_byte = 128;
  uint64_t slack_bytes = uint64_t{1} << 20;
};

// Dispatches on the extension: .obj, .gltf or .glb (case-insensitive).
Scene load_scene(const std::filesystem::path& path, const LoadLimits& limits = {});

// One mesh per OBJ shape, triangulated, with one identity instance each. Positions, normals and
// UVs are re-indexed into a single index stream; a mesh keeps normals/UVs only if every corner
// has them. Numbers and indices are checked strictly (file:line: token in the error); mtllib is
// never opened.
Scene load_obj(const std::filesystem::path& path, const LoadLimits& limits = {});

// Every triangle primitive (lists, strips, fans) of every mesh reachable from the default scene
// becomes one engine mesh; each node that uses it becomes an instance with the node's world
// transform. Meshes used by several nodes are shared. Buffers are data: URIs, the .glb's BIN
// chunk, or files inside the glTF's own folder (no absolute paths, no "..", no symlinks out).
Scene load_gltf(const std::filesystem::path& path, const LoadLimits& limits = {});

}  // namespace shadow::scenes
