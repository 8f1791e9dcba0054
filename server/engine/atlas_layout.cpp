#include "engine/atlas_layout.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace shadow
