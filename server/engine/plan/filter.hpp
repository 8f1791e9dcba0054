// What each filter is, in one table: the field its settings and refusals name, the pass that runs
// it, what it reads (a CSM basis, the soft atlas), the maps, lights and cubes it takes, its reach
// and its cost. Validation, the plan, the cost estimate and the workspace read it here instead of
// each switching on the filter, so a new filter adds a row, its pass and its tests. Pure.
#pragma once

#include <cstdint>
#include <string>

#include "wire/types.hpp"

namespace shadow {

struct FilterFacts {
  FilterKind kind;
  // The request's field its settings and refusals name ("filter" where it has no settings).
  const char* field = "filter";
  // The camera's visibility step, as the plan and the reply's passes name it.
  const char* step = "";
  // The pass that computes it per camera pixel (engine/run/workspace.cpp).
  enum class Lookup { kShadowTest, kPcfBilinear, kPcfPoisson, kPcss, kBlur, kCsm, kAtlas };
  Lookup lookup = Lookup::kShadowTest;
  // The soft atlas' prefilter it reads (the atlas filters), or none.
  enum class Atlas { kNone, kSat, kMips };
  Atlas atlas = Atlas::kNone;
  bool csm = false;          // reads a CSM basis of the map
  bool csm_blocker = false;  // ... with the blocker average's channels (PCSS-CSM)
  // Its penumbra needs an unwarped map (PCSS): PSM and LiSPSM are refused, AUTO keeps uniform.
  bool uniform_maps_only = false;
  bool class_planes = false;  // blurs the receivers' class planes (the blur)
  // Needs a light size > 0: the filter's name in that refusal, or nullptr.
  const char* light_size_for = nullptr;
  // Why cube faces refuse it (on `field`), or nullptr where a cube takes it.
  const char* cube_refusal = nullptr;
  // Why TECHNIQUE_VIRTUAL refuses it (on `field`), or nullptr where virtual maps take it.
  const char* virtual_refusal = nullptr;
  // With TECHNIQUE_VIRTUAL, reads the level whose texels hold its blocker search within
  // kMaxSoftReach (PCSS): marking picks it from the light's size (pcss_search_bound).
  bool virtual_search = false;
  // Whether AUTO may weigh PSM's cube with it: a cube takes it with a bounded reach.
  bool auto_cube = false;
  // Its own settings' checks (only the chosen filter's settings are read), or nullptr.
  void (*check)(const Filter& f) = nullptr;
  // Texels its lookup reads around a point beyond the point's own (a cube face's guard band
  // must hold them) where a setting bounds them: that setting (nullptr: the reach is 1 texel),
  // texels per unit of it, its field, and why.
  float (*reach)(const Filter& f) = nullptr;
  uint32_t reach_per_unit = 1;
  const char* reach_field = nullptr;
  const char* reach_why = "";
  // A camera pixel's work in taps of PCSS's cost at a small footprint (engine/plan/cost.cpp), each
  // filter's taps weighed by what they measured so that one rate fits all (1280x720 over
  // 2048^2, docs/benchmarks.md). `pcss_miss`: PCSS's cache-miss factor at the light's search
  // disk; `blur_planes`: the blur's class planes.
  double (*taps)(const Filter& f, double pcss_miss, uint32_t blur_planes) = nullptr;
};

const FilterFacts& filter_facts(FilterKind kind);

// The filter's settings and what it needs of `light` (named `light_field`). Throws
// InvalidArgument naming the field.
void validate_filter(const Filter& f, const Light& light, const std::string& light_field);
// What cube faces of `face_size` texels need of the filter: a bounded reach within their guard
// band (engine/light/cube_fit.hpp).
void validate_cube_filter(const Filter& f, uint32_t face_size);
// What TECHNIQUE_VIRTUAL needs of the filter: one its pages are read through (virtual_refusal).
void validate_virtual_filter(const Filter& f);

// The texels a filter reads around a point, which a cube face's guard band must hold: 1 for the
// hard and 2x2 tests, a Poisson disc's radius plus its bilinear tap, and for CSM's trilinear
// window of W texels the next level's bilinear footprint, 1.5 texels of up to 2W.
uint32_t filter_reach(const Filter& f);

// The texels a filter reads around a pixel of a virtual map's level (issue 53): PCSS's blocker
// search, at most kMaxSoftReach (its level is chosen for it), or filter_reach.
uint32_t virtual_reach(const Filter& f);

// The camera's visibility step name: filter_facts(filter).step.
const char* visibility_step_name(FilterKind filter);
// FILTER_CSM or FILTER_PCSS_CSM: the filters that read the CSM basis.
bool is_csm(FilterKind filter);
// FILTER_ATLAS_SAT and FILTER_ATLAS_MIP: VISIBILITY read from the prefiltered atlas.
bool is_atlas_filter(FilterKind filter);
// PCSS and PCSS-CSM: their penumbra takes similar triangles in the light's own projection, so
// they need uniform maps (not PSM's or LiSPSM's warped ones, nor cube faces).
bool needs_uniform_map(FilterKind filter);

}  // namespace shadow
