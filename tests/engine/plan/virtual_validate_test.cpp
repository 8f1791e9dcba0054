// Validation of TECHNIQUE_VIRTUAL requests (issue 53), without a device: a level's edge, the
// pool and the LOD bias, the filters and products virtual maps take, and the lights they draw.
// Each refusal names its field.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "validation_error.hpp"

namespace shadow {
namespace {

// One triangle under the default sun, drawn with a virtual map: accepted as it is.
RenderRequest virtual_request() {
  RenderRequest r = one_triangle_request();
  r.shadow_map.technique = Technique::kVirtual;
  r.shadow_map.size = 16384;
  r.products = {Product::kVisibility, Product::kPosition};
  return r;
}

// Whether the request is refused naming `field` and saying `why`.
::testing::AssertionResult refused(const RenderRequest& r, const std::string& field,
                                   const std::string& why = "") {
  const std::string error = validation_error(r);
  if (error.rfind(field + ": ", 0) == 0 && error.find(why) != std::string::npos)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got \"" << error << "\"";
}

TEST(VirtualValidation, MapSizeIsAPowerOfTwoFrom2048To32768) {
  RenderRequest r = virtual_request();
  for (uint32_t size : {2048u, 4096u, 16384u, 32768u}) {
    r.shadow_map.size = size;
    EXPECT_EQ(validation_error(r), "(accepted)") << size;
  }
  for (uint32_t size : {256u, 1024u, 2047u, 3000u, 12288u, 32769u, 65536u}) {
    r.shadow_map.size = size;
    EXPECT_TRUE(refused(r, "shadow_map.size", "a power of two from 2048 to 32768")) << size;
  }
  // The other techniques keep 256..8192.
  r.shadow_map.technique = Technique::kUniform;
  r.shadow_map.size = 16384;
  EXPECT_TRUE(refused(r, "shadow_map.size", "must be in [256, 8192]"));
  r.shadow_map.size = 8192;
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.shadow_map.size = 3000;  // not a power of two: fine for a dense map
  EXPECT_EQ(validation_error(r), "(accepted)");
}

TEST(VirtualValidation, PoolPagesFrom1To16384) {
  RenderRequest r = virtual_request();
  for (uint32_t pages : {1u, 1024u, 16384u}) {
    r.shadow_map.virtual_pool_pages = pages;
    EXPECT_EQ(validation_error(r), "(accepted)") << pages;
  }
  for (uint32_t pages : {0u, 16385u, 4000000000u}) {
    r.shadow_map.virtual_pool_pages = pages;
    EXPECT_TRUE(refused(r, "shadow_map.virtual_pool_pages", "[1, 16384]")) << pages;
  }
  // Out of range is refused with any technique, as the PSM and LiSPSM settings are.
  r.shadow_map.technique = Technique::kUniform;
  r.shadow_map.size = 2048;
  EXPECT_TRUE(refused(r, "shadow_map.virtual_pool_pages"));
}

TEST(VirtualValidation, LodBiasFiniteWithin4) {
  RenderRequest r = virtual_request();
  for (float bias : {-4.0f, -0.5f, 0.0f, 1.0f, 4.0f}) {
    r.shadow_map.virtual_lod_bias = bias;
    EXPECT_EQ(validation_error(r), "(accepted)") << bias;
  }
  for (float bias : {NAN, INFINITY, -INFINITY, 5.0f, -4.5f, 4.001f}) {
    r.shadow_map.virtual_lod_bias = bias;
    EXPECT_TRUE(refused(r, "shadow_map.virtual_lod_bias", "finite and in [-4, 4]")) << bias;
  }
}

TEST(VirtualValidation, FiltersOutsideThePageTableAreRefusedByName) {
  RenderRequest r = virtual_request();
  r.lights[0].size = 0.5f;  // the soft filters' light size: not what refuses them
  for (FilterKind k : {FilterKind::kHard, FilterKind::kPcf2x2, FilterKind::kPoisson}) {
    r.filter.kind = k;
    EXPECT_EQ(validation_error(r), "(accepted)") << int(k);
  }
  // Poisson's taps reach at most kMaxReach texels of a pixel's level: the pages marking gives.
  r.filter.kind = FilterKind::kPoisson;
  r.filter.poisson.radius = 15;
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.filter.poisson.radius = 15.5f;
  EXPECT_TRUE(refused(r, "filter.poisson.radius", "must be <= 15 texels with TECHNIQUE_VIRTUAL"));
  r.filter.poisson.radius = 200;
  EXPECT_TRUE(refused(r, "filter.poisson.radius", "must be <= 15 texels with TECHNIQUE_VIRTUAL"));
  // PCSS reads a level chosen for its blocker search, for a sun and a spot light; a point light's
  // faces refuse it as cube faces do.
  r.filter.kind = FilterKind::kPcss;
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.lights[0].type = LightType::kSpot;
  r.lights[0].position = {0, 5, 0};
  r.lights[0].cone_angle_deg = 60;
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.lights[0].type = LightType::kPoint;
  EXPECT_TRUE(
      refused(r, "filter.pcss", "is not available with cube maps, a virtual point light's"));
  r = virtual_request();
  r.lights[0].size = 0.5f;
  r.filter.kind = FilterKind::kBlur;
  EXPECT_TRUE(refused(r, "filter.blur", "use pcss for soft shadows with virtual maps"));
  const char* prefiltered =
      "a prefiltered product (mips, SAT, CSM basis) or the atlas has no "
      "virtual design";
  r.filter.kind = FilterKind::kCsm;
  EXPECT_TRUE(refused(r, "filter.csm", prefiltered));
  r.filter.kind = FilterKind::kPcssCsm;
  EXPECT_TRUE(refused(r, "filter.pcss_csm", prefiltered));
  r.filter.kind = FilterKind::kAtlasSat;
  EXPECT_TRUE(refused(r, "filter.atlas_sat", prefiltered));
  r.filter.kind = FilterKind::kAtlasMip;
  EXPECT_TRUE(refused(r, "filter.atlas_mip", prefiltered));
  // The same PCSS request with a uniform map is accepted.
  r.filter.kind = FilterKind::kPcss;
  r.shadow_map.technique = Technique::kUniform;
  r.shadow_map.size = 2048;
  EXPECT_EQ(validation_error(r), "(accepted)");
}

TEST(VirtualValidation, DenseMapProductsAreRefusedByName) {
  RenderRequest r = virtual_request();
  r.products = {Product::kVisibility, Product::kShadowMap};
  EXPECT_TRUE(refused(r, "products[1]",
                      "PRODUCT_SHADOW_MAP is not available with "
                      "TECHNIQUE_VIRTUAL"));
  const std::pair<Product, const char*> prefiltered[] = {
      {Product::kShadowMapMips, "PRODUCT_SHADOW_MAP_MIPS"},
      {Product::kShadowMapSat, "PRODUCT_SHADOW_MAP_SAT"},
      {Product::kCsmBasis, "PRODUCT_CSM_BASIS"},
      {Product::kBlockerDepth, "PRODUCT_BLOCKER_DEPTH"},
      {Product::kShadowAtlas, "PRODUCT_SHADOW_ATLAS"},
      {Product::kShadowAtlasMips, "PRODUCT_SHADOW_ATLAS_MIPS"},
      {Product::kShadowAtlasSat, "PRODUCT_SHADOW_ATLAS_SAT"},
      {Product::kAtlasUvs, "PRODUCT_ATLAS_UVS"}};
  for (const auto& [product, name] : prefiltered) {
    r.products = {Product::kVisibility, product};
    EXPECT_TRUE(refused(r, "products[1]",
                        std::string(name) + " is not available with TECHNIQUE_VIRTUAL: a "
                                            "prefiltered product (mips, SAT, CSM basis) or the "
                                            "atlas has no virtual design"))
        << name;
  }
  // The camera's own products are taken; texel density is not (no pixel's level is reported).
  r.products = {Product::kVisibility, Product::kPosition, Product::kVisibilityMips,
                Product::kVisibilitySat};
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.products = {Product::kVisibility, Product::kTexelDensity};
  EXPECT_TRUE(refused(r, "products[1]",
                      "PRODUCT_TEXEL_DENSITY is not available with TECHNIQUE_VIRTUAL: a pixel's "
                      "texel is its level's, which marking picks to match the pixel's footprint "
                      "(not yet reported per pixel)"));
  // The dense map with a uniform map is as before.
  r.products = {Product::kShadowMap};
  r.shadow_map.technique = Technique::kUniform;
  r.shadow_map.size = 2048;
  EXPECT_EQ(validation_error(r), "(accepted)");
}

// Every light type: a sun's clipmap, a spot light's mip chain, a point light's six of them, and
// all three in one request.
TEST(VirtualValidation, EveryLightTypeIsAccepted) {
  RenderRequest r = virtual_request();
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0, 5, 0};
  spot.cone_angle_deg = 60;
  Light point;
  point.type = LightType::kPoint;
  point.position = {0, 5, 0};
  for (const Light& l : {spot, point}) {
    r.lights[0] = l;
    EXPECT_EQ(validation_error(r), "(accepted)");
  }
  r = virtual_request();
  r.lights.push_back(spot);
  r.lights.push_back(point);
  EXPECT_EQ(validation_error(r), "(accepted)");
}

// Its levels follow the camera: MAP_FIT_SCENE is refused, as with PSM and LiSPSM.
TEST(VirtualValidation, FitSceneIsRefused) {
  RenderRequest r = virtual_request();
  r.shadow_map.fit = MapFit::kScene;
  EXPECT_TRUE(refused(r, "shadow_map.fit", "MAP_FIT_SCENE fits uniform maps and cubes only"));
  r.shadow_map.fit = MapFit::kView;
  EXPECT_EQ(validation_error(r), "(accepted)");
}

}  // namespace
}  // namespace shadow

namespace shadow {
namespace {

// The pool and page tables for clients that sample themselves: virtual only, float32 only.
TEST(VirtualValidation, ThePagesProductIsVirtualAndFloat32Only) {
  RenderRequest r = virtual_request();
  r.products = {Product::kVisibility, Product::kVirtualPages};
  EXPECT_EQ(validation_error(r), "(accepted)");
  r.output_format = PixelFormat::kFloat16;
  EXPECT_TRUE(refused(r, "products[1]", "PRODUCT_VIRTUAL_PAGES is float32 only"));
  r.output_format = PixelFormat::kFloat32;
  r.shadow_map.technique = Technique::kUniform;
  r.shadow_map.size = 2048;
  EXPECT_TRUE(refused(r, "products[1]", "PRODUCT_VIRTUAL_PAGES needs TECHNIQUE_VIRTUAL"));
}

}  // namespace
}  // namespace shadow
