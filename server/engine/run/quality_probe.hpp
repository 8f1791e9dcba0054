// A quality goal's run before the run (engine/choose/quality_pick.hpp): the probe, the candidates'
// raster loads, the pick, and the picked request with its plan. What the probe drew that the picked
// request's run needs again (the camera view, its depth range, a map of the same matrix, its hard
// test) waits here until the run takes it.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "engine/choose/quality_pick.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/passes/boundary.hpp"
#include "engine/passes/depth_range.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/passes/shadow_test.hpp"
#include "engine/passes/view_samples.hpp"
#include "engine/plan/plan.hpp"
#include "engine/run/light_fitter.hpp"
#include "engine/run/step_resources.hpp"
#include "wire/types.hpp"

namespace shadow {

class QualityProbe {
 public:
  QualityProbe(GBufferPass& gbuffer, ViewSamplesPass& view_samples, ShadowTestPass& shadow_test,
               DepthRangePass& depth_range, BoundaryPass& boundary, Rasterizer& rasterizer,
               LightFitter& fitter);

  // The request a goal picks and the plan it runs: the one place a picked request is planned.
  struct Picked {
    QualityPick quality;
    RenderRequest request;
    Plan plan;
  };
  // The goal's pick for `req` on its uploaded `scene`, from the scene's instance bounds and the
  // probe; `cost` prices each candidate as the engine admits it.
  Picked pick(const RenderRequest& req, const SceneBuffers& scene, const Calibration& calibration,
              const CandidateCost& cost, Timeline& timeline);

  // What the run takes instead of drawing it again, once each: the probe's camera view (null:
  // none) and its depth range (nullopt: none measured; a nullopt inside: none seen).
  const GBuffer* take_view() { return std::exchange(view_, nullptr); }
  std::optional<std::optional<DepthRange>> take_depth() { return std::exchange(depth_, {}); }
  // The probe's map of light `index` as the run's (into `light`), if the run's map is the same:
  // as taken_from_probe (engine/choose/quality_pick.hpp) says, and fitted with the same matrix.
  bool take_map(const RenderRequest& one, uint32_t index, const Plan& plan, LightResources& light);
  // With one light, the probe's hard test of it (null: none).
  const cl::Buffer* hard_test() const { return hard_test_; }
  // Drops what the run did not take.
  void forget();

 private:
  // Per light, the share of the camera's seen pixels on a shadow edge a map can misplace
  // (BoundaryPass), of a hard test against a uniform kQualityProbeSize map, and their count per
  // cell of the sample grid, and the camera view's samples. It draws the request's camera view
  // and, where PSM or LiSPSM is a candidate, measures its depth range, which the run then takes.
  ProbeMeasure probe(const RenderRequest& request, const SceneBuffers& scene, Timeline& timeline);
  // A candidate technique's raster load (CandidateLoads::measure): per kQualitySizes, each
  // light's map's, set up once at the largest size through candidate_matrix (`instances` and
  // the probe's `depth` fit it); timed as "quality_probe.[lightN.]load.<technique>.*".
  std::array<MapLoads, kQualitySizes.size()> candidate_loads(
      const RenderRequest& request, const SceneBuffers& scene,
      const std::vector<InstanceBounds>& instances, const std::optional<DepthRange>& depth,
      Technique technique, Timeline& timeline);

  GBufferPass& gbuffer_;
  ViewSamplesPass& view_samples_;
  ShadowTestPass& shadow_test_;
  DepthRangePass& depth_range_;
  BoundaryPass& boundary_;
  Rasterizer& rasterizer_;
  LightFitter& fitter_;

  const GBuffer* view_ = nullptr;
  std::optional<std::optional<DepthRange>> depth_;
  // Each light's probe map (a buffer set of its own, "quality_probe.[lightN.]shadow_map") and
  // the matrix it was fitted with; with one light, its hard test too (the pass's buffer is
  // shared by the lights).
  struct ProbeMap {
    glm::dmat4 world_to_ndc;
    const RasterOutput* map;
    uint64_t version;
    uint32_t draws;
  };
  std::vector<std::optional<ProbeMap>> maps_;
  const cl::Buffer* hard_test_ = nullptr;
};

}  // namespace shadow
