#include "engine/passes/scene_buffers.hpp"

#include <atomic>
#include <string>

#include "engine/device_types.hpp"
#include "engine/passes/pixel_shape.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

constexpr uint32_t kCheckChunk = 4096;  // elements per work-group in scene_buffers.cl

// Chunks over `count` elements of mesh `mesh` starting at `first`, none spanning two meshes.
void add_chunks(std::vector<ChunkItem>& out, uint32_t first, uint32_t count, uint32_t limit,
                uint32_t mesh) {
  for (uint32_t done = 0; done < count; done += kCheckChunk)
    out.push_back({first + done, std::min(kCheckChunk, count - done), limit, mesh});
}

}  // namespace

SceneBuffers::SceneBuffers(const cl::Runtime& rt, cl::Kernels& kernels, const Scene& scene,
                           Timeline& timeline)
    : id_([] {
        static std::atomic<uint64_t> last{0};
        return ++last;
      }()) {
  // Validation already bounded the totals to 32-bit element counts.
  uint64_t vertices = 0, indices = 0;
  for (const Mesh& m : scene.meshes) {
    MeshRange r;
    r.vertex_base = static_cast<uint32_t>(vertices);
    r.index_base = static_cast<uint32_t>(indices);
    r.vertex_count = static_cast<uint32_t>(m.vertex_count());
    r.triangle_count = static_cast<uint32_t>(m.triangle_count());
    meshes_.push_back(r);
    vertices += r.vertex_count;
    indices += 3ull * r.triangle_count;
  }

  positions_ = rt.alloc(vertices * 3 * sizeof(float), CL_MEM_READ_ONLY);
  indices_ = rt.alloc(indices * sizeof(uint32_t), CL_MEM_READ_ONLY);
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const Mesh& m = scene.meshes[i];
    const MeshRange& r = meshes_[i];
    timeline.add("scene.upload",
                 rt.write(positions_, m.positions.data(), m.positions.size() * sizeof(float),
                          size_t{r.vertex_base} * 3 * sizeof(float)));
    timeline.add("scene.upload",
                 rt.write(indices_, m.indices.data(), m.indices.size() * sizeof(uint32_t),
                          size_t{r.index_base} * sizeof(uint32_t)));
  }

  std::vector<ChunkItem> vchunks, ichunks;
  for (uint32_t m = 0; m < meshes_.size(); ++m) {
    const MeshRange& r = meshes_[m];
    add_chunks(vchunks, r.vertex_base, r.vertex_count, 0, m);
    add_chunks(ichunks, r.index_base, 3 * r.triangle_count, r.vertex_count, m);
  }
  const uint32_t nv = static_cast<uint32_t>(vchunks.size());
  const uint32_t ni = static_cast<uint32_t>(ichunks.size());
  cl::Buffer vchunk_buf = rt.upload(vchunks), ichunk_buf = rt.upload(ichunks);
  cl::Buffer boxes = rt.alloc(size_t{nv} * 6 * sizeof(float));
  cl::Buffer bad_vertex = rt.alloc(size_t{nv} * sizeof(int32_t));
  cl::Buffer bad_index = rt.alloc(size_t{ni} * sizeof(int32_t));

  const size_t group = chunk_group(rt);
  const std::string options = group_option(group);
  cl_kernel kb = kernels.kernel("scene_buffers.cl", "chunk_bounds", options);
  cl::set_args(kb, positions_, vchunk_buf, nv, boxes, bad_vertex);
  timeline.add("scene.check", rt.launch(kb, nv * group, group));
  cl_kernel ki = kernels.kernel("scene_buffers.cl", "check_indices", options);
  cl::set_args(ki, indices_, ichunk_buf, ni, bad_index);
  timeline.add("scene.check", rt.launch(ki, ni * group, group));

  std::vector<float> box(size_t{nv} * 6);
  std::vector<int32_t> bv(nv), bi(ni);
  timeline.add("scene.check", rt.read(boxes, box.data(), box.size() * sizeof(float)));
  timeline.add("scene.check", rt.read(bad_vertex, bv.data(), bv.size() * sizeof(int32_t)));
  timeline.add("scene.check", rt.read(bad_index, bi.data(), bi.size() * sizeof(int32_t)));

  for (uint32_t c = 0; c < nv; ++c) {
    if (bv[c] < 0) continue;
    uint32_t m = vchunks[c].mesh, v = static_cast<uint32_t>(bv[c]);
    throw InvalidArgument("scene.meshes[" + std::to_string(m) + "].positions[" +
                              std::to_string(v - meshes_[m].vertex_base) + "]",
                          "vertex position is not finite (NaN or Inf)");
  }
  for (uint32_t c = 0; c < ni; ++c) {
    if (bi[c] < 0) continue;
    uint32_t m = ichunks[c].mesh, local = static_cast<uint32_t>(bi[c]) - meshes_[m].index_base;
    throw InvalidArgument(
        "scene.meshes[" + std::to_string(m) + "].indices[" + std::to_string(local) + "]",
        "index " + std::to_string(scene.meshes[m].indices[local]) + " is out of range (mesh has " +
            std::to_string(meshes_[m].vertex_count) + " vertices)");
  }
  // Per-mesh bounds from the per-chunk boxes.
  for (uint32_t c = 0; c < nv; ++c) {
    MeshRange& r = meshes_[vchunks[c].mesh];
    r.bounds.extend(glm::dvec3(box[6 * c], box[6 * c + 1], box[6 * c + 2]));
    r.bounds.extend(glm::dvec3(box[6 * c + 3], box[6 * c + 4], box[6 * c + 5]));
  }
}

}  // namespace shadow
