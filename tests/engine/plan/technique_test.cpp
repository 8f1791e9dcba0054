// The technique table (engine/plan/technique.*): the facts the planner, validation and the
// choices read, one row per technique.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "engine/plan/technique.hpp"

namespace shadow {
namespace {

TEST(Techniques, EveryTechniqueHasARow) {
  std::set<std::string> labels;
  for (Technique t : {Technique::kUniform, Technique::kPsm, Technique::kCube, Technique::kPsmCube,
                      Technique::kLispsm, Technique::kAuto, Technique::kVirtual}) {
    EXPECT_EQ(technique_facts(t).technique, t);
    labels.insert(technique_label(t));
  }
  EXPECT_EQ(labels, (std::set<std::string>{"uniform", "psm", "cube", "psm_cube", "lispsm", "auto",
                                           "virtual"}));
}

// Virtual maps (issue 53): every light type, levels that fit themselves (no
// MAP_FIT_SCENE, no atlas), no cube, no measured receivers, and no choice weighs them yet.
TEST(Techniques, VirtualDrawsEveryLight) {
  const TechniqueFacts& f = technique_facts(Technique::kVirtual);
  EXPECT_TRUE(draws(Technique::kVirtual, LightType::kDirectional));
  EXPECT_TRUE(draws(Technique::kVirtual, LightType::kSpot));
  EXPECT_TRUE(draws(Technique::kVirtual, LightType::kPoint));
  EXPECT_FALSE(f.fits_scene);
  EXPECT_FALSE(f.warped);
  EXPECT_EQ(f.cube, TechniqueFacts::Cube::kNever);
  EXPECT_EQ(f.receivers, TechniqueFacts::Receivers::kNever);
  EXPECT_FALSE(f.candidate);
  for (FilterKind filter : {FilterKind::kHard, FilterKind::kPcss}) {
    const std::vector<Technique> c = single_map_candidates({LightType::kDirectional}, filter);
    EXPECT_EQ(std::count(c.begin(), c.end(), Technique::kVirtual), 0);
  }
}

TEST(Techniques, LightsEachDraws) {
  EXPECT_TRUE(draws(Technique::kUniform, LightType::kSpot));
  EXPECT_FALSE(draws(Technique::kUniform, LightType::kPoint));
  EXPECT_TRUE(draws(Technique::kLispsm, LightType::kDirectional));
  EXPECT_FALSE(draws(Technique::kLispsm, LightType::kSpot));
  EXPECT_FALSE(draws(Technique::kCube, LightType::kDirectional));
  EXPECT_TRUE(draws(Technique::kCube, LightType::kPoint));
  for (LightType l : {LightType::kDirectional, LightType::kSpot, LightType::kPoint}) {
    EXPECT_TRUE(draws(Technique::kPsm, l));
    EXPECT_TRUE(draws(Technique::kPsmCube, l));
    EXPECT_TRUE(draws(Technique::kAuto, l));
  }
  // Each refusal says what to use instead.
  for (Technique t : {Technique::kUniform, Technique::kLispsm, Technique::kCube})
    EXPECT_NE(std::string(technique_facts(t).refusal), "") << technique_label(t);
}

TEST(Techniques, CubesAndCameraDependence) {
  EXPECT_TRUE(may_draw_cube(Technique::kPsmCube, LightType::kDirectional));
  EXPECT_TRUE(may_draw_cube(Technique::kPsm, LightType::kPoint));
  EXPECT_FALSE(may_draw_cube(Technique::kPsm, LightType::kSpot));
  EXPECT_TRUE(may_draw_cube(Technique::kAuto, LightType::kPoint));
  EXPECT_FALSE(may_draw_cube(Technique::kAuto, LightType::kDirectional));
  EXPECT_FALSE(may_draw_cube(Technique::kUniform, LightType::kSpot));
  EXPECT_FALSE(may_draw_cube(Technique::kDefault, LightType::kPoint));  // resolved first
  for (Technique t : {Technique::kUniform, Technique::kCube})
    EXPECT_TRUE(technique_facts(t).fits_scene && !technique_facts(t).warped);
  for (Technique t : {Technique::kPsm, Technique::kPsmCube, Technique::kLispsm})
    EXPECT_TRUE(!technique_facts(t).fits_scene && technique_facts(t).warped);
}

TEST(Techniques, SingleMapCandidatesSimplestFirst) {
  using V = std::vector<Technique>;
  EXPECT_EQ(single_map_candidates({LightType::kDirectional}, FilterKind::kHard),
            (V{Technique::kUniform, Technique::kLispsm, Technique::kPsm}));
  EXPECT_EQ(single_map_candidates({LightType::kSpot}, FilterKind::kPcf2x2),
            (V{Technique::kUniform, Technique::kPsm}));
  EXPECT_EQ(single_map_candidates({LightType::kDirectional, LightType::kSpot}, FilterKind::kCsm),
            (V{Technique::kUniform, Technique::kPsm}));
  // PCSS's penumbra needs uniform maps.
  EXPECT_EQ(single_map_candidates({LightType::kDirectional}, FilterKind::kPcss),
            (V{Technique::kUniform}));
  EXPECT_EQ(single_map_candidates({}, FilterKind::kHard),
            (V{Technique::kUniform, Technique::kLispsm, Technique::kPsm}));
}

}  // namespace
}  // namespace shadow
