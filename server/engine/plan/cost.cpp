#include "engine/plan/cost.hpp"

#include "engine/plan/light_request.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <optional>
#include <utility>

#include "engine/light/virtual_levels.hpp"
#include "engine/plan/atlas_layout.hpp"
#include "engine/plan/csm_size.hpp"
#include "engine/plan/technique.hpp"
#include "engine/plan/uv_layouts.hpp"
#include "engine/plan/validate.hpp"
#include "wire/errors.hpp"
#include "wire/units.hpp"

namespace shadow {
namespace {

using R = CostRate;

constexpr double kOverlapNs = 2000;  // rasterizing one triangle over one 64^2 tile (1.2 here)
// A virtual map's levels with pages, each setting up the casters that reach into its window: in
// all, about this many times the scene's casters (issue 53).
constexpr double kVirtualLevelsDrawn = 4;

// The instances' triangles and vertices: what every rasterization transforms and sets up.
struct InstancedGeometry {
  double triangles = 0, vertices = 0;
  double raster_bytes() const { return 16 * vertices + 48 * triangles; }  // float4, set-up record
};

InstancedGeometry instanced_geometry(const Scene& scene) {
  InstancedGeometry g;
  for (const Instance& i : scene.instances) {
    g.triangles += double(scene.meshes[i.mesh].triangle_count());
    g.vertices += double(scene.meshes[i.mesh].vertex_count());
  }
  return g;
}

// PCSS' taps read the map over its blocker-search disk, up to PcssPass' 128-texel radius: the
// wider it is, the more of them miss the caches (visibility.pcss at 64/64 over 8192^2: 0.6 ns a
// tap with a 9-texel radius, 1.3 at 36, 3.1 at 107, 6.5 at the cap; docs/benchmarks.md,
// "Admission control"). The radius is the light's disk seen across the map's depth range: for a
// sun, half the map times tan(size / 2) when that range is about the map's width; spot and
// point lights' search is projected onto the map's near plane, which the plan cannot see, so
// they are priced at the cap.
double pcss_miss_factor(const RenderRequest& req, uint32_t light) {
  if (light >= req.lights.size()) return 1;
  const Light& l = req.lights[light];
  constexpr double kCapTexels = 128, kMissCost = 10;  // a miss costs ~11 hits' time
  double radius = kCapTexels;
  if (l.type == LightType::kDirectional)
    radius = 0.5 * req.shadow_map.size * std::tan(0.5 * double(l.size) * 3.14159265358979 / 180);
  return 1 + kMissCost * std::min(1.0, radius / kCapTexels);
}

// A visibility pixel's filter work in taps of PCSS' cost at a small footprint (the shadow test
// is one test pixel): the filter's row (engine/plan/filter.hpp).
double taps(const RenderRequest& req, uint32_t light, uint32_t blur_planes) {
  return filter_facts(req.filter.kind).taps(req.filter, pcss_miss_factor(req, light), blur_planes);
}

}  // namespace

const char* cost_rate_label(CostRate rate) {
  switch (rate) {
    case R::kTriangle:
      return "triangle";
    case R::kMapTexel:
      return "map_texel";
    case R::kTileOverlap:
      return "tile_overlap";
    case R::kBoxPixel:
      return "box_pixel";
    case R::kViewPixel:
      return "view_pixel";
    case R::kDensityPixel:
      return "density_pixel";
    case R::kDepthPixel:
      return "depth_pixel";
    case R::kTestPixel:
      return "test_pixel";
    case R::kTap:
      return "tap";
    case R::kPrefilterTexel:
      return "prefilter_texel";
    case R::kCsmChannelTexel:
      return "csm_channel_texel";
    case R::kBlockerTap:
      return "blocker_tap";
    case R::kLayoutTriangle:
      return "layout_triangle";
  }
  return "?";
}

const CostRates& admission_rates() {
  // From cost-check on this machine: at or above the quiet machine's figures; a busy machine can
  // take up to ~2x as long.
  static const CostRates rates = [] {
    CostRates r;
    r[R::kTriangle] = 60;
    r[R::kMapTexel] = 4;
    r[R::kTileOverlap] = kOverlapNs;
    // Admission has no load before binning; a fit without the rate falls back to this, about
    // 3x the 0.3 ns measured (shadow-bench, a default sweep's maps).
    r[R::kBoxPixel] = 1;
    r[R::kViewPixel] = 20;
    r[R::kDensityPixel] = 8;  // 3.3-4.3 ns measured (strips of 64 pixels, vectorized)
    // Measured at 0.9-2.3 ns (shadow-bench); left out of admission's total before, so 0 keeps
    // its estimates as they were measured (the other rates' margin covers it).
    r[R::kDepthPixel] = 0;
    r[R::kTestPixel] = 8;  // 5-13 ns measured at 720p-8K (cost-check, 2026-12-06)
    r[R::kTap] = 0.6;      // PCSS' tap at a small footprint; taps() weighs the other filters'

    r[R::kPrefilterTexel] = 3;
    // With the basis' fresh bytes priced at kMapTexel per 4 (estimate_cost's kCsmBasis).
    r[R::kCsmChannelTexel] = 0.4;
    // atlas.penumbra: 125-129 ms for 16 taps over 0.46 M texels (cost-check's grid, with its
    // footprint and charts); 335 ms over 4.2 M texels in shadow-atlas-bench.
    r[R::kBlockerTap] = 12;
    r[R::kLayoutTriangle] = kLayoutNsPerTriangle;
    return r;
  }();
  return rates;
}

CostEstimate estimate_cost(const RenderRequest& req, const Plan& plan, const CostRates& rates,
                           const MapLoads& loads) {
  // A virtual map draws at most its pool's pages (issue 53).
  const bool paged = technique_facts(req.shadow_map.technique).paged;
  const double pool_texels = double(req.shadow_map.virtual_pool_pages) * kPageTexels * kPageTexels;
  const double map_texels = paged ? pool_texels : double(req.shadow_map.size) * req.shadow_map.size;
  const double pixels = double(req.camera.width) * req.camera.height;
  // The atlas' layout (host work over every receiving mesh's triangles): once.
  std::optional<AtlasSize> atlas_sized;
  const auto atlas_size = [&](const RenderRequest& r) {
    if (!atlas_sized) atlas_sized = shadow::atlas_size(r);
    return *atlas_sized;
  };
  // A cube draws up to six faces; PSM falls back to one for a point light inside the view. A
  // virtual point light's faces are its levels, drawn only where pages are.
  const auto may_cube = [&](uint32_t light) {
    if (req.lights.empty() || paged) return false;
    const Technique t = resolved_technique(req.shadow_map.technique, req.lights[light].type);
    return may_draw_cube(t, req.lights[light].type) || req.lights[light].type == LightType::kPoint;
  };
  // AUTO may draw PSM's cube instead of one map: up to six faces holding one map's texels.
  const auto auto_cube = [&](uint32_t light) {
    return !req.lights.empty() && auto_may_cube(for_light(req, light));
  };
  // AUTO tries its candidates where the plan draws the camera view first
  // (LightFitter::try_candidates); PCSS's filters take uniform maps alone.
  const bool draws_view = std::any_of(plan.steps.begin(), plan.steps.end(), [](const Step& s) {
    return s.kind == StepKind::kCameraView;
  });
  const auto auto_trial = [&](uint32_t light) {
    return draws_view && !req.lights.empty() && req.shadow_map.technique == Technique::kAuto &&
           req.lights[light].type != LightType::kPoint && !needs_uniform_map(req.filter.kind);
  };
  // The shadow test and PCF take a cube in one launch, at a single map's cost; CSM looks up
  // once per face, each launch checking every pixel's face.
  const auto cube_lookups = [&](uint32_t light) {
    return (may_cube(light) || auto_cube(light)) && is_csm(req.filter.kind) ? 2.0 : 1.0;
  };
  const InstancedGeometry geometry = instanced_geometry(*req.scene);
  const double triangles = geometry.triangles;

  CostEstimate cost;
  double bytes = 0;
  // A term of `step`: its units of some rates, priced at `rates`.
  const auto add = [&](const Step& step, const std::string& what,
                       std::initializer_list<std::pair<CostRate, double>> units) {
    if (cost.steps.empty() || cost.steps.back().step != step.name)
      cost.steps.push_back({step.name, {}});
    double ns = 0;
    for (const auto& [rate, n] : units) {
      cost.steps.back().units[size_t(rate)] += n;
      ns += n * rates[rate];
    }
    const double ms = ns * 1e-6;
    cost.ms += ms;
    if (ms > cost.driver_ms) cost.driver_ms = ms, cost.driver = what;
  };
  char what[160];
  for (const Step& step : plan.steps) {
    switch (step.kind) {
      case StepKind::kUploadScene:
        for (const Mesh& m : req.scene->meshes)
          bytes += 4.0 * double(m.positions.size() + m.indices.size());
        break;
      case StepKind::kFitLight: {  // host math on a few matrices and bounds, and AUTO's trial
        if (!auto_trial(step.light)) break;
        // At most uniform, LiSPSM (directional), PSM and PSM's cube (up to six faces), each at a
        // quarter of the texels, each tested hard and with 2x2 PCF in one pass (auto_pick.hpp).
        const double singles = req.lights[step.light].type == LightType::kDirectional ? 3 : 2;
        const double faces = auto_cube(step.light) ? 6 : 0, tried = singles + (faces > 0);
        std::snprintf(what, sizeof what, "auto trial: %.0f candidates at a quarter of %.0f texels",
                      tried, map_texels);
        const double bilinear = filter_facts(FilterKind::kPcf2x2).taps(Filter{}, 1, 0);
        add(step, what,
            {{R::kTriangle, (singles + faces) * triangles},
             {R::kMapTexel, tried * map_texels / 4},
             {R::kTestPixel, tried * pixels},
             {R::kTap, tried * pixels * bilinear}});
        bytes += geometry.raster_bytes() + map_texels + pixels * 4;  // its differences
        break;
      }
      case StepKind::kDepthRange:
        add(step, "depth_range", {{R::kDepthPixel, pixels}});
        break;
      case StepKind::kCameraView:
        std::snprintf(what, sizeof what, "gbuffer: %.0f triangles, %.0f pixels", triangles, pixels);
        add(step, what, {{R::kTriangle, triangles}, {R::kViewPixel, pixels}});
        bytes += geometry.raster_bytes() + pixels * (4 + 4 + 12 + 16);  // depth, ids, G-buffer
        break;
      case StepKind::kVirtualPages: {  // a marking pass per pixel, then an allocation per page
        const double pages =
            double(req.shadow_map.size / kPageTexels) * (req.shadow_map.size / kPageTexels);
        add(step, "virtual.pages",
            {{R::kDensityPixel, pixels}, {R::kMapTexel, kMaxLevels * pages}});
        bytes += pixels + kMaxLevels * pages * 5;  // levels; marks and page tables
        break;
      }
      case StepKind::kRenderMaps: {
        const bool cube = may_cube(step.light);
        // A virtual map's levels with pages each set up the casters reaching into their window:
        // about kVirtualLevelsDrawn times the casters in all.
        const double maps = cube || auto_cube(step.light) ? 6 : paged ? kVirtualLevelsDrawn : 1;
        std::snprintf(what, sizeof what, "shadow_map: %.0f maps of %.0f texels, %.0f triangles",
                      maps, cube ? map_texels : map_texels / maps, triangles);
        const RasterLoad load = step.light < loads.size() ? loads[step.light] : RasterLoad{};
        add(step, what,
            {{R::kTriangle, maps * triangles},
             {R::kMapTexel, cube ? maps * map_texels : map_texels},
             {R::kTileOverlap, double(load.overlaps)},
             {R::kBoxPixel, double(load.box_pixels)}});
        // Every light's maps stay until the visibility pass reads them all: a cube's six faces.
        // A virtual map's pool is the request's, shared by its lights.
        bytes += geometry.raster_bytes() + map_texels * 4 * (cube ? maps : 1) * !paged;
        if (paged && step.light == 0) bytes += pool_texels * 4 + kMaxBinCounters * 4.0;
        break;
      }
      case StepKind::kBlurPlanes: {
        const double taps_per_texel =
            2.0 * (2 * req.filter.blur.radius + 1) * req.filter.blur.passes;
        std::snprintf(what, sizeof what, "blur_planes: %u planes of %.0f texels x %.0f taps",
                      plan.blur_planes, map_texels, taps_per_texel);
        // A blur tap is a coherent row or column read: a quarter of a PCSS tap.
        add(step, what, {{R::kTap, 0.25 * plan.blur_planes * map_texels * taps_per_texel}});
        bytes += map_texels * 4 * (1 + 2.0 * plan.blur_planes);  // ids, planes and scratch
        break;
      }
      case StepKind::kVisibility: {
        const double t = taps(req, step.light, plan.blur_planes) * cube_lookups(step.light);
        std::snprintf(what, sizeof what, "%s: %.0f pixels x %.0f taps' cost", step.name.c_str(),
                      pixels, t);
        const bool test = filter_facts(req.filter.kind).lookup == FilterFacts::Lookup::kShadowTest;
        const CostRate rate = test ? R::kTestPixel : R::kTap;
        add(step, what, {{rate, pixels * t}});
        bytes += pixels * 4;
        break;
      }
      case StepKind::kTexelDensity:
        add(step, "texel_density", {{R::kDensityPixel, pixels}});
        bytes += pixels * 4;
        break;
      case StepKind::kMips:
      case StepKind::kSat: {
        const bool of_atlas = step.reads[0] == Resource::kAtlas;
        double texels = step.reads[0] == Resource::kLightMaps ? map_texels : pixels;
        if (of_atlas) {
          const AtlasSize a = atlas_size(req);
          texels = double(a.width) * double(a.height);
        }
        // The atlas' SAT sums two channels (visibility, coverage).
        const double channels = of_atlas && step.kind == StepKind::kSat ? 2 : 1;
        add(step, step.name, {{R::kPrefilterTexel, texels * channels}});
        bytes += step.kind == StepKind::kMips ? texels * 4 / 3 : texels * channels * 8;
        break;
      }
      case StepKind::kCsmBasis: {
        const CsmSettings& c = req.filter.csm;
        // A cube builds a basis per face, each just before its face's lookups (one face's
        // buffers, reused): up to six bases' work.
        const double faces = may_cube(step.light) || auto_cube(step.light) ? 6 : 1;
        const double channels = faces * (plan.csm_blocker ? 4.0 * c.terms + 1 : 2.0 * c.terms);
        // Each channel texel written (and filtered into the mips), and each byte of the basis'
        // buffers touched for the first time: at 4096^2 and M = 16 the 5.8 GB of fresh float32
        // channels took 2.7 s more than the 3.0 GB of float16 ones (docs/benchmarks.md). The
        // faces of a cube share one face's buffers. A SAT per channel as one of a one-channel
        // source.
        const double texels = map_texels * channels;
        const bool mips = plan.csm_prefilter == CsmPrefilter::kMips,
                   sat = plan.csm_prefilter == CsmPrefilter::kSat;
        const double basis_bytes =
            double(csm_basis_bytes(req.shadow_map.size, c.terms, c.storage == CsmStorage::kFloat16,
                                   plan.csm_blocker, plan.csm_prefilter));
        add(step, step.name,
            {{R::kCsmChannelTexel, texels * (mips ? 2 : 1)},
             {R::kMapTexel, basis_bytes / 4},
             {R::kPrefilterTexel, sat ? texels : 0}});
        bytes += basis_bytes;
        break;
      }
      case StepKind::kAtlasView: {  // a raster of the receivers, then a resolve per texel
        const AtlasSize a = atlas_size(req);
        const double texels = double(a.width) * double(a.height);
        std::snprintf(what, sizeof what, "atlas.bake: %.0f texels, %.0f triangles", texels,
                      triangles);
        add(step, what,
            {{R::kTriangle, triangles}, {R::kMapTexel, texels}, {R::kViewPixel, texels}});
        // Owner, count, G-buffer, axes, the charts and the gutter's two.
        bytes += texels * (4 + 4 + 12 + 16 + 16 + 12);
        // Generated layouts on the host, as if none were made yet (they are kept once made).
        double unlaid = 0;
        for (uint32_t m : meshes_to_lay_out(*req.scene, req.atlas.generate_uvs))
          unlaid += double(req.scene->meshes[m].triangle_count());
        if (unlaid > 0) {
          std::snprintf(what, sizeof what, "uv_layout: %.0f triangles without UVs", unlaid);
          add(step, what, {{R::kLayoutTriangle, unlaid}});
        }
        break;
      }
      case StepKind::kAtlasVisibility: {  // the visibility passes over the atlas' texels
        const AtlasSize a = atlas_size(req);
        const double texels = double(a.width) * double(a.height);
        // The atlas filters prefilter the hard test.
        const bool lookup = is_atlas_filter(req.filter.kind);
        const double t =
            lookup ? 1 : taps(req, step.light, plan.blur_planes) * cube_lookups(step.light);
        std::snprintf(what, sizeof what, "%s: %.0f texels x %.0f taps", step.name.c_str(), texels,
                      t);
        const bool hard =
            lookup || filter_facts(req.filter.kind).lookup == FilterFacts::Lookup::kShadowTest;
        add(step, what,
            {{hard ? R::kTestPixel : R::kTap, texels * t},
             {R::kPrefilterTexel, texels * req.atlas.gutter}});
        bytes += texels * 4 * 3;  // visibility, the gutter's two
        break;
      }
      case StepKind::kAtlasSoften: {  // a blocker search, then the lookup, at every atlas texel
        const AtlasSize a = atlas_size(req);
        const double texels = double(a.width) * double(a.height);
        // The footprint's strips or probes: atlas.soften took 250 ms over 4.2 M texels with
        // either filter (shadow-atlas-bench's sphere field), 40 taps at kTap's 1.5 ns.
        const double lookup_taps = 40;
        std::snprintf(what, sizeof what, "%s: %.0f texels x %u blocker taps", step.name.c_str(),
                      texels, req.filter.pcss.blocker_samples);
        // The blocker search reads the map as PCSS' does, its misses as PCSS' (taps()).
        add(step, what,
            {{R::kBlockerTap,
              texels * req.filter.pcss.blocker_samples * pcss_miss_factor(req, step.light)},
             {R::kTap, texels * lookup_taps}});
        // The penumbra, footprint and soft atlas; the chart moments and their SAT (atlas_sat) or
        // the chart chain (atlas_mip).
        bytes +=
            texels * (4 + 12 + 4) + (filter_facts(req.filter.kind).atlas == FilterFacts::Atlas::kSat
                                         ? texels * (12 + 24)
                                         : texels * 16 * 4 / 3);
        break;
      }
      case StepKind::kReadback: {  // its time is bounded by max_output_bytes
        // Staging on the device: a CSM basis product is packed into one float32 buffer of all
        // its channels (CsmPass::pack), float16 products into halves, the largest texture's at
        // most (HalfPackPass).
        if (std::find(req.products.begin(), req.products.end(), Product::kCsmBasis) !=
            req.products.end())
          bytes +=
              map_texels *
              (plan.csm_blocker ? 4.0 * req.filter.csm.terms + 1 : 2.0 * req.filter.csm.terms) * 4;
        if (req.output_format == PixelFormat::kFloat16) bytes += double(output_bytes(req));
        // Packing and reading back: about a map texel's time per 4 bytes of the reply (the
        // reply's host memory is fresh, and a basis or float16 product is packed first).
        // Every light's readback reads the products of its own light.
        add(step, "readback",
            {{R::kMapTexel,
              double(output_bytes(req)) / 4 / double(std::max<size_t>(1, req.lights.size()))}});
        break;
      }
    }
  }
  cost.device_bytes = uint64_t(bytes);
  return cost;
}

double load_passes_ms(const RenderRequest& request, double maps, const CostRates& rates) {
  return maps * instanced_geometry(*request.scene).triangles * rates[R::kTriangle] * 1e-6;
}

void admit(const CostEstimate& cost, double max_ms, uint64_t budget_bytes) {
  if (cost.device_bytes > budget_bytes)
    throw ResourceExhausted("memory_budget",
                            "the request needs at least " + bytes_text(cost.device_bytes) +
                                " of device buffers, more than the server's "
                                "whole memory budget of " +
                                bytes_text(budget_bytes) + " (--memory-budget); ask for less");
  if (max_ms <= 0 || cost.ms <= max_ms) return;
  throw ResourceExhausted("request cost", "the request is estimated at " + ms_text(cost.ms) +
                                              " of device time (mostly " + cost.driver + ": " +
                                              ms_text(cost.driver_ms) +
                                              "), over the server's limit of " + ms_text(max_ms) +
                                              " (--max-request-cost); ask for less");
}

double raster_overlap_ms(uint64_t overlaps) {
  return double(overlaps) * admission_rates()[R::kTileOverlap] * 1e-6;
}

}  // namespace shadow
