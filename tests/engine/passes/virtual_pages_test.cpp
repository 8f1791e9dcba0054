// Page marking (kernels/virtual_pages.cl) against the same rules in double precision on the
// host, on a made-up view of three patches under a sun: one at a texel and a half of level 5, one
// twice as coarse (level 6), one too coarse for any level (counted outside), with sky and a depth
// jump between them. Positions keep a quarter texel from every level and page boundary, so float
// and double agree; both kernel shapes must mark the same bytes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/light/virtual_levels.hpp"
#include "engine/passes/virtual_pages.hpp"
#include "engine_fixture.hpp"

namespace shadow {
namespace {

constexpr uint32_t kTexels = 2048, kPages = kTexels / kPageTexels;
constexpr uint32_t kWidth = 64, kHeight = 48;
constexpr int kFirstLevel = 3, kLastLevel = 8;

struct View {
  Camera camera;
  VirtualLevels clipmap;
  std::vector<float> positions;  // kWidth x kHeight, NaN = sky
};

View made_up_view() {
  View v;
  v.camera.eye = {0.0f, 10.0f, 0.0f};
  v.camera.target = {0.0f, 0.0f, 0.0f};
  v.camera.up = {1.0f, 0.0f, 0.0f};
  v.camera.width = kWidth, v.camera.height = kHeight;
  Light sun;
  sun.direction = {0.2f, -1.0f, 0.1f};
  Bounds scene;
  scene.extend(glm::dvec3(-50, -1, -50));
  scene.extend(glm::dvec3(50, 5, 50));
  v.clipmap =
      directional_clipmap(sun, glm::dvec3(v.camera.eye), scene, kTexels, kFirstLevel, kLastLevel);
  const glm::dmat4 to_world = glm::inverse(v.clipmap.view);
  const double texel5 = clipmap_texel(5, kTexels), quarter = texel5 / 4;
  const glm::dvec2 eye_ls(v.clipmap.view * glm::dvec4(glm::dvec3(v.camera.eye), 1.0));
  v.positions.assign(size_t{kWidth} * kHeight * 3, NAN);
  for (uint32_t y = 0; y < kHeight; ++y)
    for (uint32_t x = 0; x < kWidth; ++x) {
      const uint32_t band = y / 16;  // rows 0-15: level 5, 16-31: level 6, 32-47: too coarse
      if (y % 16 == 15 || x == 40) continue;  // sky between the bands, and a column of it
      const double step = band == 0 ? 1.5 * texel5 : band == 1 ? 3 * texel5 : 40.0;
      // Around the camera's page corner of level 5 (and a whole page of level 6 on), a quarter
      // texel off the grid.
      const double page5 = texel5 * kPageTexels;
      const glm::dvec2 corner = glm::floor(eye_ls / page5) * page5 + quarter;
      const glm::dvec2 at = corner + glm::dvec2((double(x) - 30.0) * step,
                                                (double(y % 16) - 7.0) * step + band * page5);
      const glm::dvec3 p(to_world * glm::dvec4(at, x > 50 ? -30.0 : -9.0, 1.0));  // a jump
      for (int k = 0; k < 3; ++k) v.positions[(size_t(y) * kWidth + x) * 3 + k] = float(p[k]);
    }
  return v;
}

struct Marked {
  std::vector<uint8_t> marks, levels;
  uint64_t outside = 0, coarsened = 0;
  bool operator==(const Marked&) const = default;
};

// The kernel's rules in double.
Marked reference(const View& v, double bias, double reach, double coarsen_beyond) {
  const VirtualLevels& c = v.clipmap;
  Marked m;
  std::vector<uint8_t>& marks = m.marks;
  marks.assign(c.levels.size() * kPages * kPages, 0);
  std::vector<uint8_t>& levels = m.levels;
  uint64_t& outside = m.outside;
  const glm::dvec3 eye(v.camera.eye);
  const double pixel_angle = 2 * std::tan(glm::radians(0.5 * double(v.camera.fov_deg))) / kHeight;
  const auto at = [&](uint32_t i) {
    return glm::dvec3(v.positions[3 * i], v.positions[3 * i + 1], v.positions[3 * i + 2]);
  };
  outside = 0;
  levels.assign(kWidth * kHeight, kNoLevel);
  for (uint32_t i = 0; i < kWidth * kHeight; ++i) {
    const glm::dvec3 x = at(i);
    if (std::isnan(x.x)) continue;
    const double own = glm::length(x - eye) * pixel_angle;
    double footprint = 0;
    for (uint32_t q : {i % kWidth + 1 < kWidth ? i + 1 : ~0u, i + kWidth}) {
      if (q >= kWidth * kHeight) continue;
      const glm::dvec3 d = at(q) - x;
      if (std::isnan(d.x) || glm::length(d) > 4 * own) continue;
      const glm::dvec3 u(c.view[0][0], c.view[1][0], c.view[2][0]);
      const glm::dvec3 w(c.view[0][1], c.view[1][1], c.view[2][1]);
      footprint = std::max({footprint, std::abs(glm::dot(d, u)), std::abs(glm::dot(d, w))});
    }
    if (footprint == 0) footprint = own;
    int level = std::clamp(clipmap_level(footprint, bias, kTexels), kFirstLevel, kLastLevel);
    const double distance = glm::length(x - eye);
    const int coarser = std::min(
        distance > coarsen_beyond ? int(std::floor(std::log2(distance / coarsen_beyond))) + 1 : 0,
        std::max(kLastLevel - level, 0));
    level += coarser;
    const glm::dvec2 ls(c.view * glm::dvec4(x, 1.0));
    glm::dvec2 t(0.0);
    for (; level <= kLastLevel; ++level) {
      t = ls / clipmap_texel(level, kTexels) - c.levels[level - kFirstLevel].first_page * 128.0;
      if (t.x >= reach && t.y >= reach && t.x < kTexels - reach && t.y < kTexels - reach) break;
    }
    if (level > kLastLevel) {
      ++outside;
      continue;
    }
    levels[i] = uint8_t(level - kFirstLevel);
    m.coarsened += coarser > 0;
    for (double dy : {-reach, reach})
      for (double dx : {-reach, reach}) {
        const auto px = uint32_t((t.x + dx) / 128), py = uint32_t((t.y + dy) / 128);
        marks[(size_t(level - kFirstLevel) * kPages + py) * kPages + px] = 1;
      }
  }
  return m;
}

// One device per kernel shape, kept for the binary's life (as the other shape tests keep theirs).
struct Shape : testing::ProfileDevice {
  using ProfileDevice::ProfileDevice;
  VirtualPagesPass pass{runtime, kernels};
};

Shape& shape(const std::string& profile) {
  static Shape cpu("cpu"), gpu("gpu");
  return profile == "gpu" ? gpu : cpu;
}

Marked marked(const std::string& profile, const View& v, double bias, uint32_t reach,
              float coarsen_beyond) {
  Shape& s = shape(profile);
  GBuffer g;
  g.position = s.runtime.upload(v.positions);
  Timeline t;
  const VirtualMap& map = s.pass.mark(0, g, kWidth, kWidth * kHeight, v.camera, v.clipmap, bias,
                                      float(reach), t, coarsen_beyond);
  Marked m;
  m.marks.resize(v.clipmap.levels.size() * kPages * kPages);
  s.runtime.read(map.marks, m.marks.data(), m.marks.size());
  m.levels.resize(kWidth * kHeight);
  s.runtime.read(map.pixel_level, m.levels.data(), m.levels.size());
  s.runtime.finish();
  const VirtualPagesPass::PixelCounts counts = s.pass.pixel_counts();
  m.outside = counts.outside, m.coarsened = counts.coarsened;
  return m;
}

// The camera stands 19 to 40 units from the view's points; 30 coarsens the farther ones (none
// of whose distances lies near a power of two times it, where float and double could differ).
TEST(VirtualPages, MarksThePagesEachPixelsLevelAndTapsReach) {
  const View v = made_up_view();
  for (double bias : {0.0, -1.0})
    for (uint32_t reach : {1u, 6u})
      for (float coarsen : {INFINITY, 30.0f}) {
        SCOPED_TRACE(::testing::Message()
                     << "bias " << bias << ", reach " << reach << ", coarsen beyond " << coarsen);
        const Marked expected = reference(v, bias, reach, coarsen);
        size_t pages = 0;
        for (uint8_t m : expected.marks) pages += m;
        EXPECT_GE(pages, 6u);             // pages of two levels, the taps crossing page borders
        EXPECT_GT(expected.outside, 0u);  // the coarsest band
        if (std::isfinite(coarsen)) {
          EXPECT_GT(expected.coarsened, 100u);
        }
        for (const char* profile : {"cpu", "gpu"}) {
          SCOPED_TRACE(profile);
          const Marked got = marked(profile, v, bias, reach, coarsen);
          EXPECT_EQ(got.marks, expected.marks);
          EXPECT_EQ(got.levels, expected.levels);
          EXPECT_EQ(got.outside, expected.outside);
          EXPECT_EQ(got.coarsened, expected.coarsened);
        }
      }
}

// A spot light's mips: a made-up view of ground patches under the spot at one and a half texels
// of mip 2 and of mip 4 (each point placed through its texture coordinates, a quarter texel off
// every page boundary), a row that lies at twice the depth (a jump), sky, and points outside
// the map (off it: no level, not counted). The same rules in double on the host.
struct SpotView {
  Camera camera;
  VirtualLevels layout;
  std::vector<float> positions;
};

SpotView made_up_spot_view() {
  SpotView v;
  v.camera.eye = {0.0f, 10.0f, 0.0f};
  v.camera.target = {0.0f, 0.0f, 0.0f};
  v.camera.up = {1.0f, 0.0f, 0.0f};
  v.camera.width = kWidth, v.camera.height = kHeight;
  ViewSetup face;  // a spot at (1, 12, 2) looking straight down, 80 degrees, depth 2..40
  face.view = glm::lookAt(glm::dvec3(1, 12, 2), glm::dvec3(1, 0, 2), glm::dvec3(0, 0, 1));
  face.world_to_ndc =
      gl_to_texture_ndc() * glm::perspective(glm::radians(80.0), 1.0, 2.0, 40.0) * face.view;
  face.depth = {MapDepth::kPerspective, 2.0, 40.0};
  v.layout = perspective_levels({face}, {}, kTexels, virtual_mips(LightType::kSpot, kTexels));
  const glm::dmat4 to_world = glm::inverse(face.world_to_ndc);
  v.positions.assign(size_t{kWidth} * kHeight * 3, NAN);
  for (uint32_t y = 0; y < kHeight; ++y)
    for (uint32_t x = 0; x < kWidth; ++x) {
      const uint32_t band = y / 16;           // rows 0-15: mip 2, 16-31: mip 4, 32-47: off the map
      if (y % 16 == 15 || x == 40) continue;  // sky between the bands, and a column of it
      const double texel0 = 1.0 / kTexels, quarter = texel0;  // a quarter of a mip 2 texel
      const double step = band == 0 ? 1.5 * 4 * texel0 : band == 1 ? 1.5 * 16 * texel0 : 0.01;
      const double page2 = 4 * 128 * texel0;
      const glm::dvec2 start =
          band == 2 ? glm::dvec2(1.02, 0.3)
                    : glm::dvec2(0.5 - 7 * page2 / 8 + quarter, 0.4 + band * 0.25 + quarter);
      const glm::dvec2 t = start + glm::dvec2(double(x) - 30.0, double(y % 16) - 7.0) * step;
      // On the ground's plane y = 0 (depth 12) through texture point t, or at depth 24 past x 50.
      const double z_ndc = x > 50 ? 0.95 : 0.0;  // a point on the ray; scaled to the depth below
      glm::dvec4 h = to_world * glm::dvec4(t, z_ndc, 1.0);
      glm::dvec3 p = glm::dvec3(h) / h.w, o(1, 12, 2);
      const double depth = x > 50 ? 24.0 : 12.0;
      p = o + (p - o) * (depth / (o.y - p.y));
      for (int k = 0; k < 3; ++k) v.positions[(size_t(y) * kWidth + x) * 3 + k] = float(p[k]);
    }
  return v;
}

Marked spot_reference(const SpotView& v, double bias, double reach) {
  const VirtualLevels& c = v.layout;
  Marked m;
  m.marks.assign(c.levels.size() * kPages * kPages, 0);
  m.levels.assign(kWidth * kHeight, kNoLevel);
  const glm::dvec3 eye(v.camera.eye);
  const double pixel_angle = 2 * std::tan(glm::radians(0.5 * double(v.camera.fov_deg))) / kHeight;
  const auto at = [&](uint32_t i) {
    return glm::dvec3(v.positions[3 * i], v.positions[3 * i + 1], v.positions[3 * i + 2]);
  };
  const auto project = [&](const glm::dvec3& x) {
    const glm::dvec4 h = c.face_ndc[0] * glm::dvec4(x, 1.0);
    return glm::dvec2(h) / h.w;
  };
  for (uint32_t i = 0; i < kWidth * kHeight; ++i) {
    const glm::dvec3 x = at(i);
    if (std::isnan(x.x)) continue;
    const double own = glm::length(x - eye) * pixel_angle;
    const glm::dvec2 ls = project(x);
    double footprint = 0;
    for (uint32_t q : {i % kWidth + 1 < kWidth ? i + 1 : ~0u, i + kWidth}) {
      if (q >= kWidth * kHeight) continue;
      const glm::dvec3 d = at(q) - x;
      if (std::isnan(d.x) || glm::length(d) > 4 * own) continue;
      const glm::dvec2 e = glm::abs(project(at(q)) - ls);
      footprint = std::max({footprint, e.x, e.y});
    }
    for (int a = 0; a < 3 && footprint == 0; ++a)  // no neighbour: its own size along each axis
      for (int b = 0; b < 3; ++b) {
        glm::dvec3 y = x;
        y[b] += own;
        const glm::dvec2 e = glm::abs(project(y) - ls);
        footprint = std::max({footprint, e.x, e.y});
      }
    const int level = std::clamp(clipmap_level(footprint, bias, kTexels), 0, c.mips - 1);
    const double texels = kTexels >> level;
    const glm::dvec2 t = ls * texels;
    if (t.x < 0 || t.y < 0 || t.x >= texels || t.y >= texels) continue;  // off the map
    m.levels[i] = uint8_t(level);
    const int across = int(texels) / 128;
    for (double dy : {-reach, reach})
      for (double dx : {-reach, reach}) {
        const int px = std::clamp(int(std::floor((t.x + dx) / 128)), 0, across - 1);
        const int py = std::clamp(int(std::floor((t.y + dy) / 128)), 0, across - 1);
        m.marks[size_t(level) * kPages * kPages + py * across + px] = 1;
      }
  }
  return m;
}

TEST(VirtualPages, MarksASpotLightsMips) {
  const SpotView v = made_up_spot_view();
  for (double bias : {0.0, -1.0})
    for (uint32_t reach : {1u, 6u}) {
      SCOPED_TRACE(::testing::Message() << "bias " << bias << ", reach " << reach);
      const Marked expected = spot_reference(v, bias, reach);
      size_t pages = 0, off = 0, levels[8] = {};
      for (uint8_t m : expected.marks) pages += m;
      for (uint32_t i = 0; i < kWidth * kHeight; ++i) {
        if (expected.levels[i] != kNoLevel) ++levels[expected.levels[i]];
        off += !std::isnan(v.positions[3 * i]) && expected.levels[i] == kNoLevel;
      }
      std::printf("bias %g, reach %u: %zu pages\n", bias, reach, pages);
      EXPECT_GE(pages, 3u);                        // two mips, a page border crossed (3 to 10)
      EXPECT_GT(off, 100u);                        // the band off the map
      EXPECT_GT(levels[bias == 0 ? 2 : 1], 100u);  // the first band's mip
      EXPECT_GT(levels[bias == 0 ? 4 : 3], 100u);  // the second's
      for (const char* profile : {"cpu", "gpu"}) {
        SCOPED_TRACE(profile);
        Shape& s = shape(profile);
        GBuffer g;
        g.position = s.runtime.upload(v.positions);
        Timeline t;
        const VirtualMap& map =
            s.pass.mark(0, g, kWidth, kWidth * kHeight, v.camera, v.layout, bias, float(reach), t);
        Marked got;
        got.marks.resize(v.layout.levels.size() * kPages * kPages);
        s.runtime.read(map.marks, got.marks.data(), got.marks.size());
        got.levels.resize(kWidth * kHeight);
        s.runtime.read(map.pixel_level, got.levels.data(), got.levels.size());
        s.runtime.finish();
        EXPECT_EQ(got.marks, expected.marks);
        EXPECT_EQ(got.levels, expected.levels);
        EXPECT_EQ(s.pass.pixel_counts().outside, 0u);  // off a perspective map is not lost
      }
    }
}

}  // namespace
}  // namespace shadow
