// shadow-csm-images (issue 13): CSM's ringing in rendered images rather than on the
// reconstruction curve. The sphere field (sphere_field.hpp) at 640x360 with a 2048 map, hard
// test and FILTER_CSM at M = 4, 8, 16, with the ringing controls off (damping 0, depth offset 0,
// scale 1) and at their defaults, written as raw floats for scripts/plot_csm_images.py.
//
//   shadow-csm-images DIR
#include <cstdio>
#include <filesystem>
#include <string>

#include "engine/engine.hpp"
#include "sphere_field.hpp"

int main(int argc, char** argv) {
  using namespace shadow;
  if (argc != 2) {
    std::fprintf(stderr, "usage: shadow-csm-images DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::filesystem::create_directories(dir);
  Engine engine;
  RenderRequest req = bench::sphere_field(640, 360, 2048, 256);
  req.filter.kind = FilterKind::kHard;
  bench::write_floats(dir, "hard", engine.render(req).textures.at(0).data);
  req.filter.kind = FilterKind::kCsm;
  for (uint32_t terms : {4u, 8u, 16u}) {
    req.filter.csm = CsmSettings{};
    req.filter.csm.terms = terms;
    char name[32];  // not std::string +: GCC 12 warns falsely of overlap there (-Wrestrict)
    std::snprintf(name, sizeof name, "M%u_controls", terms);
    bench::write_floats(dir, name, engine.render(req).textures.at(0).data);
    req.filter.csm.damping = 0, req.filter.csm.depth_offset = 0, req.filter.csm.scale = 1;
    std::snprintf(name, sizeof name, "M%u_raw", terms);
    bench::write_floats(dir, name, engine.render(req).textures.at(0).data);
  }
  std::printf("wrote %s/{hard,M4_raw,M4_controls,M8_raw,M8_controls,M16_raw,M16_controls}.f32\n",
              dir.c_str());
  return 0;
}
