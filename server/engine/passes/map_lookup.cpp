#include "engine/passes/map_lookup.hpp"

#include <stdexcept>

#include "engine/passes/light_args.hpp"

namespace shadow {
namespace {

// A cube's matrices face by face (zero for the faces not rendered), and the map that owns each
// face; every face must have one.
CubeNdcItem cube_ndc(const std::vector<LightMap>& maps, std::array<const LightMap*, 6>& owner) {
  CubeNdcItem out{};
  owner.fill(nullptr);
  for (const LightMap& m : maps)
    for (int k = 0; k < 6; ++k)
      if (m.setup.faces.owned & (1u << k)) {
        out.to_ndc[k] = glm::mat4(m.setup.world_to_ndc);
        owner[k] = &m;
      }
  for (int k = 0; k < 6; ++k)
    if (!owner[k]) throw std::logic_error("map_lookup: a cube face without a map");
  return out;
}

}  // namespace

MapLookup map_lookup(const std::vector<LightMap>& maps, const Light& light,
                     const ShadowMapSettings& settings) {
  if (maps.empty()) throw std::logic_error("map_lookup: no map");
  MapLookup out;
  out.lookup = shadow_lookup(maps[0].setup, light, settings);
  out.faces = faces_args(maps[0].setup.faces);
  if (!is_cube(maps)) {
    out.maps.fill(maps[0].depth);
    return out;
  }
  out.option = "-DCUBE_FACES";
  std::array<const LightMap*, 6> owner;
  out.cube = cube_ndc(maps, owner);
  const LightMap* rendered = nullptr;
  for (const LightMap& m : maps)
    if (m.version != 0) rendered = &m;
  for (int k = 0; k < 6; ++k)
    out.maps[k] = owner[k]->version != 0 || !rendered ? owner[k]->depth : rendered->depth;
  return out;
}

}  // namespace shadow
