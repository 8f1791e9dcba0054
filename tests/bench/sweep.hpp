// The fixed sweep of requests that product-hashes and cost-check run: every standard scene view
// with each technique and filter, asking for every product, and the demo scene.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "oracle/standard_scenes.hpp"
#include "scenes/demo_scene.hpp"
#include "wire/types.hpp"

namespace shadow::bench {

struct SweepVariant {
  const char* name;
  Technique technique;
  uint32_t size;
  FilterKind filter;
};

inline const SweepVariant kSweepVariants[] = {
    {"uniform 1024", Technique::kUniform, 1024, FilterKind::kHard},
    {"cube 1024", Technique::kCube, 1024, FilterKind::kHard},
    {"psm 1024", Technique::kPsm, 1024, FilterKind::kHard},
    {"psm_cube 512", Technique::kPsmCube, 512, FilterKind::kHard},
    {"pcf2x2 1024", Technique::kUniform, 1024, FilterKind::kPcf2x2},
    {"poisson 1024", Technique::kUniform, 1024, FilterKind::kPoisson},
    {"pcss 1024", Technique::kUniform, 1024, FilterKind::kPcss},
    {"blur 1024 ground", Technique::kUniform, 1024, FilterKind::kBlur},
    {"psm pcf2x2 1024", Technique::kPsm, 1024, FilterKind::kPcf2x2},
    {"pcss_csm 1024", Technique::kUniform, 1024, FilterKind::kPcssCsm},
};

inline const std::vector<Product> kAllProducts = {
    Product::kShadowMap,      Product::kVisibility,    Product::kPosition,
    Product::kTexelDensity,   Product::kShadowMapMips, Product::kShadowMapSat,
    Product::kVisibilityMips, Product::kVisibilitySat};
// Cube maps have no mips or SATs.
inline const std::vector<Product> kCubeProducts = {
    Product::kShadowMap,    Product::kVisibility,     Product::kPosition,
    Product::kTexelDensity, Product::kVisibilityMips, Product::kVisibilitySat};

// Calls `run(name, request)` for every case, in a fixed order.
inline void for_each_sweep_case(
    const std::function<void(const std::string&, const RenderRequest&)>& run) {
  for (const scenes::StandardScene& sc : scenes::standard_scenes()) {
    auto classed = std::make_shared<Scene>(*sc.scene);
    classed->instances[0].receiver_class = 0;  // the ground, for the blur
    for (const scenes::View& view : sc.views)
      for (const SweepVariant& v : kSweepVariants) {
        RenderRequest req;
        req.scene = v.filter == FilterKind::kBlur ? classed : sc.scene;
        req.camera = view.camera;
        req.lights = {view.light};
        req.shadow_map.technique = v.technique;
        req.shadow_map.size = v.size;
        req.filter.kind = v.filter;
        req.products = v.technique == Technique::kCube || v.technique == Technique::kPsmCube
                           ? kCubeProducts
                           : kAllProducts;
        run(sc.name + "/" + view.name + "/" + v.name, req);
      }
  }
  const scenes::DemoSetup demo = scenes::demo_scene();
  RenderRequest req;
  req.scene = std::make_shared<Scene>(demo.scene);
  req.camera = demo.camera;
  req.lights = {demo.light};
  req.shadow_map = demo.shadow_map;
  req.products = kAllProducts;
  run("demo", req);
}

}  // namespace shadow::bench
