// One request's share of the device: its own in-order queue (cl::Runtime), its own kernel
// objects, and the passes with the scratch buffers they grow. The engine keeps a few and hands
// each running request one, so concurrent requests share only the compiled programs and the
// device-memory budget. Its job is to run a plan's steps (and keep their results for a request
// that continues the last); fitting lights, a quality goal's probe and the reads are the
// classes it owns (LightFitter, QualityProbe, Readback).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/choose/quality_pick.hpp"
#include "engine/cl/program_cache.hpp"
#include "engine/passes/atlas.hpp"
#include "engine/passes/atlas_soften.hpp"
#include "engine/passes/blur.hpp"
#include "engine/passes/boundary.hpp"
#include "engine/passes/csm.hpp"
#include "engine/passes/depth_range.hpp"
#include "engine/passes/edge_sampling.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/half_pack.hpp"
#include "engine/passes/light_distance.hpp"
#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/pcf.hpp"
#include "engine/passes/pcss.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/passes/shadow_test.hpp"
#include "engine/passes/summed_area.hpp"
#include "engine/passes/texel_density.hpp"
#include "engine/passes/view_samples.hpp"
#include "engine/passes/virtual_pages.hpp"
#include "engine/plan/plan.hpp"
#include "engine/run/light_fitter.hpp"
#include "engine/run/quality_probe.hpp"
#include "engine/run/readback.hpp"
#include "engine/run/resident_scenes.hpp"
#include "engine/run/step_resources.hpp"
#include "wire/types.hpp"

namespace shadow {

// What one render may use and when it must stop.
struct RenderControl {
  double max_cost_ms = 0;  // checked again where only the device knows the cost (raster overlaps)
  bool profile = true;     // per-pass device timings in the result
  // Asked before every launch and read; once it says yes the render throws Cancelled.
  std::function<bool()> cancelled;
  // Where a held scene's device copy is kept (RenderRequest::scene_held); null: nowhere.
  ResidentScenes* resident = nullptr;
  // The calibration TECHNIQUE_AUTO and a quality goal predict with (null: AUTO ranks by the
  // under-sampled share), and each of a goal's candidates' cost.
  const Calibration* calibration = nullptr;
  CandidateCost candidate_cost;
  // Whom its device time is charged to (the device's fair turns), and its admitted estimate: past
  // cl::Runtime::kGuardFactor times it, the render stops (0: no guard).
  std::string client;
  double estimate_ms = 0;
  double guard_slack_ms = cl::Runtime::kGuardSlackMs;  // the guard's room above 3x the estimate
  // Told how far the render is before every launch and read, on the rendering thread. Empty:
  // nothing.
  std::function<void(const RenderProgress&)> progress;
};

class Workspace {
 public:
  Workspace(std::shared_ptr<const cl::Device> device, cl::ProgramCache& programs);
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;

  // Runs the plan of a validated request. The queue is drained before any exception leaves.
  RenderResult render(const RenderRequest& request, const Plan& plan,
                      const RenderControl& control = {});

  // Creates every kernel object of every pass (the programs build once, engine-wide).
  void create_kernels();

  // Uploads and checks `scene` into `resident` unless held there (Engine::check_scene).
  void make_resident(const std::shared_ptr<const Scene>& scene, ResidentScenes& resident,
                     std::function<bool()> cancelled, const std::string& client = {});

  // The budget set aside for the next renders' new buffers (cl::Runtime::set_pledge); an empty
  // one gives back what is left.
  void pledge(cl::Reservation bytes) { runtime.set_pledge(std::move(bytes)); }

  // A sequence's frames render between these: the scene is uploaded by the first frame and
  // kept (later frames move instances but share its meshes), and every pass whose inputs equal
  // its last run's is not run again (RenderResult::reused), and TECHNIQUE_AUTO keeps each
  // light's trial while its prediction holds (auto_pick.hpp, verdict_holds). end_sequence
  // forgets all of it. begin_sequence returns the sequence's id, which sequence() reports until
  // end_sequence (0 outside one): the engine lends a sequence's workspace to other requests
  // between frames, and the sequence continues from its state only where it is still there.
  uint64_t begin_sequence();
  void end_sequence();
  uint64_t sequence() const { return sequence_; }

  // Between separate requests the same holds for a request that continues the last one: the
  // same held scene, still resident, with the same products and settings (engine/plan/sequence.hpp,
  // same_settings()). Its atlas' bake, its lights' maps and soft atlases and its CSM basis are
  // taken from the last request where their inputs are equal, and TECHNIQUE_AUTO keeps each
  // light's trial as a sequence does (the requests counted as its frames from the first).
  // warm_scene() is that scene (null: nothing kept), for the engine to route such requests here.
  const Scene* warm_scene() const;

 private:
  // The plan's steps in order (engine/plan/plan.hpp), timed in `timeline`: each step reads the
  // resources earlier steps wrote (StepLedger checks the plan's declarations) and writes its
  // own into the shared ones or the current light's, which start empty for every light.
  RenderResult run(const RenderRequest& request, const Plan& plan, const RenderControl& control,
                   Timeline& timeline);
  // What a step runner reads and writes (Workspace::run sets it up for each step).
  struct StepContext {
    const RenderRequest& req;  // the request
    RenderRequest& one;        // narrowed to the current light (engine/plan/light_request.hpp)
    const Plan& plan;
    const Step& step;
    uint32_t light;      // the current light
    std::string prefix;  // its passes' prefix ("light1.")
    std::string pass;    // the step's name without the prefix (the timeline adds it)
    const ViewSetup& camera;
    SharedResources& shared;
    LightResources& res;  // the current light's
    const RenderControl& control;
    std::vector<Texture>& textures;  // the readbacks'
    Timeline& timeline;
    bool blocker_depth;  // the request asks for CSM's blocker depth
    uint32_t pixels() const { return req.camera.width * req.camera.height; }
  };
  // One step kind's runner (workspace_steps.cpp: a short function each, over its pass).
  using StepRunner = void (Workspace::*)(StepContext&);
  void run_upload_scene(StepContext& s);
  void run_camera_view(StepContext& s);
  void run_depth_range(StepContext& s);
  void run_fit_light(StepContext& s);
  void run_virtual_pages(StepContext& s);
  // The slots of `map`'s pages that changes since the frame before made stale (run_virtual_pages).
  void invalidate_pages(StepContext& s, VirtualMap& map);
  void run_render_maps(StepContext& s);
  void run_blur_planes(StepContext& s);
  void run_visibility(StepContext& s);
  void run_texel_density(StepContext& s);
  void run_mips(StepContext& s);
  void run_sat(StepContext& s);
  void run_csm_basis(StepContext& s);
  void run_atlas_view(StepContext& s);
  void run_atlas_visibility(StepContext& s);
  void run_atlas_soften(StepContext& s);
  void run_readback(StepContext& s);
  static StepRunner runner(StepKind kind);
  // The texture a mip chain or SAT filters: the light's map, its atlas or its visibility.
  DeviceTexture source(const StepContext& s, Resource r) const;
  // The scene on the device (a held one from the resident set); with `reuse`, the copy already
  // there (a sequence's) if any.
  void upload_scene(const RenderRequest& request, const RenderControl& control, bool reuse,
                    const std::string& pass, Timeline& timeline);
  // The filtered shadow test of `view`'s points (`pixels` of them, `width` a row: the camera's
  // or the atlas') against one light's maps: a cube's faces in one launch, but CSM's once per
  // face, each after its face's basis (into `light.csm_basis`). `blocker_depth`: CSM writes the
  // blocker average too.
  const cl::Buffer& visibility(const RenderRequest& req, const Plan& plan, const GBuffer& view,
                               uint32_t pixels, uint32_t width, LightResources& light,
                               bool blocker_depth, Timeline& timeline);
  // A cube face's CSM basis, built just before the face's lookups: the faces share one basis'
  // buffers.
  const CsmBasis& face_basis(const RenderRequest& req, const Plan& plan, const LightMap& map,
                             Timeline& timeline);
  // The key of a mips or SAT step's source, when it is a kept result (the light's map or atlas;
  // 0: the camera's visibility, made anew every frame).
  uint64_t source_key(const StepContext& s, Resource r) const;

  cl::Runtime runtime;
  cl::Kernels kernels;
  // Which results later frames or requests may take (passes/step_cache.hpp): the rasterizer's, the
  // G-buffer's and the atlas' own, and the steps' below.
  StepCache cache;
  Rasterizer rasterizer;
  GBufferPass gbuffer;
  ShadowTestPass shadow_test;
  TexelDensityPass texel_density;
  PcfPass pcf;
  PcssPass pcss;
  AtlasSoftenPass atlas_soften;
  MipPyramidPass mips;
  SummedAreaPass sat;
  CsmPass csm;
  BlurPass blur;
  LightDistancePass light_distance;
  DepthRangePass depth_range;
  BoundaryPass boundary;
  EdgeSamplingPass edge_sampling;
  ViewSamplesPass view_samples;
  HalfPackPass half_pack;
  AtlasPass atlas;
  VirtualPagesPass virtual_pages;  // TECHNIQUE_VIRTUAL's pages (issue 53)
  // One float, bound for the cube faces not rendered: every pixel is off such a map (w = 0),
  // so no kernel reads it (PCF skips the taps of strips with nothing to filter).
  cl::Buffer empty_map;
  // What the workspace does besides running steps: fitting and drawing lights (with AUTO's
  // trials and the verdicts a sequence keeps), a quality goal's probe and pick, and the reads.
  LightFitter fitter;
  QualityProbe quality;
  Readback readback;

  // The scene on the device: one request's, or a sequence's from its first frame on (shared
  // with ResidentScenes when the scene is held).
  std::shared_ptr<const SceneBuffers> scene_;
  uint64_t sequence_ = 0;  // the sequence whose frames render here (begin_sequence)
  // The last request, while its results are kept for one that continues it (its scene and
  // settings; the scene's device copy as it was, to know it is still the one held).
  struct Warm {
    std::weak_ptr<const Scene> scene;
    RenderRequest settings;  // without its scene and lights
    std::weak_ptr<const SceneBuffers> buffers;
  };
  std::optional<Warm> warm_;
  // Forgets every result kept for a later frame or request; `keep`: keep this run's (a sequence,
  // or warm_).
  void start_keeping(bool keep);
  bool scene_uploaded_ = false;  // this request's scene is in scene_ already (a quality pick's)
};

}  // namespace shadow
