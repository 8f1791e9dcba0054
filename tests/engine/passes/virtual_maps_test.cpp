// Virtual maps' pages against dense maps (issue 53): a clipmap level's pages, drawn into the pool
// through its page table (rasterizer.cl's PAGED), hold the texels of a dense map on the level's
// window bit for bit; and the filters reading a pixel's level through the page table (pcf.cl's
// VIRTUAL) give the dense map's visibility bit for bit. Windows of 2048^2 texels (16 x 16 pages),
// where dense maps fit, under both kernel shapes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "engine/light/virtual_levels.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/pcf.hpp"
#include "engine/passes/poisson_disk.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/passes/virtual_pages.hpp"
#include "engine_fixture.hpp"

namespace shadow {
namespace {

constexpr uint32_t kTexels = 2048, kPages = kTexels / kPageTexels;
constexpr int kFirstLevel = 3, kLastLevel = 6;  // windows 8 to 64 world units across
constexpr uint32_t kLevels = kLastLevel - kFirstLevel + 1;

struct Shape : testing::ProfileDevice {
  using ProfileDevice::ProfileDevice;
  Rasterizer rasterizer{runtime, kernels};
  VirtualPagesPass pages{runtime, kernels};
};

Shape& shape(const std::string& profile) {
  static Shape cpu("cpu"), gpu("gpu");  // kept: PoCL does not take a context's end mid-binary
  return profile == "gpu" ? gpu : cpu;
}

// A ground of 80 x 80 world units at y = 0 and 400 random triangles up to 3 units above it, with
// some large ones crossing many pages.
Scene made_up_scene() {
  Mesh m;
  m.positions = {-40, 0, -40, 40, 0, -40, 40, 0, 40, -40, 0, 40};
  m.indices = {0, 2, 1, 0, 3, 2};
  std::mt19937 rng(53);
  std::uniform_real_distribution<float> at(-30, 30), up(0.2f, 3), size(0.05f, 1.5f);
  for (int t = 0; t < 400; ++t) {
    const float x = at(rng), z = at(rng), s = t % 50 == 0 ? 12.0f : size(rng);
    const uint32_t base = uint32_t(m.positions.size() / 3);
    m.positions.insert(m.positions.end(),
                       {x, up(rng), z, x + s, up(rng), z + 0.3f * s, x - 0.4f * s, up(rng), z + s});
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
  }
  Scene scene;
  scene.meshes.push_back(std::move(m));
  scene.instances.push_back(Instance{});
  return scene;
}

DirectionalClipmap made_up_clipmap() {
  Light sun;
  sun.direction = {0.3f, -1.0f, 0.2f};
  Bounds b;
  b.extend(glm::dvec3(-40, 0, -40));
  b.extend(glm::dvec3(40, 4, 40));
  return directional_clipmap(sun, {1.3, 1.7, -2.1}, b, kTexels, kFirstLevel, kLastLevel);
}

// Pages marked: about two in three, from a fixed hash.
std::vector<uint8_t> some_pages() {
  std::vector<uint8_t> marks(size_t{kLevels} * kPages * kPages);
  for (size_t i = 0; i < marks.size(); ++i) marks[i] = (i * 2654435761u >> 7) % 3 != 0;
  return marks;
}

std::vector<float> dense(Shape& s, const SceneBuffers& buffers, const Scene& scene,
                         const ClipmapLevel& level, Timeline& t) {
  const auto draws = make_draws(scene, buffers, glm::mat4(level.setup.world_to_ndc),
                                [](const Instance&) { return true; });
  const RasterOutput& out =
      s.rasterizer.run(buffers, draws, kTexels, kTexels, false, "dense", "size", t);
  return s.read(out.depth, size_t{kTexels} * kTexels);
}

TEST(VirtualMaps, ResidentPagesHoldTheDenseMapsTexels) {
  const Scene scene = made_up_scene();
  const DirectionalClipmap clipmap = made_up_clipmap();
  const std::vector<uint8_t> marks = some_pages();
  size_t marked = 0;
  for (uint8_t m : marks) marked += m;
  for (const char* profile : {"cpu", "gpu"})
    for (uint32_t pool_pages : {1024u, 300u}) {  // every marked page resident; the pool too small
      SCOPED_TRACE(::testing::Message() << profile << ", pool " << pool_pages);
      Shape& s = shape(profile);
      Timeline t;
      SceneBuffers buffers(s.runtime, s.kernels, scene, t);
      VirtualMap map;
      map.clipmap = clipmap;
      map.marks = s.runtime.upload(marks);
      s.pages.begin(pool_pages, false, t);
      s.pages.allocate(0, map, t);
      const VirtualPagesPass::Counts counts = s.pages.counts();
      EXPECT_EQ(counts.marked, marked);
      EXPECT_EQ(counts.held, std::min<size_t>(marked, pool_pages));
      EXPECT_EQ(counts.drawn, counts.held);  // a fresh pool draws every page it holds
      for (uint32_t i = 0; i < kLevels; ++i) {
        const ClipmapLevel& level = clipmap.levels[i];
        const auto draws = make_draws(scene, buffers, glm::mat4(level.setup.world_to_ndc),
                                      [](const Instance&) { return true; });
        const PageTarget target = s.pages.target(map, i);
        s.rasterizer.run(buffers, draws, kTexels, kTexels, false, "pages", "size", t, {}, &target);
      }
      const std::vector<uint32_t> table = s.read<uint32_t>(map.table, marks.size());
      const std::vector<float> pool = s.read(s.pages.pool(), size_t{pool_pages} * 128 * 128);
      size_t resident = 0, covered = 0;
      for (uint32_t i = 0; i < kLevels; ++i) {
        const std::vector<float> d = dense(s, buffers, scene, clipmap.levels[i], t);
        for (uint32_t py = 0; py < kPages; ++py)
          for (uint32_t px = 0; px < kPages; ++px) {
            const size_t page = (size_t{i} * kPages + py) * kPages + px;
            const uint32_t slot = table[page];
            if (!marks[page]) {
              EXPECT_EQ(slot, kNoPage);
              continue;
            }
            if (slot == kNoPage) continue;  // past the pool
            ASSERT_LT(slot, pool_pages);
            ++resident;
            for (uint32_t y = 0; y < 128; ++y) {
              const float* want = &d[(size_t{py} * 128 + y) * kTexels + px * 128];
              const float* got = &pool[(size_t{slot} * 128 + y) * 128];
              ASSERT_EQ(std::memcmp(want, got, 128 * sizeof(float)), 0)
                  << "level " << i << ", page " << px << "," << py << ", row " << y;
              for (uint32_t x = 0; x < 128; ++x) covered += want[x] < 1.0f;
            }
          }
      }
      EXPECT_EQ(resident, counts.held);
      EXPECT_GT(covered, resident * 128 * 128 / 2);  // the ground and triangles were drawn
    }
}

// Kept across frames: the same marks again draw nothing and give every page its slot again; a
// page the marks no longer hold frees its slot for a new one, the least recently marked first.
TEST(VirtualMaps, PagesKeepTheirSlotsFromFrameToFrame) {
  const DirectionalClipmap clipmap = made_up_clipmap();
  const std::vector<uint8_t> marks = some_pages();
  size_t marked = 0;
  for (uint8_t m : marks) marked += m;
  for (const char* profile : {"cpu", "gpu"}) {
    SCOPED_TRACE(profile);
    Shape& s = shape(profile);
    Timeline t;
    VirtualMap map;
    map.clipmap = clipmap;
    map.marks = s.runtime.upload(marks);
    std::vector<uint32_t> first;
    for (int frame = 0; frame < 3; ++frame) {
      SCOPED_TRACE(frame);
      s.pages.begin(1024, frame > 0, t);
      s.pages.allocate(0, map, t);
      const VirtualPagesPass::Counts c = s.pages.counts();
      EXPECT_EQ(c.marked, marked);
      EXPECT_EQ(c.held, marked);
      EXPECT_EQ(c.drawn, frame == 0 ? marked : 0u);
      const std::vector<uint32_t> table = s.read<uint32_t>(map.table, marks.size());
      if (frame == 0) first = table;
      EXPECT_EQ(table, first);
    }
    // A pool of 20: frame A marks pages 0-9, B 10-19, C 20-29. B takes the slots A left free
    // (never owned first), C those of A (marked two frames ago) before those of B (one).
    std::vector<uint8_t> abc(marks.size(), 0);
    std::vector<uint32_t> slots_of[3];
    for (int frame = 0; frame < 3; ++frame) {
      std::fill(abc.begin(), abc.end(), 0);
      std::fill(abc.begin() + 10 * frame, abc.begin() + 10 * frame + 10, 1);
      map.marks = s.runtime.upload(abc);
      s.pages.begin(20, frame > 0, t);
      s.pages.allocate(0, map, t);
      const VirtualPagesPass::Counts c = s.pages.counts();
      EXPECT_EQ(c.held, 10u);
      EXPECT_EQ(c.drawn, 10u);
      const std::vector<uint32_t> table = s.read<uint32_t>(map.table, marks.size());
      slots_of[frame].assign(table.begin() + 10 * frame, table.begin() + 10 * frame + 10);
    }
    for (int k = 0; k < 10; ++k) {
      EXPECT_EQ(slots_of[0][k], uint32_t(k));
      EXPECT_EQ(slots_of[1][k], uint32_t(10 + k));
      EXPECT_EQ(slots_of[2][k], uint32_t(k));
    }
  }
}

// Receivers on the ground under the finest window, each given a level (by its index); every page
// resident. The virtual lookup reads each pixel's level as the dense lookup reads that level's map.
TEST(VirtualMaps, TheLookupThroughThePageTableIsTheDenseLookup) {
  const Scene scene = made_up_scene();
  const DirectionalClipmap clipmap = made_up_clipmap();
  constexpr uint32_t kWidth = 97, kPixels = kWidth * 61;
  std::vector<float> positions, normals;
  std::vector<uint8_t> levels;
  const glm::dmat4 to_world = glm::inverse(clipmap.view);
  const ClipmapLevel& finest = clipmap.levels.front();
  for (uint32_t p = 0; p < kPixels; ++p) {
    // Across the finest window in light space, dropped onto the ground along the light.
    const glm::dvec2 page0 = finest.first_page * double(clipmap_texel(kFirstLevel, kTexels) * 128);
    const glm::dvec2 ls = page0 + glm::dvec2(0.3 + 7.4 * (p % kWidth) / kWidth,
                                             0.3 + 7.4 * (p / kWidth) / (kPixels / kWidth));
    const glm::dvec3 a(to_world * glm::dvec4(ls, 0, 1)), b(to_world * glm::dvec4(ls, -1, 1));
    const glm::dvec3 ground = a + (b - a) * (a.y / (a.y - b.y));
    positions.insert(positions.end(), {float(ground.x), 0.0f, float(ground.z)});
    normals.insert(normals.end(), {0, 1, 0, 1});
    levels.push_back(p % 7 == 6 ? kNoLevel : uint8_t(p % kLevels));
  }
  std::vector<uint8_t> every(size_t{kLevels} * kPages * kPages, 1);
  Light sun;
  sun.direction = {0.3f, -1.0f, 0.2f};
  ShadowMapSettings settings;
  settings.size = kTexels;
  for (const char* profile : {"cpu", "gpu"}) {
    SCOPED_TRACE(profile);
    Shape& s = shape(profile);
    Timeline t;
    SceneBuffers buffers(s.runtime, s.kernels, scene, t);
    GBuffer g;
    g.position = s.runtime.upload(positions);
    g.normal = s.runtime.upload(normals);
    VirtualMap map;
    map.clipmap = clipmap;
    map.marks = s.runtime.upload(every);
    map.pixel_level = s.runtime.upload(levels);
    std::vector<glm::mat4> ndc;
    for (const ClipmapLevel& l : clipmap.levels) ndc.emplace_back(l.setup.world_to_ndc);
    map.level_ndc = s.runtime.upload(ndc);
    s.pages.begin(kLevels * kPages * kPages, false, t);
    s.pages.allocate(0, map, t);
    s.pages.counts();
    for (uint32_t i = 0; i < kLevels; ++i) {
      const auto draws = make_draws(scene, buffers, glm::mat4(clipmap.levels[i].setup.world_to_ndc),
                                    [](const Instance&) { return true; });
      const PageTarget target = s.pages.target(map, i);
      s.rasterizer.run(buffers, draws, kTexels, kTexels, false, "pages", "size", t, {}, &target);
    }
    const std::vector<glm::vec2> disk = poisson_disk(16);
    const cl::Buffer taps = s.runtime.upload(disk);
    const cl::Buffer out = s.runtime.upload(std::vector<float>(kPixels));
    for (int mode : {PcfParams::kNearestMode, int(PcfParams::Mode::kBilinear),
                     int(PcfParams::Mode::kPoisson)}) {
      SCOPED_TRACE(mode);
      launch_pcf(s.runtime, s.kernels, g, kPixels, kWidth,
                 {{finest.setup, &s.pages.pool(), 0, &map}}, sun, settings, mode, taps, 16, 3.0f,
                 true, out);
      const std::vector<float> got = s.read(out, kPixels);
      std::vector<float> want(kPixels, 1.0f);  // kNoLevel: lit
      size_t shadowed = 0;
      for (uint32_t i = 0; i < kLevels; ++i) {
        const std::vector<float> d = dense(s, buffers, scene, clipmap.levels[i], t);
        const cl::Buffer depth = s.runtime.upload(d);
        launch_pcf(s.runtime, s.kernels, g, kPixels, kWidth, {{clipmap.levels[i].setup, &depth}},
                   sun, settings, mode, taps, 16, 3.0f, true, out);
        const std::vector<float> level_vis = s.read(out, kPixels);
        for (uint32_t p = 0; p < kPixels; ++p)
          if (levels[p] == i) want[p] = level_vis[p];
      }
      for (uint32_t p = 0; p < kPixels; ++p) {
        ASSERT_EQ(std::memcmp(&got[p], &want[p], sizeof(float)), 0)
            << "pixel " << p << " level " << int(levels[p]) << ": " << got[p] << " vs " << want[p];
        shadowed += got[p] < 1.0f;
      }
      EXPECT_GT(shadowed, kPixels / 50);  // the triangles' shadows fall on the ground
    }
  }
}

}  // namespace
}  // namespace shadow
