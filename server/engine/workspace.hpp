// One request's share of the device: its own in-order queue (cl::Runtime), its own kernel
// objects, and the passes with the scratch buffers they grow. The engine keeps a few and hands
// each running request one, so concurrent requests share only the compiled programs and the
// device-memory budget.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/auto_pick.hpp"
#include "engine/cl/program_cache.hpp"
#include "engine/cube_fit.hpp"
#include "engine/passes/atlas.hpp"
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
#include "engine/plan.hpp"
#include "engine/quality_pick.hpp"
#include "engine/resident_scenes.hpp"
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
                     std::function<bool()> cancelled);

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
  // same held scene, still resident, with the same products and settings (engine/sequence.hpp,
  // same_settings()). Its atlas' bake, its lights' maps and soft atlases and its CSM basis are
  // taken from the last request where their inputs are equal, and TECHNIQUE_AUTO keeps each
  // light's trial as a sequence does (the requests counted as its frames from the first).
  // warm_scene() is that scene (null: nothing kept), for the engine to route such requests here.
  const Scene* warm_scene() const;

 private:
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
    LightFitReport report;
  };

  // The plan's steps in order (engine/plan.hpp), timed in `timeline`.
  RenderResult run(const RenderRequest& request, const Plan& plan, const RenderControl& control,
                   Timeline& timeline);
  // The scene on the device (a held one from the resident set); with `reuse`, the copy already
  // there (a sequence's) if any.
  void upload_scene(const RenderRequest& request, const RenderControl& control, bool reuse,
                    const std::string& pass, Timeline& timeline);
  // A quality goal's pick, from the scene's instance bounds and the probe (uploading the scene:
  // the run then keeps it).
  QualityPick pick(const RenderRequest& request, const RenderControl& control, Timeline& timeline);
  // The quality goal's probe (engine/quality_pick.hpp): per light, the share of the camera's
  // seen pixels on a shadow edge a map can misplace (BoundaryPass), of a hard test against a
  // uniform kQualityProbeSize map, and their count per cell of the sample grid, and the camera
  // view's samples. It draws the request's camera view and, where PSM or LiSPSM is a candidate,
  // measures its depth range, which the run then takes (probe_view_, probe_depth_).
  ProbeMeasure probe(const RenderRequest& request, Timeline& timeline);
  // Drops what the probe left for the run.
  void forget_probe();
  // A candidate technique's raster load (CandidateLoads::measure): per kQualitySizes, each
  // light's map's, set up once at the largest size through candidate_matrix (`instances` and
  // the probe's `depth` fit it); timed as "quality_probe.[lightN.]load.<technique>.*".
  std::array<MapLoads, kQualitySizes.size()> candidate_loads(
      const RenderRequest& request, const std::vector<InstanceBounds>& instances,
      const std::optional<DepthRange>& depth, Technique technique, Timeline& timeline);
  // The light's matrices (and for a point light's cube, or PSM's maps where a caster's box
  // holds the light, the light-distance pass that bounds the near planes); `measured` is the
  // receivers' depth range when PSM pushes to it. `view`: the camera view when the plan draws
  // it (AUTO predicts from its samples and tries its candidates), else null; `light`: the
  // request's light index, whose trial a sequence keeps.
  LightPlan fit_light(const RenderRequest& req, uint32_t light, const SceneBuffers& buffers,
                      const std::optional<DepthRange>& measured, const GBuffer* view,
                      Timeline& timeline);
  // TECHNIQUE_AUTO's trial (auto_pick.hpp, trial_candidates): draws each candidate's maps at
  // trial_size, tests `view` against them hard and bilinear 2x2 (EdgeSamplingPass, one launch)
  // and picks by the mean difference (choose_by_trial). Its passes are timed as
  // "[lightN.]light_fit.trial.*". In a sequence, or a request that continues the last one, a
  // frame whose prediction still holds takes light `light`'s last trial instead (verdicts_).
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
  // The maps the per-pixel passes take: rasterized when `render` (a cube's rendered faces, with
  // one more map that decides the pixels of the faces not rendered: all lit), else only their
  // set-ups, which is all texel density reads. `blur_planes` > 0 draws class receivers too.
  // `drawn`, if given, gains the raster load of the maps drawn.
  std::vector<LightMap> light_maps(const RenderRequest& req, const SceneBuffers& buffers,
                                   const LightPlan& plan, bool render, uint32_t blur_planes,
                                   Timeline& timeline, RasterLoad* drawn = nullptr);

  // A float texture of the request's output format, sized, with nothing read yet.
  Texture float_texture(std::string name, Product kind, uint32_t w, uint32_t h, uint32_t channels,
                        uint32_t faces = 1) const;
  // `count` floats of `src` from float `first` on, into `t`'s values from `at` on: as they are,
  // or converted to halves on the device first (PixelFormat::kFloat16).
  void read_floats(const cl::Buffer& src, size_t first, size_t count, Texture& t, size_t at,
                   Timeline& timeline);
  Texture read_texture(const cl::Buffer& buffer, std::string name, Product kind, uint32_t w,
                       uint32_t h, uint32_t channels, Timeline& timeline);
  // The filtered shadow test of `view`'s points (`pixels` of them, `width` a row: the camera's
  // or the atlas') against one light's maps: a cube's faces in one launch, but CSM's once per
  // face, each after its face's basis.
  const cl::Buffer& visibility(const RenderRequest& req, const Plan& plan, const GBuffer& view,
                               uint32_t pixels, uint32_t width, const std::vector<LightMap>& maps,
                               Timeline& timeline);
  // A cube face's CSM basis, built just before the face's lookups: the faces share one basis'
  // buffers.
  const CsmBasis& face_basis(const RenderRequest& req, const Plan& plan, const LightMap& map,
                             Timeline& timeline);
  // Level 0 (a copy of `src`) .. the 1x1 level, one texture each, named "<name>_mip<i>".
  std::vector<Texture> read_mips(const DeviceTexture& src, const MipChain& chain,
                                 const std::string& name, Product kind, Timeline& timeline);
  Texture read_sat(const SummedAreaTable& table, const std::string& name, Product kind,
                   Timeline& timeline);
  // The rendered faces of a cube as one texture (`name`, faces in +x..-z order).
  Texture read_cube(const std::vector<LightMap>& maps, uint32_t size, std::string name,
                    Timeline& timeline);
  // A light's readback: its products in the order asked for, with its matrices, named with the
  // light's suffix `sfx`; with `shared`, also the products that need no light.
  std::vector<Texture> read_products(const RenderRequest& req, bool shared, const std::string& sfx,
                                     const LightPlan& light, const ViewSetup& camera,
                                     const std::vector<LightMap>& maps, const cl::Buffer* vis,
                                     const GBuffer* view, const cl::Buffer* density,
                                     const std::map<Resource, const MipChain*>& chains,
                                     const std::map<Resource, const SummedAreaTable*>& tables,
                                     const std::function<DeviceTexture(Resource)>& source,
                                     Timeline& timeline);

  cl::Runtime runtime;
  cl::Kernels kernels;
  Rasterizer rasterizer;
  GBufferPass gbuffer;
  ShadowTestPass shadow_test;
  TexelDensityPass texel_density;
  PcfPass pcf;
  PcssPass pcss;
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
  // One float, bound for the cube faces not rendered: every pixel is off such a map (w = 0),
  // so no kernel reads it (PCF skips the taps of strips with nothing to filter).
  cl::Buffer empty_map;
  // This request's single map (its raster output and how many draws it drew) and blurred class
  // planes, if any.
  // The camera view a quality goal's probe drew and its depth range (none where no receiver is
  // seen), until the run takes them as its own.
  const GBuffer* probe_view_ = nullptr;
  std::optional<std::optional<DepthRange>> probe_depth_;
  // Each light's probe map (a buffer set of its own, "quality_probe.[lightN.]shadow_map") and
  // the matrix it was fitted with; with one light, its hard test too (the pass's buffer is
  // shared by the lights). A run that picked the probe's map takes them instead of drawing
  // them again (take_probe_map).
  struct ProbeMap {
    glm::dmat4 world_to_ndc;
    const RasterOutput* map;
    uint64_t version;
    uint32_t draws;
  };
  std::vector<std::optional<ProbeMap>> probe_maps_;
  const cl::Buffer* probe_hard_test_ = nullptr;
  // The probe's map of light `index` as the run's, if the run's map is the same: as
  // taken_from_probe (engine/quality_pick.hpp) says, and fitted with the same matrix.
  bool take_probe_map(const RenderRequest& one, uint32_t index, const LightPlan& light,
                      const Plan& plan, std::vector<LightMap>& maps);
  const RasterOutput* single_map = nullptr;
  uint32_t single_map_draws = 0;
  const cl::Buffer* blurred = nullptr;
  // This request's CSM basis, if any, and whether its visibility pass writes the blocker depth.
  const CsmBasis* csm_basis = nullptr;
  bool csm_blocker_depth = false;
  bool half_ = false;  // this request's float products travel as halves
  // The atlas' surfaces (shared by the lights) and this light's atlas visibility, if any.
  const GBuffer* atlas_view = nullptr;
  const cl::Buffer* atlas_visibility = nullptr;
  bool atlas_kept = false;  // this light's atlas is the one kept from the last frame
  // Whether a mips or SAT step over the atlas may take its pass's last result: the atlas was
  // kept, and one light only (with several, the lights' prefilters share their pass names).
  bool kept_atlas_prefilter(const Step& step, const std::string& prefix) const {
    return atlas_kept && prefix.empty() && step.reads.at(0) == Resource::kAtlas;
  }

  // The scene on the device: one request's, or a sequence's from its first frame on (shared
  // with ResidentScenes when the scene is held).
  std::shared_ptr<const SceneBuffers> scene_;
  uint64_t sequence_ = 0;  // the sequence whose frames render here (begin_sequence)
  // The frame being rendered: a sequence's, or of the requests that continue one another.
  uint64_t frame_ = 0;
  std::map<uint32_t, TrialVerdict> verdicts_;  // per light: its last trial, while keeping_
  // The last request, while its results are kept for one that continues it (its scene and
  // settings; the scene's device copy as it was, to know it is still the one held).
  struct Warm {
    std::weak_ptr<const Scene> scene;
    RenderRequest settings;  // without its scene and lights
    std::weak_ptr<const SceneBuffers> buffers;
  };
  std::optional<Warm> warm_;
  bool keeping_ = false;  // passes may take their last run's results: a sequence or warm_
  // Forgets every result kept for a later frame or request; `keep`: keep this run's.
  void start_keeping(bool keep);
  bool scene_uploaded_ = false;  // this request's scene is in scene_ already (a quality pick's)
  const Calibration* calibration_ = nullptr;  // this request's (RenderControl), for AUTO
  // Everything the CSM basis in `csm` was built from, while a sequence may reuse it.
  struct CsmInputs {
    const RasterOutput* map;
    uint64_t version;
    MapDepth depth;
    CsmSettings settings;
    bool blocker;
    CsmPrefilter prefilter;
    bool operator==(const CsmInputs& o) const;
  };
  std::optional<CsmInputs> csm_made_from_;
};

}  // namespace shadow
