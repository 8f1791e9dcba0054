// Numerical extremes through the real server: every accepted value gives a meaningful result,
// checked pixel by pixel against an independent analytic ray cast in double precision (the test
// scene is a ground quad and an axis-aligned box, so rays and shadow rays are slab tests), or it
// is refused with a message that names the real problem.
#include <cmath>
#include <cstring>
#include <functional>
#include <optional>

#include <gmock/gmock.h>

#include "server_fixture.hpp"
#include "test_scene.hpp"

namespace shadow::test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

// Ray t of the nearest entry into box [lo, hi], if any beyond t_min.
std::optional<double> hit_box(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& lo,
                              const glm::dvec3& hi, double t_min) {
  double t0 = t_min, t1 = INFINITY;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return std::nullopt;
      continue;
    }
    double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
  }
  if (t0 > t1) return std::nullopt;
  return t0;
}

// The ground's half-size: ground_and_box() has 10; tests may scale its instance.
double ground_half(const RenderRequest& r) {
  return 10.0 * double(r.scene->instances[0].transform[0][0]);
}

// The nearest surface along camera pixel (i, j)'s ray, at any depth (near and far aside):
// its view depth (infinity where the ray meets nothing), whether it is the box, the ray.
struct Hit {
  double depth = INFINITY;
  bool on_box = false;
  glm::dvec3 eye, d;
};

// The box of ground_and_box().
const glm::dvec3 kBoxLo(-0.5, 1.0, -0.5), kBoxHi(0.5, 2.0, 0.5);

Hit nearest_hit(const RenderRequest& r, uint32_t i, uint32_t j) {
  const Camera& c = r.camera;
  const glm::dvec3 eye(c.eye), f = glm::normalize(glm::dvec3(c.target) - eye);
  const glm::dvec3 right = glm::normalize(glm::cross(f, glm::dvec3(c.up)));
  const glm::dvec3 up = glm::cross(right, f);
  const double t = std::tan(glm::radians(double(c.fov_deg)) / 2);
  const double x = (2.0 * (i + 0.5) / c.width - 1.0) * t * c.width / c.height;
  const double y = (1.0 - 2.0 * (j + 0.5) / c.height) * t;
  Hit h{INFINITY, false, eye, f + x * right + y * up};  // view depth = ray t
  if (auto tb = hit_box(eye, h.d, kBoxLo, kBoxHi, 0.0)) h.depth = *tb, h.on_box = true;
  if (h.d.y != 0.0) {
    const double tg = -eye.y / h.d.y;
    const glm::dvec3 p = eye + tg * h.d;
    if (tg > 0.0 && tg < h.depth && std::abs(p.x) <= ground_half(r) &&
        std::abs(p.z) <= ground_half(r))
      h.depth = tg, h.on_box = false;
  }
  return h;
}

// The visibility ground_and_box() should get for one camera pixel: 1 lit, 0 shadowed, NaN
// where the ray meets nothing between near and far.
float reference_pixel(const RenderRequest& r, uint32_t i, uint32_t j) {
  const Camera& c = r.camera;
  const auto [best, on_box, eye, d] = nearest_hit(r, i, j);
  if (!(best >= c.near && best <= c.far)) return NAN;
  const glm::dvec3 p = eye + best * d,
                   to_light = -glm::normalize(glm::dvec3(r.lights[0].direction));
  if (on_box) {
    // The face's outward normal: the axis where p lies on the box's surface.
    const glm::dvec3 centre(0.0, 1.5, 0.0), q = (p - centre) / 0.5;
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (std::abs(q[a]) > std::abs(q[axis])) axis = a;
    glm::dvec3 n(0.0);
    n[axis] = q[axis] > 0 ? 1.0 : -1.0;
    if (glm::dot(n, to_light) <= 0.0) return 0.0f;
    return 1.0f;  // a lit box face: nothing else is above the box
  }
  return hit_box(p, to_light, kBoxLo, kBoxHi, 1e-9) ? 0.0f : 1.0f;
}

struct Agreement {
  double disagree = 0;   // fraction of pixels where the server and the reference differ
  double covered = 0;    // fraction of pixels the reference sees something in
  double shadowed = 0;   // fraction of the covered pixels the reference shadows
  double near_band = 0;  // fraction that differ within near_rows of the near plane (compare)
};

// Whether the nearest surface at (i, j) and at some pixel within `rows` rows of it in its column
// lie on different sides of the near plane.
bool near_the_near_plane(const RenderRequest& r, uint32_t i, uint32_t j, uint32_t rows) {
  const auto in_front = [&](uint32_t jj) { return nearest_hit(r, i, jj).depth >= r.camera.near; };
  const bool here = in_front(j);
  for (uint32_t k = j > rows ? j - rows : 0; k <= std::min(j + rows, r.camera.height - 1); ++k)
    if (in_front(k) != here) return true;
  return false;
}

// Pixels that differ within near_rows rows of where the near plane cuts a surface count in
// near_band instead of disagree.
Agreement compare(const RenderRequest& r, const RenderResult& result, uint32_t near_rows = 0) {
  Agreement a;
  const Texture* vis = nullptr;
  for (const Texture& t : result.textures)
    if (t.kind == Product::kVisibility) vis = &t;
  EXPECT_NE(vis, nullptr);
  if (!vis) return a;
  size_t differ = 0, covered = 0, shadowed = 0, near_band = 0;
  for (uint32_t j = 0; j < r.camera.height; ++j) {
    for (uint32_t i = 0; i < r.camera.width; ++i) {
      const float want = reference_pixel(r, i, j), got = vis->data[j * r.camera.width + i];
      if (!std::isnan(want)) ++covered, shadowed += want < 0.5f;
      if (std::isnan(want) != std::isnan(got) ||
          (!std::isnan(want) && (want < 0.5f) != (got < 0.5f)))
        ++(near_rows && near_the_near_plane(r, i, j, near_rows) ? near_band : differ);
    }
  }
  const double n = double(r.camera.width) * r.camera.height;
  a.near_band = near_band / n, a.disagree = differ / n, a.covered = covered / n,
  a.shadowed = covered ? shadowed / double(covered) : 0;
  return a;
}

class ExtremesTest : public ServerFixture<> {
 protected:
  RenderRequest request(std::function<void(RenderRequest&)> change) {
    RenderRequest r = small_request({Product::kVisibility});
    r.camera.width = 96, r.camera.height = 64;
    change(r);
    return r;
  }
  Agreement render(const RenderRequest& r, uint32_t near_rows = 0) {
    return compare(r, client().render(r), near_rows);
  }
  std::string refusal(const RenderRequest& r) {
    try {
      client().render(r);
    } catch (const client::RpcError& e) {
      EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT) << e.what();
      return e.what();
    }
    ADD_FAILURE() << "accepted";
    return "";
  }
};

// A ground scaled by `s` in x and z (the box stays).
void wide_ground(RenderRequest& r, float s) {
  auto scene = std::make_shared<Scene>(*r.scene);
  scene->instances[0].transform = glm::mat4(1.0f);
  scene->instances[0].transform[0][0] = s;
  scene->instances[0].transform[2][2] = s;
  r.scene = scene;
}

// Shadow-map texels and the reference's exact edges disagree along shadow edges only.
constexpr double kEdgeDisagreement = 0.005;

TEST_F(ExtremesTest, TheReferenceAgreesWithAnOrdinaryView) {
  const Agreement a = render(request([](RenderRequest&) {}));
  EXPECT_GT(a.shadowed, 0.005);
  EXPECT_LT(a.disagree, kEdgeDisagreement);
}

// Found by the fuzzer: a direction whose float length underflows was refused as zero.
TEST_F(ExtremesTest, ATinyDirectionIsNormalizedInDouble) {
  auto tiny = request([](RenderRequest& r) { r.lights[0].direction = {3e-31f, -1e-30f, 2e-31f}; });
  auto plain = request([](RenderRequest& r) { r.lights[0].direction = {0.3f, -1.0f, 0.2f}; });
  const RenderResult a = client().render(tiny), b = client().render(plain);
  ASSERT_EQ(a.textures.size(), 1u);
  // The same unit direction in double, so the same bytes (NaN where the camera sees nothing).
  ASSERT_EQ(a.textures[0].data.size(), b.textures[0].data.size());
  EXPECT_EQ(
      std::memcmp(a.textures[0].data.data(), b.textures[0].data.data(), a.textures[0].byte_size()),
      0);
  auto diagonal = request([](RenderRequest& r) {
    r.lights[0].direction = {1e-30f, -1e-30f, 0.0f};
  });
  EXPECT_LT(render(diagonal).disagree, kEdgeDisagreement);
}

// Found by the fuzzer: this was "camera.up: is zero or parallel", though up is fine.
TEST_F(ExtremesTest, AnEyeBeyondFloatRangeIsReportedAsOverflow) {
  const std::string message = refusal(request([](RenderRequest& r) {
    r.camera.eye = {-3e38f, 0.0f, 0.0f};
    r.camera.target = {3e38f, 0.0f, 0.0f};
  }));
  EXPECT_THAT(message, StartsWith("camera.eye: overflows float32"));
  EXPECT_THAT(message, HasSubstr("6e+38 apart"));
}

// Found by the fuzzer: one stray vertex at 1e38 stretched the light's depth range until every
// shadow disappeared. Refused, naming the instance whose bounds reach up the light's path.
TEST_F(ExtremesTest, AVertexAtFloatRangeUpTheLightIsRefusedNamingItsInstance) {
  auto far_vertex = [](float y) {
    return [y](RenderRequest& r) {
      auto scene = std::make_shared<Scene>(*r.scene);
      auto& p = scene->meshes[1].positions;  // the box; the extra vertex is in no triangle
      p.insert(p.end(), {0.0f, y, 0.0f});
      r.scene = scene;
    };
  };
  EXPECT_THAT(refusal(request(far_vertex(1e38f))),
              StartsWith("scene.instances[1]: reaches 9.41e+37 world units up the light's path"));
  EXPECT_THAT(refusal(request(far_vertex(1e10f))), StartsWith("scene.instances[1]: reaches"));
  // Not far enough to matter: the same shadows as without it.
  const Agreement a = render(request(far_vertex(100.0f)));
  EXPECT_GT(a.shadowed, 0.005);
  EXPECT_LT(a.disagree, kEdgeDisagreement);
}

// Found by the fuzzer: fov 1e-30 came back all shadowed (a lit target) or all lit (a dark one).
TEST_F(ExtremesTest, AFieldOfViewFinerThanFloatResolvesIsRefused) {
  for (float fov : {1e-30f, 1e-10f, 1e-6f, 1e-4f}) {
    EXPECT_THAT(refusal(request([fov](RenderRequest& r) { r.camera.fov_deg = fov; })),
                StartsWith("camera.fov_deg: "))
        << fov;
  }
  // The narrowest accepted here (96x64 at 13.4 units) is about 0.001 degrees.
  for (float fov : {2e-3f, 1e-2f, 1.0f}) {
    for (glm::vec3 target : {glm::vec3(3, 0, 3), glm::vec3(0.45f, 0, 0.4f)}) {
      const Agreement a = render(request([&](RenderRequest& r) {
        r.camera.fov_deg = fov;
        r.camera.target = target;  // the middle of a lit and of a shadowed patch
      }));
      EXPECT_EQ(a.disagree, 0.0) << fov;
      EXPECT_EQ(a.covered, 1.0);
    }
  }
}

// Near 180 degrees the scene shrinks to the middle of the image; what remains is right, but for
// where the near plane (0.1) cuts a ground reaching 10^5 units away. Clip coordinates are float32,
// as in a hardware rasterizer, and the near plane's line on that ground comes from its corners:
// one ulp of 10^5 (0.008) is 8% of the near distance, and at these angles the rows by the image's
// edge are thin (under 10^-3 rad at 179 degrees). Measured: whole rows within 2 of that line
// flip, at most 2 rows an image; none with the ground reaching 10^3 units; 8 to 13 rows with the
// near plane at 0.01. So the float32 corners decide them, not the kernels' arithmetic. Every
// pixel farther from that line agrees.
TEST_F(ExtremesTest, AFieldOfViewNear180AgreesWithTheReference) {
  for (float ground : {1e2f, 1e4f}) {  // the instance's scale: corners 10^3 and 10^5 away
    for (float fov : {170.0f, 179.0f, 179.9f, 179.9999f}) {
      for (glm::vec3 eye : {glm::vec3(0, 6, 12), glm::vec3(1, 0.3f, 3)}) {
        const Agreement a = render(request([&](RenderRequest& r) {
                                     r.camera.fov_deg = fov;
                                     r.camera.eye = eye;
                                     r.camera.far = 1e5f;
                                     wide_ground(r, ground);
                                   }),
                                   2);
        EXPECT_EQ(a.disagree, 0.0) << fov << " " << ground;
        EXPECT_LE(a.near_band, ground > 1e3f ? 2.0 / 64 + 1e-9 : 0.0) << fov << " " << ground;
        if (fov <= 179.0f) {
          EXPECT_GT(a.covered, 0.01) << fov;
        }
      }
    }
  }
}

// A far plane more than 2^24 near planes away puts every surface at float32 depth 1, the far
// plane itself: the view came back empty.
TEST_F(ExtremesTest, AFarPlaneBeyondFloatDepthIsRefused) {
  EXPECT_THAT(refusal(request([](RenderRequest& r) {
                r.camera.eye = {0, 1e10f, 1e10f};
                r.camera.far = 3e10f;
              })),
              StartsWith("camera.far: "));
  const Agreement a = render(request([](RenderRequest& r) {
    r.camera.eye = {0, 1e4f, 1e4f};
    r.camera.fov_deg = 0.1f;
    r.camera.near = 1e3f;
    r.camera.far = 1e5f;
  }));
  EXPECT_GT(a.covered, 0.2);
  EXPECT_LT(a.disagree, 0.002);  // measured 2 of 6144 pixels, with attached shadows
}

}  // namespace
}  // namespace shadow::test
