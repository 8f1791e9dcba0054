// The planner: a validated request -> the passes its products need, in the order they run, and
// the device resources each reads and writes. Pure (no OpenCL): tests assert request -> plan
// without a device, and the workspace runs the plan step by step (engine/run/workspace.hpp).
// Techniques and filters add steps through their own small tables here, not through switches
// in the runner; readback is the plan's last step.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/plan/filter.hpp"
#include "wire/types.hpp"

namespace shadow {

// What a step produces on the device for later steps (and readback) to use.
enum class Resource {
  kScene,         // the scene's vertices and indices, checked
  kCameraView,    // G-buffer: world position and normal per camera pixel
  kDepthRange,    // the visible receivers' depth range (PSM's near plane)
  kLightFit,      // the light's matrices: one map or cube faces
  kLightMaps,     // the rasterized depth of the map or of each rendered face
  kBlurPlanes,    // the blurred receiver-class planes (the blur filter)
  kVisibility,    // the filtered shadow test per camera pixel
  kTexelDensity,  // texel footprint per camera pixel
  kMapMips,       // mip chains and summed-area tables of the map and of the visibility
  kMapSat,
  kVisibilityMips,
  kVisibilitySat,
  kCsmBasis,      // the CSM Fourier basis of the map (and its mips when a lookup reads it)
  kBlockerDepth,  // the CSM blocker average per camera pixel (written by the visibility step)
  kAtlasView,     // the receiving instances' surfaces in their UV tiles (a G-buffer)
  kAtlas,         // the filtered shadow test of every atlas texel, with its gutter
  kAtlasMips,     // its mip chain and its SAT (with coverage)
  kAtlasSat,
  kAtlasSoft,  // the atlas filters' soft visibility of every atlas texel
  kPageTable,  // a virtual map's pages the camera reads, their pool slots, each pixel's level
};
inline constexpr size_t kResourceCount = size_t(Resource::kPageTable) + 1;  // the last, above

enum class StepKind {
  kUploadScene,
  kCameraView,
  kDepthRange,
  kFitLight,
  kVirtualPages,  // marks and allocates a virtual map's pages (issue 53)
  kRenderMaps,
  kBlurPlanes,
  kVisibility,
  kTexelDensity,
  kMips,  // of the step's one read resource (map or visibility)
  kSat,
  kCsmBasis,
  kAtlasView,
  kAtlasVisibility,
  kAtlasSoften,  // the atlas filters' blocker search and prefiltered lookup at every atlas texel
  kReadback,
};

struct Step {
  StepKind kind;
  // The prefix of its passes' timing names, e.g. "shadow_map", "visibility.pcf"; with several
  // lights a light's own steps start with "light<i>.".
  std::string name;
  std::vector<Resource> reads;
  std::vector<Resource> writes;
  // The light whose resources it reads and writes (an index in RenderRequest::lights); 0 for the
  // scene and the camera view, which every light shares.
  uint32_t light = 0;
};

// How the CSM basis is prefiltered for its lookups (CsmSettings::lookup), if any reads it.
enum class CsmPrefilter { kNone, kMips, kSat };

struct Plan {
  std::vector<Step> steps;
  // The blur filter's receiver classes: one plane per class up to the highest one used (0: no
  // class receivers, so the blur filter leaves the hard test as it is).
  uint32_t blur_planes = 0;
  // The CSM basis: with the z-weighted channels (PCSS-CSM or the blocker depth asked for), and
  // prefiltered as its lookups read it, if a CSM filter looks it up.
  bool csm_blocker = false;
  CsmPrefilter csm_prefilter = CsmPrefilter::kNone;

  bool has(StepKind kind) const;
  std::vector<std::string> step_names() const;
};

// The steps for a validated request: the scene and the camera view once, then each light's steps
// in turn, each light's ending with the readback of its products.
Plan make_plan(const RenderRequest& request);

// The steps every light shares (the scene, the camera view and its depth range, the atlas'
// surfaces): planned once, with no light prefix.
bool is_shared(StepKind kind);

// Whether TECHNIQUE_AUTO may draw a one-light request's light as a PSM cube (auto_pick.hpp): a
// directional or spot light filtered by a lookup that cube faces serve (hard, 2x2, Poisson,
// CSM), with no atlas and no light-space product, which are one map of the requested size.
bool auto_may_cube(const RenderRequest& one);

}  // namespace shadow
