#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "scenes/scene_loader.hpp"

namespace shadow::scenes {

Scene load_scene(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".obj") return load_obj(path);
  if (ext == ".gltf" || ext == ".glb") return load_gltf(path);
  throw std::runtime_error(path.string() + ": unknown scene format '" + ext +
                           "' (expected .obj, .gltf or .glb)");
}

}  // namespace shadow::scenes
