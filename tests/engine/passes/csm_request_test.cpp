// CSM through Engine::render on the occluder scene (a 2 m square 2 m above the ground under a
// sun straight down): the basis product against sin/cos of the shadow map it came from, the
// blocker depth and visibility where the geometry says what they are, and validation naming
// each field.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/cl/runtime.hpp"
#include "engine/engine.hpp"
#include "engine/passes/csm.hpp"
#include "engine/plan/validate.hpp"
#include "occluder_scene.hpp"

namespace shadow {
namespace {

using testing::engine;

RenderRequest request() {
  RenderRequest r = testing::occluder_request();
  r.camera.width = 160;
  r.camera.height = 120;
  r.shadow_map.size = 256;
  r.lights[0].size = 2.0f;
  r.filter.kind = FilterKind::kPcssCsm;
  r.filter.csm.terms = 4;
  return r;
}

const Texture& find(const RenderResult& r, Product p) {
  for (const Texture& t : r.textures)
    if (t.kind == p) return t;
  throw std::runtime_error("product missing");
}

// Uniform (an orthographic map: linear) and LiSPSM (a warped map: its depth as stored): either
// way the basis' depth is the map's NDC z.
TEST(CsmRequest, BasisIsTheFourierBasisOfTheReturnedMap) {
  for (Technique technique : {Technique::kUniform, Technique::kLispsm})
    for (CsmStorage storage : {CsmStorage::kFloat32, CsmStorage::kFloat16}) {
      RenderRequest r = request();
      r.filter.csm.storage = storage;
      r.shadow_map.technique = technique;
      r.products = {Product::kShadowMap, Product::kCsmBasis};
      if (technique == Technique::kLispsm) {  // no PCSS-CSM there: the blocker depth adds z
        r.filter.kind = FilterKind::kCsm;
        r.products.push_back(Product::kBlockerDepth);
      }
      const RenderResult res = engine().render(r);
      const Texture& map = find(res, Product::kShadowMap);
      const Texture& basis = find(res, Product::kCsmBasis);
      const uint32_t m = 4;
      ASSERT_EQ(basis.channels, 4 * m + 1);  // PCSS-CSM: the z-weighted channels too
      EXPECT_EQ(basis.channel_names.front(), "sin1");
      EXPECT_EQ(basis.channel_names[m], "cos1");
      EXPECT_EQ(basis.channel_names[2 * m], "zsin1");
      EXPECT_EQ(basis.channel_names.back(), "z");
      EXPECT_EQ(basis.csm_terms, m);
      EXPECT_EQ(basis.csm_storage, storage);
      EXPECT_EQ(
          basis.depth_mapping.rfind(technique == Technique::kUniform ? "linear" : "stored", 0), 0u)
          << basis.depth_mapping;
      EXPECT_EQ(basis.world_to_ndc, map.world_to_ndc);
      double err = 0;
      for (size_t t = 0; t < map.data.size(); ++t) {
        const double z = 0.5 * map.data[t];  // directional: the linear depth is the NDC z, halved
        const float* c = &basis.data[t * basis.channels];
        for (uint32_t k = 1; k <= m; ++k) {
          const double ck = M_PI * (2.0 * k - 1);
          err = std::max({err, std::abs(c[k - 1] - std::sin(ck * z)),
                          std::abs(c[m + k - 1] - std::cos(ck * z)),
                          std::abs(c[3 * m + k - 1] - z * std::cos(ck * z))});
        }
        err = std::max(err, std::abs(c[4 * m] - z));
      }
      std::printf("basis product (%s, %s) vs the map: max |error| %.3g\n",
                  technique == Technique::kUniform ? "uniform" : "lispsm",
                  storage == CsmStorage::kFloat16 ? "float16" : "float32", err);
      EXPECT_LT(err, storage == CsmStorage::kFloat16 ? 5e-4 : 5e-6);  // measured 2.4e-4, 1.2e-6
    }
}

TEST(CsmRequest, BlockerDepthAndVisibilityFollowTheGeometry) {
  RenderRequest r = request();
  r.products = {Product::kVisibility, Product::kBlockerDepth, Product::kPosition};
  const RenderResult res = engine().render(r);
  const std::vector<float>& vis = res.textures[0].data;
  const std::vector<float>& blocker = res.textures[1].data;
  const std::vector<float>& pos = res.textures[2].data;
  size_t under = 0, open = 0;
  for (size_t p = 0; p < vis.size(); ++p) {
    const float x = pos[3 * p], y = pos[3 * p + 1], z = pos[3 * p + 2];
    if (std::isnan(x)) {
      EXPECT_TRUE(std::isnan(vis[p]) && std::isnan(blocker[p])) << p;
      continue;
    }
    ASSERT_TRUE(std::isfinite(vis[p]) && std::isfinite(blocker[p])) << p;
    EXPECT_GE(blocker[p], 0.0f);
    EXPECT_LE(blocker[p], 1.0f);
    if (y > 0.5f) continue;  // the occluder itself
    // The map's depth runs from the occluder (0) to the ground (1).
    if (std::abs(x) < 0.5f && std::abs(z) < 0.5f) {
      ++under;
      EXPECT_LT(vis[p], 0.02f) << x << "," << z;
      EXPECT_LT(blocker[p], 0.05f) << x << "," << z;
    } else if (std::abs(x) > 2.5f || std::abs(z) > 2.5f) {
      ++open;
      // The ground's own texels sit within the series' transition (offset 0.25 / M): they read
      // a little occluded (measured 0.980) and count as their own blocker, at the offset
      // receiver depth 1 - 0.25 / 4 (measured 0.936).
      EXPECT_GT(vis[p], 0.97f) << x << "," << z;
      EXPECT_GT(blocker[p], 0.93f) << x << "," << z;
    }
  }
  EXPECT_GT(under, 20u);  // 32 at 160 x 120
  EXPECT_GT(open, 1000u);
}

std::string field_of(const RenderRequest& r) {
  return testing::refused_field(r);
}

// The field validation refuses `r` for under a per-buffer limit of `max_buffer_bytes` (as
// refused_field names it), without rendering.
std::string field_within(const RenderRequest& r, uint64_t max_buffer_bytes) {
  try {
    validate(r, Limits{EngineOptions{}.max_output_bytes, max_buffer_bytes});
  } catch (const InvalidArgument& e) {
    return e.field();
  } catch (const ResourceExhausted& e) {
    return "exhausted: " + e.field();
  }
  return "(accepted)";
}

uint64_t device_buffer_limit() {
  static const uint64_t limit = cl::Device().max_alloc_bytes();
  return limit;
}

TEST(CsmRequest, InvalidSettingsNameTheirField) {
  RenderRequest r = request();
  r.products = {Product::kVisibility};
  r.filter.csm.terms = 0;
  EXPECT_EQ(field_of(r), "filter.pcss_csm.terms");
  r.filter.kind = FilterKind::kCsm;
  r.filter.csm.terms = 17;
  EXPECT_EQ(field_of(r), "filter.csm.terms");
  r.filter.csm.terms = 8;
  for (float w : {0.0f, -1.0f, 0.5f, NAN}) {
    r.filter.csm.window = w;
    EXPECT_EQ(field_of(r), "filter.csm.window") << w;
  }
  r.filter.csm.window = 4;
  r.filter.csm.damping = -1;
  EXPECT_EQ(field_of(r), "filter.csm.damping");
  r.filter.csm.damping = 1;
  r.filter.csm.depth_offset = 17;
  EXPECT_EQ(field_of(r), "filter.csm.depth_offset");
  r.filter.csm.depth_offset = 0.5f;
  r.filter.csm.scale = 0.5f;
  EXPECT_EQ(field_of(r), "filter.csm.scale");
  r.filter.csm.scale = 1;
  r.filter.kind = FilterKind::kPcssCsm;
  r.lights[0].size = 0;
  EXPECT_EQ(field_of(r), "lights[0].size");  // soft shadows need an area light
  r.lights[0].size = 2;
  r.shadow_map.technique = Technique::kPsm;
  EXPECT_EQ(field_of(r), "shadow_map.technique");
  r.shadow_map.technique = Technique::kUniform;
  r.filter.kind = FilterKind::kHard;
  r.products = {Product::kVisibility, Product::kCsmBasis};
  EXPECT_EQ(field_of(r), "products[1]");  // the basis takes the CSM filter's settings
  r.products = {Product::kBlockerDepth};
  EXPECT_EQ(field_of(r), "products[0]");
  // Cube faces: FILTER_CSM with a window their guard band holds (3 x the window: 42 texels at
  // 1024^2); no PCSS-CSM; no basis or blocker depth product (one per face).
  RenderRequest cube = request();
  cube.lights[0].type = LightType::kPoint;
  cube.lights[0].position = {0, 3, 0};
  cube.shadow_map.size = 1024;
  cube.products = {Product::kVisibility};
  EXPECT_EQ(field_of(cube), "filter.pcss_csm");
  cube.filter.kind = FilterKind::kCsm;
  cube.filter.csm.window = 43;
  EXPECT_EQ(field_of(cube), "filter.csm.window");
  cube.filter.csm.window = 42;
  EXPECT_EQ(field_of(cube), "(accepted)");
  cube.products = {Product::kVisibility, Product::kCsmBasis};
  EXPECT_EQ(field_of(cube), "products[1]");
  cube.products = {Product::kBlockerDepth};
  EXPECT_EQ(field_of(cube), "products[0]");
  // PSM and LiSPSM take FILTER_CSM but not PCSS-CSM.
  r.shadow_map.technique = Technique::kPsm;
  r.filter.kind = FilterKind::kCsm;
  r.products = {Product::kVisibility, Product::kCsmBasis};
  EXPECT_EQ(field_of(r), "(accepted)");
  r.filter.kind = FilterKind::kPcssCsm;
  EXPECT_EQ(field_of(r), "shadow_map.technique");
  r.shadow_map.technique = Technique::kUniform;
  // M = 16 float32 at 8192^2: 5.7 GB per family. Refused by name over a per-buffer limit below
  // that, and by this device's own limit where it is below (PoCL's 4 GiB; not a 140 GB GPU's).
  r.filter.kind = FilterKind::kCsm;
  r.filter.csm.terms = 16;
  r.shadow_map.size = 8192;
  r.products = {Product::kVisibility};
  const uint64_t mips16 = csm_family_bytes(8192, 16, false, CsmPrefilter::kMips);
  EXPECT_EQ(field_within(r, mips16 - 1), "exhausted: filter.csm.terms");
  EXPECT_EQ(field_within(r, mips16), "(accepted)");
  if (mips16 > device_buffer_limit()) {
    EXPECT_EQ(field_of(r), "exhausted: filter.csm.terms");
  }
  // The SAT lookup: float32 only; its tables take 8 bytes a channel texel: at M = 12 and
  // 8192^2 a family's SAT is 6.4 GB where its mips take 4.3 GB.
  r.filter.csm.lookup = CsmLookup::kSat;
  r.filter.csm.storage = CsmStorage::kFloat16;
  EXPECT_EQ(field_of(r), "filter.csm.storage");
  r.filter.csm.storage = CsmStorage::kFloat32;
  r.filter.csm.terms = 12;
  const uint64_t sat12 = csm_family_bytes(8192, 12, false, CsmPrefilter::kSat);
  EXPECT_EQ(field_within(r, sat12 - 1), "exhausted: filter.csm.terms");
  EXPECT_EQ(field_within(r, sat12), "(accepted)");
  if (sat12 > device_buffer_limit()) {
    EXPECT_EQ(field_of(r), "exhausted: filter.csm.terms");
  }
  EXPECT_EQ(csm_family_bytes(8192, 12, false, CsmPrefilter::kSat), uint64_t{8192} * 8192 * 12 * 8);
  EXPECT_LT(csm_family_bytes(8192, 12, false, CsmPrefilter::kMips),
            csm_family_bytes(8192, 12, false, CsmPrefilter::kSat));
}

}  // namespace
}  // namespace shadow
