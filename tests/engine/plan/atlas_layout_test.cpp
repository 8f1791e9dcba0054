// The shadow atlas' layout (engine/plan/atlas_layout): tiles sized from the world, packed without
// overlap, and the limits that refuse by name. Host code only, no device.
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/plan/atlas_layout.hpp"
#include "engine/plan/validate.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

// A unit square in x-z (world area 1) whose UVs cover its whole tile.
Mesh unit_square() {
  Mesh m;
  m.positions = {0, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1};
  m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  m.indices = {0, 2, 1, 0, 3, 2};
  return m;
}

Instance scaled(float s, glm::vec3 at = glm::vec3(0)) {
  Instance i{0};
  i.transform = glm::scale(glm::translate(glm::mat4(1.0f), at), glm::vec3(s));
  return i;
}

RenderRequest request_of(std::vector<Instance> instances) {
  auto scene = std::make_shared<Scene>();
  scene->meshes = {unit_square()};
  scene->instances = std::move(instances);
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 30, 30};
  r.lights[0].type = LightType::kDirectional;
  r.lights[0].direction = {0, -1, 0};
  r.shadow_map.fit = MapFit::kScene;
  r.products = {Product::kShadowAtlas};
  return r;
}

const AtlasTile& tile_of(const AtlasLayout& l, uint32_t instance) {
  return *std::find_if(l.tiles.begin(), l.tiles.end(),
                       [&](const AtlasTile& t) { return t.instance == instance; });
}

// No two tiles share a texel; each lies in the atlas, at a multiple of its own size; and the
// cell grid names the tile over every texel.
void expect_packed(const AtlasLayout& l) {
  for (size_t a = 0; a < l.tiles.size(); ++a) {
    const AtlasTile& t = l.tiles[a];
    EXPECT_EQ(t.x % t.size, 0u);
    EXPECT_EQ(t.y % t.size, 0u);
    EXPECT_LE(t.x + t.size, l.size.width);
    EXPECT_LE(t.y + t.size, l.size.height);
    EXPECT_EQ(t.size % l.cell, 0u);
    for (size_t b = a + 1; b < l.tiles.size(); ++b) {
      const AtlasTile& u = l.tiles[b];
      const bool apart =
          t.x + t.size <= u.x || u.x + u.size <= t.x || t.y + t.size <= u.y || u.y + u.size <= t.y;
      EXPECT_TRUE(apart) << t.instance << " and " << u.instance;
    }
  }
  const std::vector<glm::uvec4> cells = tile_cells(l);
  const uint64_t row = l.size.width / l.cell;
  ASSERT_EQ(cells.size(), row * (l.size.height / l.cell));
  uint64_t covered = 0;
  for (const glm::uvec4& c : cells) covered += c.w;
  uint64_t tiled = 0;
  for (const AtlasTile& t : l.tiles) {
    tiled += uint64_t{t.size / l.cell} * (t.size / l.cell);
    const glm::uvec4 c = cells[(t.y / l.cell) * row + t.x / l.cell];
    EXPECT_EQ(c, glm::uvec4(t.x, t.y, t.size, 1u));
  }
  EXPECT_EQ(covered, tiled);
}

TEST(AtlasLayout, EqualTilesLieInInstanceOrderRowByRow) {
  // What a fixed tile always gave: a near-square grid, instance order, row by row.
  const AtlasLayout l = pack_atlas({64, 0, 64, 64, 64, 64});
  ASSERT_EQ(l.tiles.size(), 5u);
  EXPECT_EQ(l.size.width, 3u * 64);
  EXPECT_EQ(l.size.height, 2u * 64);
  const uint32_t want[5][3] = {{0, 0, 0}, {2, 64, 0}, {3, 128, 0}, {4, 0, 64}, {5, 64, 64}};
  for (size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(l.tiles[k].instance, want[k][0]);
    EXPECT_EQ(l.tiles[k].x, want[k][1]);
    EXPECT_EQ(l.tiles[k].y, want[k][2]);
    EXPECT_EQ(l.tiles[k].size, 64u);
  }
  expect_packed(l);
}

TEST(AtlasLayout, MixedPowersOfTwoPackWithoutOverlapOrGaps) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<uint32_t> sizes(1 + random() % 60);
    uint64_t area = 0;
    for (uint32_t& s : sizes) {
      s = random() % 7 == 0 ? 0 : 16u << (random() % 6);  // 16..512, some instances without
      area += uint64_t{s} * s;
    }
    const AtlasLayout l = pack_atlas(sizes);
    expect_packed(l);
    if (l.tiles.empty()) continue;
    // Largest first along a Z-order curve: every block of the largest tile's side but the
    // last is full, and the blocks lie in a near-square grid.
    const uint64_t block = uint64_t{l.largest} * l.largest, blocks = (area + block - 1) / block;
    const uint64_t columns = uint64_t(std::ceil(std::sqrt(double(blocks) - 1e-9)));
    EXPECT_LE(l.size.width * l.size.height, columns * ((blocks + columns - 1) / columns) * block);
  }
}

TEST(AtlasLayout, TilesFollowTheDensityOnEachInstancesSurface) {
  RenderRequest r = request_of({scaled(64), scaled(4, {100, 0, 0}), scaled(0.5f, {-50, 0, 0})});
  r.atlas.texel_world_size = 0.25;
  // 64 m / 0.25 = 256 texels; 4 m: 16; 0.5 m: 2, raised to the smallest tile.
  const AtlasLayout l = atlas_layout(r);
  EXPECT_EQ(tile_of(l, 0).size, 256u);
  EXPECT_EQ(tile_of(l, 1).size, 16u);
  EXPECT_EQ(tile_of(l, 2).size, kMinAtlasTile);
  EXPECT_EQ(l.halved, 0u);
  expect_packed(l);
  // Not a power of two: the next one up (texels at least as fine as asked).
  r.atlas.texel_world_size = 0.3;  // 213 texels
  EXPECT_EQ(tile_of(atlas_layout(r), 0).size, 256u);
  // Past the largest tile: the largest.
  r.atlas.texel_world_size = 0.001;
  EXPECT_EQ(tile_of(atlas_layout(r), 0).size, kMaxAtlasTile);
  // A gutter of 16 needs tiles over 64 texels.
  r.atlas.texel_world_size = 0.25;
  r.atlas.gutter = 16;
  EXPECT_EQ(tile_of(atlas_layout(r), 1).size, 128u);
}

TEST(AtlasLayout, TheUvAreaCounts) {
  RenderRequest r = request_of({scaled(32)});
  r.atlas.texel_world_size = 0.25;
  EXPECT_EQ(tile_of(atlas_layout(r), 0).size, 128u);
  // UVs over a quarter of the square: one UV unit spans twice the world.
  auto scene = std::make_shared<Scene>(*r.scene);
  for (float& uv : scene->meshes[0].uvs) uv *= 0.5f;
  r.scene = scene;
  EXPECT_EQ(tile_of(atlas_layout(r), 0).size, 256u);
  // A layout the server generates counts as kGeneratedUvCoverage of its square.
  r.atlas.generate_uvs = true;
  EXPECT_EQ(tile_of(atlas_layout(r), 0).size, 256u);  // 32 / sqrt(0.6) / 0.25 = 165
}

// The default: the shadow map's texel on each receiver. A directional map fitted to the scene
// spans the receivers: 2048 texels over the 64 m square.
TEST(AtlasLayout, TheDefaultFollowsTheMapsTexelFootprint) {
  RenderRequest r = request_of({scaled(64, {-32, 0, -32}), scaled(2, {0, 0.5f, 0})});
  r.shadow_map.size = 2048;
  const std::vector<double> texel = map_texel_world_size(r);
  ASSERT_EQ(texel.size(), 2u);
  EXPECT_NEAR(texel[0], 64.0 / 2048, 64.0 / 2048 * 0.05);  // the fit adds a small margin
  EXPECT_EQ(texel[0], texel[1]);                           // orthographic: one texel size
  const AtlasLayout l = atlas_layout(r);
  EXPECT_EQ(tile_of(l, 0).size, 2048u);
  EXPECT_EQ(tile_of(l, 1).size, 64u);  // 2 m at 1/32 m: 64 texels
  // A spot light's texel grows with the distance: the farther square gets fewer texels.
  RenderRequest spot = request_of({scaled(4, {-2, 0, -2}), scaled(4, {-2, -40, -2})});
  spot.lights[0].type = LightType::kSpot;
  spot.lights[0].position = {0, 10, 0};
  spot.lights[0].cone_angle_deg = 60;
  const std::vector<double> st = map_texel_world_size(spot);
  EXPECT_NEAR(st[1] / st[0], 50.0 / 10.0, 1e-9);
  const AtlasLayout sl = atlas_layout(spot);
  EXPECT_EQ(tile_of(sl, 0).size / tile_of(sl, 1).size, 4u);  // 5x farther: 2 powers of two
}

// Where the footprint would pass the default budget, every tile is halved until it fits; a
// density the request names is kept, and validate() refuses it past the limits by name.
TEST(AtlasLayout, TheBudgetHalvesTheDefaultAndRefusesANamedDensityByName) {
  std::vector<Instance> many;
  for (int i = 0; i < 8; ++i) many.push_back(scaled(64, {80.0f * i, 0, 0}));
  RenderRequest r = request_of(many);
  r.shadow_map.size = 8192;
  const AtlasLayout l = atlas_layout(r);
  EXPECT_GT(l.halved, 0u);
  EXPECT_LE(l.size.width * l.size.height, kDefaultAtlasTexels);
  expect_packed(l);
  const Limits limits{uint64_t{1} << 40, uint64_t{1} << 31};
  EXPECT_NO_THROW(validate(r, limits));

  r.atlas.texel_world_size = 64.0 / 4096;  // 8 tiles of 4096 in a 3 x 3 grid: 12288^2
  EXPECT_EQ(atlas_layout(r).halved, 0u);
  try {
    validate(r, limits);
    FAIL() << "an atlas over the buffer limit";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "atlas.texel_world_size");
    EXPECT_NE(std::string(e.what()).find("--atlas-density"), std::string::npos) << e.what();
  }
  r.atlas.texel_world_size = 64.0 / 1024;
  EXPECT_NO_THROW(validate(r, limits));

  // A tile and a density together, and a density that is no number, are named.
  r.atlas.tile = 64;
  try {
    validate(r, limits);
    FAIL() << "tile and density together";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.field(), "atlas.texel_world_size");
  }
  r.atlas.tile = 0;
  for (double bad : {-1.0, double(NAN), double(INFINITY)}) {
    r.atlas.texel_world_size = bad;
    try {
      validate(r, limits);
      FAIL() << bad;
    } catch (const InvalidArgument& e) {
      EXPECT_EQ(e.field(), "atlas.texel_world_size") << bad;
    }
  }
}

}  // namespace
}  // namespace shadow
