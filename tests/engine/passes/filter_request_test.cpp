// Filters and prefilter products through Engine::render: mip/SAT products against CPU double
// references of the returned source texture, the filter choice reaching VISIBILITY, and
// validation messages naming the field.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/engine.hpp"
#include "occluder_scene.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

using testing::engine;

// The occluder scene at sizes that are not powers of two.
RenderRequest request() {
  RenderRequest r = testing::occluder_request();
  r.camera.width = 203;
  r.camera.height = 117;
  r.shadow_map.size = 300;
  r.products.clear();
  return r;
}

std::string field_of(const RenderRequest& r) {
  return testing::refused_field(r);
}

TEST(FilterRequest, MipProductsAreTheBoxPyramidOfTheSource) {
  RenderRequest r = request();
  r.products = {Product::kVisibility, Product::kVisibilityMips, Product::kShadowMapMips};
  const RenderResult res = engine().render(r);
  const Texture& vis = res.textures[0];
  // 203x117 -> 101x58 -> 50x29 -> 25x14 -> 12x7 -> 6x3 -> 3x1 -> 1x1.
  std::vector<const Texture*> vm, sm;
  for (const Texture& t : res.textures) {
    if (t.kind == Product::kVisibilityMips) vm.push_back(&t);
    if (t.kind == Product::kShadowMapMips) sm.push_back(&t);
  }
  ASSERT_EQ(vm.size(), 8u);
  ASSERT_EQ(sm.size(), 9u);  // 300 -> 150 -> 75 -> 37 -> 18 -> 9 -> 4 -> 2 -> 1
  EXPECT_EQ(vm[0]->name, "visibility_mip0");
  EXPECT_EQ(sm[8]->name, "shadowmap_mip8");
  EXPECT_EQ(vm[0]->data.size(), vis.data.size());
  for (size_t i = 0; i < vis.data.size(); ++i)
    ASSERT_TRUE(vis.data[i] == vm[0]->data[i] ||
                (std::isnan(vis.data[i]) && std::isnan(vm[0]->data[i])));
  EXPECT_EQ(vm[1]->width, 101u);
  EXPECT_EQ(vm[1]->height, 58u);
  EXPECT_EQ(vm[7]->width, 1u);
  EXPECT_EQ(vm[7]->height, 1u);
  EXPECT_EQ(sm[1]->world_to_ndc, sm[0]->world_to_ndc);
  // Level 1 of the even-sized shadow map: plain 2x2 averages (no NaN in a depth map).
  const Texture& a = *sm[0];
  const Texture& b = *sm[1];
  double worst = 0;
  for (uint32_t y = 0; y < b.height; ++y)
    for (uint32_t x = 0; x < b.width; ++x) {
      double s = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) s += a.data[(2 * y + dy) * a.width + 2 * x + dx];
      worst = std::max(worst, std::abs(s / 4 - b.data[y * b.width + x]));
    }
  std::printf("shadowmap mip1 vs CPU 2x2 mean: max |error| %.3g\n", worst);
  EXPECT_LT(worst, 1e-6);
}

TEST(FilterRequest, SatProductsAreExactPrefixSumsInFloat64) {
  RenderRequest r = request();
  r.filter.kind = FilterKind::kPoisson;  // fractional visibilities
  r.products = {Product::kVisibility, Product::kVisibilitySat, Product::kShadowMap,
                Product::kShadowMapSat};
  const RenderResult res = engine().render(r);
  for (int k : {0, 2}) {
    const Texture& src = res.textures[k];
    const Texture& sat = res.textures[k + 1];
    ASSERT_EQ(sat.format, PixelFormat::kFloat64);
    ASSERT_TRUE(sat.data.empty());
    ASSERT_EQ(sat.data64.size(), src.data.size());
    std::vector<double> ref(src.data.size());
    double worst = 0;
    for (uint32_t y = 0; y < src.height; ++y) {
      double row = 0;
      for (uint32_t x = 0; x < src.width; ++x) {
        const size_t i = size_t{y} * src.width + x;
        row += std::isnan(src.data[i]) ? 0.0 : double(src.data[i]);
        ref[i] = row + (y > 0 ? ref[i - src.width] : 0.0);
        worst = std::max(worst, std::abs(ref[i] - sat.data64[i]));
      }
    }
    std::printf("%s vs CPU double prefix sums: max |error| %.3g (total %.6g)\n", sat.name.c_str(),
                worst, ref.back());
    EXPECT_LT(worst, 1e-5);
  }
}

TEST(FilterRequest, VisibilityUsesTheChosenFilter) {
  RenderRequest r = request();
  r.products = {Product::kVisibility};
  auto fractional = [](const Texture& t) {
    size_t n = 0;
    for (float v : t.data) n += v > 0.01f && v < 0.99f;
    return n;
  };
  const RenderResult hard = engine().render(r);
  EXPECT_EQ(fractional(hard.textures[0]), 0u);
  for (FilterKind k : {FilterKind::kPcf2x2, FilterKind::kPoisson}) {
    r.filter.kind = k;
    r.filter.poisson.radius = 3;
    const RenderResult res = engine().render(r);
    EXPECT_GT(fractional(res.textures[0]), 10u) << int(k);
    EXPECT_NE(std::find(res.passes.begin(), res.passes.end(), "visibility.pcf"), res.passes.end());
  }
}

TEST(FilterRequest, InvalidSettingsNameTheirField) {
  RenderRequest r = request();
  r.products = {Product::kVisibility};
  r.filter.kind = FilterKind::kPoisson;
  r.filter.poisson.taps = 0;
  EXPECT_EQ(field_of(r), "filter.poisson.taps");
  r.filter.poisson.taps = 65;
  EXPECT_EQ(field_of(r), "filter.poisson.taps");
  r.filter.poisson.taps = 8;
  r.filter.poisson.radius = 0;
  EXPECT_EQ(field_of(r), "filter.poisson.radius");
  r.filter.poisson.radius = NAN;
  EXPECT_EQ(field_of(r), "filter.poisson.radius");
  r.filter.kind = FilterKind::kPcss;
  EXPECT_EQ(field_of(r), "lights[0].size");  // PCSS needs an area light
  r.lights[0].size = 1.0f;
  r.filter.pcss.filter_samples = 0;
  EXPECT_EQ(field_of(r), "filter.pcss.filter_samples");
  r.filter.pcss.filter_samples = 16;
  r.filter.pcss.blocker_samples = 100;
  EXPECT_EQ(field_of(r), "filter.pcss.blocker_samples");
  r.filter.kind = FilterKind::kBlur;
  r.filter.blur.radius = 0;
  EXPECT_EQ(field_of(r), "filter.blur.radius");
  r.filter.blur.radius = 4;
  r.filter.blur.passes = 17;
  EXPECT_EQ(field_of(r), "filter.blur.passes");
  r.filter.blur.passes = 1;
  auto scene = std::make_shared<Scene>(*r.scene);
  scene->instances[1].receiver_class = 4;
  r.scene = scene;
  EXPECT_EQ(field_of(r), "scene.instances[1].receiver_class");
}

}  // namespace
}  // namespace shadow
