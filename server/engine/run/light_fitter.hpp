// How a light is drawn: the technique (TECHNIQUE_AUTO's pick, with its trial), the fit of its
// matrices, and the maps drawn with them. The workspace owns one; so do a sequence's trial
// verdicts, which it keeps from frame to frame.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "engine/choose/auto_pick.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/light/cube_fit.hpp"
#include "engine/light/light_space.hpp"
#include "engine/light/psm_fit.hpp"
#include "engine/light/virtual_levels.hpp"
#include "engine/passes/edge_sampling.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/light_distance.hpp"
#include "engine/passes/map_lookup.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/passes/scene_buffers.hpp"
#include "engine/passes/step_cache.hpp"
#include "engine/passes/view_samples.hpp"
#include "engine/passes/virtual_pages.hpp"
#include "wire/types.hpp"

namespace shadow {

class Calibration;

// How the light is drawn: a cube's faces (some rendered, some not) or one map.
struct LightPlan {
  bool cube = false;
  // Its maps' edge: the request's, or the faces' when AUTO picked PSM's cube (equal texels).
  uint32_t map_size = 0;
  ViewSetup light;  // the single map
  // The single map's matrix is an ordinary projection (uniform maps), so the casters whose
  // boxes lie outside it can be left out of its draws: they would cover no texel, and a
  // sequence then keeps the map while they move.
  bool cull = false;
  std::array<CubeFaceFit, 6> faces;  // the cube's
  // TECHNIQUE_VIRTUAL's levels (issue 53); `light` is then the first level's set-up.
  std::optional<VirtualLevels> virtual_levels;
  LightFitReport report;
};

// The maps the per-pixel passes take, and where they came from.
struct DrawnMaps {
  std::vector<LightMap> maps;
  // The single map's raster output and how many draws it drew (null: a cube, or not drawn).
  const RasterOutput* single = nullptr;
  uint32_t single_draws = 0;
  RasterLoad load;  // of the maps drawn
};

// Each instance's world box and roles, as the fits take them.
std::vector<InstanceBounds> instance_bounds(const Scene& scene, const SceneBuffers& buffers);

class LightFitter {
 public:
  // `empty_map`: one float, bound for the cube faces not rendered (no kernel reads it).
  LightFitter(Rasterizer& rasterizer, ViewSamplesPass& view_samples,
              LightDistancePass& light_distance, EdgeSamplingPass& edge_sampling,
              const cl::Buffer& empty_map);

  // The calibration TECHNIQUE_AUTO predicts with (null: it ranks by the under-sampled share).
  void set_calibration(const Calibration* calibration) { calibration_ = calibration; }
  // Forgets every light's kept trial and starts counting frames from 0. While the workspace's
  // step cache keeps (a sequence, or requests that continue one another), each frame's trials
  // are kept for the next frames. A verdict is not a keyed result: it holds while its
  // prediction does (auto_pick.hpp, verdict_holds).
  void set_cache(const StepCache* cache) { cache_ = cache; }
  void forget_trials();
  // The frame rendered: the next one counts one more.
  void frame_done() { ++frame_; }

  // The light's matrices (and for a point light's cube, or PSM's maps where a caster's box
  // holds the light, the light-distance pass that bounds the near planes); `measured` is the
  // receivers' depth range when PSM pushes to it. `view`: the camera view when the plan draws
  // it (AUTO predicts from its samples and tries its candidates), else null; `light`: the
  // request's light index, whose trial a sequence keeps.
  LightPlan fit(const RenderRequest& req, uint32_t light, const SceneBuffers& buffers,
                const std::optional<DepthRange>& measured, const GBuffer* view, Timeline& timeline);

  // The maps the per-pixel passes take: rasterized when `render` (a cube's rendered faces, with
  // one more map that decides the pixels of the faces not rendered: all lit), else only their
  // set-ups, which is all texel density reads. `blur_planes` > 0 draws class receivers too.
  DrawnMaps draw(const RenderRequest& req, const SceneBuffers& buffers, const LightPlan& plan,
                 bool render, uint32_t blur_planes, Timeline& timeline);

  // A virtual map's pages (issue 53): each level with pages in `map`'s table drawn into `pages`'
  // pool (the casters only, each level's window through the same one buffer set, "shadow_map").
  DrawnMaps draw_pages(const RenderRequest& req, const SceneBuffers& buffers,
                       const VirtualPagesPass& pages, const VirtualMap& map, Timeline& timeline);

  // Whether `map` holds a rendered map (not the empty one a face not rendered is bound to).
  bool rendered(const LightMap& map) const { return map.depth != &empty_map_; }

 private:
  // TECHNIQUE_VIRTUAL's levels: a directional light's clipmap around the camera, or a spot or
  // point light's mip chains over the scene (a point light's faces measure its nearest caster).
  VirtualLevels fit_virtual(const RenderRequest& req, const SceneBuffers& buffers,
                            const std::vector<InstanceBounds>& bounds, Timeline& timeline);
  // TECHNIQUE_AUTO's trial (auto_pick.hpp, trial_candidates): draws each candidate's maps at
  // trial_size, tests `view` against them hard and bilinear 2x2 (EdgeSamplingPass, one launch)
  // and picks by the mean difference (choose_by_trial). Its passes are timed as
  // "[lightN.]light_fit.trial.*". While keeping, a frame whose prediction still holds takes
  // light `light`'s last trial instead (verdicts_).
  void try_candidates(const RenderRequest& req, uint32_t light, const SceneBuffers& buffers,
                      const std::optional<DepthRange>& measured, const GBuffer& view,
                      AutoPick& pick, Timeline& timeline);
  // A lower bound of the distance from the request's (spot or point) light to every caster
  // triangle.
  double nearest_caster(const RenderRequest& req, const SceneBuffers& buffers, Timeline& timeline);
  // `distance`: nearest_caster's, measured here if not given.
  std::array<CubeFaceFit, 6> fit_point_cube(const RenderRequest& req, const SceneBuffers& buffers,
                                            const std::vector<InstanceBounds>& bounds,
                                            Timeline& timeline,
                                            std::optional<double> distance = std::nullopt);

  Rasterizer& rasterizer_;
  ViewSamplesPass& view_samples_;
  LightDistancePass& light_distance_;
  EdgeSamplingPass& edge_sampling_;
  const cl::Buffer& empty_map_;
  const Calibration* calibration_ = nullptr;
  const StepCache* cache_ = nullptr;
  uint64_t frame_ = 0;                         // the frame being rendered, while keeping
  std::map<uint32_t, TrialVerdict> verdicts_;  // per light: its last trial, while keeping
};

}  // namespace shadow
