// The grid of requests admission's estimates are held to (issue 51): every technique with the
// products it has, every filter, CSM's storages, lookups and products, the atlas filters, and
// maps up to 8192^2. One descriptor drives both the memory test (tests/engine/
// estimate_table_test.cpp: estimate over the buffers' peak within [0.5, 3]) and the time
// benchmark (tests/bench/cost_check.cpp, which adds the large requests).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "scenes/demo_scene.hpp"
#include "scenes/shapes.hpp"
#include "wire/names.hpp"
#include "wire/types.hpp"

namespace shadow::testing {

struct EstimateCase {
  std::string name;
  RenderRequest request;
};

// The demo scene under its sun (1 degree across, for the soft filters), PCSS and Poisson at 64
// taps.
inline RenderRequest demo_request(uint32_t width, uint32_t height, uint32_t map, FilterKind filter,
                                  std::vector<Product> products = {Product::kVisibility}) {
  const scenes::DemoSetup d = scenes::demo_scene();
  RenderRequest r;
  r.scene = std::make_shared<Scene>(d.scene);
  r.camera = d.camera;
  r.camera.width = width;
  r.camera.height = height;
  r.lights = {d.light};
  r.lights[0].size = 1.0f;
  r.shadow_map = d.shadow_map;
  r.shadow_map.size = map;
  r.filter.kind = filter;
  r.filter.pcss.blocker_samples = r.filter.pcss.filter_samples = 64;
  r.filter.poisson.taps = 64;
  r.products = std::move(products);
  return r;
}

// `spheres` spheres over a ground, all receiving in their own UVs (shadow-atlas-bench's scene),
// with the atlas' products and tiles of `tile`.
inline RenderRequest atlas_request(uint32_t width, uint32_t height, FilterKind filter,
                                   uint32_t tile, int spheres) {
  RenderRequest r =
      demo_request(width, height, 2048, filter, {Product::kShadowAtlas, Product::kVisibility});
  auto scene = std::make_shared<Scene>();
  scene->meshes = {scenes::make_grid(24.0f, 8), scenes::make_sphere(32, 16)};
  scene->instances = {Instance{0}};
  for (int i = 0; i < spheres; ++i) {
    Instance s{1};
    s.transform =
        glm::translate(glm::mat4(1.0f), glm::vec3(3 * (i % 4) - 4.5f, 1.5f, 3 * (i / 4) - 3.0f));
    scene->instances.push_back(s);
  }
  r.scene = scene;
  r.shadow_map.fit = MapFit::kScene;
  r.shadow_map.technique = Technique::kUniform;
  r.atlas.tile = tile;
  r.filter.pcss.blocker_samples = 16;
  return r;
}

// At `width` x `height` with `map`^2 maps (cubes at half the edge); CSM's M = 16 at `csm_map`.
inline std::vector<EstimateCase> estimate_grid(uint32_t width, uint32_t height, uint32_t map,
                                               uint32_t csm_map) {
  const std::vector<Product> every = {Product::kShadowMap,      Product::kVisibility,
                                      Product::kPosition,       Product::kTexelDensity,
                                      Product::kShadowMapMips,  Product::kShadowMapSat,
                                      Product::kVisibilityMips, Product::kVisibilitySat};
  std::vector<EstimateCase> out;
  for (Technique t : {Technique::kUniform, Technique::kPsm, Technique::kLispsm, Technique::kAuto}) {
    RenderRequest r = demo_request(width, height, map, FilterKind::kHard, every);
    r.shadow_map.technique = t;
    out.push_back({std::string(names::kTechniques.name(t)) + ", every product", r});
  }
  for (Technique t : {Technique::kCube, Technique::kPsmCube}) {
    RenderRequest r =
        demo_request(width, height, map / 2, FilterKind::kHard,
                     {Product::kShadowMap, Product::kVisibility, Product::kTexelDensity,
                      Product::kVisibilityMips, Product::kVisibilitySat});
    r.lights[0].type = LightType::kPoint;
    r.lights[0].position = {2, 6, 2};
    r.shadow_map.technique = t;
    out.push_back({"point light, " + std::string(names::kTechniques.name(t)), r});
  }
  for (FilterKind f : {FilterKind::kPcf2x2, FilterKind::kPoisson, FilterKind::kPcss,
                       FilterKind::kBlur, FilterKind::kCsm, FilterKind::kPcssCsm}) {
    RenderRequest r = demo_request(width, height, map, f);
    if (f == FilterKind::kBlur) {
      auto classed = std::make_shared<Scene>(*r.scene);
      classed->instances[0].receiver_class = 0;
      r.scene = classed;
    }
    out.push_back({std::string(names::kFilterKinds.name(f)) + ", visibility", r});
  }
  {
    RenderRequest r = demo_request(width, height, map / 2, FilterKind::kCsm);
    r.lights[0].type = LightType::kPoint;
    r.lights[0].position = {2, 6, 2};
    r.filter.csm.terms = 16;
    out.push_back({"point light, cube, csm M16 (a basis per face)", r});
  }
  for (uint32_t terms : {4u, 16u})
    for (CsmStorage storage : {CsmStorage::kFloat32, CsmStorage::kFloat16})
      for (CsmLookup lookup : {CsmLookup::kMips, CsmLookup::kSat}) {
        if (storage == CsmStorage::kFloat16 && lookup == CsmLookup::kSat) continue;
        // The basis as a product at M = 4 only: at M = 16 and 4096^2 it is over a 1 GiB reply.
        RenderRequest r =
            demo_request(width, height, terms == 16 ? csm_map : map, FilterKind::kPcssCsm,
                         {Product::kVisibility, Product::kBlockerDepth, Product::kShadowMapSat});
        if (terms == 4) r.products.push_back(Product::kCsmBasis);
        r.filter.csm.terms = terms;
        r.filter.csm.storage = storage;
        r.filter.csm.lookup = lookup;
        out.push_back({"pcss_csm M" + std::to_string(terms) + " " +
                           std::string(names::kCsmStorages.name(storage)) + " " +
                           std::string(names::kCsmLookups.name(lookup)) + " " +
                           std::to_string(r.shadow_map.size) +
                           (terms == 4 ? ", every CSM product" : ", blocker depth, SAT"),
                       r});
      }
  out.push_back({"pcss 64/64, 8192", demo_request(width, height, 8192, FilterKind::kPcss)});
  out.push_back({"hard, 8192, every map product",
                 demo_request(width, height, 8192, FilterKind::kHard,
                              {Product::kShadowMap, Product::kShadowMapMips, Product::kShadowMapSat,
                               Product::kVisibility})});
  for (FilterKind f : {FilterKind::kAtlasSat, FilterKind::kAtlasMip})
    out.push_back({std::string(names::kFilterKinds.name(f)) + ", 6 spheres, tiles of 256",
                   atlas_request(width, height, f, 256, 6)});
  return out;
}

}  // namespace shadow::testing
