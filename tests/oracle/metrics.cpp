#include "oracle/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace shadow::oracle {

DepthAgreement compare_depth(std::span<const float> engine, std::span<const double> reference,
                             double tolerance) {
  if (engine.size() != reference.size()) throw std::invalid_argument("compare_depth: sizes");
  DepthAgreement a;
  a.texels = engine.size();
  for (size_t i = 0; i < engine.size(); ++i) {
    const double e = engine[i], r = reference[i];
    const double err = std::isfinite(e) ? std::abs(e - r) : INFINITY;
    if (err <= tolerance) ++a.agree;
    const bool ec = e < 1.0, rc = r < 1.0;
    if (ec && !rc) ++a.engine_only;
    if (rc && !ec) ++a.oracle_only;
    if (ec && rc && err > a.max_error_both_covered) a.max_error_both_covered = err;
    if (err > a.max_error) {
      a.max_error = err;
      a.worst = i;
    }
  }
  return a;
}

std::string DepthAgreement::summary() const {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "agree %.5f%% (%zu/%zu), engine-only %zu, oracle-only %zu, max err %.3g "
                "(both covered %.3g) at texel %zu",
                100.0 * fraction(), agree, texels, engine_only, oracle_only, max_error,
                max_error_both_covered, worst);
  return buf;
}

VisibilityError compare_visibility(std::span<const float> engine,
                                   std::span<const float> reference) {
  if (engine.size() != reference.size()) throw std::invalid_argument("compare_visibility: sizes");
  VisibilityError v;
  v.pixels = engine.size();
  double sum_abs = 0.0, sum_sq = 0.0, pen_abs = 0.0;
  for (size_t i = 0; i < engine.size(); ++i) {
    const bool en = std::isnan(engine[i]), rn = std::isnan(reference[i]);
    if (en != rn) {
      if (v.nan_mismatch++ == 0) v.first_nan_mismatch = i;
      continue;
    }
    if (en) continue;
    ++v.both_valid;
    const double d = std::abs(double{engine[i]} - reference[i]);
    sum_abs += d;
    sum_sq += d * d;
    if (d > 0.5 && v.misclassified++ == 0) v.first_misclassified = i;
    if (reference[i] > 0.02f && reference[i] < 0.98f) {
      ++v.penumbra_pixels;
      pen_abs += d;
    }
  }
  if (v.both_valid) {
    v.mae = sum_abs / v.both_valid;
    v.rmse = std::sqrt(sum_sq / v.both_valid);
  }
  if (v.penumbra_pixels) v.penumbra_mae = pen_abs / v.penumbra_pixels;
  return v;
}

std::string VisibilityError::summary() const {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "misclassified %.4f%% (%zu/%zu), NaN mismatches %zu, MAE %.4g, RMSE %.4g",
                100.0 * misclassified_rate(), misclassified, both_valid, nan_mismatch, mae, rmse);
  return buf;
}

std::vector<DistanceBand> compare_visibility_by_distance(std::span<const float> engine,
                                                         std::span<const float> reference,
                                                         std::span<const double> distance,
                                                         std::span<const double> edges) {
  if (engine.size() != distance.size())
    throw std::invalid_argument("compare_visibility_by_distance: sizes");
  std::vector<DistanceBand> bands(edges.size() + 1);
  for (size_t b = 0; b < bands.size(); ++b) {
    bands[b].from = b == 0 ? 0.0 : edges[b - 1];
    bands[b].to = b < edges.size() ? edges[b] : INFINITY;
  }
  std::vector<float> e, r;
  for (DistanceBand& band : bands) {
    e.clear();
    r.clear();
    for (size_t i = 0; i < engine.size(); ++i) {
      if (!(distance[i] >= band.from && distance[i] < band.to)) continue;  // NaN: seen nothing
      e.push_back(engine[i]);
      r.push_back(reference[i]);
    }
    band.error = compare_visibility(e, r);
  }
  return bands;
}

ViewSurface view_surface(const CameraHits& hits, const Scene& scene, const Camera& camera,
                         const Light& light) {
  ViewSurface s;
  s.position = hits.position;
  s.normal = hits.normal;
  s.eye = glm::dvec3(camera.eye);
  s.pixel = 2 * std::tan(glm::radians(0.5 * double(camera.fov_deg))) / double(camera.height);
  s.lit.resize(hits.size());
  const glm::dvec3 axis = glm::normalize(glm::dvec3(light.direction));
  for (size_t i = 0; i < hits.size(); ++i) {
    if (!hits.hit(i) || !scene.instances.at(size_t(hits.instance[i])).receives_shadows) continue;
    const glm::dvec3 p = hits.position[i];
    const glm::dvec3 to_light =
        light.type == LightType::kDirectional ? -axis : glm::dvec3(light.position) - p;
    const bool in_cone = light.type != LightType::kSpot ||
                         glm::dot(glm::normalize(p - glm::dvec3(light.position)), axis) >=
                             std::cos(glm::radians(0.5 * double(light.cone_angle_deg)));
    s.lit[i] = in_cone && glm::dot(hits.normal[i], to_light) > 0;
  }
  return s;
}

namespace {

// Whether seen 4-neighbours i and j lie on one lit surface (boundary_share).
bool one_lit_surface(const ViewSurface& s, size_t i, size_t j) {
  if (!s.lit[i] || !s.lit[j] || glm::dot(s.normal[i], s.normal[j]) <= 0.9) return false;
  const glm::dvec3 ray = s.position[i] - s.eye;
  const double distance = glm::length(ray);
  const double facing = std::max(std::abs(glm::dot(ray, s.normal[i])) / distance, 0.05);
  return glm::length(s.position[j] - s.position[i]) * facing <= 3 * distance * s.pixel;
}

// Whether seen pixel (x, y) lies on a shadow edge a map can misplace (boundary_share).
bool on_boundary(std::span<const float> v, size_t width, size_t height, const ViewSurface& s,
                 size_t x, size_t y) {
  const size_t i = y * width + x;
  const auto differs = [&](size_t j) {
    return !std::isnan(v[j]) && std::abs(double(v[i]) - double(v[j])) > 0.5 &&
           one_lit_surface(s, i, j);
  };
  return (x > 0 && differs(i - 1)) || (x + 1 < width && differs(i + 1)) ||
         (y > 0 && differs(i - width)) || (y + 1 < height && differs(i + width));
}

}  // namespace

double boundary_share(std::span<const float> v, size_t width, size_t height,
                      const ViewSurface& surface) {
  const std::vector<CellBoundary> whole = boundary_cells(v, width, height, 1, 1, surface);
  return whole[0].seen ? double(whole[0].boundary) / double(whole[0].seen) : 0.0;
}

std::vector<CellBoundary> boundary_cells(std::span<const float> v, size_t width, size_t height,
                                         size_t columns, size_t rows, const ViewSurface& surface) {
  const size_t n = width * height;
  if (v.size() != n || surface.position.size() != n || surface.normal.size() != n ||
      surface.lit.size() != n)
    throw std::invalid_argument("boundary_cells: size");
  std::vector<CellBoundary> cells(columns * rows);
  for (size_t y = 0; y < height; ++y)
    for (size_t x = 0; x < width; ++x) {
      if (std::isnan(v[y * width + x])) continue;
      // The cell whose [c width / columns, (c + 1) width / columns) holds x.
      size_t c = x * columns / width, r = y * rows / height;
      while ((c + 1) * width / columns <= x) ++c;
      while ((r + 1) * height / rows <= y) ++r;
      CellBoundary& cell = cells[r * columns + c];
      ++cell.seen;
      cell.boundary += on_boundary(v, width, height, surface, x, y);
    }
  return cells;
}

std::vector<float> local_boundary_share(std::span<const float> v, size_t width, size_t height,
                                        size_t columns, size_t rows, const ViewSurface& surface) {
  const std::vector<CellBoundary> cells = boundary_cells(v, width, height, columns, rows, surface);
  std::vector<float> share(width * height, 0.0f);
  for (size_t r = 0; r < rows; ++r)
    for (size_t c = 0; c < columns; ++c) {
      const CellBoundary& cell = cells[r * columns + c];
      if (!cell.seen) continue;
      const float s = float(double(cell.boundary) / double(cell.seen));
      for (size_t y = r * height / rows; y < (r + 1) * height / rows; ++y)
        for (size_t x = c * width / columns; x < (c + 1) * width / columns; ++x)
          share[y * width + x] = s;
    }
  return share;
}

double edge_sampling_estimate(std::span<const float> hard, std::span<const float> bilinear) {
  if (hard.size() != bilinear.size()) throw std::invalid_argument("edge_sampling_estimate: sizes");
  double sum = 0;
  size_t seen = 0;
  for (size_t i = 0; i < hard.size(); ++i) {
    if (std::isnan(hard[i]) || std::isnan(bilinear[i])) continue;
    sum += std::abs(double(hard[i]) - double(bilinear[i]));
    ++seen;
  }
  return seen ? sum / double(seen) : 0.0;
}

std::string DistanceBand::label() const {
  char buf[64];
  if (from <= 0.0)
    std::snprintf(buf, sizeof buf, "<%g m", to);
  else if (std::isinf(to))
    std::snprintf(buf, sizeof buf, ">=%g m", from);
  else
    std::snprintf(buf, sizeof buf, "%g-%g m", from, to);
  return buf;
}

}  // namespace shadow::oracle
