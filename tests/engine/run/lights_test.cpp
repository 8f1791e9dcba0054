// Several lights in one request (Engine::render): each light's textures are bit-identical to that
// light rendered alone, the camera view is rendered once, names and indices say which light a
// texture belongs to, and bad light lists are refused naming the field.
#include <gtest/gtest.h>

#include <cstring>

#include "occluder_scene.hpp"

namespace shadow {
namespace {

using testing::engine;

Light sun(glm::vec3 direction, float size = 0.0f) {
  Light l;
  l.direction = direction;
  l.size = size;
  return l;
}

Light point(glm::vec3 position) {
  Light l;
  l.type = LightType::kPoint;
  l.position = position;
  return l;
}

bool same_bits(const Texture& a, const Texture& b) {
  return a.width == b.width && a.height == b.height && a.channels == b.channels &&
         a.faces == b.faces && a.data.size() == b.data.size() &&
         a.data64.size() == b.data64.size() &&
         std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0 &&
         std::memcmp(a.data64.data(), b.data64.data(), a.data64.size() * sizeof(double)) == 0 &&
         a.world_to_ndc == b.world_to_ndc;
}

size_t count(const std::vector<std::string>& passes, const std::string& name) {
  return std::count(passes.begin(), passes.end(), name);
}

// Two suns and a point light (its default technique: the cube) with hard, 2x2 PCF and the
// prefilter products: every texture of light i equals the same request with light i alone.
TEST(Lights, EachLightEqualsThatLightAlone) {
  RenderRequest r = testing::occluder_request();
  r.lights = {sun({0, -1, 0}), sun({0.6f, -1, 0.2f}), point({1, 5, 0})};
  r.products = {Product::kShadowMap, Product::kVisibility, Product::kPosition,
                Product::kTexelDensity};
  for (FilterKind filter : {FilterKind::kHard, FilterKind::kPcf2x2}) {
    SCOPED_TRACE(int(filter));
    r.filter.kind = filter;
    const RenderResult all = engine().render(r);
    // The camera view once, each light's passes under its prefix.
    EXPECT_EQ(count(all.passes, "gbuffer.resolve"), 1u);
    EXPECT_EQ(count(all.passes, "light1.shadow_map.raster"), 1u);
    EXPECT_EQ(count(all.passes, "light2.cube.light_distance"), 1u);
    ASSERT_EQ(all.light_fits.size(), 3u);
    EXPECT_EQ(all.light_fits[2].light_case, "cube: point light");
    // Product-major, light-minor: shadow maps, visibilities, the position, densities.
    std::vector<std::string> names;
    for (const Texture& t : all.textures) names.push_back(t.name);
    EXPECT_EQ(names, (std::vector<std::string>{
                         "shadowmap_light0", "shadowmap_light1", "shadowmap_cube_light2",
                         "visibility_light0", "visibility_light1", "visibility_light2", "position",
                         "texel_density_light0", "texel_density_light1", "texel_density_light2"}));
    for (size_t i = 0; i < r.lights.size(); ++i) {
      RenderRequest alone = r;
      alone.lights = {r.lights[i]};
      const RenderResult one = engine().render(alone);
      EXPECT_EQ(one.light_fits[0].light_case, all.light_fits[i].light_case);
      for (const Texture& t : one.textures) {
        if (t.kind == Product::kPosition) continue;
        const auto it = std::find_if(all.textures.begin(), all.textures.end(), [&](const auto& a) {
          return a.kind == t.kind && a.light == i;
        });
        ASSERT_NE(it, all.textures.end()) << t.name << " of light " << i;
        EXPECT_EQ(it->name, t.name + "_light" + std::to_string(i));
        EXPECT_TRUE(same_bits(*it, t)) << it->name;
      }
    }
  }
}

// One light keeps the names and passes a single-light request always had.
TEST(Lights, OneLightKeepsThePlainNames) {
  RenderRequest r = testing::occluder_request();
  const RenderResult res = engine().render(r);
  ASSERT_EQ(res.textures.size(), 2u);
  EXPECT_EQ(res.textures[0].name, "visibility");
  EXPECT_EQ(res.textures[0].light, 0u);
  EXPECT_EQ(count(res.passes, "shadow_map.raster"), 1u);
}

TEST(Lights, BadListsNameTheField) {
  RenderRequest r = testing::occluder_request();
  r.lights.clear();
  EXPECT_EQ(testing::refused_field(r), "lights");  // VISIBILITY needs a light
  r.products = {Product::kPosition};
  EXPECT_EQ(testing::refused_field(r), "(accepted)");  // POSITION does not
  r = testing::occluder_request();
  r.lights.assign(17, sun({0, -1, 0}));
  EXPECT_EQ(testing::refused_field(r), "lights");
  r.lights = {sun({0, -1, 0}), sun({0, 0, 0})};
  EXPECT_EQ(testing::refused_field(r), "lights[1].directional.direction");
  r.lights = {sun({0, -1, 0}, 1.0f), sun({0, -1, 0})};
  r.filter.kind = FilterKind::kPcss;
  EXPECT_EQ(testing::refused_field(r), "lights[1].size");  // PCSS needs every light's size
}

}  // namespace
}  // namespace shadow
