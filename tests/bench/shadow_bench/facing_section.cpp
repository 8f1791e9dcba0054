#include "facing_section.hpp"

#include <algorithm>
#include <cstdio>

namespace shadow::bench {

std::vector<std::string> facing_variants() {
  return {"uniform 2048", "psm 2048", "psm_cube " + std::to_string(kPsmCubeFaceSize)};
}

namespace {

// "1/1843 .. 1/1024", or "" when the case drew no PSM cube.
std::string texel_range(const Case& c) {
  if (c.cube_texel_min <= 0 || c.cube_texel_max <= 0) return "";
  char s[64];
  std::snprintf(s, sizeof s, "1/%.0f .. 1/%.0f", 1 / c.cube_texel_min, 1 / c.cube_texel_max);
  return s;
}

}  // namespace

void write_facing_section(const std::vector<Case>& cases, std::ostream& md) {
  const std::vector<std::string> variants = facing_variants();
  // The cases come in bench order: by scene, then in variant order (uniform, psm, psm_cube).
  std::vector<const Case*> rows;
  for (const Case& c : cases) {
    if (c.view == kFacingView &&
        std::find(variants.begin(), variants.end(), c.variant) != variants.end())
      rows.push_back(&c);
  }
  if (rows.empty()) return;
  md << "\n## Light facing the camera: uniform, PSM and PSM_CUBE at equal texel count\n\n"
        "The `"
     << kFacingView
     << "` views (Kozlov 14.2: plain PSM degrades when the light faces the camera; the cube "
        "approach should not). Maps = the maps the server drew (the rendered cube faces, else "
        "1), texels = maps x size^2; a PSM cube that fell back to the one PSM map says so in "
        "its light case. Cube texels: the texel sizes the PSM cube achieved, as fractions of "
        "the unit cube's edge. Near = misclassified rate in the nearest distance band ("
     << (rows.front()->bands.empty() ? std::string("none") : rows.front()->bands.front().label())
     << ").\n\n"
        "| scene | variant | light case | maps | texels (M) | cube texels | wall ms | device ms "
        "| MAE | misclass. | near misclass. |\n"
        "|---|---|---|---:|---:|---|---:|---:|---:|---:|---:|\n";
  char line[768];
  for (const Case* c : rows) {
    const double near = c->bands.empty() ? 0.0 : c->bands.front().error.misclassified_rate();
    std::snprintf(line, sizeof line,
                  "| %s | %s | %s | %u | %.2f | %s | %.1f | %.1f | %.5f | %.3f%% | %.3f%% |\n",
                  c->scene.c_str(), c->variant.c_str(), c->light_case.c_str(), c->map_faces,
                  double(c->map_texels) / 1e6, texel_range(*c).c_str(), c->wall_median,
                  c->device_ms, c->error.mae, 100 * c->error.misclassified_rate(), 100 * near);
    md << line;
  }
}

}  // namespace shadow::bench
