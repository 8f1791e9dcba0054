#include "engine/plan/technique.hpp"

#include <algorithm>
#include <stdexcept>

#include "engine/plan/plan.hpp"

namespace shadow {
namespace {

using Cube = TechniqueFacts::Cube;
using Receivers = TechniqueFacts::Receivers;

// Simplest first: the order AUTO and quality goals break ties in.
constexpr TechniqueFacts kTechniques[] = {
    {Technique::kUniform, "uniform", true, true, false,
     "a point light shines in every direction, which no single map covers: use TECHNIQUE_CUBE "
     "(the default for point lights) or TECHNIQUE_PSM",
     true, true, false, Cube::kNever, Receivers::kNever, true},
    {Technique::kLispsm, "lispsm", true, false, false,
     "TECHNIQUE_LISPSM needs a directional light (use TECHNIQUE_PSM for spot and point lights)",
     false, false, true, Cube::kNever, Receivers::kAlways, true},
    {Technique::kPsm, "psm", true, true, true, "", false, false, true, Cube::kPointLight,
     Receivers::kUnlessNearIsCamera, true},
    {Technique::kPsmCube, "psm_cube", true, true, true, "", false, false, true, Cube::kAlways,
     Receivers::kUnlessNearIsCamera, false},
    {Technique::kCube, "cube", false, false, true, "TECHNIQUE_CUBE needs a point light", false,
     true, false, Cube::kAlways, Receivers::kNever, false},
    // Its levels fit themselves (a sun's follow the camera, a spot or point light's mips cover
    // the scene: no MAP_FIT_SCENE); not a choice's candidate until measured.
    {Technique::kVirtual, "virtual", true, true, true, "", false, false, false, Cube::kNever,
     Receivers::kNever, false, true},
    {Technique::kAuto, "auto", true, true, true, "", false, false, false, Cube::kPointLight,
     Receivers::kUnlessPointLight, false},
    {Technique::kDefault, "uniform", true, true, true, "", false, false, false, Cube::kNever,
     Receivers::kNever, false},
};

}  // namespace

const TechniqueFacts& technique_facts(Technique technique) {
  for (const TechniqueFacts& f : kTechniques)
    if (f.technique == technique) return f;
  throw std::logic_error("a technique without a row in kTechniques");
}

const char* technique_label(Technique technique) {
  return technique_facts(technique).label;
}

bool draws(Technique technique, LightType type) {
  const TechniqueFacts& f = technique_facts(technique);
  switch (type) {
    case LightType::kDirectional:
      return f.directional;
    case LightType::kSpot:
      return f.spot;
    case LightType::kPoint:
      return f.point;
  }
  return false;
}

bool may_draw_cube(Technique technique, LightType type) {
  const Cube cube = technique_facts(technique).cube;
  return cube == Cube::kAlways || (cube == Cube::kPointLight && type == LightType::kPoint);
}

std::vector<Technique> single_map_candidates(const std::vector<LightType>& types,
                                             FilterKind filter) {
  std::vector<Technique> out;
  for (const TechniqueFacts& f : kTechniques) {
    if (!f.candidate || (f.warped && needs_uniform_map(filter))) continue;
    if (std::all_of(types.begin(), types.end(),
                    [&](LightType type) { return draws(f.technique, type); }))
      out.push_back(f.technique);
  }
  return out;
}

}  // namespace shadow
