#include "engine/auto_pick.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "engine/calibration.hpp"
#include "engine/lispsm_fit.hpp"
#include "engine/plan.hpp"

namespace shadow {
namespace {

// d(ndc.xy)/dt for tangent t at c = M (p, 1), scaled to texels or pixels.
glm::dvec2 ndc_step(const glm::dmat4& m, const glm::dvec4& c, const glm::dvec3& t,
                    const glm::dvec2& scale) {
  const glm::dvec4 mt = m * glm::dvec4(t, 0.0);
  return (glm::dvec2(mt) - glm::dvec2(c) / c.w * mt.w) / c.w * scale;
}

}  // namespace

const char* technique_label(Technique t) {
  switch (t) {
    case Technique::kLispsm:
      return "lispsm";
    case Technique::kPsm:
      return "psm";
    case Technique::kPsmCube:
      return "psm_cube";
    case Technique::kCube:
      return "cube";
    case Technique::kAuto:
      return "auto";
    default:
      return "uniform";
  }
}

std::vector<Sample> receiver_samples(const Camera& camera,
                                     const std::vector<InstanceBounds>& instances) {
  const CameraRays rays = camera_rays(camera);
  const glm::dvec3 eye(rays.eye);
  std::vector<Sample> out;
  for (uint32_t j = 0; j < kSampleRows; ++j)
    for (uint32_t i = 0; i < kSampleColumns; ++i) {
      const double u = (i + 0.5) / kSampleColumns, v = (j + 0.5) / kSampleRows;
      const glm::dvec3 dir = glm::normalize(glm::dvec3(rays.ray_00) + u * glm::dvec3(rays.ray_du) +
                                            v * glm::dvec3(rays.ray_dv));
      double best = INFINITY;
      const InstanceBounds* hit = nullptr;
      int axis = 0;
      for (const InstanceBounds& ib : instances) {
        if (ib.world.empty()) continue;
        double lo = camera.near, hi = camera.far;
        int entry = -1;
        for (int k = 0; k < 3 && lo <= hi; ++k) {
          if (dir[k] == 0.0) {
            if (eye[k] < ib.world.lo[k] || eye[k] > ib.world.hi[k]) lo = INFINITY;
            continue;
          }
          double a = (ib.world.lo[k] - eye[k]) / dir[k], b = (ib.world.hi[k] - eye[k]) / dir[k];
          if (a > b) std::swap(a, b);
          if (a > lo) lo = a, entry = k;
          hi = std::min(hi, b);
        }
        if (lo <= hi && lo < best && entry >= 0) best = lo, hit = &ib, axis = entry;
      }
      if (!hit || !hit->receives) continue;
      glm::dvec3 n(0.0);
      n[axis] = dir[axis] > 0 ? -1.0 : 1.0;
      out.push_back({eye + best * dir, n});
    }
  return out;
}

bool faces_light(const Light& light, const Sample& s) {
  const glm::dvec3 to_light = light.type == LightType::kDirectional
                                  ? -glm::dvec3(light.direction)
                                  : glm::dvec3(light.position) - s.p;
  return glm::dot(s.n, to_light) > 0.0;
}

glm::dmat4 fitted_matrix(Technique t, const Light& light, const Camera& camera,
                         const std::vector<InstanceBounds>& instances,
                         const std::optional<DepthRange>& measured) {
  if (t == Technique::kLispsm)
    return fit_lispsm_light(light, camera, instances, {}, measured).setup.world_to_ndc;
  if (t == Technique::kPsm)
    return fit_psm_light(light, camera, instances, {}, measured).setup.world_to_ndc;
  return fit_uniform_light(light, camera, instances).world_to_ndc;
}

double texel_footprint(const glm::dmat4& light_to_ndc, uint32_t map_size,
                       const glm::dmat4& camera_to_ndc, uint32_t width, uint32_t height,
                       const glm::dvec3& p, const glm::dvec3& n) {
  const glm::dvec4 cl = light_to_ndc * glm::dvec4(p, 1.0);
  const glm::dvec2 s = glm::dvec2(cl) / cl.w;
  if (!(cl.w > 0.0 && s.x >= 0.0 && s.y >= 0.0 && s.x < 1.0 && s.y < 1.0)) return NAN;
  const glm::dvec3 t1 = glm::normalize(std::abs(n.x) < 0.9 ? glm::cross(n, glm::dvec3(1, 0, 0))
                                                           : glm::cross(n, glm::dvec3(0, 1, 0)));
  const glm::dvec3 t2 = glm::cross(n, t1);
  const glm::dvec4 cc = camera_to_ndc * glm::dvec4(p, 1.0);
  const glm::dvec2 texels(map_size), pixels(width, height);
  const glm::dvec2 l1 = ndc_step(light_to_ndc, cl, t1, texels),
                   l2 = ndc_step(light_to_ndc, cl, t2, texels);
  const glm::dvec2 c1 = ndc_step(camera_to_ndc, cc, t1, pixels),
                   c2 = ndc_step(camera_to_ndc, cc, t2, pixels);
  const double det = l1.x * l2.y - l2.x * l1.y;
  if (det == 0.0) return INFINITY;
  const glm::dvec2 a1 = (c1 * l2.y - c2 * l1.y) / det, a2 = (c2 * l1.x - c1 * l2.x) / det;
  return 0.5 * (std::hypot(a1.x + a2.y, a1.y - a2.x) + std::hypot(a1.x - a2.y, a1.y + a2.x));
}

AutoPick pick_technique(const Light& light, const Camera& camera,
                        const std::vector<InstanceBounds>& instances, uint32_t map_size,
                        FilterKind filter, const std::optional<DepthRange>& measured,
                        const Calibration* calibration, const std::vector<Sample>* view) {
  AutoPick pick;
  if (light.type == LightType::kPoint) {
    pick.technique = Technique::kCube;
    pick.reason = "cube: a point light shines every way, which only cube faces cover";
    return pick;
  }
  std::vector<Technique> order = {Technique::kUniform};
  if (!needs_uniform_map(filter)) {
    if (light.type == LightType::kDirectional) order.push_back(Technique::kLispsm);
    order.push_back(Technique::kPsm);
  }
  const std::vector<Sample> samples = view ? *view : receiver_samples(camera, instances);
  const glm::dmat4 cam = camera_setup(camera).world_to_ndc;
  for (Technique t : order) {
    const glm::dmat4 m = fitted_matrix(t, light, camera, instances, measured);
    AutoCandidate c{t};
    double sum = 0, above = 0, error = 0;
    for (const Sample& s : samples) {
      const double f = texel_footprint(m, map_size, cam, camera.width, camera.height, s.p, s.n);
      if (calibration && (!view || faces_light(light, s)))
        error += calibration->per_boundary_at(t, f);
      if (std::isnan(f)) continue;
      sum += std::min(f, kFootprintCap);
      above += f > 1.0;
      ++c.samples;
    }
    c.mean_footprint = c.samples ? sum / double(c.samples) : INFINITY;
    c.undersampled = c.samples ? above / double(c.samples) : 1.0;
    if (calibration) c.predicted_error = samples.empty() ? 0.0 : error / double(samples.size());
    pick.candidates.push_back(c);
  }
  // The smallest score; the simpler (earlier) candidate within the tie of it.
  const auto score = [&](const AutoCandidate& c) {
    return calibration ? c.predicted_error : c.undersampled;
  };
  const double tie = calibration ? kErrorTie : kTie;
  double best = INFINITY;
  for (const AutoCandidate& c : pick.candidates) best = std::min(best, score(c));
  for (const AutoCandidate& c : pick.candidates)
    if (score(c) <= best + tie) {
      pick.technique = c.technique;
      break;
    }
  char text[128];
  std::string others;
  for (const AutoCandidate& c : pick.candidates) {
    if (c.technique == pick.technique) continue;
    if (calibration)
      std::snprintf(text, sizeof text, "%s%s %.3f (%.3g px)", others.empty() ? "" : ", ",
                    technique_label(c.technique), c.predicted_error, c.mean_footprint);
    else
      std::snprintf(text, sizeof text, "%s%s %.1f%% (%.3g px)", others.empty() ? "" : ", ",
                    technique_label(c.technique), 100 * c.undersampled, c.mean_footprint);
    others += text;
  }
  const AutoCandidate& chosen =
      *std::find_if(pick.candidates.begin(), pick.candidates.end(),
                    [&](const AutoCandidate& c) { return c.technique == pick.technique; });
  if (calibration)
    std::snprintf(text, sizeof text,
                  ": predicted %.3f misclassified per shadow-boundary pixel (calibrated, %zu "
                  "samples, mean footprint %.3g px)",
                  chosen.predicted_error, chosen.samples, chosen.mean_footprint);
  else
    std::snprintf(text, sizeof text,
                  ": predicted texel > 1 px at %.1f%% of %zu samples (mean footprint %.3g px)",
                  100 * chosen.undersampled, chosen.samples, chosen.mean_footprint);
  pick.reason =
      std::string(technique_label(pick.technique)) + text +
      (others.empty() ? std::string(" (pcss needs an ordinary projection)") : "; " + others);
  return pick;
}

}  // namespace shadow
