// One light's maps as the per-pixel kernels take them in one launch (pcf.cl, texel_density.cl):
// a single map, or a cube whose faces each decide the camera pixels they own.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "engine/cl/runtime.hpp"
#include "engine/device_types.hpp"
#include "engine/light/light_space.hpp"
#include "wire/types.hpp"

namespace shadow {

// One map: its set-up (which owns some or all pixels) and its depth. A cube gives one per
// rendered face and one for the faces not rendered (owned bits of them all, a zero matrix).
struct VirtualMap;

struct LightMap {
  ViewSetup setup;
  const cl::Buffer* depth = nullptr;
  uint64_t version = 0;  // its RasterOutput's (0: not rendered)
  // A virtual map (issue 53): its levels, pages and pixels' levels; `depth` is the pool and
  // `setup` the finest level's.
  const VirtualMap* pages = nullptr;
};

struct MapLookup {
  ShadowLookupItem lookup{};  // a cube's: every field but to_ndc
  FacesItem faces{};          // how pixels pick their face (a single map: owned = 0)
  CubeNdcItem cube{};         // each face's matrix (a single map: unused)
  // Each face's depth. A face not rendered has the one-float empty map, never read: its zero
  // matrix puts its pixels off every map, and pcf.cl tests a face's map only when some pixel
  // of that face is filtered.
  std::array<const cl::Buffer*, 6> maps{};
  const char* option = "";            // the program variant: "-DCUBE_FACES" for a cube, "-DVIRTUAL"
  const VirtualMap* pages = nullptr;  // a virtual map's
};

MapLookup map_lookup(const std::vector<LightMap>& maps, const Light& light,
                     const ShadowMapSettings& settings);

// Whether `maps` are a cube's faces (each owns some pixels) rather than one map.
inline bool is_cube(const std::vector<LightMap>& maps) {
  return !maps.empty() && maps[0].setup.faces.owned != 0;
}

}  // namespace shadow
