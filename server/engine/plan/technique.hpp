// What each shadow-map technique is, in one table: its name, the lights it draws, how its fit
// depends on the camera, and whether it may draw a cube. Validation, the plan, the cost estimate
// and the choices (AUTO, quality goals) read it here instead of each switching on the technique,
// so a new technique adds a row, its fit (engine/run/light_fitter.cpp) and its tests. Pure.
#pragma once

#include <vector>

#include "wire/types.hpp"

namespace shadow {

struct TechniqueFacts {
  Technique technique;
  // As reason texts and the calibration table name it (prose like light_case: the wire's names
  // for the enum are wire/names.*, which the engine does not link).
  const char* label;
  // The lights it draws; another is refused with `refusal`, on shadow_map.technique or, where
  // `refusal_on_light`, on the light's own ".point" field.
  bool directional, spot, point;
  const char* refusal;
  bool refusal_on_light;
  // Camera-independent (uniform maps, cubes): the only ones MAP_FIT_SCENE and the atlas take.
  bool fits_scene;
  // Warps the map to the camera's view (PSM, LiSPSM): the filters that need uniform maps (PCSS)
  // cannot take it.
  bool warped;
  // Whether it may draw a cube's faces (which ones, only the fit knows).
  enum class Cube { kNever, kPointLight, kAlways } cube;
  // Whether its fit reads the receivers' measured view-depth range, so the plan draws the camera
  // view and measures it before the light's fit.
  enum class Receivers { kNever, kAlways, kUnlessNearIsCamera, kUnlessPointLight } receivers;
  // One map that AUTO and quality goals weigh as a candidate (PSM's cube is AUTO's own).
  bool candidate;
  // Draws only the pages the camera's pixels read (virtual maps, issue 53): the plan draws the
  // camera view, then marks the pages, before the maps.
  bool paged = false;
};

// The technique's row; TECHNIQUE_DEFAULT's is the uniform map's label with no light (the engine
// resolves it per light first: engine/plan/light_request.hpp).
const TechniqueFacts& technique_facts(Technique technique);

// technique_facts(t).label.
const char* technique_label(Technique technique);

// Whether `technique` draws a light of `type`.
bool draws(Technique technique, LightType type);
// Whether `technique` may draw a light of `type` as a cube's faces.
bool may_draw_cube(Technique technique, LightType type);

// The single-map techniques a choice (AUTO, a quality goal) weighs for lights of `types`, simplest
// first (uniform, LiSPSM, PSM): those that draw every one of them, warped ones only where `filter`
// takes them.
std::vector<Technique> single_map_candidates(const std::vector<LightType>& types,
                                             FilterKind filter);

}  // namespace shadow
