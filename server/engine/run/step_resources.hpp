// What the plan's steps hand one another (engine/plan/plan.hpp declares each step's reads and
// writes): the resources the shared steps write once per request, and those each light's steps
// write, which start empty for every light. The runner keeps them here, and the ledger checks the
// plan's declarations as it goes: a step never runs before what it reads was written.
#pragma once

#include <bitset>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "engine/light/psm_fit.hpp"
#include "engine/passes/csm.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/passes/summed_area.hpp"
#include "engine/plan/plan.hpp"
#include "engine/run/light_fitter.hpp"

namespace shadow {

// Which resources the steps run so far wrote: the shared steps' for the whole request, a
// light's from its first step to the next light's. Pure: tests walk plans through it.
class StepLedger {
 public:
  // Enters `step`: true when it is the first of a light other than the current one (the light's
  // resources start empty). Throws std::logic_error naming the step and the resource when the
  // step reads one that no step before it wrote.
  bool enter(const Step& step);
  // The step entered last is done: its writes are there for the steps after it.
  void done(const Step& step);
  bool written(Resource r, bool shared) const;
  uint32_t light() const { return light_; }

 private:
  std::bitset<kResourceCount> shared_, light_written_;
  uint32_t light_ = 0;
};

// The shared steps' resources (is_shared): written once, read by every light.
struct SharedResources {
  const GBuffer* view = nullptr;        // kCameraView
  std::optional<DepthRange> measured;   // kDepthRange (none where no receiver is seen)
  const GBuffer* atlas_view = nullptr;  // kAtlasView
  // kPageTable: the request's virtual pages, summed over its lights (the pool is shared).
  std::optional<VirtualPageCounts> virtual_pages;
};

// One light's resources; every light starts with none.
struct LightResources {
  LightPlan fit;               // kLightFit
  std::vector<LightMap> maps;  // kLightFit's set-ups, then kLightMaps' rasterized maps
  // The single map (kLightMaps; null for a cube) and how many draws it drew.
  const RasterOutput* single_map = nullptr;
  uint32_t single_map_draws = 0;
  bool map_from_probe = false;                        // the map is the quality probe's
  const cl::Buffer* blurred = nullptr;                // kBlurPlanes
  const CsmBasis* csm_basis = nullptr;                // kCsmBasis (a cube's: the last face's)
  const cl::Buffer* visibility = nullptr;             // kVisibility
  const cl::Buffer* density = nullptr;                // kTexelDensity
  std::map<Resource, const MipChain*> chains;         // kMapMips, kVisibilityMips, kAtlasMips
  std::map<Resource, const SummedAreaTable*> tables;  // kMapSat, kVisibilitySat, kAtlasSat
  const cl::Buffer* atlas = nullptr;                  // kAtlas
  uint64_t atlas_key = 0;  // the atlas' step key: its prefilters and soft atlas key on it
  const VirtualMap* pages = nullptr;  // kPageTable
};

}  // namespace shadow
