// Virtual maps' pages against dense maps (issue 53): a clipmap level's pages, drawn into the pool
// through its page table (rasterizer.cl's PAGED), hold the texels of a dense map on the level's
// window bit for bit; and the filters reading a pixel's level through the page table (pcf.cl's
// VIRTUAL) give the dense map's visibility bit for bit. Windows of 2048^2 texels (16 x 16 pages),
// where dense maps fit, under both kernel shapes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "engine/light/cube_fit.hpp"
#include "engine/light/virtual_levels.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/pcf.hpp"
#include "engine/passes/pcss.hpp"
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
  PcssPass pcss{runtime, kernels};
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

VirtualLevels made_up_clipmap() {
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
                         const ViewSetup& setup, uint32_t size, Timeline& t) {
  const auto draws = make_draws(scene, buffers, glm::mat4(setup.world_to_ndc),
                                [](const Instance&) { return true; });
  const RasterOutput& out = s.rasterizer.run(buffers, draws, size, size, false, "dense", "size", t);
  return s.read(out.depth, size_t{size} * size);
}
std::vector<float> dense(Shape& s, const SceneBuffers& buffers, const Scene& scene,
                         const ClipmapLevel& level, Timeline& t) {
  return dense(s, buffers, scene, level.setup, kTexels, t);
}

TEST(VirtualMaps, ResidentPagesHoldTheDenseMapsTexels) {
  const Scene scene = made_up_scene();
  const VirtualLevels clipmap = made_up_clipmap();
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
      map.layout = clipmap;
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
  const VirtualLevels clipmap = made_up_clipmap();
  const std::vector<uint8_t> marks = some_pages();
  size_t marked = 0;
  for (uint8_t m : marks) marked += m;
  for (const char* profile : {"cpu", "gpu"}) {
    SCOPED_TRACE(profile);
    Shape& s = shape(profile);
    Timeline t;
    VirtualMap map;
    map.layout = clipmap;
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
  const VirtualLevels clipmap = made_up_clipmap();
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
    map.layout = clipmap;
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

// A spot light's mip chain and a point light's six (issue 53), over the same ground and triangles:
// mip m's pages hold the texels of a dense map of kTexels >> m on its face, and the lookup
// through the tables is the dense lookup of each pixel's face and mip.
struct Perspective {
  const char* name;
  Light light;
  VirtualLevels layout;
};

std::vector<Perspective> perspective_layouts(const Scene& scene) {
  Bounds b;
  const std::vector<float>& p = scene.meshes[0].positions;
  for (size_t i = 0; i < p.size(); i += 3) b.extend(glm::dvec3(p[i], p[i + 1], p[i + 2]));
  const std::vector<InstanceBounds> bounds = {{b, true, true}};
  Camera camera;  // the fits below cover the scene: the camera plays no part
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {4, 14, -3};
  spot.direction = {-0.2f, -1, 0.1f};
  spot.cone_angle_deg = 100;
  Light point;
  point.type = LightType::kPoint;
  point.position = {2, 4, 1};
  const int spot_mips = virtual_mips(LightType::kSpot, kTexels);
  const int point_mips = virtual_mips(LightType::kPoint, kTexels);
  const CubeFit cube =
      fit_cube(point, camera, bounds, kTexels >> (point_mips - 1), 4, 0.1, MapFit::kScene);
  std::vector<ViewSetup> faces;
  for (const CubeFaceFit& f : cube.faces) faces.push_back(f.setup);
  return {
      {"spot", spot,
       perspective_levels({fit_uniform_light(spot, camera, bounds, MapFit::kScene)}, {}, kTexels,
                          spot_mips)},
      {"point", point, perspective_levels(faces, cube.faces[0].setup.faces, kTexels, point_mips)}};
}

// The pages a mip's texture holds (its first (kTexels >> m) / 128 pages across), about two in
// three of them marked.
std::vector<uint8_t> some_mip_pages(const VirtualLevels& layout) {
  std::vector<uint8_t> marks(layout.levels.size() * kPages * kPages, 0);
  for (size_t l = 0; l < layout.levels.size(); ++l) {
    const uint32_t across = layout.extent(l) / kPageTexels;  // the level's rows of pages
    for (uint32_t y = 0; y < across; ++y)
      for (uint32_t x = 0; x < across; ++x) {
        const size_t i = l * kPages * kPages + y * across + x;
        marks[i] = (i * 2654435761u >> 7) % 3 != 0;
      }
  }
  return marks;
}

TEST(VirtualMaps, PerspectiveMipsHoldTheDenseMapsTexels) {
  const Scene scene = made_up_scene();
  for (const Perspective& light : perspective_layouts(scene))
    for (const char* profile : {"cpu", "gpu"}) {
      SCOPED_TRACE(::testing::Message() << light.name << ", " << profile);
      const VirtualLevels& layout = light.layout;
      const std::vector<uint8_t> marks = some_mip_pages(layout);
      size_t marked = 0;
      for (uint8_t m : marks) marked += m;
      Shape& s = shape(profile);
      Timeline t;
      SceneBuffers buffers(s.runtime, s.kernels, scene, t);
      VirtualMap map;
      map.layout = layout;
      map.marks = s.runtime.upload(marks);
      s.pages.begin(uint32_t(marked), false, t);
      s.pages.allocate(0, map, t);
      ASSERT_EQ(s.pages.counts().held, marked);
      for (uint32_t i = 0; i < layout.levels.size(); ++i) {
        if (map.level_drawn[i] == 0) continue;
        const auto draws =
            make_draws(scene, buffers, glm::mat4(layout.levels[i].setup.world_to_ndc),
                       [](const Instance&) { return true; });
        const PageTarget target = s.pages.target(map, i);
        const uint32_t size = layout.extent(i);
        s.rasterizer.run(buffers, draws, size, size, false, "pages", "size", t, {}, &target);
      }
      const std::vector<uint32_t> table = s.read<uint32_t>(map.table, marks.size());
      const std::vector<float> pool = s.read(s.pages.pool(), marked * 128 * 128);
      size_t compared = 0, covered = 0;
      for (uint32_t i = 0; i < layout.levels.size(); ++i) {
        const uint32_t size = kTexels >> layout.levels[i].level, across = size / kPageTexels;
        const ViewSetup& face = layout.levels[i].setup;  // its face's
        const std::vector<float> d = dense(s, buffers, scene, face, size, t);
        for (uint32_t py = 0; py < across; ++py)
          for (uint32_t px = 0; px < across; ++px) {
            const size_t page = size_t{i} * kPages * kPages + py * across + px;
            if (!marks[page]) continue;
            ASSERT_LT(table[page], marked);
            ++compared;
            for (uint32_t y = 0; y < 128; ++y) {
              const float* want = &d[(size_t{py} * 128 + y) * size + px * 128];
              const float* got = &pool[(size_t{table[page]} * 128 + y) * 128];
              ASSERT_EQ(std::memcmp(want, got, 128 * sizeof(float)), 0)
                  << "level " << i << ", page " << px << "," << py << ", row " << y;
              for (uint32_t x = 0; x < 128; ++x) covered += want[x] < 1.0f;
            }
          }
      }
      EXPECT_EQ(compared, marked);
      EXPECT_GT(covered, compared * 128 * 128 / 4);  // the ground and triangles were drawn
    }
}

// Every page of `layout` marked, resident in a pool just its size and drawn, with the pixels'
// levels `levels`: what the lookups read.
VirtualMap every_page_drawn(Shape& s, const Scene& scene, const SceneBuffers& buffers,
                            const VirtualLevels& layout, const std::vector<uint8_t>& levels,
                            Timeline& t) {
  std::vector<uint8_t> every(layout.levels.size() * kPages * kPages, 0);
  size_t pages = 0;
  for (size_t l = 0; l < layout.levels.size(); ++l) {
    const uint32_t across = layout.extent(l) / kPageTexels;  // a level's rows of pages
    std::fill_n(every.begin() + l * kPages * kPages, across * across, 1);
    pages += across * across;
  }
  VirtualMap map;
  map.layout = layout;
  map.marks = s.runtime.upload(every);
  map.pixel_level = s.runtime.upload(levels);
  s.pages.begin(uint32_t(pages), false, t);
  s.pages.allocate(0, map, t);
  s.pages.counts();
  for (uint32_t i = 0; i < layout.levels.size(); ++i) {
    const auto draws = make_draws(scene, buffers, glm::mat4(layout.levels[i].setup.world_to_ndc),
                                  [](const Instance&) { return true; });
    const PageTarget target = s.pages.target(map, i);
    const uint32_t size = layout.extent(i);
    s.rasterizer.run(buffers, draws, size, size, false, "pages", "size", t, {}, &target);
  }
  return map;
}

TEST(VirtualMaps, PerspectiveLookupsAreTheDenseLookups) {
  const Scene scene = made_up_scene();
  constexpr uint32_t kWidth = 97, kPixels = kWidth * 61;
  std::vector<float> positions, normals;
  for (uint32_t p = 0; p < kPixels; ++p) {  // the ground under the lights
    positions.insert(positions.end(), {-25.0f + 50.0f * (p % kWidth) / kWidth, 0.0f,
                                       -25.0f + 50.0f * (p / kWidth) / (kPixels / kWidth)});
    normals.insert(normals.end(), {0, 1, 0, 1});
  }
  for (const Perspective& light : perspective_layouts(scene)) {
    const VirtualLevels& layout = light.layout;
    // Each pixel reads its face (as marking picks it) at a mip from a fixed hash; one in seven
    // none.
    std::vector<uint8_t> levels;
    for (uint32_t p = 0; p < kPixels; ++p) {
      const glm::dvec3 x(positions[3 * p], positions[3 * p + 1], positions[3 * p + 2]);
      const int face = layout.faces == 6 ? face_of(layout.cube, x) : 0;
      levels.push_back(p % 7 == 6 ? kNoLevel
                                  : uint8_t(face * layout.mips + (p * 7919u) % layout.mips));
    }
    for (const char* profile : {"cpu", "gpu"}) {
      SCOPED_TRACE(::testing::Message() << light.name << ", " << profile);
      Shape& s = shape(profile);
      Timeline t;
      SceneBuffers buffers(s.runtime, s.kernels, scene, t);
      GBuffer g;
      g.position = s.runtime.upload(positions);
      g.normal = s.runtime.upload(normals);
      const VirtualMap map = every_page_drawn(s, scene, buffers, layout, levels, t);
      const std::vector<glm::vec2> disk = poisson_disk(16);
      const cl::Buffer taps = s.runtime.upload(disk);
      const cl::Buffer out = s.runtime.upload(std::vector<float>(kPixels));
      for (int mode : {PcfParams::kNearestMode, int(PcfParams::Mode::kBilinear),
                       int(PcfParams::Mode::kPoisson)}) {
        SCOPED_TRACE(mode);
        ShadowMapSettings settings;
        settings.size = kTexels;
        launch_pcf(s.runtime, s.kernels, g, kPixels, kWidth,
                   {{layout.levels.front().setup, &s.pages.pool(), 0, &map}}, light.light, settings,
                   mode, taps, 16, 3.0f, true, out);
        const std::vector<float> got = s.read(out, kPixels);
        std::vector<float> want(kPixels);
        size_t shadowed = 0, lit = 0;
        for (uint32_t i = 0; i < layout.levels.size(); ++i) {
          const uint32_t size = kTexels >> layout.levels[i].level;
          const ViewSetup& face = layout.levels[i].setup;
          const std::vector<float> d = dense(s, buffers, scene, face, size, t);
          const cl::Buffer depth = s.runtime.upload(d);
          settings.size = size;
          launch_pcf(s.runtime, s.kernels, g, kPixels, kWidth, {{face, &depth}}, light.light,
                     settings, mode, taps, 16, 3.0f, true, out);
          const std::vector<float> level_vis = s.read(out, kPixels);
          for (uint32_t p = 0; p < kPixels; ++p)
            if (levels[p] == i) want[p] = level_vis[p];
        }
        for (uint32_t p = 0; p < kPixels; ++p) {
          if (levels[p] == kNoLevel) {  // off every map: lit, or unlit outside a spot's cone
            EXPECT_TRUE(got[p] == 0.0f || got[p] == 1.0f) << got[p];
            continue;
          }
          ASSERT_EQ(std::memcmp(&got[p], &want[p], sizeof(float)), 0)
              << "pixel " << p << " level " << int(levels[p]) << ": " << got[p] << " vs "
              << want[p];
          shadowed += got[p] < 1.0f;
          lit += got[p] > 0.0f;
        }
        EXPECT_GT(shadowed, kPixels / 50);  // the triangles' shadows fall on the ground
        EXPECT_GT(lit, kPixels / 4);
      }
    }
  }
}

// PCSS through the page tables (pcss.cl's VIRTUAL): each pixel's level read as the dense map of
// that level, bit for bit, for a sun's clipmap and a spot light's mips. The lights are small
// enough that no blocker search reaches PcssPass::kMaxVirtualSearch texels (where the virtual
// search stops and the dense one goes on).
TEST(VirtualMaps, PcssThroughThePageTableIsTheDensePcss) {
  const Scene scene = made_up_scene();
  constexpr uint32_t kWidth = 97, kPixels = kWidth * 61;
  std::vector<float> positions, normals;
  for (uint32_t p = 0; p < kPixels; ++p) {  // the ground under the finest window
    positions.insert(positions.end(), {-2.0f + 5.0f * (p % kWidth) / kWidth, 0.0f,
                                       -4.0f + 5.0f * (p / kWidth) / (kPixels / kWidth)});
    normals.insert(normals.end(), {0, 1, 0, 1});
  }
  Light sun;
  sun.direction = {0.3f, -1.0f, 0.2f};
  sun.size = 0.2f;  // degrees: searches up to ~9 texels of level 3 (the depth runs ~20 units)
  const VirtualLevels clipmap = made_up_clipmap();
  std::vector<Perspective> lights = {{"sun", sun, clipmap}};
  for (Perspective& p : perspective_layouts(scene))
    if (p.layout.faces == 1) {
      p.light.size = 0.3f;  // the spot's radius: searches up to ~5 texels of mip 0
      lights.push_back(p);
    }
  PcssSettings params;
  params.blocker_samples = 16;
  params.filter_samples = 32;
  for (const Perspective& light : lights) {
    const VirtualLevels& layout = light.layout;
    std::vector<uint8_t> levels;
    for (uint32_t p = 0; p < kPixels; ++p)
      levels.push_back(p % 7 == 6 ? kNoLevel : uint8_t((p * 7919u) % layout.levels.size()));
    for (const char* profile : {"cpu", "gpu"}) {
      SCOPED_TRACE(::testing::Message() << light.name << ", " << profile);
      Shape& s = shape(profile);
      Timeline t;
      SceneBuffers buffers(s.runtime, s.kernels, scene, t);
      GBuffer g;
      g.position = s.runtime.upload(positions);
      g.normal = s.runtime.upload(normals);
      const VirtualMap map = every_page_drawn(s, scene, buffers, layout, levels, t);
      ShadowMapSettings settings;
      settings.size = kTexels;
      const std::vector<float> got =
          s.read(s.pcss.run(g, kPixels, kWidth, s.pages.pool(), layout.levels.front().setup,
                            light.light, settings, params, t, &map),
                 kPixels);
      std::vector<float> want(kPixels, 1.0f);  // kNoLevel: off every map, lit
      for (uint32_t i = 0; i < layout.levels.size(); ++i) {
        const uint32_t size = layout.extent(i);
        const std::vector<float> d = dense(s, buffers, scene, layout.levels[i].setup, size, t);
        const cl::Buffer depth = s.runtime.upload(d);
        settings.size = size;
        const std::vector<float> level_vis =
            s.read(s.pcss.run(g, kPixels, kWidth, depth, layout.levels[i].setup, light.light,
                              settings, params, t),
                   kPixels);
        for (uint32_t p = 0; p < kPixels; ++p)
          if (levels[p] == i) want[p] = level_vis[p];
      }
      size_t penumbra = 0, shadowed = 0;
      for (uint32_t p = 0; p < kPixels; ++p) {
        if (light.layout.faces == 1 && levels[p] == kNoLevel) continue;  // the cone decides
        ASSERT_EQ(std::memcmp(&got[p], &want[p], sizeof(float)), 0)
            << "pixel " << p << " level " << int(levels[p]) << ": " << got[p] << " vs " << want[p];
        penumbra += got[p] > 0.0f && got[p] < 1.0f;
        shadowed += got[p] == 0.0f;
      }
      std::printf("%s, %s: %zu penumbra pixels, %zu shadowed of %u\n", light.name, profile,
                  penumbra, shadowed, kPixels);
      EXPECT_GT(penumbra, 20u);  // soft edges (measured: 42 under the sun, 285 under the spot)
      EXPECT_GT(shadowed, kPixels / 10);  // and umbrae
    }
  }
}

}  // namespace
}  // namespace shadow
