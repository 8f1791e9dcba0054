#include "engine/plan/uv_layouts.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <xatlas.h>

namespace shadow {

Mesh generate_uv_layout(const Mesh& mesh) {
  xatlas::Atlas* atlas = xatlas::Create();
  xatlas::MeshDecl decl;
  decl.vertexPositionData = mesh.positions.data();
  decl.vertexCount = uint32_t(mesh.vertex_count());
  decl.vertexPositionStride = 3 * sizeof(float);
  decl.indexData = mesh.indices.data();
  decl.indexCount = uint32_t(mesh.indices.size());
  decl.indexFormat = xatlas::IndexFormat::UInt32;
  const xatlas::AddMeshError added = xatlas::AddMesh(atlas, decl);
  if (added != xatlas::AddMeshError::Success) {
    xatlas::Destroy(atlas);
    throw std::runtime_error(std::string("xatlas refused a checked mesh: ") +
                             xatlas::StringForEnum(added));
  }
  // Charts 4 texels apart at xatlas' own 1024-texel scale: a few texels apart in a tile of 256.
  // No chart larger than that scale: one vertex 1e10 away made a chart xatlas packed for minutes
  // in gigabytes (found by RequestFuzzTest.MutatedAtlasRequests...).
  xatlas::PackOptions pack;
  pack.resolution = 1024;
  pack.padding = 4;
  pack.maxChartSize = 1024;
  xatlas::Generate(atlas, xatlas::ChartOptions(), pack);
  const xatlas::Mesh& out = atlas->meshes[0];
  Mesh m;
  const bool ok = atlas->meshCount == 1 && out.indexCount == mesh.indices.size() &&
                  atlas->width > 0 && atlas->height > 0;
  if (ok) {
    m.indices.assign(out.indexArray, out.indexArray + out.indexCount);
    const float w = float(atlas->width), h = float(atlas->height);
    for (uint32_t i = 0; i < out.vertexCount; ++i) {
      const xatlas::Vertex& v = out.vertexArray[i];
      const float* p = &mesh.positions[size_t{v.xref} * 3];
      m.positions.insert(m.positions.end(), p, p + 3);
      if (!mesh.normals.empty()) {
        const float* n = &mesh.normals[size_t{v.xref} * 3];
        m.normals.insert(m.normals.end(), n, n + 3);
      }
      // Vertices of faces xatlas leaves out (no area) lie in no chart: (0, 0), still in range.
      const bool charted = v.atlasIndex >= 0;
      m.uvs.insert(m.uvs.end(), {charted ? std::clamp(v.uv[0] / w, 0.0f, 1.0f) : 0.0f,
                                 charted ? std::clamp(v.uv[1] / h, 0.0f, 1.0f) : 0.0f});
    }
  }
  xatlas::Destroy(atlas);
  if (!ok) throw std::runtime_error("xatlas did not lay out every triangle of a checked mesh");
  return m;
}

std::vector<uint32_t> meshes_to_lay_out(const Scene& scene, bool all) {
  std::vector<bool> lay_out(scene.meshes.size(), false);
  for (const Instance& inst : scene.instances)
    lay_out[inst.mesh] = lay_out[inst.mesh] ||
                         (inst.receives_shadows && (all || scene.meshes[inst.mesh].uvs.empty()));
  std::vector<uint32_t> out;
  for (uint32_t m = 0; m < lay_out.size(); ++m)
    if (lay_out[m]) out.push_back(m);
  return out;
}

std::shared_ptr<const Mesh> UvLayouts::layout_of(const Mesh& mesh) {
  for (auto it = meshes_.begin(); it != meshes_.end(); ++it)
    if (it->source.positions == mesh.positions && it->source.indices == mesh.indices &&
        it->source.normals == mesh.normals) {
      meshes_.splice(meshes_.begin(), meshes_, it);
      return it->laid_out;
    }
  Mesh key;
  key.positions = mesh.positions;
  key.indices = mesh.indices;
  key.normals = mesh.normals;
  meshes_.push_front({std::move(key), std::make_shared<const Mesh>(generate_uv_layout(mesh))});
  if (meshes_.size() > kMeshes) meshes_.pop_back();
  return meshes_.front().laid_out;
}

std::shared_ptr<const Scene> UvLayouts::apply(const std::shared_ptr<const Scene>& scene, bool all) {
  const std::vector<uint32_t> meshes = meshes_to_lay_out(*scene, all);
  if (meshes.empty()) return scene;
  std::lock_guard<std::mutex> lock(mutex_);
  scenes_.remove_if([](const ByScene& s) { return s.source.expired(); });
  for (auto it = scenes_.begin(); it != scenes_.end(); ++it)
    if (it->source.lock() == scene && it->all == all) {
      scenes_.splice(scenes_.begin(), scenes_, it);
      return it->laid_out;
    }
  auto laid_out = std::make_shared<Scene>(*scene);
  for (uint32_t m : meshes) laid_out->meshes[m] = *layout_of(scene->meshes[m]);
  scenes_.push_front({scene, all, laid_out});
  if (scenes_.size() > kScenes) scenes_.pop_back();
  return laid_out;
}

}  // namespace shadow
