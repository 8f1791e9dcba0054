// shadow-bench's "equal texels" section (issues 5 and 17): uniform, PSM, PSM_CUBE and LiSPSM at
// about the same total texel count on every view, side by side, overall and near the viewer;
// and TECHNIQUE_AUTO's pick against the best of them.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "case.hpp"
#include "frames.hpp"

namespace shadow::bench {

// The variants compared: uniform 2048, psm 2048 and lispsm 2048 (2048^2 = 4.19 M texels), and
// psm_cube with faces of kPsmCubeFaceSize (5 faces x 912^2 = 4.16 M; 3 faces 2.5 M, 6 faces
// 5.0 M: the count depends on the light, so each row gives its own total).
inline constexpr int kPsmCubeFaceSize = 912;
std::vector<std::string> equal_texel_variants();

// Writes the section's markdown: a summary per variant over the views where all of them ran,
// then a row per view and variant (nothing when no compared variant ran).
void write_equal_texel_section(const std::vector<Case>& cases, std::ostream& md);

// TECHNIQUE_AUTO at the equal-texel variants' size, and whether `variant` is it or one of them.
inline constexpr const char* kAutoVariant = "auto 2048";
bool compared_with_auto(const std::string& variant);

// AUTO's pick against the best of the equal-texel variants per view: what it picked and the
// predicted texel footprints (its light case), its misclassified rate beside the best fixed
// one's, overall and near; then over the view and its nudged frames (frames.hpp) the mean of
// each and the standard error of their paired difference (nothing when AUTO did not run).
void write_auto_section(const std::vector<Case>& cases, const std::vector<FrameError>& frames,
                        std::ostream& md);

}  // namespace shadow::bench
