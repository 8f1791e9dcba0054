// OBJ through tinyobjloader. OBJ indexes positions, normals and UVs separately; the engine wants
// one index per vertex, so every distinct (position, normal, uv) corner becomes one vertex.
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>

#include <tiny_obj_loader.h>

#include "scenes/scene_loader.hpp"

namespace shadow::scenes {
namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& why) {
  throw std::runtime_error(path.string() + ": " + why);
}

Mesh convert_shape(const std::filesystem::path& path, const tinyobj::attrib_t& attrib,
                   const tinyobj::shape_t& shape) {
  const auto& corners = shape.mesh.indices;
  const int vertex_count = static_cast<int>(attrib.vertices.size() / 3);
  const int normal_count = static_cast<int>(attrib.normals.size() / 3);
  const int uv_count = static_cast<int>(attrib.texcoords.size() / 2);

  bool has_normals = true, has_uvs = true;
  for (size_t i = 0; i < corners.size(); ++i) {
    const auto& c = corners[i];
    const std::string where = "shape '" + shape.name + "' face " + std::to_string(i / 3);
    if (c.vertex_index < 0 || c.vertex_index >= vertex_count)
      fail(path, where + ": position index " + std::to_string(c.vertex_index + 1) +
                     " out of range (file has " + std::to_string(vertex_count) + ")");
    if (c.normal_index >= normal_count)
      fail(path, where + ": normal index " + std::to_string(c.normal_index + 1) + " out of range");
    if (c.texcoord_index >= uv_count)
      fail(path, where + ": uv index " + std::to_string(c.texcoord_index + 1) + " out of range");
    has_normals = has_normals && c.normal_index >= 0;
    has_uvs = has_uvs && c.texcoord_index >= 0;
  }

  Mesh mesh;
  std::map<std::tuple<int, int, int>, uint32_t> vertex_of;
  mesh.indices.reserve(corners.size());
  for (const auto& c : corners) {
    const int n = has_normals ? c.normal_index : -1;
    const int t = has_uvs ? c.texcoord_index : -1;
    auto [it, inserted] =
        vertex_of.try_emplace({c.vertex_index, n, t}, static_cast<uint32_t>(mesh.vertex_count()));
    if (inserted) {
      for (int k = 0; k < 3; ++k) mesh.positions.push_back(attrib.vertices[3 * c.vertex_index + k]);
      if (has_normals)
        for (int k = 0; k < 3; ++k) mesh.normals.push_back(attrib.normals[3 * n + k]);
      if (has_uvs)
        for (int k = 0; k < 2; ++k) mesh.uvs.push_back(attrib.texcoords[2 * t + k]);
    }
    mesh.indices.push_back(it->second);
  }
  return mesh;
}

}  // namespace

Scene load_obj(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) fail(path, "no such file");

  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(path.string(), config)) {
    std::string why = reader.Error();
    while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
    fail(path, "not a readable OBJ file: " + (why.empty() ? std::string("parse failed") : why));
  }

  Scene scene;
  for (const auto& shape : reader.GetShapes()) {
    if (shape.mesh.indices.empty()) continue;  // lines or points only
    for (unsigned char n : shape.mesh.num_face_vertices)
      if (n != 3) fail(path, "shape '" + shape.name + "' has a face that did not triangulate");
    scene.meshes.push_back(convert_shape(path, reader.GetAttrib(), shape));
    Instance instance;
    instance.mesh = static_cast<uint32_t>(scene.meshes.size() - 1);
    scene.instances.push_back(instance);
  }
  if (scene.meshes.empty()) fail(path, "contains no triangles");
  return scene;
}

}  // namespace shadow::scenes
