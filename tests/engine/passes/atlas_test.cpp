// Shadow atlases (PRODUCT_SHADOW_ATLAS) against closed forms: a 20 m ground under a 2 m square
// occluder 2 m up and a sun straight down, so a ground point (x, z) is shadowed exactly when
// |x| < 1 and |z| < 1; the ground's UVs map (x, z) linearly to its tile. Also: slivers thinner
// than a texel still cover every texel (conservative coverage, shared edges once), the gutter's
// width, the tile layout, and bad UVs and settings refused naming the field.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/plan/atlas_layout.hpp"
#include "engine/plan/uv_layouts.hpp"
#include "occluder_scene.hpp"

namespace shadow {
namespace {

// The ground as `strips` vertical strips of two triangles each, UVs u = (x + 10) / 20 and
// v = (z + 10) / 20 scaled by `scale` about the tile's centre.
Mesh ground(int strips, float scale = 1.0f) {
  Mesh m;
  for (int k = 0; k <= strips; ++k) {
    const float x = -10.0f + 20.0f * float(k) / float(strips);
    for (float z : {-10.0f, 10.0f}) {
      m.positions.insert(m.positions.end(), {x, 0.0f, z});
      const float u = (x + 10.0f) / 20.0f, v = (z + 10.0f) / 20.0f;
      m.uvs.insert(m.uvs.end(), {0.5f + (u - 0.5f) * scale, 0.5f + (v - 0.5f) * scale});
    }
  }
  for (uint32_t k = 0; k < uint32_t(strips); ++k) {
    const uint32_t a = 2 * k, b = a + 1, c = a + 2, d = a + 3;  // (x0,-10) (x0,10) (x1,-10) (x1,10)
    m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
  }
  return m;
}

RenderRequest atlas_request(int strips, float scale = 1.0f) {
  RenderRequest r = testing::occluder_request();
  auto scene = std::make_shared<Scene>();
  scene->meshes = {ground(strips, scale), testing::quad(1, 2)};
  Instance occluder{1};
  occluder.receives_shadows = false;
  scene->instances = {Instance{0}, occluder};
  r.scene = scene;
  r.products = {Product::kShadowAtlas};
  r.shadow_map.fit = MapFit::kScene;  // the atlas covers every receiver
  r.atlas.tile = 256;
  r.atlas.gutter = 2;
  return r;
}

// By value: callers pass the render's temporary result.
Texture the_atlas(const RenderResult& result) {
  EXPECT_EQ(result.textures.size(), 1u);
  return result.textures.at(0);
}

// Texels of the tile at (x0, y0) that disagree with the closed form, away from the occluder's
// shadow edge by more than `band` metres, and NaN texels.
struct Mismatch {
  int wrong = 0, empty = 0;
};
Mismatch against_closed_form(const Texture& t, uint32_t x0, uint32_t y0, uint32_t size, float band,
                             float offset_x = 0.0f) {
  Mismatch m;
  for (uint32_t j = 0; j < size; ++j)
    for (uint32_t i = 0; i < size; ++i) {
      const float v = t.data[size_t(y0 + j) * t.width + x0 + i];
      if (std::isnan(v)) {
        ++m.empty;
        continue;
      }
      const float x = 20.0f * (i + 0.5f) / size - 10.0f + offset_x,
                  z = 20.0f * (j + 0.5f) / size - 10.0f;
      const float edge = std::min(std::abs(std::abs(x) - 1.0f), std::abs(std::abs(z) - 1.0f));
      const bool shadowed = std::abs(x) < 1.0f && std::abs(z) < 1.0f;
      if (edge > band && v != (shadowed ? 0.0f : 1.0f)) ++m.wrong;
    }
  return m;
}

TEST(Atlas, MatchesTheClosedFormShadow) {
  const RenderResult r = testing::engine().render(atlas_request(1));
  const Texture t = the_atlas(r);
  EXPECT_EQ(t.name, "shadow_atlas");
  EXPECT_EQ(t.width, 256u);
  EXPECT_EQ(t.height, 256u);
  ASSERT_EQ(t.atlas_tiles.size(), 1u);
  EXPECT_EQ(t.atlas_tiles[0].instance, 0u);
  const float texel = 20.0f / 256;
  const Mismatch m = against_closed_form(t, 0, 0, 256, texel);
  EXPECT_EQ(m.wrong, 0);
  EXPECT_EQ(m.empty, 0);  // the chart covers the whole tile
}

// 1000 strips 0.256 texels wide: every texel is covered (none empty, no overlap refused though
// texel centres fall on strip edges), and the shadow is the same.
TEST(Atlas, SliversThinnerThanATexelCoverEveryTexel) {
  const RenderResult r = testing::engine().render(atlas_request(1000));
  const Mismatch m = against_closed_form(the_atlas(r), 0, 0, 256, 20.0f / 256);
  EXPECT_EQ(m.wrong, 0);
  EXPECT_EQ(m.empty, 0);
}

// A triangle with no area in UV space (collinear UVs) covers nothing: the atlas is the one
// without it, bit for bit.
TEST(Atlas, ZeroAreaUvTrianglesCoverNothing) {
  RenderRequest req = atlas_request(1);
  const RenderResult without = testing::engine().render(req);
  auto scene = std::make_shared<Scene>(*req.scene);
  // A vertical sliver on the ground's edge x = -10 (edge-on to the sun: it casts nothing) whose
  // UVs lie on the line u = 0.
  Mesh& g = scene->meshes[0];
  const uint32_t v = uint32_t(g.vertex_count());
  g.positions.insert(g.positions.end(), {-10.0f, 0.001f, 0.0f});
  g.uvs.insert(g.uvs.end(), {0.0f, 0.5f});
  g.indices.insert(g.indices.end(), {0, 1, v});
  req.scene = scene;
  const Texture with = the_atlas(testing::engine().render(req));
  EXPECT_EQ(std::memcmp(with.data.data(), the_atlas(without).data.data(), with.byte_size()), 0);
}

// A chart on [0.25, 0.75]^2 of a 256 tile covers texels 64..191; the gutter fills `gutter`
// more on each side and no further.
TEST(Atlas, GutterFillsItsWidthAroundTheChart) {
  for (uint32_t gutter : {0u, 2u, 5u}) {
    SCOPED_TRACE(gutter);
    RenderRequest req = atlas_request(1, 0.5f);
    req.atlas.gutter = gutter;
    const Texture t = the_atlas(testing::engine().render(req));
    const uint32_t row = 128;
    for (uint32_t i = 0; i < 256; ++i) {
      const bool inside = i + gutter >= 64 && i <= 191 + gutter;
      EXPECT_EQ(!std::isnan(t.data[row * 256 + i]), inside) << "column " << i;
      EXPECT_EQ(!std::isnan(t.data[i * 256 + row]), inside) << "row " << i;
    }
    // The corner texel diagonal to the chart stays empty past the gutter's 4-neighbour reach.
    EXPECT_TRUE(std::isnan(t.data[size_t(63 - gutter) * 256 + 63 - gutter]));
  }
}

// Two receiving instances: two tiles side by side; the second ground, 30 m to the right, is
// lit everywhere.
TEST(Atlas, OneTilePerReceivingInstance) {
  RenderRequest req = atlas_request(1);
  auto scene = std::make_shared<Scene>(*req.scene);
  Instance moved{0};
  moved.transform = glm::translate(glm::mat4(1.0f), glm::vec3(30, 0, 0));
  scene->instances.push_back(moved);
  req.scene = scene;
  req.atlas.tile = 128;
  const Texture t = the_atlas(testing::engine().render(req));
  EXPECT_EQ(t.width, 256u);
  EXPECT_EQ(t.height, 128u);
  ASSERT_EQ(t.atlas_tiles.size(), 2u);
  EXPECT_EQ(t.atlas_tiles[1].instance, 2u);
  EXPECT_EQ(t.atlas_tiles[1].x, 128u);
  EXPECT_EQ(against_closed_form(t, 0, 0, 128, 20.0f / 128).wrong, 0);
  const Mismatch far = against_closed_form(t, 128, 0, 128, 20.0f / 128, 30.0f);
  EXPECT_EQ(far.wrong, 0);
  EXPECT_EQ(far.empty, 0);
}

// Filtered like VISIBILITY: 2x2 PCF gives fractions only near the shadow's edge (a 300 tile
// over a 256 map, so texel centres fall between map texels).
TEST(Atlas, FiltersAsVisibilityDoes) {
  RenderRequest req = atlas_request(1);
  req.filter.kind = FilterKind::kPcf2x2;
  req.shadow_map.size = 256;
  req.atlas.tile = 300;
  const Texture t = the_atlas(testing::engine().render(req));
  EXPECT_EQ(against_closed_form(t, 0, 0, 300, 2 * 20.0f / 256).wrong, 0);
  int fractions = 0;
  for (float v : t.data) fractions += v > 0.0f && v < 1.0f;
  EXPECT_GT(fractions, 0);
}

// The atlas' mips and SAT with the atlas in one request: level 1 is the mean of each 2x2 block's
// non-empty texels; the SAT's channels are the visibility at surface texels (empty and gutter
// texels as 0: they hold no surface point) and their coverage, so box sums over them give the
// mean over the box's surface points, against double sums.
TEST(Atlas, MipsAndSatLeaveEmptyTexelsOut) {
  RenderRequest req = atlas_request(1, 0.5f);  // a chart in the tile's middle: empty around it
  req.products = {Product::kShadowAtlas, Product::kShadowAtlasMips, Product::kShadowAtlasSat};
  const RenderResult r = testing::engine().render(req);
  ASSERT_EQ(r.textures.size(), 1u + 9u + 1u);  // 256^2 and 8 levels down to 1x1, the SAT
  const Texture &atlas = r.textures[0], &mip1 = r.textures[2], &sat = r.textures.back();
  EXPECT_EQ(mip1.name, "shadow_atlas_mip1");
  EXPECT_EQ(r.textures[1].atlas_tiles.size(), 1u);  // level 0 and the SAT carry the tiles
  EXPECT_EQ(sat.atlas_tiles.size(), 1u);
  int mixed = 0;
  for (uint32_t j = 0; j < 128; ++j)
    for (uint32_t i = 0; i < 128; ++i) {
      double sum = 0;
      int n = 0;
      for (uint32_t k = 0; k < 4; ++k) {
        const float v = atlas.data[(2 * j + k / 2) * 256 + 2 * i + k % 2];
        if (!std::isnan(v)) sum += v, ++n;
      }
      const float got = mip1.data[j * 128 + i];
      if (n == 0) {
        EXPECT_TRUE(std::isnan(got)) << i << ", " << j;
        continue;
      }
      mixed += n < 4;
      EXPECT_NEAR(got, sum / n, 1e-6) << i << ", " << j;
    }
  EXPECT_GT(mixed, 0);  // the chart's border has blocks with empty texels

  RenderRequest bare_req = req;  // its surface texels: the atlas without a gutter
  bare_req.atlas.gutter = 0;
  bare_req.products = {Product::kShadowAtlas};
  const Texture bare = the_atlas(testing::engine().render(bare_req));
  ASSERT_EQ(sat.name, "shadow_atlas_sat");
  ASSERT_EQ(sat.channels, 2u);
  EXPECT_EQ(sat.channel_names, (std::vector<std::string>{"visibility", "coverage"}));
  const auto box = [&](uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1, uint32_t c) {
    const auto at = [&](int64_t x, int64_t y) {
      return x < 0 || y < 0 ? 0.0 : sat.data64[(size_t(y) * 256 + size_t(x)) * 2 + c];
    };
    return at(x1, y1) - at(int64_t(x0) - 1, y1) - at(x1, int64_t(y0) - 1) +
           at(int64_t(x0) - 1, int64_t(y0) - 1);
  };
  for (auto [x0, y0, x1, y1] :
       {std::array<uint32_t, 4>{0, 0, 255, 255}, {50, 100, 90, 180}, {120, 120, 135, 140}}) {
    double sum = 0, n = 0;
    for (uint32_t y = y0; y <= y1; ++y)
      for (uint32_t x = x0; x <= x1; ++x) {
        const float v = bare.data[y * 256 + x];
        if (!std::isnan(v)) sum += atlas.data[y * 256 + x], ++n;
      }
    EXPECT_NEAR(box(x0, y0, x1, y1, 0), sum, 1e-6 * (1 + sum)) << x0 << ", " << y0;
    EXPECT_EQ(box(x0, y0, x1, y1, 1), n) << x0 << ", " << y0;
  }
}

// The atlas filters against their closed form: under a sun of angular diameter theta overhead,
// PCSS's penumbra at the ground is a disk of radius R = h tan(theta / 2) (h = 2 m, the
// occluder's height), and that disk's mean over the hard atlas across a straight edge of the
// occluder's shadow, at distance d outside it, is the share of the disk on the lit side:
// 1 - (acos t - t sqrt(1 - t^2)) / pi, t = d / R. The disk's size in atlas texels comes from the
// footprint (pcss.cl's atlas_footprint): with tiles of 128 and 512 texels the ramp stays the same
// in metres. Pixels near the square's corners are left out.
struct RampError {
  double worst = 0, mean = 0;
  int pixels = 0;
};
RampError against_ramp(FilterKind kind, uint32_t tile) {
  RenderRequest req = atlas_request(1);
  req.products = {Product::kVisibility, Product::kPosition};
  req.filter.kind = kind;
  req.filter.pcss.rotate = false;
  req.lights[0].size = 10.0f;  // degrees
  req.atlas.tile = tile;
  req.camera.width = 640, req.camera.height = 480;
  const RenderResult r = testing::engine().render(req);
  const Texture &vis = r.textures.at(0), &pos = r.textures.at(1);
  const double half = 2.0 * std::tan(glm::radians(5.0));  // the ramp's half-width
  RampError e;
  for (size_t p = 0; p < vis.data.size(); ++p) {
    const double x = pos.data[3 * p], y = pos.data[3 * p + 1], z = pos.data[3 * p + 2];
    if (std::isnan(x) || std::abs(y) > 1e-3) continue;  // the ground only
    // Distance outside the shadow square along the nearer axis, away from the corners.
    const double ox = std::abs(x) - 1, oz = std::abs(z) - 1;
    const double inside = -(half + 0.05);  // well within the square along the edge
    double out;
    if (oz < inside && std::abs(ox) <= 2 * half)
      out = ox;
    else if (ox < inside && std::abs(oz) <= 2 * half)
      out = oz;
    else
      continue;
    const double t = std::clamp(out / half, -1.0, 1.0);
    const double want = 1.0 - (std::acos(t) - t * std::sqrt(1.0 - t * t)) / std::numbers::pi;
    const double err = std::abs(vis.data[p] - want);
    e.worst = std::max(e.worst, err);
    e.mean += err;
    ++e.pixels;
  }
  e.mean /= std::max(e.pixels, 1);
  std::printf("[ atlas    ] %s, %u-texel tile: %d penumbra pixels, worst %.3f, mean %.4f\n",
              kind == FilterKind::kAtlasSat ? "atlas_sat" : "atlas_mip", tile, e.pixels, e.worst,
              e.mean);
  return e;
}

// Measured (mean, worst) against the disk: SAT 0.083, 0.26 at 128 texels a tile (a texel is
// 0.16 m, about the disk's radius: the ellipse snaps to whole texels) and 0.020, 0.059 at 512;
// mips 0.082, 0.40 and 0.018, 0.077. Against a linear ramp (the box the filters took before
// they took the disk) the SAT measured 0.020, 0.047 at 512; without the footprint's scale the
// 512 tile's disk would be twice as wide and the 128 tile's eight times.
// Tiles of 128 and 512 texels against their measured bounds.
void expect_ramps(FilterKind kind, double coarse_mean, double fine_mean, double fine_worst) {
  const RampError coarse = against_ramp(kind, 128);
  const RampError fine = against_ramp(kind, 512);
  EXPECT_GT(fine.pixels, 2000);
  EXPECT_LT(coarse.mean, coarse_mean);
  EXPECT_LT(fine.mean, fine_mean);
  EXPECT_LT(fine.worst, fine_worst);
}

// Attached shadows (attached_shadow_test.cpp) under the atlas filters: under a sun from below
// the ground's seen side is dark; the occluder, which receives no shadows, stays lit.
TEST(Atlas, FiltersLeaveASideFacingAwayFromTheLightDark) {
  for (FilterKind kind : {FilterKind::kAtlasSat, FilterKind::kAtlasMip}) {
    RenderRequest req = atlas_request(1);
    req.products = {Product::kVisibility, Product::kPosition};
    req.filter.kind = kind;
    req.lights[0].direction = {0.3f, 1.0f, 0.2f};
    req.lights[0].size = 2.0f;
    const RenderResult r = testing::engine().render(req);
    const Texture &vis = r.textures.at(0), &pos = r.textures.at(1);
    size_t ground = 0, dark = 0, square = 0, lit = 0;
    for (size_t p = 0; p < vis.data.size(); ++p) {
      if (std::isnan(pos.data[3 * p])) continue;
      const bool on_ground = std::abs(pos.data[3 * p + 1]) < 1e-3;
      ground += on_ground, dark += on_ground && vis.data[p] == 0.0f;
      square += !on_ground, lit += !on_ground && vis.data[p] == 1.0f;
    }
    EXPECT_GT(ground, 50000u);
    EXPECT_EQ(dark, ground) << int(kind);
    EXPECT_GT(square, 1000u);
    EXPECT_EQ(lit, square) << int(kind);
  }
}

TEST(Atlas, SatFilterRampsAsTheClosedForm) {
  expect_ramps(FilterKind::kAtlasSat, 0.095, 0.023, 0.07);
}

TEST(Atlas, MipFilterRampsAsTheClosedForm) {
  expect_ramps(FilterKind::kAtlasMip, 0.095, 0.021, 0.09);
}

// A ground without UVs gets a generated layout (xatlas): every triangle in [0, 1] without
// overlaps (the bake would refuse them), and the atlas' texels are shadowed in the proportion
// of the ground the occluder shades (a planar chart keeps areas in proportion): 4 of 400 m^2.
TEST(Atlas, MeshesWithoutUvsGetAGeneratedLayout) {
  RenderRequest req = atlas_request(8);
  auto scene = std::make_shared<Scene>(*req.scene);
  scene->meshes[0].uvs.clear();
  req.scene = scene;
  const Texture t = the_atlas(testing::engine().render(req));
  size_t covered = 0, shadowed = 0;
  for (float v : t.data) {
    covered += !std::isnan(v);
    shadowed += v == 0.0f;
  }
  const double fraction = double(shadowed) / double(covered);
  std::printf("[ atlas    ] generated layout: %zu of %zu texels covered, %.4f shadowed\n", covered,
              t.data.size(), fraction);
  EXPECT_GT(covered, t.data.size() / 4);  // the chart fills a good part of the tile
  EXPECT_NEAR(fraction, 0.01, 0.002);

  // PRODUCT_ATLAS_UVS returns the layout: each corner's UV, against the layout made here.
  req.products = {Product::kShadowAtlas, Product::kAtlasUvs};
  const RenderResult with_uvs = testing::engine().render(req);
  ASSERT_EQ(with_uvs.textures.size(), 2u);
  const Texture& corners = with_uvs.textures[1];
  EXPECT_EQ(corners.name, "atlas_uvs_mesh0");
  EXPECT_EQ(corners.mesh, 0u);
  ASSERT_EQ(corners.width, 3u);
  ASSERT_EQ(corners.height, uint32_t(scene->meshes[0].triangle_count()));
  ASSERT_EQ(corners.channels, 2u);

  // The layout itself: the same triangles in the same order, each vertex where it came from.
  const Mesh& m = scene->meshes[0];
  const Mesh laid = generate_uv_layout(m);
  ASSERT_EQ(laid.indices.size(), m.indices.size());
  ASSERT_EQ(laid.uvs.size(), 2 * laid.vertex_count());
  for (size_t i = 0; i < m.indices.size(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(laid.positions[3 * laid.indices[i] + k], m.positions[3 * m.indices[i] + k]);
  for (float uv : laid.uvs) EXPECT_TRUE(uv >= 0.0f && uv <= 1.0f);
  for (size_t c = 0; c < laid.indices.size(); ++c)
    for (int k = 0; k < 2; ++k)
      EXPECT_EQ(corners.data[2 * c + k], laid.uvs[2 * laid.indices[c] + k]) << c;
  // Meshes with their own UVs have none; without an atlas the product is refused.
  req.scene = atlas_request(8).scene;
  EXPECT_EQ(testing::engine().render(req).textures.size(), 1u);
  req.products = {Product::kVisibility, Product::kAtlasUvs};
  EXPECT_EQ(testing::refused_field(req), "products");
}

// Tiled UVs (the ground's 8 strips each spanning the whole square) are refused; with
// generate_uvs the server lays the mesh out instead, as if it had none, and says so.
TEST(Atlas, GenerateUvsLaysOutMeshesWhoseUvsOverlap) {
  RenderRequest req = atlas_request(8);
  auto scene = std::make_shared<Scene>(*req.scene);
  Mesh& tiled = scene->meshes[0];
  for (size_t v = 0; v < tiled.vertex_count(); ++v) tiled.uvs[2 * v] = float((v / 2) % 2);
  req.scene = scene;
  EXPECT_EQ(testing::refused_field(req), "scene.meshes[0].uvs");
  req.atlas.generate_uvs = true;
  req.products = {Product::kShadowAtlas, Product::kAtlasUvs};
  const RenderResult r = testing::engine().render(req);
  ASSERT_EQ(r.textures.size(), 2u);
  EXPECT_EQ(r.textures[1].name, "atlas_uvs_mesh0");
  RenderRequest without = req;
  auto bare = std::make_shared<Scene>(*scene);
  bare->meshes[0].uvs.clear();
  without.scene = bare;
  without.atlas.generate_uvs = false;
  const RenderResult expected = testing::engine().render(without);
  ASSERT_EQ(expected.textures.size(), 2u);
  EXPECT_EQ(r.textures[0].data.size(), expected.textures[0].data.size());
  EXPECT_TRUE(std::memcmp(r.textures[0].data.data(), expected.textures[0].data.data(),
                          r.textures[0].data.size() * sizeof(float)) == 0);
  // The limit of a generated layout, named by the setting.
  auto big = std::make_shared<Scene>(*scene);
  big->meshes[0] = ground(10001);  // 20 002 triangles
  req.scene = big;
  EXPECT_EQ(testing::refused_field(req), "exhausted: atlas.generate_uvs");
}

TEST(Atlas, BadUvsAndSettingsAreNamed) {
  RenderRequest req = atlas_request(1);
  auto scene = std::make_shared<Scene>(*req.scene);
  req.scene = scene;
  scene->meshes[0].uvs[3] = 1.5f;
  EXPECT_EQ(testing::refused_field(req), "scene.meshes[0].uvs");
  scene->meshes[0].uvs[3] = NAN;
  EXPECT_EQ(testing::refused_field(req), "scene.meshes[0].uvs");
  // Every face on one UV point (assimp's WusonOBJ maps each face to one vt): an empty atlas,
  // refused by name; with generate_uvs the server lays the mesh out instead.
  scene->meshes[0] = ground(4);
  std::fill(scene->meshes[0].uvs.begin(), scene->meshes[0].uvs.end(), 0.5f);
  EXPECT_EQ(testing::refused_field(req), "scene.meshes[0].uvs");
  req.atlas.generate_uvs = true;
  EXPECT_EQ(testing::refused_field(req), "(accepted)");
  req.atlas.generate_uvs = false;
  // Both triangles on the same UV triangle: overlap.
  scene->meshes[0] = ground(1);
  scene->meshes[0].indices = {0, 1, 3, 0, 3, 1};
  EXPECT_EQ(testing::refused_field(req), "scene.meshes[0].uvs");
  // No UVs: a generated layout, up to kMaxLayoutTriangles.
  scene->meshes[0] = ground(int(kMaxLayoutTriangles / 2) + 1);
  scene->meshes[0].uvs.clear();
  EXPECT_EQ(testing::refused_field(req), "exhausted: scene.meshes[0].uvs");
  scene->meshes[0] = ground(1);
  req.atlas.tile = 8;
  EXPECT_EQ(testing::refused_field(req), "atlas.tile_size");
  req.atlas.tile = 64;
  req.atlas.gutter = 16;
  EXPECT_EQ(testing::refused_field(req), "atlas.gutter");
  req.atlas.gutter = 2;
  req.atlas.tile = 4096;
  for (int k = 0; k < 30; ++k) scene->instances.push_back(Instance{0});  // 6x6 tiles of 4096
  EXPECT_EQ(testing::refused_field(req), "exhausted: atlas.tile_size");
  scene->instances.resize(2);
  req.atlas.tile = 256;
  req.shadow_map.fit = MapFit::kView;  // a map of what is in view cannot serve the atlas
  EXPECT_EQ(testing::refused_field(req), "shadow_map.fit");
  try {  // the refusal names the command-line flag too
    testing::engine().render(req);
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("--fit scene"), std::string::npos) << e.what();
  }
  req.shadow_map.fit = MapFit::kScene;
  // An index past the vertices is refused by name, before any check reads through it (the
  // UV checks run on the host, ahead of the device's index check).
  scene->meshes[0] = ground(1);
  scene->meshes[0].indices[2] = 0xfffffff0u;
  EXPECT_EQ(testing::refused_field(req), "scene.meshes[0].indices[2]");
  scene->meshes[0].uvs.clear();  // a layout to generate: the same refusal before it is made
  EXPECT_EQ(testing::refused_field(req), "scene.meshes[0].indices[2]");
  // A layout to generate takes coordinates within 1e18 (xatlas did not return for one vertex at
  // 1e20, 1e38 or Inf: their squares overflow float). One at 1e10 is laid out at once, since no
  // chart may exceed xatlas' 1024 texels (it took minutes and gigabytes), and then refused for
  // the scene's extent.
  for (const float y : {1e10f, 1e20f, 1e38f, INFINITY, NAN}) {
    scene->meshes[0] = ground(4);
    scene->meshes[0].uvs.clear();
    scene->meshes[0].positions[4] = y;
    EXPECT_EQ(testing::refused_field(req), y == 1e10f ? "scene" : "scene.meshes[0].positions[1]")
        << y;
  }
  scene->meshes[0] = ground(1);
  scene->instances[0].receives_shadows = false;
  EXPECT_EQ(testing::refused_field(req), "products");
}

// Tiles from the world (AtlasSettings without a tile): the 20 m ground and a 5 m one (the same
// mesh scaled by a quarter, lit, beside it) get tiles in proportion to their size, each at least
// as fine as the map's texel on it (the map spans the two: 25.6 x 20 m over 1024 texels, 2.2 cm).
// Both are baked right in their own tiles, and the soft atlas filters read each point in its
// own tile: the small ground stays lit, the large one's shadow matches the closed form.
TEST(Atlas, TilesFollowEachInstancesWorldSize) {
  RenderRequest req = atlas_request(1);
  auto scene = std::make_shared<Scene>(*req.scene);
  Instance small{0};  // x 10.6 .. 15.6, z -2.5 .. 2.5
  small.transform =
      glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(13.1f, 0, 0)), glm::vec3(0.25f));
  scene->instances.push_back(small);
  req.scene = scene;
  req.atlas.tile = 0;
  const Texture t = the_atlas(testing::engine().render(req));
  ASSERT_EQ(t.atlas_tiles.size(), 2u);
  const AtlasTile &large = t.atlas_tiles[0], &little = t.atlas_tiles[1];
  EXPECT_EQ(large.instance, 0u);
  EXPECT_EQ(little.instance, 2u);
  EXPECT_EQ(large.size, 1024u);  // 20 m at <= 2.2 cm a texel: over 905 texels
  EXPECT_EQ(little.size, 256u);  // 5 m: over 226
  EXPECT_EQ(t.width, 1024u + 256u);
  EXPECT_EQ(t.height, 1024u);
  // Each tile says what one of its texels spans on its instance: 20 m / 1024, 5 m / 256.
  EXPECT_NEAR(large.texel_world_size, 20.0 / 1024, 1e-12);
  EXPECT_NEAR(little.texel_world_size, 5.0 / 256, 1e-12);
  const Mismatch m = against_closed_form(t, large.x, large.y, large.size, 2 * 20.0f / 1024);
  EXPECT_EQ(m.wrong, 0);
  EXPECT_EQ(m.empty, 0);
  int lit = 0, other = 0;
  for (uint32_t j = 0; j < little.size; ++j)
    for (uint32_t i = 0; i < little.size; ++i)
      (t.data[size_t(little.y + j) * t.width + little.x + i] == 1.0f ? lit : other)++;
  EXPECT_EQ(other, 0);
  EXPECT_EQ(lit, 256 * 256);

  // The soft atlas on that layout, seen by the camera: lit on the small ground, and on the large
  // one as the closed form says away from the shadow's penumbra.
  req.products = {Product::kVisibility, Product::kPosition};
  req.lights[0].size = 2.0f;
  req.camera.eye = {6, 14, 10};
  req.camera.target = {4, 0, 0};
  for (FilterKind kind : {FilterKind::kAtlasSat, FilterKind::kAtlasMip}) {
    req.filter.kind = kind;
    const RenderResult r = testing::engine().render(req);
    const Texture &vis = r.textures.at(0), &pos = r.textures.at(1);
    int small_seen = 0, wrong = 0, seen = 0;
    for (size_t p = 0; p < vis.data.size(); ++p) {
      const float x = pos.data[3 * p], z = pos.data[3 * p + 2], v = vis.data[p];
      if (std::isnan(x) || pos.data[3 * p + 1] > 0.5f) continue;  // no ground
      ++seen;
      const bool on_small = x > 10.5f;
      small_seen += on_small;
      // The penumbra under a 2-degree sun 2 m down reaches 3.5 cm past the edge; atlas_mip's
      // trilinear reach leaves up to 0.013 at 10 cm (measured).
      const float edge = std::min(std::abs(std::abs(x) - 1.0f), std::abs(std::abs(z) - 1.0f));
      const bool shadowed = std::abs(x) < 1.0f && std::abs(z) < 1.0f;
      const float error = std::abs(v - (shadowed ? 0.0f : 1.0f));
      if (on_small ? error > 1e-3f : edge > 0.1f && error > 0.02f) ++wrong;
    }
    EXPECT_GT(small_seen, 1000) << int(kind);
    EXPECT_GT(seen, 20000) << int(kind);
    EXPECT_EQ(wrong, 0) << int(kind);
  }
}

// A box whose faces share their corners, laid out by xatlas: square charts split along 45-degree
// diagonals through texel centres. Both triangles of a diagonal once claimed those texels
// (their edge functions rounded differently), and the bake refused the layout as overlapping.
TEST(Atlas, GeneratedLayoutsOfSharedVertexBoxesDoNotOverlap) {
  Mesh box;
  for (int i = 0; i < 8; ++i)
    box.positions.insert(box.positions.end(),
                         {i & 1 ? 0.5f : -0.5f, i & 2 ? 0.5f : -0.5f, i & 4 ? 0.5f : -0.5f});
  for (int axis = 0; axis < 3; ++axis) {
    const uint32_t u = 1u << ((axis + 1) % 3), v = 1u << ((axis + 2) % 3);
    for (int side = 0; side < 2; ++side) {
      const uint32_t b = side ? (1u << axis) : 0u;
      box.indices.insert(box.indices.end(), {b, b | u, b | u | v, b, b | u | v, b | v});
    }
  }
  RenderRequest req = atlas_request(1);
  auto scene = std::make_shared<Scene>(*req.scene);
  scene->meshes[0] = box;
  scene->instances[0].transform = glm::scale(glm::mat4(1.0f), glm::vec3(4.0f));
  req.scene = scene;
  const Texture t = the_atlas(testing::engine().render(req));
  size_t covered = 0;
  for (float x : t.data) covered += !std::isnan(x);
  EXPECT_GT(covered, t.data.size() / 3);  // six square charts of a third of the tile each
}

// Many charts (issue 43): the lit ground as cells that are each their own UV island, in a layout
// whose neighbours in UV space are not neighbours on the surface. A renderer's plain bilinear
// tap into the hard atlas (README, "A shadow atlas on your own mesh": no tap skips anything,
// the gutter keeps them off empty texels) at ground point (x, z), `uv_of` its UV.
template <typename UvOf>
float hard_lookup(const Texture& atlas, float x, float z, UvOf uv_of) {
  const glm::vec2 q = uv_of(x, z) * float(atlas.width) - 0.5f;
  const int i0 = int(std::floor(q.x)), j0 = int(std::floor(q.y));
  const float fx = q.x - float(i0), fy = q.y - float(j0);
  const auto at = [&](int i, int j) {
    const int w = int(atlas.width);
    return atlas.data[size_t(std::clamp(j, 0, w - 1)) * w + size_t(std::clamp(i, 0, w - 1))];
  };
  return (1 - fy) * ((1 - fx) * at(i0, j0) + fx * at(i0 + 1, j0)) +
         fy * ((1 - fx) * at(i0, j0 + 1) + fx * at(i0 + 1, j0 + 1));
}

// The 20 m ground as kCells x kCells square cells, each its own UV island: cell k sits in slot
// (7 k + 3) mod kCells^2 of a kCells x kCells grid of the UV square, inset by `gap` UV units on
// every side; every other island is mirrored in u, and every third turned a quarter, as
// generated layouts do.
constexpr int kCells = 8;
Mesh chart_grid(float gap) {
  Mesh m;
  const float cell = 20.0f / kCells, slot = 1.0f / kCells;
  for (int k = 0; k < kCells * kCells; ++k) {
    const int s = (7 * k + 3) % (kCells * kCells);
    const glm::vec2 lo(float(s % kCells) * slot + gap, float(s / kCells) * slot + gap);
    const float span = slot - 2 * gap;
    const float x0 = -10.0f + float(k % kCells) * cell, z0 = -10.0f + float(k / kCells) * cell;
    const uint32_t base = uint32_t(m.vertex_count());
    for (glm::vec2 st : {glm::vec2(0, 0), glm::vec2(1, 0), glm::vec2(1, 1), glm::vec2(0, 1)}) {
      m.positions.insert(m.positions.end(), {x0 + st.x * cell, 0.0f, z0 + st.y * cell});
      glm::vec2 t = st;
      if (k % 2) t.x = 1 - t.x;
      if (k % 3 == 0) t = glm::vec2(t.y, 1 - t.x);
      const glm::vec2 uv = lo + t * span;
      m.uvs.insert(m.uvs.end(), {uv.x, uv.y});
    }
    // Facing up (counter-clockwise seen from +y).
    m.indices.insert(m.indices.end(), {base, base + 3, base + 2, base, base + 2, base + 1});
  }
  return m;
}

// The UV of ground point (x, z) in chart_grid's layout.
glm::vec2 chart_grid_uv(float x, float z, float gap) {
  const float cell = 20.0f / kCells, slot = 1.0f / kCells;
  const int i = std::clamp(int((x + 10.0f) / cell), 0, kCells - 1);
  const int j = std::clamp(int((z + 10.0f) / cell), 0, kCells - 1);
  const int k = j * kCells + i, s = (7 * k + 3) % (kCells * kCells);
  glm::vec2 t((x + 10.0f) / cell - float(i), (z + 10.0f) / cell - float(j));
  if (k % 2) t.x = 1 - t.x;
  if (k % 3 == 0) t = glm::vec2(t.y, 1 - t.x);
  return glm::vec2(float(s % kCells) * slot + gap, float(s / kCells) * slot + gap) +
         t * (slot - 2 * gap);
}

// The 20 m ground as 40 x 40 cells of 0.5 m, each its own UV island in the slot of its column
// and row, inset by `gap`, except that columns 16 and 19 trade places: the island of cell (17, j)
// (x in [-1.5, -1]) then lies, in UV space, beside that of cell (19, j) (x in [-0.5, 0]), under
// the occluder of atlas_request, not beside its surface neighbour (16, j).
constexpr int kSwapCells = 40;
int swapped_column(int i) {
  return i == 16 ? 19 : i == 19 ? 16 : i;
}
Mesh swapped_columns(float gap) {
  Mesh m;
  const float cell = 20.0f / kSwapCells, span = 1.0f / kSwapCells - 2 * gap;
  for (int j = 0; j < kSwapCells; ++j)
    for (int i = 0; i < kSwapCells; ++i) {
      const glm::vec2 lo(float(swapped_column(i)) / kSwapCells + gap, float(j) / kSwapCells + gap);
      const uint32_t base = uint32_t(m.vertex_count());
      for (glm::vec2 st : {glm::vec2(0, 0), glm::vec2(1, 0), glm::vec2(1, 1), glm::vec2(0, 1)}) {
        m.positions.insert(m.positions.end(), {-10.0f + (float(i) + st.x) * cell, 0.0f,
                                               -10.0f + (float(j) + st.y) * cell});
        const glm::vec2 uv = lo + st * span;
        m.uvs.insert(m.uvs.end(), {uv.x, uv.y});
      }
      m.indices.insert(m.indices.end(), {base, base + 3, base + 2, base, base + 2, base + 1});
    }
  return m;
}
glm::vec2 swapped_columns_uv(float x, float z, float gap) {
  const float cell = 20.0f / kSwapCells, span = 1.0f / kSwapCells - 2 * gap;
  const int i = std::clamp(int((x + 10.0f) / cell), 0, kSwapCells - 1);
  const int j = std::clamp(int((z + 10.0f) / cell), 0, kSwapCells - 1);
  const glm::vec2 t((x + 10.0f) / cell - float(i), (z + 10.0f) / cell - float(j));
  return glm::vec2(float(swapped_column(i)) / kSwapCells + gap, float(j) / kSwapCells + gap) +
         t * span;
}

// Per filter, the pixels of `r` (visibility, position, and with the hard filter the atlas) on the
// ground that `lit` selects, and how many of them are not lit within 1e-3.
struct LitCheck {
  size_t seen = 0, dark = 0;
  double worst = 0;
};
template <typename Select, typename UvOf>
LitCheck check_lit(const RenderResult& r, bool hard_lookup_of_atlas, Select lit, UvOf uv_of) {
  const Texture &vis = r.textures.at(0), &pos = r.textures.at(1);
  LitCheck c;
  for (size_t p = 0; p < vis.data.size(); ++p) {
    const float x = pos.data[3 * p], z = pos.data[3 * p + 2];
    if (std::isnan(x) || std::abs(pos.data[3 * p + 1]) > 1e-4f || !lit(x, z)) continue;
    ++c.seen;
    const float v = hard_lookup_of_atlas ? hard_lookup(r.textures.at(2), x, z, uv_of) : vis.data[p];
    const double err = std::isnan(v) ? 1.0 : std::abs(1.0 - v);
    c.worst = std::max(c.worst, err);
    c.dark += err > 1e-3;
  }
  return c;
}

const char* filter_name(FilterKind kind) {
  return kind == FilterKind::kAtlasSat   ? "atlas_sat"
         : kind == FilterKind::kAtlasMip ? "atlas_mip"
         : kind == FilterKind::kPcss     ? "pcss"
                                         : "hard atlas, bilinear";
}

// A lit ground of 64 charts, nothing above it, under a soft oblique sun: every atlas lookup says
// lit at every pixel. (Before the chart-aware filters this passed too: the soft filters only
// filter where the blocker search finds a blocker, and the hard atlas of an unshadowed ground is
// 1 at every texel and gutter texel, so no chart border alone darkens it.)
TEST(Atlas, ALitGroundOfManyChartsStaysLitUnderEveryAtlasLookup) {
  constexpr float kGap = 1.5f / 256;  // a texel and a half on each side of every island
  RenderRequest req = testing::occluder_request();
  auto scene = std::make_shared<Scene>();
  scene->meshes = {chart_grid(kGap)};
  scene->instances = {Instance{0}};
  req.scene = scene;
  req.lights[0].direction = glm::normalize(glm::vec3(0.4f, -1.0f, 0.3f));
  req.lights[0].size = 6.0f;
  req.shadow_map.fit = MapFit::kScene;
  req.atlas.tile = 256;
  req.atlas.gutter = 2;
  for (FilterKind kind : {FilterKind::kAtlasSat, FilterKind::kAtlasMip, FilterKind::kHard}) {
    req.filter.kind = kind;
    req.products = {Product::kVisibility, Product::kPosition};
    if (kind == FilterKind::kHard) req.products.push_back(Product::kShadowAtlas);
    const LitCheck c = check_lit(
        testing::engine().render(req), kind == FilterKind::kHard, [](float, float) { return true; },
        [&](float x, float z) { return chart_grid_uv(x, z, kGap); });
    std::printf("[ atlas    ] unshadowed charts, %s: %zu of %zu pixels below 1 - 1e-3\n",
                filter_name(kind), c.dark, c.seen);
    EXPECT_GT(c.seen, 50000u) << filter_name(kind);
    EXPECT_EQ(c.dark, 0u) << filter_name(kind) << ", worst " << c.worst;
  }
}

// The defect of issue 43: a lit surface darkened where its chart ends. The ground of
// swapped_columns under the 2 m square occluder 2 m up and a sun of 10 degrees straight down, and
// a small caster 20 m up over a far corner that widens the blocker search (its reach follows
// the map's near plane: 20 m x tan 5 degrees = 1.75 m) without shading what is checked. Every
// ground pixel farther than the penumbra (2 m x tan 5 degrees = 0.175 m) and 0.15 m of margin
// (3 atlas texels) outside the shadow square is fully lit in the closed form. Before the filters
// kept to their chart, the box or mip texels of such a point in cell (17, j) reached across its
// island's border into that of the shadowed cell (19, j): atlas_sat darkened 170 of these
// pixels (by up to 0.29), atlas_mip 527 (by up to 0.32).
TEST(Atlas, LitChartsBesideAnotherChartsShadowStayLit) {
  constexpr float kGap = 1.5f / 512;
  RenderRequest req = atlas_request(1);
  auto scene = std::make_shared<Scene>(*req.scene);
  scene->meshes = {swapped_columns(kGap), testing::quad(1, 2), testing::quad(0.05f, 20)};
  Instance high{2};
  high.receives_shadows = false;
  high.transform = glm::translate(glm::mat4(1.0f), glm::vec3(9.5f, 0, -9.5f));
  scene->instances.push_back(high);
  req.scene = scene;
  req.lights[0].size = 10.0f;
  req.atlas.tile = 512;
  const double half = 2.0 * std::tan(glm::radians(5.0));
  const auto lit = [&](float x, float z) {
    const double out = std::max(std::abs(x), std::abs(z)) - 1.0;  // outside the square's shadow
    return out > half + 0.15 && !(x > 5 && z < -5);  // the high caster's faint shadow left out
  };
  const auto uv_of = [&](float x, float z) { return swapped_columns_uv(x, z, kGap); };
  for (FilterKind kind :
       {FilterKind::kAtlasSat, FilterKind::kAtlasMip, FilterKind::kHard, FilterKind::kPcss}) {
    req.filter.kind = kind;
    req.products = {Product::kVisibility, Product::kPosition};
    if (kind == FilterKind::kHard) req.products.push_back(Product::kShadowAtlas);
    const LitCheck c =
        check_lit(testing::engine().render(req), kind == FilterKind::kHard, lit, uv_of);
    std::printf(
        "[ atlas    ] lit beside another chart's shadow, %s: %zu of %zu pixels below 1 - "
        "1e-3, worst %.4f\n",
        filter_name(kind), c.dark, c.seen, c.worst);
    EXPECT_GT(c.seen, 50000u) << filter_name(kind);
    EXPECT_EQ(c.dark, 0u) << filter_name(kind) << ", worst " << c.worst;
  }
}

// The gutter between two charts holds one chart's values, never their blend. swapped_columns with
// islands 0.7 texel short of their slots' edges in a 512 tile: the island of cell (19, j), in
// the occluder's shadow at its edge x = 0, ends in texel column 216; that of cell (17, j), lit
// at its edge x = -1.5, starts in column 218; column 217 is the gutter of both. It extends the
// lower chart, cell (17, j)'s (charts are numbered in triangle order): 1 where the old gutter
// averaged 0 and 1 to 0.5.
TEST(Atlas, GutterTexelsExtendOneChart) {
  RenderRequest req = atlas_request(1);
  auto scene = std::make_shared<Scene>(*req.scene);
  scene->meshes[0] = swapped_columns(0.7f / 512);
  req.scene = scene;
  req.atlas.tile = 512;
  const Texture t = the_atlas(testing::engine().render(req));
  req.atlas.gutter = 0;
  const Texture bare = the_atlas(testing::engine().render(req));
  int rows = 0;
  for (int j = 18; j <= 21; ++j)  // the cells' rows under the occluder, z in [-1, 1]
    for (int y = int(12.8 * j) + 2; y <= int(12.8 * (j + 1)) - 2; ++y, ++rows) {
      const auto at = [&](const Texture& a, int x) { return a.data[size_t(y) * 512 + x]; };
      ASSERT_EQ(at(bare, 216), 0.0f) << y;
      ASSERT_TRUE(std::isnan(at(bare, 217))) << y;
      ASSERT_EQ(at(bare, 218), 1.0f) << y;
      EXPECT_EQ(at(t, 217), 1.0f) << y;
    }
  EXPECT_GT(rows, 30);
}

// atlas_sat and atlas_mip read the same hard atlas over the same footprint (the penumbra's disk
// as an ellipse in the atlas) through different prefilters: strips of boxes from the SAT,
// trilinear probes from the mips. So they agree exactly where the footprint is under half an
// atlas texel: the strips hold the texel itself, and the probes read level 0 at the texel's
// centre. Under a 0.5-degree sun the penumbra (2 m x tan 0.25 degrees = 9 mm, at least half a
// map texel: 10 mm) is far under a 128-texel tile's 0.16 m: the two images are the same bit for
// bit. Under a 10-degree sun on a 512-texel tile (a radius of about 4.5 texels) the prefilters
// show: up to 0.056 apart (measured), though sized to the same spread their mean errors on the
// standard scenes agree within 0.0002 (docs/benchmarks.md).
TEST(Atlas, SatAndMipAgreeExactlyWhereTheFilterIsUnderAnAtlasTexel) {
  const auto render = [](FilterKind kind, float sun_deg, uint32_t tile) {
    RenderRequest req = atlas_request(1);
    req.products = {Product::kVisibility};
    req.filter.kind = kind;
    req.lights[0].size = sun_deg;
    req.atlas.tile = tile;
    return testing::engine().render(req).textures.at(0).data;
  };
  const std::vector<float> sat = render(FilterKind::kAtlasSat, 0.5f, 128),
                           mip = render(FilterKind::kAtlasMip, 0.5f, 128);
  ASSERT_EQ(sat.size(), mip.size());
  EXPECT_EQ(std::memcmp(sat.data(), mip.data(), sat.size() * sizeof(float)), 0);
  size_t soft = 0;
  for (float v : sat) soft += v > 0.0f && v < 1.0f;
  EXPECT_GT(soft, 100u);  // the camera's bilinear lookup still ramps across each texel
  const std::vector<float> wide_sat = render(FilterKind::kAtlasSat, 10.0f, 512),
                           wide_mip = render(FilterKind::kAtlasMip, 10.0f, 512);
  double most = 0;
  for (size_t p = 0; p < wide_sat.size(); ++p)
    if (!std::isnan(wide_sat[p]))
      most = std::max(most, double(std::abs(wide_sat[p] - wide_mip[p])));
  std::printf("[ atlas    ] atlas_sat against atlas_mip under a 10-degree sun: up to %.3f apart\n",
              most);
  EXPECT_GT(most, 0.03);
}

// The charts the filters keep to: triangles joined where they share a corner's position and UV.
TEST(Atlas, ChartsAreTheUvIslands) {
  const UvCharts grid = uv_charts(chart_grid(0.01f));
  EXPECT_EQ(grid.count, uint32_t(kCells * kCells));
  for (size_t t = 0; t < grid.of_triangle.size(); ++t) EXPECT_EQ(grid.of_triangle[t], t / 2);
  // Two triangles whose shared edge's corners are split vertices: one chart while the copies
  // agree in UV, two once the second triangle's UVs move away.
  Mesh two;
  two.positions = {0, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 1};
  two.uvs = {0, 0, 0.5f, 0, 0.5f, 0.5f, 0, 0, 0.5f, 0.5f, 0, 0.5f};
  two.indices = {0, 2, 1, 3, 5, 4};
  EXPECT_EQ(uv_charts(two).count, 1u);
  for (size_t v = 3; v < 6; ++v) two.uvs[2 * v] += 0.5f;
  const UvCharts split = uv_charts(two);
  EXPECT_EQ(split.count, 2u);
  EXPECT_EQ(split.of_triangle, (std::vector<uint32_t>{0, 1}));
}

// uv_charts against its definition, checked pair by pair: random meshes whose vertices are
// drawn from a few points and UVs, so split copies, shared corners, -0 and vertices with no UV
// all occur.
TEST(Atlas, ChartsMatchTheirDefinitionPairByPair) {
  std::mt19937 rng(43);
  for (int trial = 0; trial < 40; ++trial) {
    Mesh m;
    const uint32_t vertices = 6 + rng() % 40, triangles = 1 + rng() % 60;
    for (uint32_t v = 0; v < vertices; ++v) {
      const float x = float(rng() % 4), z = rng() % 5 == 0 ? -0.0f : float(rng() % 3);
      m.positions.insert(m.positions.end(), {x, 0.0f, z});
    }
    const uint32_t with_uv = trial % 4 == 0 ? vertices / 2 : vertices;  // the rest have none
    for (uint32_t v = 0; v < with_uv; ++v)
      m.uvs.insert(m.uvs.end(), {float(rng() % 3) * 0.25f, float(rng() % 2) * 0.5f});
    for (uint32_t i = 0; i < 3 * triangles; ++i) m.indices.push_back(rng() % vertices);
    // Two corners are one point when their position and UV (0, 0 where there is none) are
    // equal as numbers (-0 == 0); triangles that share one are in one chart.
    const auto point = [&](uint32_t v) {
      const bool uv = 2 * (size_t{v} + 1) <= m.uvs.size();
      return std::array<float, 5>{m.positions[3 * v], m.positions[3 * v + 1],
                                  m.positions[3 * v + 2], uv ? m.uvs[2 * v] : 0.0f,
                                  uv ? m.uvs[2 * v + 1] : 0.0f};
    };
    const auto touch = [&](uint32_t a, uint32_t b) {
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (point(m.indices[3 * a + i]) == point(m.indices[3 * b + j])) return true;
      return false;
    };
    std::vector<uint32_t> want(triangles, UINT32_MAX);
    uint32_t charts = 0;
    for (uint32_t t = 0; t < triangles; ++t) {
      if (want[t] != UINT32_MAX) continue;
      std::vector<uint32_t> todo{t};  // flood fill over touching triangles
      want[t] = charts;
      while (!todo.empty()) {
        const uint32_t a = todo.back();
        todo.pop_back();
        for (uint32_t b = 0; b < triangles; ++b)
          if (want[b] == UINT32_MAX && touch(a, b)) want[b] = charts, todo.push_back(b);
      }
      ++charts;
    }
    const UvCharts got = uv_charts(m);
    EXPECT_EQ(got.count, charts) << trial;
    EXPECT_EQ(got.of_triangle, want) << trial;
  }
}

}  // namespace
}  // namespace shadow
