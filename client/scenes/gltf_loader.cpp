// glTF 2.0 (.gltf with external or embedded buffers, and .glb) through tinygltf. Geometry only:
// images are skipped so a missing texture never stops a shadow render.
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include <tiny_gltf.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "scenes/gltf_accessor.hpp"
#include "scenes/scene_loader.hpp"

namespace shadow::scenes {
namespace {

bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                const unsigned char*, int, void*) {
  return true;
}

bool is_glb(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  return in && std::string(magic, 4) == "glTF";
}

glm::dmat4 local_transform(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) return glm::make_mat4(node.matrix.data());  // column-major
  glm::dmat4 t(1.0), r(1.0), s(1.0);
  if (node.translation.size() == 3)
    t = glm::translate(glm::dmat4(1.0), glm::make_vec3(node.translation.data()));
  if (node.rotation.size() == 4) {
    const auto& q = node.rotation;  // glTF stores x, y, z, w
    r = glm::mat4_cast(glm::dquat(q[3], q[0], q[1], q[2]));
  }
  if (node.scale.size() == 3) s = glm::scale(glm::dmat4(1.0), glm::make_vec3(node.scale.data()));
  return t * r * s;
}

// Triangle list from the primitive's index stream, whatever its topology.
std::vector<uint32_t> triangle_list(int mode, const std::vector<uint32_t>& idx) {
  std::vector<uint32_t> out;
  const size_t n = idx.size();
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    out.assign(idx.begin(), idx.begin() + n / 3 * 3);
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 0; i + 2 < n; ++i) {  // alternate winding so every triangle faces the same way
      const size_t odd = i % 2;
      out.insert(out.end(), {idx[i], idx[i + 1 + odd], idx[i + 2 - odd]});
    }
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t i = 1; i + 1 < n; ++i) out.insert(out.end(), {idx[i], idx[i + 1], idx[0]});
  }
  return out;
}

class Builder {
 public:
  Builder(const std::filesystem::path& path, const tinygltf::Model& model)
      : path_(path), model_(model) {}

  Scene build() {
    std::vector<int> roots;
    const int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
    if (scene < static_cast<int>(model_.scenes.size())) {
      roots = model_.scenes[scene].nodes;
    } else {  // no scenes: every node that is nobody's child is a root
      std::vector<bool> child(model_.nodes.size(), false);
      for (const auto& n : model_.nodes)
        for (int c : n.children)
          if (c >= 0 && c < static_cast<int>(child.size())) child[c] = true;
      for (size_t i = 0; i < child.size(); ++i)
        if (!child[i]) roots.push_back(static_cast<int>(i));
    }
    for (int root : roots) visit(root, glm::dmat4(1.0), 0);
    if (scene_.instances.empty()) fail("the scene contains no triangle primitives");
    return std::move(scene_);
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(path_.string() + ": " + why);
  }

  void visit(int index, const glm::dmat4& parent, int depth) {
    if (index < 0 || index >= static_cast<int>(model_.nodes.size()))
      fail("nodes[" + std::to_string(index) + "] does not exist");
    if (depth > 256) fail("node hierarchy is deeper than 256 levels (a cycle?)");
    const auto& node = model_.nodes[index];
    const glm::dmat4 world = parent * local_transform(node);
    if (node.mesh >= 0) {
      if (node.mesh >= static_cast<int>(model_.meshes.size()))
        fail("nodes[" + std::to_string(index) + "].mesh " + std::to_string(node.mesh) +
             " does not exist");
      const auto& prims = model_.meshes[node.mesh].primitives;
      for (size_t p = 0; p < prims.size(); ++p) {
        const int mesh = mesh_for(node.mesh, static_cast<int>(p));
        if (mesh < 0) continue;
        Instance instance;
        instance.mesh = static_cast<uint32_t>(mesh);
        instance.transform = glm::mat4(world);
        scene_.instances.push_back(instance);
      }
    }
    for (int child : node.children) visit(child, world, depth + 1);
  }

  // Engine mesh index for a primitive, converted once; -1 if it has no triangles.
  int mesh_for(int gltf_mesh, int primitive) {
    auto [it, inserted] = cache_.try_emplace({gltf_mesh, primitive}, -1);
    if (!inserted) return it->second;
    const std::string where =
        "meshes[" + std::to_string(gltf_mesh) + "].primitives[" + std::to_string(primitive) + "]";
    try {
      Mesh mesh = convert(model_.meshes[gltf_mesh].primitives[primitive]);
      if (mesh.indices.empty()) return -1;
      scene_.meshes.push_back(std::move(mesh));
      it->second = static_cast<int>(scene_.meshes.size() - 1);
    } catch (const std::runtime_error& e) {
      fail(where + ": " + e.what());
    }
    return it->second;
  }

  Mesh convert(const tinygltf::Primitive& prim) const {
    Mesh mesh;
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        prim.mode != TINYGLTF_MODE_TRIANGLE_FAN)
      return mesh;  // points and lines cast no shadows
    const auto attr = [&](const char* name) {
      auto it = prim.attributes.find(name);
      return it == prim.attributes.end() ? -1 : it->second;
    };
    const int position = attr("POSITION");
    if (position < 0) throw std::runtime_error("has no POSITION attribute");
    mesh.positions = read_float_accessor(model_, position, 3);
    const size_t vertices = mesh.vertex_count();
    if (const int normal = attr("NORMAL"); normal >= 0) {
      mesh.normals = read_float_accessor(model_, normal, 3);
      if (mesh.normals.size() != mesh.positions.size())
        throw std::runtime_error("NORMAL count differs from POSITION count");
    }
    if (const int uv = attr("TEXCOORD_0"); uv >= 0) {
      mesh.uvs = read_float_accessor(model_, uv, 2);
      if (mesh.uvs.size() / 2 != vertices)
        throw std::runtime_error("TEXCOORD_0 count differs from POSITION count");
    }
    std::vector<uint32_t> indices;
    if (prim.indices >= 0) {
      indices = read_index_accessor(model_, prim.indices);
    } else {
      indices.resize(vertices);
      for (size_t i = 0; i < vertices; ++i) indices[i] = static_cast<uint32_t>(i);
    }
    for (size_t i = 0; i < indices.size(); ++i)
      if (indices[i] >= vertices)
        throw std::runtime_error("index " + std::to_string(i) + " is " +
                                 std::to_string(indices[i]) + ", but there are only " +
                                 std::to_string(vertices) + " vertices");
    mesh.indices = triangle_list(prim.mode, indices);
    return mesh;
  }

  const std::filesystem::path& path_;
  const tinygltf::Model& model_;
  Scene scene_;
  std::map<std::pair<int, int>, int> cache_;
};

}  // namespace

Scene load_gltf(const std::filesystem::path& path, const LoadLimits&) {
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error(path.string() + ": no such file");
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = is_glb(path) ? loader.LoadBinaryFromFile(&model, &err, &warn, path.string())
                               : loader.LoadASCIIFromFile(&model, &err, &warn, path.string());
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
    throw std::runtime_error(path.string() + ": not a readable glTF 2.0 file: " +
                             (err.empty() ? std::string("parse failed") : err));
  }
  return Builder(path, model).build();
}

}  // namespace shadow::scenes
