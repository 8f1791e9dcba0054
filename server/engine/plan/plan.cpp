#include "engine/plan/plan.hpp"

#include <algorithm>

#include "engine/plan/atlas_layout.hpp"
#include "engine/plan/light_request.hpp"
#include "engine/plan/technique.hpp"

namespace shadow {
namespace {

bool wants(const RenderRequest& r, Product p) {
  return std::find(r.products.begin(), r.products.end(), p) != r.products.end();
}
bool wants_any(const RenderRequest& r, std::initializer_list<Product> ps) {
  return std::any_of(ps.begin(), ps.end(), [&](Product p) { return wants(r, p); });
}

// How a technique shapes the plan: PSM and PSM_CUBE push their near plane to the receivers the
// camera sees, and LiSPSM's n_opt comes from their depth range, so the camera view and its
// depth range come before the light's fit; AUTO's candidates may need them.
bool measures_receivers(const ShadowMapSettings& s, LightType light) {
  using Receivers = TechniqueFacts::Receivers;
  switch (technique_facts(s.technique).receivers) {
    case Receivers::kNever:
      return false;
    case Receivers::kAlways:
      return true;
    case Receivers::kUnlessNearIsCamera:
      return s.psm.near != PsmNear::kCamera;
    case Receivers::kUnlessPointLight:  // AUTO may pick LiSPSM or PSM, but a point light's cube
      return light != LightType::kPoint;
  }
  return false;
}

// One plane per receiver class up to the highest one used.
uint32_t class_planes(const Scene& scene) {
  uint32_t planes = 0;
  for (const Instance& i : scene.instances)
    if (i.receiver_class != Instance::kNoClass) planes = std::max(planes, i.receiver_class + 1);
  return planes;
}

}  // namespace

bool auto_may_cube(const RenderRequest& one) {
  return one.shadow_map.technique == Technique::kAuto && !one.lights.empty() &&
         one.lights[0].type != LightType::kPoint && filter_facts(one.filter.kind).auto_cube &&
         !uses_atlas(one) &&
         !wants_any(one, {Product::kShadowMap, Product::kShadowMapMips, Product::kShadowMapSat,
                          Product::kCsmBasis, Product::kBlockerDepth});
}

bool is_shared(StepKind kind) {
  return kind == StepKind::kUploadScene || kind == StepKind::kCameraView ||
         kind == StepKind::kDepthRange || kind == StepKind::kAtlasView;
}

bool Plan::has(StepKind kind) const {
  return std::any_of(steps.begin(), steps.end(), [&](const Step& s) { return s.kind == kind; });
}

std::vector<std::string> Plan::step_names() const {
  std::vector<std::string> names;
  for (const Step& s : steps) names.push_back(s.name);
  return names;
}

namespace {

// The steps of a request narrowed to one light (for_light), or of one with no light at all. With
// `shared`, the readback takes the products that need no light too.
Plan plan_one(const RenderRequest& req, bool shared) {
  using R = Resource;
  const FilterFacts& filter = filter_facts(req.filter.kind);
  const bool need_vis = wants_any(req, {Product::kVisibility, Product::kVisibilityMips,
                                        Product::kVisibilitySat, Product::kBlockerDepth});
  // The atlas filters read VISIBILITY from the prefiltered hard atlas.
  const bool atlas_lookup = need_vis && is_atlas_filter(req.filter.kind);
  const bool need_atlas = wants_atlas(req) || atlas_lookup;
  const bool need_map =
      need_vis || need_atlas ||
      wants_any(req, {Product::kShadowMap, Product::kShadowMapMips, Product::kShadowMapSat,
                      Product::kCsmBasis, Product::kVirtualPages});
  const bool csm_lookup = (need_vis || need_atlas) && is_csm(req.filter.kind);
  const bool need_basis = csm_lookup || wants(req, Product::kCsmBasis);
  const bool need_view = need_vis || wants_any(req, {Product::kPosition, Product::kTexelDensity});
  // Texel density needs the light's matrices, not the rasterized map.
  const bool need_light = need_map || wants(req, Product::kTexelDensity);
  const bool measures = need_light && measures_receivers(req.shadow_map, req.lights[0].type);
  const bool paged = need_map && technique_facts(req.shadow_map.technique).paged;
  const bool view_first = measures || paged;

  Plan plan;
  auto& s = plan.steps;
  s.push_back({StepKind::kUploadScene, "scene", {}, {R::kScene}});
  if (view_first) {
    s.push_back({StepKind::kCameraView, "gbuffer", {R::kScene}, {R::kCameraView}});
    if (measures)
      s.push_back({StepKind::kDepthRange, "depth_range", {R::kCameraView}, {R::kDepthRange}});
  }
  if (need_light) {
    std::vector<R> reads = {R::kScene};
    if (measures) reads.push_back(R::kDepthRange);
    s.push_back({StepKind::kFitLight, "light_fit", reads, {R::kLightFit}});
  }
  if (paged)
    s.push_back({StepKind::kVirtualPages,
                 "virtual.pages",
                 {R::kCameraView, R::kLightFit},
                 {R::kPageTable}});
  if (need_map) {
    std::vector<R> reads = {R::kScene, R::kLightFit};
    if (paged) reads.push_back(R::kPageTable);
    s.push_back({StepKind::kRenderMaps, "shadow_map", reads, {R::kLightMaps}});
    if (need_vis && filter.class_planes) plan.blur_planes = class_planes(*req.scene);
    if (plan.blur_planes > 0)
      s.push_back({StepKind::kBlurPlanes, "blur_planes", {R::kLightMaps}, {R::kBlurPlanes}});
    if (need_basis) {
      plan.csm_blocker = filter.csm_blocker || wants(req, Product::kBlockerDepth);
      plan.csm_prefilter = !csm_lookup                                ? CsmPrefilter::kNone
                           : req.filter.csm.lookup == CsmLookup::kSat ? CsmPrefilter::kSat
                                                                      : CsmPrefilter::kMips;
      s.push_back({StepKind::kCsmBasis, "csm.basis", {R::kLightMaps}, {R::kCsmBasis}});
    }
  }
  if (need_atlas) {  // before the camera's visibility: both use the visibility passes' buffers
    s.push_back({StepKind::kAtlasView, "atlas.bake", {R::kScene}, {R::kAtlasView}});
    std::vector<R> reads = {R::kAtlasView, R::kLightFit, R::kLightMaps};
    if (plan.blur_planes > 0) reads.push_back(R::kBlurPlanes);
    if (csm_lookup) reads.push_back(R::kCsmBasis);
    s.push_back({StepKind::kAtlasVisibility, "atlas.visibility", reads, {R::kAtlas}});
  }
  const Step atlas_mips{StepKind::kMips, "atlas.mips", {R::kAtlas}, {R::kAtlasMips}};
  const Step atlas_sat{StepKind::kSat, "atlas.sat", {R::kAtlas}, {R::kAtlasSat}};
  if (atlas_lookup) {
    const bool sat = filter.atlas == FilterFacts::Atlas::kSat;
    s.push_back(sat ? atlas_sat : atlas_mips);
    s.push_back({StepKind::kAtlasSoften,
                 "atlas.soften",
                 {R::kAtlasView, R::kLightFit, R::kLightMaps, sat ? R::kAtlasSat : R::kAtlasMips},
                 {R::kAtlasSoft}});
  }
  const auto once = [&](const Step& step) {  // the atlas filter may have made it already
    if (std::none_of(s.begin(), s.end(), [&](const Step& t) { return t.name == step.name; }))
      s.push_back(step);
  };
  if (need_view && !view_first)
    s.push_back({StepKind::kCameraView, "gbuffer", {R::kScene}, {R::kCameraView}});
  if (need_vis) {
    std::vector<R> reads = {R::kCameraView, R::kLightFit, R::kLightMaps};
    if (paged) reads.push_back(R::kPageTable);
    if (plan.blur_planes > 0) reads.push_back(R::kBlurPlanes);
    std::vector<R> writes = {R::kVisibility};
    if (csm_lookup) reads.push_back(R::kCsmBasis);
    if (atlas_lookup) reads.push_back(R::kAtlasSoft);
    if (wants(req, Product::kBlockerDepth)) writes.push_back(R::kBlockerDepth);
    s.push_back({StepKind::kVisibility, visibility_step_name(req.filter.kind), reads, writes});
  }

  // The products' own steps, in the order asked for, then one readback of them all.
  std::vector<R> out;
  for (Product p : req.products) {
    if (!shared && !per_light(p)) continue;
    switch (p) {
      case Product::kShadowMap:
        out.push_back(R::kLightMaps);
        break;
      case Product::kVisibility:
        out.push_back(R::kVisibility);
        break;
      case Product::kPosition:
        out.push_back(R::kCameraView);
        break;
      case Product::kTexelDensity:
        s.push_back({StepKind::kTexelDensity,
                     "texel_density",
                     {R::kCameraView, R::kLightFit},
                     {R::kTexelDensity}});
        out.push_back(R::kTexelDensity);
        break;
      case Product::kShadowMapMips:
        s.push_back({StepKind::kMips, "shadowmap.mips", {R::kLightMaps}, {R::kMapMips}});
        out.push_back(R::kMapMips);
        break;
      case Product::kShadowMapSat:
        s.push_back({StepKind::kSat, "shadowmap.sat", {R::kLightMaps}, {R::kMapSat}});
        out.push_back(R::kMapSat);
        break;
      case Product::kVisibilityMips:
        s.push_back({StepKind::kMips, "visibility.mips", {R::kVisibility}, {R::kVisibilityMips}});
        out.push_back(R::kVisibilityMips);
        break;
      case Product::kVisibilitySat:
        s.push_back({StepKind::kSat, "visibility.sat", {R::kVisibility}, {R::kVisibilitySat}});
        out.push_back(R::kVisibilitySat);
        break;
      case Product::kCsmBasis:
        out.push_back(R::kCsmBasis);
        break;
      case Product::kBlockerDepth:
        out.push_back(R::kBlockerDepth);
        break;
      case Product::kShadowAtlas:
        out.push_back(R::kAtlas);
        break;
      case Product::kShadowAtlasMips:
        once(atlas_mips);
        out.push_back(R::kAtlasMips);
        break;
      case Product::kShadowAtlasSat:
        once(atlas_sat);
        out.push_back(R::kAtlasSat);
        break;
      case Product::kVirtualPages:  // the pool the maps drew, the tables, the pixels' levels
        out.push_back(R::kLightMaps);
        out.push_back(R::kPageTable);
        break;
      case Product::kAtlasUvs:  // read from the bake's uploaded UVs
        out.push_back(R::kAtlasView);
        break;
    }
  }
  s.push_back({StepKind::kReadback, "readback", out, {}});
  return plan;
}

}  // namespace

Plan make_plan(const RenderRequest& req) {
  if (req.lights.empty()) return plan_one(req, true);  // POSITION alone (validated)
  // Each light's steps in turn, its readback last (the passes' buffers serve the next light);
  // the scene and the camera view once, where the first light needs them.
  Plan plan;
  for (size_t i = 0; i < req.lights.size(); ++i) {
    const Plan one = plan_one(for_light(req, i), i == 0);
    const std::string prefix = light_pass_prefix(req, i);
    for (Step step : one.steps) {
      const bool shared = is_shared(step.kind);
      if (shared) {
        if (!plan.has(step.kind)) plan.steps.push_back(step);
        continue;
      }
      step.light = uint32_t(i);
      step.name = prefix + step.name;
      plan.steps.push_back(step);
    }
    // The same for every light: they depend on the scene, the filter and the products.
    plan.blur_planes = one.blur_planes;
    plan.csm_blocker = one.csm_blocker;
    plan.csm_prefilter = one.csm_prefilter;
  }
  return plan;
}

}  // namespace shadow
