// Page marking (kernels/virtual_pages.cl) against the same rules in double precision on the
// host, on a made-up view of three patches under a sun: one at a texel and a half of level 5, one
// twice as coarse (level 6), one too coarse for any level (counted outside), with sky and a depth
// jump between them. Positions keep a quarter texel from every level and page boundary, so float
// and double agree; both kernel shapes must mark the same bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

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
  DirectionalClipmap clipmap;
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
  const DirectionalClipmap& c = v.clipmap;
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
        if (std::isfinite(coarsen)) EXPECT_GT(expected.coarsened, 100u);
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

}  // namespace
}  // namespace shadow
