// shadow-bench's "light facing the camera" section (issue 5): uniform, PSM and PSM_CUBE at about
// the same total texel count on the views whose light faces the camera, side by side.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "case.hpp"

namespace shadow::bench {

inline constexpr const char* kFacingView = "light_facing_camera";

// The variants compared: uniform 2048 and psm 2048 (2048^2 = 4.19 M texels), and psm_cube with
// faces of kPsmCubeFaceSize (5 faces x 912^2 = 4.16 M; 3 faces 2.5 M, 6 faces 5.0 M: the count
// depends on the light, so each row gives its own total).
inline constexpr int kPsmCubeFaceSize = 912;
std::vector<std::string> facing_variants();

// Writes the section's markdown (nothing when no case is on a facing view).
void write_facing_section(const std::vector<Case>& cases, std::ostream& md);

}  // namespace shadow::bench
