#include "engine/choose/auto_pick.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "engine/choose/calibration.hpp"
#include "engine/light/cube_fit.hpp"
#include "engine/light/lispsm_fit.hpp"
#include "engine/plan/plan.hpp"
#include "engine/plan/validate.hpp"

namespace shadow {
namespace {

// d(ndc.xy)/dt for tangent t at c = M (p, 1), scaled to texels or pixels.
glm::dvec2 ndc_step(const glm::dmat4& m, const glm::dvec4& c, const glm::dvec3& t,
                    const glm::dvec2& scale) {
  const glm::dvec4 mt = m * glm::dvec4(t, 0.0);
  return (glm::dvec2(mt) - glm::dvec2(c) / c.w * mt.w) / c.w * scale;
}

// A candidate's maps: one for every sample, or the PSM cube's face that decides each.
struct CandidateMaps {
  Technique technique;
  uint32_t size;
  glm::dmat4 single{1.0};
  std::optional<PsmCubeFit> cube;
  int faces = 1;  // rendered

  // World -> map NDC of the map that decides point p; null where no rendered face holds it.
  const glm::dmat4* deciding(const glm::dvec3& p) const {
    if (!cube) return &single;
    const CubeFaceFit& face = cube->faces[face_of(cube->faces[0].setup.faces, p)];
    return face.rendered ? &face.setup.world_to_ndc : nullptr;
  }
};

// PSM's cube at about map_size^2 texels in all, if the light needs one: none where PSM's fit is
// one map (the PSM candidate is that map), or where the faces would be under the smallest map
// or too small for the guard band.
std::optional<CandidateMaps> psm_cube_maps(const Light& light, const Camera& camera,
                                           const std::vector<InstanceBounds>& instances,
                                           const std::optional<DepthRange>& measured,
                                           uint32_t map_size, uint32_t guard) {
  const PsmCubeFit full = fit_psm_cube(light, camera, instances, {}, measured, map_size, guard);
  if (!full.cube) return std::nullopt;
  const int faces = int(std::count_if(full.faces.begin(), full.faces.end(),
                                      [](const CubeFaceFit& f) { return f.rendered; }));
  if (faces == 0) return std::nullopt;
  const uint32_t edge = psm_cube_face_size(map_size, faces);
  if (edge < kMinMapSize || guard > max_guard(edge)) return std::nullopt;
  CandidateMaps m{Technique::kPsmCube, edge, glm::dmat4(1.0), std::nullopt, 0};
  m.cube = fit_psm_cube(light, camera, instances, {}, measured, edge, guard);
  m.faces = int(std::count_if(m.cube->faces.begin(), m.cube->faces.end(),
                              [](const CubeFaceFit& f) { return f.rendered; }));
  // faces x edge^2 <= map_size^2 must hold for the faces drawn (which do not depend on the edge).
  if (!m.cube->cube || m.faces == 0 || m.faces > faces) return std::nullopt;
  return m;
}

// "psm_cube (4 faces of 1024^2)": the cube's texels are spread over its faces.
std::string candidate_name(const AutoCandidate& c, uint32_t size) {
  char n[64];
  if (c.technique == Technique::kPsmCube)
    std::snprintf(n, sizeof n, "psm_cube (%d faces of %u^2)", c.faces, size);
  else
    std::snprintf(n, sizeof n, "%s", technique_label(c.technique));
  return n;
}

}  // namespace

uint32_t psm_cube_face_size(uint32_t map_size, int faces) {
  if (faces <= 0) return 0;
  const uint64_t texels = uint64_t{map_size} * map_size;
  uint64_t edge = uint64_t(double(map_size) / std::sqrt(double(faces))) / 16 * 16 + 16;
  while (edge > 0 && uint64_t(faces) * edge * edge > texels) edge -= 16;
  return uint32_t(edge);
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
                        const Calibration* calibration, const std::vector<Sample>* view,
                        std::optional<uint32_t> psm_cube_guard) {
  AutoPick pick;
  if (light.type == LightType::kPoint) {
    pick.technique = Technique::kCube;
    pick.size = map_size;
    pick.reason =
        std::string(kPicked) + "cube: a point light shines every way, which only cube faces cover";
    return pick;
  }
  const std::vector<Technique> order = single_map_candidates({light.type}, filter);
  const std::vector<Sample> samples = view ? *view : receiver_samples(camera, instances);
  const glm::dmat4 cam = camera_setup(camera).world_to_ndc;
  std::vector<CandidateMaps> maps;
  for (Technique t : order)
    maps.push_back(
        {t, map_size, fitted_matrix(t, light, camera, instances, measured), std::nullopt, 1});
  if (psm_cube_guard && !needs_uniform_map(filter) &&
      (!calibration || calibration->has(Technique::kPsmCube)))
    if (std::optional<CandidateMaps> cube =
            psm_cube_maps(light, camera, instances, measured, map_size, *psm_cube_guard))
      maps.push_back(std::move(*cube));
  for (const CandidateMaps& m : maps) {
    AutoCandidate c{m.technique, m.size};
    double sum = 0, above = 0, error = 0;
    for (const Sample& s : samples) {
      const glm::dmat4* to_ndc = m.deciding(s.p);
      const double f =
          to_ndc ? texel_footprint(*to_ndc, m.size, cam, camera.width, camera.height, s.p, s.n)
                 : NAN;
      if (calibration && (!view || faces_light(light, s)))
        error += calibration->per_boundary_at(m.technique, f);
      if (std::isnan(f)) continue;
      sum += std::min(f, kFootprintCap);
      above += f > 1.0;
      ++c.samples;
    }
    c.mean_footprint = c.samples ? sum / double(c.samples) : INFINITY;
    c.undersampled = c.samples ? above / double(c.samples) : 1.0;
    if (calibration) c.predicted_error = samples.empty() ? 0.0 : error / double(samples.size());
    c.faces = m.faces;
    pick.candidates.push_back(c);
  }
  // The smallest score; the simpler (earlier) candidate within the tie of it.
  const auto score = [&](const AutoCandidate& c) {
    return calibration ? c.predicted_error : c.undersampled;
  };
  double best = INFINITY;
  for (const AutoCandidate& c : pick.candidates) best = std::min(best, score(c));
  const double tied = calibration ? best * (1 + kErrorTie) : best + kTie;
  for (const AutoCandidate& c : pick.candidates)
    if (score(c) <= tied) {
      pick.technique = c.technique;
      pick.size = c.size;
      break;
    }
  char text[160];
  std::string others;
  for (const AutoCandidate& c : pick.candidates) {
    if (c.technique == pick.technique) continue;
    if (calibration)
      std::snprintf(text, sizeof text, "%s%s %.3f (%.3g px)", others.empty() ? "" : ", ",
                    candidate_name(c, c.size).c_str(), c.predicted_error, c.mean_footprint);
    else
      std::snprintf(text, sizeof text, "%s%s %.1f%% (%.3g px)", others.empty() ? "" : ", ",
                    candidate_name(c, c.size).c_str(), 100 * c.undersampled, c.mean_footprint);
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
      kPicked + candidate_name(chosen, chosen.size) + text +
      (others.empty() ? std::string(" (pcss needs an ordinary projection)") : "; " + others);
  return pick;
}

std::vector<size_t> trial_candidates(const AutoPick& pick) {
  const std::vector<AutoCandidate>& c = pick.candidates;
  double best = INFINITY;
  for (const AutoCandidate& a : c) best = std::min(best, a.predicted_error);
  std::vector<size_t> out;
  for (size_t i = 0; i < c.size(); ++i)
    if (std::isnan(c[i].predicted_error) || c[i].predicted_error <= kTrialRatio * best)
      out.push_back(i);
  if (out.size() < 2) out.clear();
  return out;
}

uint32_t trial_size(uint32_t size) {
  return std::min(size, std::max(kMinMapSize, size / 2 / 16 * 16));
}

bool verdict_holds(const AutoPick& pick, const std::vector<size_t>& tried,
                   const TrialVerdict& verdict, uint64_t frame) {
  if (frame < verdict.frame || frame - verdict.frame > kVerdictFrames ||
      tried.size() != verdict.tried.size())
    return false;
  for (size_t k = 0; k < tried.size(); ++k) {
    const AutoCandidate &now = pick.candidates.at(tried[k]), &then = verdict.tried[k];
    if (now.technique != then.technique || now.size != then.size || now.faces != then.faces)
      return false;
    // Without a calibration the prediction is the under-sampled share.
    const double a = std::isnan(now.predicted_error) ? now.undersampled : now.predicted_error,
                 b = std::isnan(then.predicted_error) ? then.undersampled : then.predicted_error;
    if (!(std::abs(a - b) <= kVerdictDrift * std::max(a, b))) return false;
  }
  return true;
}

void choose_by_trial(AutoPick& pick, const std::vector<size_t>& tried,
                     const std::vector<double>& edge, const std::vector<uint32_t>& sizes,
                     std::optional<Technique> kept, std::optional<uint64_t> from_frame) {
  if (tried.empty() || edge.size() != tried.size() || sizes.size() != tried.size())
    throw std::logic_error("choose_by_trial: one edge and size per candidate tried");
  double least = INFINITY;
  for (size_t k = 0; k < tried.size(); ++k) {
    AutoCandidate& c = pick.candidates.at(tried[k]);
    c.trial_edge = edge[k];
    c.trial_size = sizes[k];
    least = std::min(least, edge[k]);
  }
  size_t chosen = tried[0];
  bool tied = false;
  for (size_t k = 0; k < tried.size(); ++k) {
    const bool close = edge[k] <= least * (1 + kTrialTie);
    if (close && kept == pick.candidates[tried[k]].technique) {
      chosen = tried[k];
      break;
    }
    if (close && !tied) chosen = tried[k], tied = true;
  }
  const AutoCandidate& c = pick.candidates[chosen];
  const bool agreed = pick.technique == c.technique;
  pick.technique = c.technique;
  pick.size = c.size;
  // "lispsm 1024^2", "psm_cube 4 x 512^2": what the trial drew.
  const auto drawn = [](const AutoCandidate& a) {
    char n[64];
    if (a.technique == Technique::kPsmCube)
      std::snprintf(n, sizeof n, "psm_cube %d x %u^2", a.faces, a.trial_size);
    else
      std::snprintf(n, sizeof n, "%s %u^2", technique_label(a.technique), a.trial_size);
    return std::string(n);
  };
  char text[200];
  std::string trial = "the trial";
  if (from_frame) trial = "frame " + std::to_string(*from_frame) + "'s trial (kept)";
  std::snprintf(text, sizeof text, ": least edge sampling in %s, %.5f of the seen pixels (%s)",
                trial.c_str(), c.trial_edge, drawn(c).c_str());
  std::string reason = kPicked + candidate_name(c, c.size) + text;
  for (size_t i : tried) {
    if (i == chosen) continue;
    const AutoCandidate& o = pick.candidates[i];
    std::snprintf(text, sizeof text, ", %s %.5f", drawn(o).c_str(), o.trial_edge);
    reason += text;
  }
  // The prediction's own pick, named as such: where the trial overrules it, a reader must not
  // take it for the pick.
  const std::string predicted =
      pick.reason.substr(pick.reason.rfind(kPicked, 0) == 0 ? std::strlen(kPicked) : 0);
  pick.reason = reason + (agreed ? "; the prediction agreed: " : "; the prediction alone picked ") +
                predicted;
}

}  // namespace shadow
