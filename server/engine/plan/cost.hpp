// A request's device time estimated from its plan before anything runs, in milliseconds of this
// 2-core machine (PoCL, AVX-512): a linear model over what drives each step's time. Admission
// prices it at rates that err on the high side, so a server can refuse what would hold a
// workspace for too long; a quality goal at the calibration's typical rates (calibration.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/plan/plan.hpp"

namespace shadow {

// What drives a step's time; a request's cost is its units of each times a rate per unit.
enum class CostRate {
  kTriangle,         // transform, set-up, binning, per triangle per view
  kMapTexel,         // clearing, writing and reading back a map texel
  kTileOverlap,      // a map's raster: one triangle over one 64^2 tile (RasterLoad)
  kBoxPixel,         // a map's raster: one pixel of a triangle's box, in a tile (RasterLoad)
  kViewPixel,        // G-buffer raster and resolve per camera pixel
  kDensityPixel,     // PRODUCT_TEXEL_DENSITY per camera pixel
  kDepthPixel,       // the depth-range reduction (PSM, LiSPSM) per camera pixel
  kTestPixel,        // the hard shadow test per pixel
  kTap,              // one filter tap of one pixel (PCF, Poisson, PCSS, blur, CSM, atlas)
  kPrefilterTexel,   // a mip chain or SAT, per source texel
  kCsmChannelTexel,  // a CSM basis channel per map texel
  kBlockerTap,       // one blocker-search tap of an atlas texel
  kLayoutTriangle,   // UV-unwrapping one triangle on the host
};
inline constexpr size_t kCostRates = size_t(CostRate::kLayoutTriangle) + 1;

// The one name table: "triangle", "map_texel", ... (the calibration table's rate names).
const char* cost_rate_label(CostRate rate);

// What a map's raster costs besides its texels and triangles, which the plan cannot know: where
// the triangles land. A warp that magnifies casters near the eye (PSM, LiSPSM) makes their boxes
// cover many pixels; the raster visits each box pixel of each tile the box overlaps.
// Rasterizer::run measures it, a quality goal's probe predicts it (Rasterizer::load).
struct RasterLoad {
  uint64_t overlaps = 0;    // triangle-tile pairs binned
  uint64_t box_pixels = 0;  // pixels of the triangles' boxes (pixel centres they may cover)
  RasterLoad& operator+=(const RasterLoad& o) {
    overlaps += o.overlaps, box_pixels += o.box_pixels;
    return *this;
  }
  bool operator==(const RasterLoad&) const = default;
};
// Per light, in the request's order: the sum over the light's maps.
using MapLoads = std::vector<RasterLoad>;

// Nanoseconds per unit of each rate.
struct CostRates {
  std::array<double, kCostRates> ns{};
  double operator[](CostRate r) const { return ns[size_t(r)]; }
  double& operator[](CostRate r) { return ns[size_t(r)]; }
};

// Admission's rates: measured on this machine (docs/benchmarks.md, "Admission control") at or
// above the quiet machine's figures, so an admitted request stays under the limit here.
const CostRates& admission_rates();

// One step's units of each rate (Step::name, the prefix of its passes' timing names).
struct StepCost {
  std::string step;
  std::array<double, kCostRates> units{};
};

struct CostEstimate {
  double ms = 0;  // the whole request
  // The device buffers its passes need at least (the scene, its maps, the camera view and the
  // products' own); triangle-tile bins, known only after binning, are left out.
  uint64_t device_bytes = 0;
  std::string driver;  // the largest term, e.g. "visibility.pcss: 33177600 pixels x 128 taps"
  double driver_ms = 0;
  std::vector<StepCost> steps;  // what ms is made of, for fitting rates to measured passes
};

// For a validated request and its plan, at `rates`; its maps' raster load where known (`loads`,
// one per light or none: admission has none, and checks the overlaps after binning).
CostEstimate estimate_cost(const RenderRequest& request, const Plan& plan,
                           const CostRates& rates = admission_rates(), const MapLoads& loads = {});

// Transforming and setting up the request's scene `maps` times without rasterizing
// (Rasterizer::load: a quality goal's probe predicting its candidates' raster loads), at `rates`.
double load_passes_ms(const RenderRequest& request, double maps,
                      const CostRates& rates = admission_rates());

// Throws ResourceExhausted("request cost", ...) naming the estimate, its largest term and the
// limit when the estimate is over `max_ms` (0: no limit), or ResourceExhausted("memory_budget",
// ...) when its device buffers alone are over `budget_bytes`: it could never run.
void admit(const CostEstimate& cost, double max_ms, uint64_t budget_bytes);

// The rasterizer's binning counters (tiles x chunks) are capped at this many: at most 16 MiB.
inline constexpr uint64_t kMaxBinCounters = uint64_t{1} << 22;

// Rasterizing costs per triangle-tile overlap, which only binning knows (a few large triangles
// can cover every tile of an 8192^2 map): the same limit, checked after binning, before the
// raster pass. `overlaps` triangle-tile pairs of kTile^2 texels each.
double raster_overlap_ms(uint64_t overlaps);

}  // namespace shadow
