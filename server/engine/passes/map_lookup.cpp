#include "engine/passes/map_lookup.hpp"

#include <stdexcept>

#include "engine/passes/light_args.hpp"

namespace shadow {

MapLookup map_lookup(const std::vector<LightMap>& maps, const Light& light,
                     const ShadowMapSettings& settings) {
  if (maps.empty()) throw std::logic_error("map_lookup: no map");
  MapLookup out;
  out.lookup = shadow_lookup(maps[0].setup, light, settings);
  out.faces = faces_args(maps[0].setup.faces);
  if (maps[0].pages) {  // every level in map 0's pool
    out.option = "-DVIRTUAL";
    out.pages = maps[0].pages;
  }
  if (!is_cube(maps)) {
    out.maps.fill(maps[0].depth);
    return out;
  }
  out.option = "-DCUBE_FACES";
  for (const LightMap& m : maps)
    for (int k = 0; k < 6; ++k)
      if (m.setup.faces.owned & (1u << k)) {
        out.cube.to_ndc[k] = glm::mat4(m.setup.world_to_ndc);
        out.maps[k] = m.depth;
      }
  for (int k = 0; k < 6; ++k)
    if (!out.maps[k]) throw std::logic_error("map_lookup: a cube face without a map");
  return out;
}

}  // namespace shadow
