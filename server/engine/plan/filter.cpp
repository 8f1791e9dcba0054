#include "engine/plan/filter.hpp"

#include <cmath>
#include <stdexcept>

#include "engine/light/cube_fit.hpp"
#include "engine/light/virtual_levels.hpp"
#include "engine/plan/require.hpp"

namespace shadow {
namespace {

using Lookup = FilterFacts::Lookup;
using Atlas = FilterFacts::Atlas;

void check_poisson(const Filter& f) {
  require_range(f.poisson.taps, 1, 64, "filter.poisson.taps");
  require(std::isfinite(f.poisson.radius) && f.poisson.radius > 0.0f && f.poisson.radius <= 256.0f,
          "filter.poisson.radius",
          "must be in (0, 256] texels, got " + std::to_string(f.poisson.radius));
}

void check_pcss(const Filter& f) {
  require_range(f.pcss.blocker_samples, 1, 64, "filter.pcss.blocker_samples");
  require_range(f.pcss.filter_samples, 1, 64, "filter.pcss.filter_samples");
}

void check_blur(const Filter& f) {
  require_range(f.blur.radius, 1, 32, "filter.blur.radius");
  require_range(f.blur.passes, 1, 16, "filter.blur.passes");
}

void check_csm(const Filter& f) {
  const CsmSettings& c = f.csm;
  const std::string field = filter_facts(f.kind).field;
  require_range(c.terms, 1, 16, field + ".terms");
  if (f.kind == FilterKind::kCsm)  // PCSS-CSM's window comes from its penumbra
    require(std::isfinite(c.window) && c.window >= 1.0f && c.window <= 8192.0f, field + ".window",
            "must be in [1, 8192] texels, got " + std::to_string(c.window));
  require(std::isfinite(c.damping) && c.damping >= 0.0f && c.damping <= 100.0f, field + ".damping",
          "must be in [0, 100], got " + std::to_string(c.damping));
  require(std::isfinite(c.depth_offset) && c.depth_offset >= 0.0f && c.depth_offset <= 16.0f,
          field + ".depth_offset",
          "must be in [0, 16] (units of 1/M of the linear depth), got " +
              std::to_string(c.depth_offset));
  require(std::isfinite(c.scale) && c.scale >= 1.0f && c.scale <= 1000.0f, field + ".scale",
          "must be in [1, 1000], got " + std::to_string(c.scale));
}

void check_atlas(const Filter& f) {  // and the atlas' own needs (validate_atlas)
  require_range(f.pcss.blocker_samples, 1, 64,
                std::string(filter_facts(f.kind).field) + ".blocker_samples");
}

// Virtual maps' refusals: their lookups read through the page table, page by page.
constexpr const char* kVirtualPrefiltered =
    "is not available with TECHNIQUE_VIRTUAL: a prefiltered product (mips, SAT, CSM basis) or the "
    "atlas has no virtual design";
// The blur is a prefilter over the map too: its class planes come from the map's primitive ids and
// are blurred up to 16 passes of radius 32 (512 texels, four pages), so a marked page would need
// its neighbours' planes drawn and blurred as well.
constexpr const char* kVirtualBlur =
    "is not available with TECHNIQUE_VIRTUAL: the blur filters class planes across up to 512 "
    "texels of the map, beyond a page's neighbours; use pcss for soft shadows with virtual maps";

// One row per FilterKind, in the enum's order.
constexpr FilterFacts kFilters[] = {
    {.kind = FilterKind::kHard,
     .step = "visibility.shadow_test",
     .lookup = Lookup::kShadowTest,
     .auto_cube = true,
     .taps = [](const Filter&, double, uint32_t) { return 1.0; }},
    {.kind = FilterKind::kPcf2x2,
     .step = "visibility.pcf",
     .lookup = Lookup::kPcfBilinear,
     .auto_cube = true,
     // Four bilinear weights and the branch around them: 1.2 ns a tap.
     .taps = [](const Filter&, double, uint32_t) { return 2.0 * 4; }},
    {.kind = FilterKind::kPoisson,
     .field = "filter.poisson",
     .step = "visibility.pcf",
     .lookup = Lookup::kPcfPoisson,
     .auto_cube = true,
     .check = check_poisson,
     .reach = [](const Filter& f) { return f.poisson.radius; },
     .reach_field = "filter.poisson.radius",
     // Coherent taps of a fixed disk: 0.22 ns each.
     .taps = [](const Filter& f, double, uint32_t) { return 0.4 * f.poisson.taps; }},
    {.kind = FilterKind::kPcss,
     .field = "filter.pcss",
     .step = "visibility.pcss",
     .lookup = Lookup::kPcss,
     .uniform_maps_only = true,
     .light_size_for = "PCSS",
     .cube_refusal = "is not available with cube maps",
     .virtual_search = true,
     .check = check_pcss,
     // The blocker search's taps miss the cache in proportion to its disk (pcss_miss).
     .taps = [](const Filter& f, double pcss_miss,
                uint32_t) { return (f.pcss.blocker_samples + f.pcss.filter_samples) * pcss_miss; }},
    {.kind = FilterKind::kBlur,
     .field = "filter.blur",
     .step = "visibility.blur",
     .lookup = Lookup::kBlur,
     .class_planes = true,
     .cube_refusal = "is not available with cube maps",
     .virtual_refusal = kVirtualBlur,
     .check = check_blur,
     .taps = [](const Filter&, double, uint32_t planes) { return 1.0 + planes; }},
    {.kind = FilterKind::kCsm,
     .field = "filter.csm",
     .step = "visibility.csm",
     .lookup = Lookup::kCsm,
     .csm = true,
     .virtual_refusal = kVirtualPrefiltered,
     .auto_cube = true,
     .check = check_csm,
     .reach = [](const Filter& f) { return f.csm.window; },
     .reach_per_unit = 3,
     .reach_field = "filter.csm.window",
     .reach_why = "a trilinear window reads 3 x its width around a point; ",
     // Trilinear lookups of 2M channels: 22 ns a pixel at M = 8.
     .taps = [](const Filter& f, double, uint32_t) { return 5.0 * f.csm.terms; }},
    {.kind = FilterKind::kPcssCsm,
     .field = "filter.pcss_csm",
     .step = "visibility.pcss_csm",
     .lookup = Lookup::kCsm,
     .csm = true,
     .csm_blocker = true,
     .uniform_maps_only = true,
     .light_size_for = "PCSS-CSM",
     .cube_refusal = "is not available with cube maps (use csm)",
     .virtual_refusal = kVirtualPrefiltered,
     .check = check_csm,
     // 4M + 1 channels for the blocker, 2M for the test.
     .taps = [](const Filter& f, double, uint32_t) { return 8.0 * f.csm.terms; }},
    {.kind = FilterKind::kAtlasSat,
     .field = "filter.atlas_sat",
     .step = "visibility.atlas",
     .lookup = Lookup::kAtlas,
     .atlas = Atlas::kSat,
     .light_size_for = "the atlas filters",
     .cube_refusal = "is not available with cube maps",
     .virtual_refusal = kVirtualPrefiltered,
     .check = check_atlas,
     // A camera pixel: the soft atlas' lookup at its surface point, 14-19 ns at 720p.
     .taps = [](const Filter&, double, uint32_t) { return 30.0; }},
    {.kind = FilterKind::kAtlasMip,
     .field = "filter.atlas_mip",
     .step = "visibility.atlas",
     .lookup = Lookup::kAtlas,
     .atlas = Atlas::kMips,
     .light_size_for = "the atlas filters",
     .cube_refusal = "is not available with cube maps",
     .virtual_refusal = kVirtualPrefiltered,
     .check = check_atlas,
     .taps = [](const Filter&, double, uint32_t) { return 30.0; }},
};

// The light's size for the filters that need one (`what`).
void require_light_size(const Light& light, const std::string& what, const std::string& lf) {
  require(light.size > 0.0f, lf + ".size", what + " needs a light size > 0");
  if (light.type == LightType::kDirectional)
    require(light.size < 90.0f, lf + ".size",
            "a directional light's angular diameter must be < 90 degrees for " + what);
}

}  // namespace

const FilterFacts& filter_facts(FilterKind kind) {
  for (const FilterFacts& f : kFilters)
    if (f.kind == kind) return f;
  throw std::logic_error("a filter without a row in kFilters");
}

void validate_filter(const Filter& f, const Light& light, const std::string& light_field) {
  const FilterFacts& facts = filter_facts(f.kind);
  if (facts.check) facts.check(f);
  if (facts.light_size_for) require_light_size(light, facts.light_size_for, light_field);
}

void validate_cube_filter(const Filter& f, uint32_t face_size) {
  const FilterFacts& facts = filter_facts(f.kind);
  if (facts.cube_refusal) throw InvalidArgument(facts.field, facts.cube_refusal);
  const uint32_t guard = max_guard(face_size);
  if (facts.reach)
    require(filter_reach(f) <= guard, facts.reach_field,
            "must be <= " + std::to_string((guard - 1) / facts.reach_per_unit) +
                " texels on cube faces of " + std::to_string(face_size) + " (" + facts.reach_why +
                "the guard band is at most 1/8 of a face)");
}

void validate_virtual_filter(const Filter& f) {
  const FilterFacts& facts = filter_facts(f.kind);
  if (facts.virtual_refusal) throw InvalidArgument(facts.field, facts.virtual_refusal);
  // Marking gives a pixel the pages of its taps' square's corners, and a level's window a
  // margin of kMaxReach texels: a wider filter would read pages nobody marked.
  if (facts.reach)
    require(filter_reach(f) <= kMaxReach, facts.reach_field,
            "must be <= " + std::to_string((kMaxReach - 1) / facts.reach_per_unit) +
                " texels with TECHNIQUE_VIRTUAL (" + facts.reach_why +
                "a pixel's level is chosen for its footprint, and its taps reach at most " +
                std::to_string(kMaxReach) + " of that level's texels)");
}

uint32_t filter_reach(const Filter& f) {
  const FilterFacts& facts = filter_facts(f.kind);
  if (!facts.reach) return 1;
  return uint32_t(std::ceil(float(facts.reach_per_unit) * facts.reach(f))) + 1;
}

uint32_t virtual_reach(const Filter& f) {
  return filter_facts(f.kind).virtual_search ? kMaxSoftReach : filter_reach(f);
}

const char* visibility_step_name(FilterKind filter) {
  return filter_facts(filter).step;
}

bool is_csm(FilterKind filter) {
  return filter_facts(filter).csm;
}

bool is_atlas_filter(FilterKind filter) {
  return filter_facts(filter).atlas != Atlas::kNone;
}

bool needs_uniform_map(FilterKind filter) {
  return filter_facts(filter).uniform_maps_only;
}

}  // namespace shadow
