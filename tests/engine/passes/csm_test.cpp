// Convolution shadow maps (kernels/csm.cl) against double-precision CPU references:
// - the basis channels (float32 and float16, directional and spot depth mappings);
// - the prefiltered test and the blocker average at mip level texel centres, where the
//   trilinear lookup (and the SAT's box of 2^l texels) is exactly the box average of a
//   2^l x 2^l block: first against the same truncated series in double (the implementation),
//   then against the brute-force box filter of the exact Heaviside test and the brute-force
//   blocker average (the approximation, per M);
// - the SAT lookup's boxes of any width, clipped at the map's edges, against the series summed
//   over the same texels in double;
// - no blocker, extremes (z, d at 0 and 1, d - z within 1e-7, M = 16 in float16): never NaN/Inf.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "engine/passes/csm.hpp"

namespace shadow {
namespace {

struct Device {
  cl::Runtime runtime;
  cl::Kernels kernels{runtime};
  MipPyramidPass mips{runtime, kernels};
  SummedAreaPass sats{runtime, kernels};
  CsmPass csm{runtime, kernels, mips, sats};
  cl::Buffer map;
};

Device& device() {
  static Device d;
  return d;
}

constexpr uint32_t kSize = 64;
const MapDepth kOrtho{MapDepth::kOrthographic, 0.0, 1.0};  // linear z = NDC z
const CsmControlsItem kNoControls{0.0f, 0.0f, 1.0f, CsmPass::kMinOccluded};

const CsmBasis& build(const std::vector<float>& z, uint32_t terms, bool half, bool blocker,
                      const MapDepth& mapping = kOrtho,
                      CsmPrefilter prefilter = CsmPrefilter::kMips) {
  Device& d = device();
  const uint32_t size = uint32_t(std::lround(std::sqrt(double(z.size()))));
  d.runtime.ensure(d.map, z.size() * sizeof(float));
  d.runtime.write(d.map, z.data(), z.size() * sizeof(float));
  Timeline t;
  return d.csm.build(d.map, size, mapping, terms, half, blocker, prefilter, t);
}

double ck(uint32_t k) {
  return M_PI * (2.0 * k - 1.0);
}  // k = 1..M
constexpr double kRange = 0.5;  // the basis holds half the linear depth (CSM_RANGE)

// The truncated series H~(t) = 1/2 + sum_k w_k sin(c_k t), w_k = 2 exp(-a (k/M)^2) / c_k.
double series(double t, uint32_t terms, double damping) {
  double s = 0.5;
  for (uint32_t k = 1; k <= terms; ++k)
    s += 2.0 * std::exp(-damping * double(k * k) / (terms * terms)) / ck(k) * std::sin(ck(k) * t);
  return s;
}

// Box statistics over texels [x0, x1] x [y0, y1] for receiver depth d.
struct Window {
  double series_occluded = 0, series_mass = 0;  // truncated series, averaged (what CSM computes)
  double occluded = 0, blocker = NAN;           // exact: fraction with z < d, their mean depth
};
Window box(const std::vector<float>& z, uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1,
           double d, uint32_t terms) {
  Window w;
  double sum_z = 0;
  for (uint32_t y = y0; y <= y1; ++y)
    for (uint32_t x = x0; x <= x1; ++x) {
      const double zz = z[size_t{y} * kSize + x], h = series(kRange * (d - zz), terms, 0.0);
      w.series_occluded += h;
      w.series_mass += zz * h;
      if (zz < d) w.occluded += 1, sum_z += zz;
    }
  if (w.occluded > 0) w.blocker = sum_z / w.occluded;
  const double area = double(x1 - x0 + 1) * (y1 - y0 + 1);
  w.series_occluded /= area, w.series_mass /= area, w.occluded /= area;
  return w;
}
// The 2^l x 2^l block of level-l texel (i, j).
Window window(const std::vector<float>& z, uint32_t l, uint32_t i, uint32_t j, double d,
              uint32_t terms) {
  const uint32_t n = 1u << l;
  return box(z, i * n, (i + 1) * n - 1, j * n, (j + 1) * n - 1, d, terms);
}

std::vector<float> step_edge() {  // casters at z 0.3 left of x = 27, receiver at 0.7 beyond
  std::vector<float> z(kSize * kSize);
  for (uint32_t y = 0; y < kSize; ++y)
    for (uint32_t x = 0; x < kSize; ++x) z[y * kSize + x] = x < 27 + y / 8 ? 0.3f : 0.7f;
  return z;
}

std::vector<float> random_map(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> z(kSize * kSize);
  for (float& v : z) v = u(rng);
  return z;
}

TEST(Csm, BasisChannelsMatchDoublePrecision) {
  std::vector<float> z = random_map(1);
  z[5] = 0.0f, z[6] = 1.0f, z[7] = 0.99999994f;
  // A spot mapping: NDC z = alpha + beta / d for d in [2, 50].
  const double dn = 2, df = 50, beta = -dn * df / (df - dn), alpha = -beta / dn;
  const MapDepth spot{MapDepth::kPerspective, dn, df};
  for (const MapDepth& mapping : {kOrtho, spot})
    for (bool half : {false, true}) {
      const uint32_t terms = 16;
      Device& d = device();
      const CsmBasis& b = build(z, terms, half, true, mapping);
      Timeline t;
      const cl::Buffer& packed = d.csm.pack(b, t);
      std::vector<float> got(z.size() * b.channels());
      d.runtime.read(packed, got.data(), got.size() * sizeof(float));
      double err = 0;
      for (size_t i = 0; i < z.size(); ++i) {
        double zl = z[i];
        if (mapping.kind == MapDepth::kPerspective)
          zl = z[i] >= 1 ? 1.0 : std::clamp((beta / (z[i] - alpha) - dn) / (df - dn), 0.0, 1.0);
        const float* c = &got[i * b.channels()];
        zl *= kRange;
        for (uint32_t k = 1; k <= terms; ++k) {
          const double s = std::sin(ck(k) * zl), co = std::cos(ck(k) * zl);
          err = std::max({err, std::abs(c[k - 1] - s), std::abs(c[terms + k - 1] - co),
                          std::abs(c[2 * terms + k - 1] - zl * s),
                          std::abs(c[3 * terms + k - 1] - zl * co)});
        }
        err = std::max(err, std::abs(c[4 * terms] - zl));
      }
      std::printf("basis M=16 %s %s: max |error| %.3g\n", half ? "float16" : "float32",
                  mapping.kind == MapDepth::kPerspective ? "spot" : "directional", err);
      // Measured: float32 6.6e-6 (spot 9.6e-5: the float NDC z near the far plane, where
      // d(linear)/dz is 25 here, times c_16 = 97), float16 2.5e-4 (2.9e-4 spot).
      EXPECT_LT(err, half ? 4e-4 : (mapping.kind == MapDepth::kPerspective ? 1.5e-4 : 1e-5));
    }
}

// Probes at every level-l texel centre with receiver depths d; returns the GPU results.
std::vector<glm::vec4> probe_level(const CsmBasis& b, uint32_t l, const std::vector<float>& ds,
                                   const CsmControlsItem& controls) {
  const uint32_t n = kSize >> l;
  std::vector<glm::vec4> points;
  for (float d : ds)
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i)
        points.emplace_back((i + 0.5f) / n, (j + 0.5f) / n, float(1u << l), d);
  Timeline t;
  return device().csm.probe(b, points, controls, t);
}

struct Errors {
  double impl = 0;          // |GPU - truncated series in double|, occluded fraction
  double impl_blocker = 0;  // the same for the blocker average
  double test_mae = 0;      // mean |GPU - exact box-filtered Heaviside|
  double overshoot = 0;     // largest excursion of the raw occluded fraction outside [0, 1]
  double blocker_mae = 0;   // mean |blocker - exact blocker average| where >= 1/4 occludes
};

Errors measure(const std::vector<float>& z, uint32_t terms, bool half, uint32_t l,
               const std::vector<float>& ds, CsmPrefilter prefilter = CsmPrefilter::kMips) {
  const CsmBasis& b = build(z, terms, half, true, kOrtho, prefilter);
  const std::vector<glm::vec4> got = probe_level(b, l, ds, kNoControls);
  const uint32_t n = kSize >> l;
  Errors e;
  size_t count = 0, blockers = 0;
  for (size_t p = 0; p < got.size(); ++p) {
    const uint32_t i = p % n, j = (p / n) % n;
    const double d = ds[p / (n * n)];
    const Window w = window(z, l, i, j, d, terms);
    const glm::vec4 r = got[p];
    EXPECT_TRUE(std::isfinite(r.x) && std::isfinite(r.y) && std::isfinite(r.z)) << p;
    e.impl = std::max(e.impl, std::abs(r.y - w.series_occluded));
    e.test_mae += std::abs((1.0 - r.y) - (1.0 - w.occluded));
    e.overshoot = std::max({e.overshoot, double(r.y) - 1.0, -double(r.y)});
    ++count;
    if (w.series_occluded > 0.25) {
      const double series_blocker = std::clamp(w.series_mass / w.series_occluded, 0.0, d);
      e.impl_blocker = std::max(e.impl_blocker, std::abs(r.z - series_blocker));
    }
    if (w.occluded >= 0.25) {
      e.blocker_mae += std::abs(r.z - w.blocker);
      ++blockers;
    }
  }
  e.test_mae /= count;
  e.blocker_mae /= std::max<size_t>(blockers, 1);
  return e;
}

const std::vector<float> kDepths = {0.05f, 0.25f, 0.5f, 0.68f, 0.72f, 0.9f, 1.0f};

TEST(Csm, PrefilteredTestAndBlockerAverageMatchBruteForcePerM) {
  // Mean errors against the exact box-filtered test / blocker average (step edge, random map),
  // per M, at windows 2 and 8: the bounds are ~1.3x the larger measured figure (M = 1: 0.233,
  // 0.115, 0.0080, 0.067; M = 4: 0.120, 0.055, 0.0046, 0.027; M = 8: 0.074, 0.035, 0.0032,
  // 0.017; M = 16: 0.047, 0.022, 0.0024, 0.0106). The basis holds half the depth range, so M
  // terms resolve depth like M / 2 would over the whole range.
  struct Bound {
    uint32_t terms;
    double step_test, random_test, step_blocker, random_blocker;
  };
  const Bound bounds[] = {{1, 0.30, 0.15, 0.0105, 0.087},
                          {4, 0.156, 0.072, 0.006, 0.036},
                          {8, 0.096, 0.046, 0.0042, 0.022},
                          {16, 0.061, 0.029, 0.0031, 0.0138}};
  for (CsmPrefilter prefilter : {CsmPrefilter::kMips, CsmPrefilter::kSat})
    for (const Bound& bd : bounds)
      for (uint32_t l : {1u, 3u}) {
        const Errors s = measure(step_edge(), bd.terms, false, l, kDepths, prefilter);
        const Errors r = measure(random_map(2), bd.terms, false, l, kDepths, prefilter);
        std::printf(
            "%s M=%2u window %2u: test MAE step %.4f random %.4f, overshoot %.3f; blocker MAE step "
            "%.4f random %.4f; vs double series %.2g / %.2g\n",
            prefilter == CsmPrefilter::kSat ? "sat " : "mips", bd.terms, 1u << l, s.test_mae,
            r.test_mae, std::max(s.overshoot, r.overshoot), s.blocker_mae, r.blocker_mae,
            std::max(s.impl, r.impl), std::max(s.impl_blocker, r.impl_blocker));
        EXPECT_LT(std::max(s.impl, r.impl), 5e-6);                  // measured 8e-7
        EXPECT_LT(std::max(s.impl_blocker, r.impl_blocker), 1e-5);  // measured 8e-7
        EXPECT_LT(s.test_mae, bd.step_test);
        EXPECT_LT(r.test_mae, bd.random_test);
        EXPECT_LT(s.blocker_mae, bd.step_blocker);
        EXPECT_LT(r.blocker_mae, bd.random_blocker);
      }
}

// Boxes of odd, even and fractional widths around texel centres near and at the edges (where the
// box is clipped to the map), against the series over the same texels in double.
TEST(Csm, SatBoxesOfAnyWidthMatchTheSeriesOverTheirTexels) {
  const std::vector<float> z = random_map(4);
  const uint32_t terms = 8;
  const CsmBasis& b = build(z, terms, false, true, kOrtho, CsmPrefilter::kSat);
  std::vector<glm::vec4> points;
  struct Expect {
    uint32_t x0, x1, y0, y1;
    double d;
  };
  std::vector<Expect> expect;
  const auto lo = [](double c, double r) {
    return std::clamp(std::floor(c - r + 0.5), 0.0, double(kSize - 1));
  };
  const auto hi = [](double c, double r) {
    return std::clamp(std::floor(c + r - 0.5), 0.0, double(kSize - 1));
  };
  for (float win : {1.0f, 3.0f, 4.0f, 5.5f, 17.0f, 64.0f, 200.0f})
    for (uint32_t i : {0u, 1u, 7u, 31u, 62u, 63u})
      for (uint32_t j : {0u, 5u, 40u, 63u})
        for (float d : {0.2f, 0.6f, 1.0f}) {
          const double cx = i + 0.5, cy = j + 0.5, r = 0.5 * win;
          points.emplace_back(float(cx / kSize), float(cy / kSize), win, d);
          expect.push_back({uint32_t(lo(cx, r)), uint32_t(std::max(lo(cx, r), hi(cx, r))),
                            uint32_t(lo(cy, r)), uint32_t(std::max(lo(cy, r), hi(cy, r))), d});
        }
  Timeline t;
  const std::vector<glm::vec4> got = device().csm.probe(b, points, kNoControls, t);
  double err = 0, err_blocker = 0;
  for (size_t p = 0; p < got.size(); ++p) {
    const Expect& e = expect[p];
    const Window w = box(z, e.x0, e.x1, e.y0, e.y1, e.d, terms);
    err = std::max(err, std::abs(got[p].y - w.series_occluded));
    if (w.series_occluded > 0.25)
      err_blocker =
          std::max(err_blocker,
                   std::abs(got[p].z - std::clamp(w.series_mass / w.series_occluded, 0.0, e.d)));
  }
  std::printf("sat boxes: occluded vs double series %.2g, blocker %.2g over %zu lookups\n", err,
              err_blocker, got.size());
  EXPECT_LT(err, 5e-6);
  EXPECT_LT(err_blocker, 1e-5);
}

TEST(Csm, DampingReducesRinging) {
  // The step edge's raw occluded fraction overshoots [0, 1] (Gibbs: ~9% of the jump) for
  // receivers swept across the edge's depths; damping pulls it in.
  std::vector<float> sweep;
  for (int i = 0; i <= 256; ++i) sweep.push_back(i / 256.0f);
  for (uint32_t terms : {4u, 16u}) {
    const CsmBasis& b = build(step_edge(), terms, false, false);
    double over[2] = {0, 0};
    for (int damped = 0; damped < 2; ++damped) {
      CsmControlsItem c = kNoControls;
      c.damping = damped ? 1.0f : 0.0f;
      for (const glm::vec4& r : probe_level(b, 1, sweep, c))
        over[damped] = std::max({over[damped], double(r.y) - 1.0, -double(r.y)});
    }
    std::printf("M=%u overshoot: undamped %.4f, damping 1: %.4f\n", terms, over[0], over[1]);
    EXPECT_GT(over[0], 0.06);
    EXPECT_LT(over[1], 0.7 * over[0]);
  }
}

TEST(Csm, NoBlockerAndExtremesStayFinite) {
  // Nothing nearer than the receiver: no blocker, the blocker average is d itself.
  const std::vector<float> empty(kSize * kSize, 1.0f);
  for (bool half : {false, true}) {
    const CsmBasis& b = build(empty, 16, half, true);
    for (const glm::vec4& r : probe_level(b, 2, {0.0f, 0.3f, 0.9f, 1.0f}, kNoControls)) {
      ASSERT_TRUE(std::isfinite(r.x) && std::isfinite(r.z)) << r.w;
      EXPECT_LE(r.z, 1.0f);
    }
  }
  // Extremes: z and d at 0 and 1, d - z within 1e-7, M = 16 in float16.
  std::vector<float> z(kSize * kSize);
  for (size_t i = 0; i < z.size(); ++i) z[i] = (i % 3 == 0) ? 0.0f : (i % 3 == 1 ? 1.0f : 0.5f);
  const std::vector<float> ds = {0.0f, 1e-7f, 0.5f - 1e-7f, 0.5f, 0.5f + 1e-7f, 1.0f - 1e-7f, 1.0f};
  for (bool half : {false, true}) {
    const CsmBasis& b = build(z, 16, half, true);
    CsmControlsItem c{1.0f, 0.02f, 1.5f, CsmPass::kMinOccluded};
    for (uint32_t l : {0u, 2u, 6u})
      for (const glm::vec4& r : probe_level(b, l, ds, c)) {
        ASSERT_TRUE(std::isfinite(r.x) && std::isfinite(r.y) && std::isfinite(r.z) &&
                    std::isfinite(r.w));
        EXPECT_GE(r.x, 0.0f);
        EXPECT_LE(r.x, 1.0f);
        EXPECT_GE(r.z, 0.0f);
      }
  }
}

TEST(Csm, HalfStorageCostsLittle) {
  const std::vector<float> z = random_map(3);
  for (uint32_t terms : {4u, 16u}) {
    const Errors f = measure(z, terms, false, 2, kDepths);
    const Errors h = measure(z, terms, true, 2, kDepths);
    std::printf("M=%u float16 vs float32: test MAE %.5f / %.5f, vs double series %.2g / %.2g\n",
                terms, h.test_mae, f.test_mae, h.impl, f.impl);
    EXPECT_LT(h.impl, 6e-4);  // measured 2.6e-4: half rounding of every channel over M terms
    EXPECT_LT(std::abs(h.test_mae - f.test_mae), 2e-4);
  }
}

}  // namespace
}  // namespace shadow
