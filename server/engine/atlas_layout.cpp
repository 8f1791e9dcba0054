#include "engine/atlas_layout.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

namespace shadow {

AtlasSize atlas_size(const Scene& scene, const AtlasSettings& settings) {
  AtlasSize size;
  for (const Instance& inst : scene.instances) size.receivers += inst.receives_shadows;
  if (size.receivers == 0) return size;
  size.columns = uint64_t(std::ceil(std::sqrt(double(size.receivers))));
  while (size.columns * size.columns < size.receivers) ++size.columns;  // sqrt's rounding
  const uint64_t rows = (size.receivers + size.columns - 1) / size.columns;
  size.width = size.columns * settings.tile;
  size.height = rows * settings.tile;
  return size;
}

bool wants_atlas(const RenderRequest& request) {
  return std::any_of(request.products.begin(), request.products.end(), [](Product p) {
    return p == Product::kShadowAtlas || p == Product::kShadowAtlasMips ||
           p == Product::kShadowAtlasSat;
  });
}

bool is_atlas_filter(FilterKind kind) {
  return kind == FilterKind::kAtlasSat || kind == FilterKind::kAtlasMip;
}

bool uses_atlas(const RenderRequest& request) {
  return wants_atlas(request) || is_atlas_filter(request.filter.kind);
}

std::vector<AtlasTile> atlas_tiles(const Scene& scene, const AtlasSettings& settings) {
  const uint64_t columns = atlas_size(scene, settings).columns;
  std::vector<AtlasTile> tiles;
  for (uint32_t j = 0; j < scene.instances.size(); ++j) {
    if (!scene.instances[j].receives_shadows) continue;
    const uint64_t k = tiles.size();
    tiles.push_back({j, uint32_t(k % columns * settings.tile),
                     uint32_t(k / columns * settings.tile), settings.tile});
  }
  return tiles;
}

UvCharts uv_charts(const Mesh& mesh) {
  const size_t triangles = mesh.triangle_count();
  std::vector<uint32_t> parent(triangles);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto root = [&](uint32_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];
    return t;
  };
  // A corner by its bits: position and UV (split vertices that agree in both are one point).
  using Key = std::array<uint32_t, 5>;
  struct Hash {
    size_t operator()(const Key& k) const {
      size_t h = 0;
      for (uint32_t v : k) h = h * 0x9e3779b97f4a7c15ull + v;
      return h;
    }
  };
  std::unordered_map<Key, uint32_t, Hash> first_triangle;
  first_triangle.reserve(mesh.vertex_count());
  for (uint32_t t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.indices[3 * size_t{t} + k];
      // + 0.0f: -0 and 0 are one point. No UVs: joined by position alone.
      const bool uv = mesh.uvs.size() >= 2 * (size_t{v} + 1);
      const float corner[5] = {
          mesh.positions[3 * size_t{v}] + 0.0f, mesh.positions[3 * size_t{v} + 1] + 0.0f,
          mesh.positions[3 * size_t{v} + 2] + 0.0f, uv ? mesh.uvs[2 * size_t{v}] + 0.0f : 0.0f,
          uv ? mesh.uvs[2 * size_t{v} + 1] + 0.0f : 0.0f};
      Key key;
      std::memcpy(key.data(), corner, sizeof corner);
      const auto [it, added] = first_triangle.emplace(key, t);
      if (!added) parent[root(t)] = root(it->second);
    }
  UvCharts out;
  out.of_triangle.resize(triangles);
  std::unordered_map<uint32_t, uint32_t> label;
  for (uint32_t t = 0; t < triangles; ++t) {
    const auto [it, added] = label.emplace(root(t), out.count);
    out.count += added;
    out.of_triangle[t] = it->second;
  }
  return out;
}

bool uvs_degenerate(const Mesh& mesh) {
  if (mesh.uvs.empty() || mesh.indices.empty()) return false;  // laid out by the server; none
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
    const float* a = &mesh.uvs[2 * size_t{mesh.indices[i]}];
    const float* b = &mesh.uvs[2 * size_t{mesh.indices[i + 1]}];
    const float* c = &mesh.uvs[2 * size_t{mesh.indices[i + 2]}];
    const double area = (double(b[0]) - a[0]) * (double(c[1]) - a[1]) -
                        (double(b[1]) - a[1]) * (double(c[0]) - a[0]);
    if (area != 0.0) return false;
  }
  return true;
}

}  // namespace shadow
