// Admission control: a request's cost estimated from its plan before anything runs, in
// milliseconds of this 2-core machine (PoCL, AVX-512), so a server can refuse what would hold a
// workspace for too long. A linear model over what drives each step's time; its coefficients are
// measured (docs/benchmarks.md, "Admission control") and err on the high side.
#pragma once

#include <cstdint>
#include <string>

#include "engine/plan.hpp"

namespace shadow {

struct CostEstimate {
  double ms = 0;  // the whole request
  // The device buffers its passes need at least (the scene, its maps, the camera view and the
  // products' own); triangle-tile bins, known only after binning, are left out.
  uint64_t device_bytes = 0;
  std::string driver;  // the largest term, e.g. "visibility.pcss: 33177600 pixels x 128 taps"
  double driver_ms = 0;
};

// For a validated request and its plan.
CostEstimate estimate_cost(const RenderRequest& request, const Plan& plan);

// Throws ResourceExhausted("request cost", ...) naming the estimate, its largest term and the
// limit when the estimate is over `max_ms` (0: no limit), or ResourceExhausted("memory_budget",
// ...) when its device buffers alone are over `budget_bytes`: it could never run.
void admit(const CostEstimate& cost, double max_ms, uint64_t budget_bytes);

// Rasterizing costs per triangle-tile overlap, which only binning knows (a few large triangles
// can cover every tile of an 8192^2 map): the same limit, checked after binning, before the
// raster pass. `overlaps` triangle-tile pairs of kTile^2 texels each.
double raster_overlap_ms(uint64_t overlaps);

}  // namespace shadow
