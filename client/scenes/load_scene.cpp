#include <algorithm>
#include <cctype>
#include <new>
#include <stdexcept>

#include "scenes/scene_loader.hpp"

namespace shadow::scenes {

Scene load_scene(const std::filesystem::path& path, const LoadLimits& limits) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  // The loaders throw std::runtime_error; anything else from the libraries under them (an
  // allocation that failed, a library's own logic_error) becomes one too, naming the file.
  try {
    if (ext == ".obj") return load_obj(path, limits);
    if (ext == ".gltf" || ext == ".glb") return load_gltf(path, limits);
  } catch (const std::runtime_error&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(path.string() + ": out of memory while loading the scene");
  } catch (const std::exception& e) {
    throw std::runtime_error(path.string() + ": cannot load the scene: " + e.what());
  }
  throw std::runtime_error(path.string() + ": unknown scene format '" + ext +
                           "' (expected .obj, .gltf or .glb)");
}

}  // namespace shadow::scenes
