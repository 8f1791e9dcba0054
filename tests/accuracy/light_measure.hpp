// What the PSM and LiSPSM oracle tests share: the test scene under a light at an angle to the
// view, and one render measured against the Embree oracle (the map's depth through its own
// matrix, visibility against shadow rays from the engine's surface points, per distance band).
// PSM_DEBUG=1 splits the misses; PSM_SLOPE / PSM_CONST override the biases; PSM_DEPTH_DEBUG=1
// splits the depth disagreements by size and by whether they sit at a depth edge.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "oracle/metrics.hpp"
#include "oracle/oracle.hpp"
#include "oracle/scenes.hpp"
#include "wire/types.hpp"

namespace shadow::accuracy {

// The test scene seen from low over its edge (a street-like view), far = 60, far/near as given;
// the light's travel at `angle_deg` from the view direction (0 = along it, from behind), turned
// towards "down and to the side" so that it still reaches the ground at mid angles. With
// `behind_wall`, a wall behind the camera whose shadow falls into view.
scenes::Setup angled_setup(double angle_deg, double far_over_near, bool behind_wall);

struct Measured {
  oracle::DepthAgreement depth;
  oracle::VisibilityError vis;
  std::vector<oracle::DistanceBand> bands;  // vis split by distance from the eye
  std::string light_case;
  size_t shadowed = 0;  // oracle pixels in shadow
  size_t acne = 0;      // engine dark, oracle lit
  size_t leak = 0;      // engine lit, oracle dark (missing shadow, peter-panning)
  // Aliasing measure (TEXEL_DENSITY: a texel's footprint in pixels), median per distance band
  // (<10 m, 10-50 m, >=50 m); only when asked for.
  std::vector<double> density_median;
  LightFitReport fit;
};

using Tweak = std::function<void(RenderRequest&)>;

// Renders the map, visibility and positions (and texel density) and measures them; checks that
// every matrix, texel and reported number is finite.
Measured measure(const scenes::Setup& s, const oracle::RayOracle& oracle, Technique technique,
                 PsmCasters casters, uint32_t map_size, bool with_depth, const Tweak& tweak = {},
                 bool with_density = false);

// The misclassified rate per distance band, for printing.
std::string bands(const Measured& m);

}  // namespace shadow::accuracy
