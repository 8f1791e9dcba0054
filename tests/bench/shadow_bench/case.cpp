#include "case.hpp"

#include <algorithm>

namespace shadow::bench {

void set_map_report(Case& c, const LightFitReport& fit, uint32_t map_size) {
  c.light_case = fit.light_case;
  c.map_faces = 1;
  if (!fit.cube_faces.empty()) {
    c.map_faces = uint32_t(std::count_if(fit.cube_faces.begin(), fit.cube_faces.end(),
                                         [](const CubeFaceReport& f) { return f.rendered; }));
  }
  c.map_texels = uint64_t{c.map_faces} * map_size * map_size;
  c.cube_texel_min = fit.cube_texel_min;
  c.cube_texel_max = fit.cube_texel_max;
}

}  // namespace shadow::bench
