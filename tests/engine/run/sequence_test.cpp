// Sequences (Engine::render_sequence): each frame is bit-identical to the same frame rendered
// alone, a pass runs again only when its inputs changed (a moved caster re-renders only the maps
// of the lights that see it; a moved camera only the camera view when the maps are fitted to the
// scene), and bad frames are refused naming the field.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/plan/sequence.hpp"
#include "occluder_scene.hpp"

namespace shadow {
namespace {

using testing::engine;

bool has(const std::vector<std::string>& list, const std::string& name) {
  return std::find(list.begin(), list.end(), name) != list.end();
}

bool has_prefix(const std::vector<std::string>& list, const std::string& prefix) {
  return std::any_of(list.begin(), list.end(),
                     [&](const std::string& p) { return p.rfind(prefix, 0) == 0; });
}

bool same_bits(const Texture& a, const Texture& b) {
  return a.name == b.name && a.width == b.width && a.height == b.height &&
         a.channels == b.channels && a.faces == b.faces && a.data.size() == b.data.size() &&
         a.data64.size() == b.data64.size() &&
         std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0 &&
         std::memcmp(a.data64.data(), b.data64.data(), a.data64.size() * sizeof(double)) == 0 &&
         a.world_to_ndc == b.world_to_ndc;
}

std::vector<RenderResult> run(const SequenceRequest& s) {
  std::vector<RenderResult> out;
  engine().render_sequence(s, [&](RenderResult&& r) { out.push_back(std::move(r)); });
  return out;
}

glm::mat4 moved_to(float x, float z) {
  return glm::translate(glm::mat4(1.0f), glm::vec3(x, 0.0f, z));
}

// The occluder scene with a second occluder far to the right (x = 7), a sun straight down that
// sees both and a narrow spot over the first that sees only it; maps fitted to the scene.
SequenceRequest two_lights() {
  SequenceRequest s;
  RenderRequest& r = s.base;
  r = testing::occluder_request();
  auto scene = std::make_shared<Scene>(*r.scene);
  scene->instances.push_back(Instance{1});
  scene->instances.back().transform = moved_to(7, 0);
  r.scene = scene;
  Light spot;
  spot.type = LightType::kSpot;
  spot.position = {0, 8, 0};
  spot.direction = {0, -1, 0};
  spot.cone_angle_deg = 40.0f;
  r.lights = {r.lights[0], spot};
  r.shadow_map.fit = MapFit::kScene;
  r.shadow_map.size = 512;
  r.products = {Product::kShadowMap, Product::kVisibility, Product::kPosition};
  return s;
}

TEST(Sequence, ReusesExactlyWhatDidNotChange) {
  SequenceRequest s = two_lights();
  Camera moved_camera = s.base.camera;
  moved_camera.eye = {2, 10, 8};
  s.frames.resize(4);
  s.frames[2].transforms = {{2, moved_to(7.5f, 0.5f)}};  // the occluder only the sun sees
  s.frames[3].transforms = s.frames[2].transforms;
  s.frames[3].camera = moved_camera;
  const std::vector<RenderResult> frames = run(s);
  ASSERT_EQ(frames.size(), 4u);
  for (uint32_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    const RenderResult& f = frames[i];
    EXPECT_EQ(f.frame, i);
    const RenderResult alone = engine().render(frame_request(s, i));
    ASSERT_EQ(f.textures.size(), alone.textures.size());
    for (size_t t = 0; t < f.textures.size(); ++t)
      EXPECT_TRUE(same_bits(f.textures[t], alone.textures[t])) << f.textures[t].name;
    EXPECT_TRUE(alone.reused.empty());
  }
  // Frame 0 runs everything; frame 1 changes nothing.
  EXPECT_TRUE(frames[0].reused.empty());
  EXPECT_TRUE(has(frames[0].passes, "light1.shadow_map.raster"));
  for (const char* kept :
       {"scene", "gbuffer", "gbuffer.resolve", "light0.shadow_map", "light1.shadow_map"})
    EXPECT_TRUE(has(frames[1].reused, kept)) << kept;
  EXPECT_FALSE(has(frames[1].passes, "light0.shadow_map.raster"));
  EXPECT_FALSE(has(frames[1].passes, "gbuffer.raster"));
  EXPECT_TRUE(has_prefix(frames[1].passes, "light0.visibility"));  // per-pixel work still runs
  // Frame 2 moves a caster the spot cannot see: the sun and the camera view run again.
  EXPECT_TRUE(has(frames[2].passes, "light0.shadow_map.raster"));
  EXPECT_TRUE(has(frames[2].passes, "gbuffer.raster"));
  EXPECT_TRUE(has(frames[2].reused, "light1.shadow_map"));
  EXPECT_FALSE(has(frames[2].passes, "light1.shadow_map.raster"));
  // Frame 3 moves the camera: scene-fitted maps stay.
  EXPECT_TRUE(has(frames[3].passes, "gbuffer.raster"));
  EXPECT_TRUE(has(frames[3].reused, "light0.shadow_map"));
  EXPECT_TRUE(has(frames[3].reused, "light1.shadow_map"));
  // The step cache's misses: what could have been kept but ran again because an input changed.
  EXPECT_TRUE(frames[0].rerun.empty());
  EXPECT_TRUE(frames[1].rerun.empty());
  EXPECT_EQ(frames[2].rerun,
            (std::vector<std::string>{"light0.shadow_map", "gbuffer", "gbuffer.resolve"}));
  EXPECT_EQ(frames[3].rerun, (std::vector<std::string>{"gbuffer", "gbuffer.resolve"}));
}

// Fitted to the view, a uniform map follows the camera: a moved camera re-renders it.
TEST(Sequence, ViewFittedMapFollowsTheCamera) {
  SequenceRequest s = two_lights();
  s.base.shadow_map.fit = MapFit::kView;
  s.base.lights.resize(1);
  s.frames.resize(2);
  s.frames[1].camera = s.base.camera;
  s.frames[1].camera->eye = {2, 10, 8};
  const std::vector<RenderResult> frames = run(s);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_TRUE(has(frames[1].passes, "shadow_map.raster"));
  EXPECT_TRUE(has(frames[1].reused, "scene"));
}

// The CSM basis is kept with its map, and rebuilt when the map changes.
TEST(Sequence, KeepsTheCsmBasisWithItsMap) {
  SequenceRequest s = two_lights();
  s.base.lights.resize(1);
  s.base.filter.kind = FilterKind::kCsm;
  s.base.filter.csm.terms = 4;
  s.base.products = {Product::kVisibility, Product::kCsmBasis};
  s.frames.resize(3);
  s.frames[2].transforms = {{1, moved_to(0.5f, 0)}};
  const std::vector<RenderResult> frames = run(s);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_TRUE(has(frames[1].reused, "csm.basis"));
  EXPECT_FALSE(has(frames[1].passes, "csm.basis"));
  EXPECT_TRUE(has(frames[2].passes, "csm.basis"));
  for (uint32_t i = 1; i < 3; ++i) {
    const RenderResult alone = engine().render(frame_request(s, i));
    for (size_t t = 0; t < alone.textures.size(); ++t)
      EXPECT_TRUE(same_bits(frames[i].textures[t], alone.textures[t])) << i;
  }
}

// The shadow atlas: the bake is kept while the receivers stand still, each light's atlas while
// its maps do too; moving a caster that receives nothing re-filters, moving a receiver rebakes.
TEST(Sequence, KeepsTheAtlasWithItsMapsAndReceivers) {
  SequenceRequest s = two_lights();
  auto scene = std::make_shared<Scene>(*s.base.scene);
  for (Mesh& m : scene->meshes) m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  scene->instances[2].receives_shadows = false;  // the far occluder only casts
  s.base.scene = scene;
  s.base.products = {Product::kShadowAtlas, Product::kVisibility};
  s.base.atlas.tile = 64;
  s.frames.resize(4);
  s.frames[2].transforms = {{2, moved_to(7.5f, 0.5f)}};  // the caster only the sun sees
  s.frames[3].transforms = {{2, moved_to(7.5f, 0.5f)}, {1, moved_to(0.5f, 0)}};  // a receiver
  const std::vector<RenderResult> frames = run(s);
  ASSERT_EQ(frames.size(), 4u);
  for (uint32_t i = 1; i < 4; ++i) {
    const RenderResult alone = engine().render(frame_request(s, i));
    ASSERT_EQ(frames[i].textures.size(), alone.textures.size());
    for (size_t t = 0; t < alone.textures.size(); ++t)
      EXPECT_TRUE(same_bits(frames[i].textures[t], alone.textures[t]))
          << i << " " << alone.textures[t].name;
  }
  for (const char* kept : {"atlas.bake", "light0.atlas.visibility", "light1.atlas.visibility"})
    EXPECT_TRUE(has(frames[1].reused, kept)) << kept;
  EXPECT_TRUE(has(frames[2].reused, "atlas.bake"));
  EXPECT_TRUE(has(frames[2].reused, "light1.atlas.visibility"));  // the spot does not see it
  EXPECT_TRUE(has_prefix(frames[2].passes, "light0.atlas.gutter"));
  EXPECT_TRUE(has_prefix(frames[3].passes, "atlas.cover"));  // a receiver moved: rebaked
}

// Soft shadows through the atlas with a moving camera: the bake, the atlas, its penumbra and its
// SAT are kept; each frame costs the G-buffer and the lookups, bit-identical to a rerun.
TEST(Sequence, AtlasFiltersKeepTheirPrefilteredAtlas) {
  SequenceRequest s = two_lights();
  auto scene = std::make_shared<Scene>(*s.base.scene);
  for (Mesh& m : scene->meshes) m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  scene->instances[2].receives_shadows = false;
  s.base.scene = scene;
  s.base.lights.resize(1);
  s.base.lights[0].size = 5.0f;
  s.base.products = {Product::kVisibility};
  s.base.filter.kind = FilterKind::kAtlasSat;
  s.base.atlas.tile = 64;
  s.frames.resize(3);
  s.frames[1].camera = s.base.camera;
  s.frames[1].camera->eye = {2, 10, 8};
  s.frames[2].camera = s.frames[1].camera;
  s.frames[2].camera->eye = {-3, 9, 7};
  const std::vector<RenderResult> frames = run(s);
  ASSERT_EQ(frames.size(), 3u);
  for (uint32_t i = 1; i < 3; ++i) {
    const RenderResult alone = engine().render(frame_request(s, i));
    EXPECT_TRUE(same_bits(frames[i].textures.at(0), alone.textures.at(0))) << i;
    for (const char* kept :
         {"atlas.bake", "atlas.visibility", "atlas.sat", "atlas.soften", "shadow_map"})
      EXPECT_TRUE(has(frames[i].reused, kept)) << i << " " << kept;
    EXPECT_FALSE(has_prefix(frames[i].passes, "atlas.penumbra")) << i;
    EXPECT_FALSE(has_prefix(frames[i].passes, "atlas.soften")) << i;
    EXPECT_TRUE(has_prefix(frames[i].passes, "visibility.atlas")) << i;
  }
}

// Separate requests over one held scene: a request with the same products and settings as the
// last continues it as a sequence's next frame would (the atlas' bake, the light's map, atlas
// and soft atlas are kept across requests), bit-identical to a request that keeps nothing;
// other settings start afresh, and a scene sent inline keeps nothing.
TEST(Sequence, RequestsOnAHeldSceneContinueTheLastOne) {
  RenderRequest r = two_lights().base;
  auto scene = std::make_shared<Scene>(*r.scene);
  for (Mesh& m : scene->meshes) m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  scene->instances[2].receives_shadows = false;
  r.scene = scene;
  r.scene_held = true;
  r.lights.resize(1);
  r.lights[0].size = 5.0f;
  r.products = {Product::kVisibility};
  r.filter.kind = FilterKind::kAtlasSat;
  r.atlas.tile = 64;
  const RenderResult first = engine().render(r);
  EXPECT_FALSE(has(first.reused, "atlas.bake"));
  r.camera.eye = {2, 10, 8};
  const RenderResult second = engine().render(r);
  for (const char* kept :
       {"scene", "atlas.bake", "atlas.visibility", "atlas.sat", "atlas.soften", "shadow_map"})
    EXPECT_TRUE(has(second.reused, kept)) << kept;
  EXPECT_TRUE(has_prefix(second.passes, "visibility.atlas"));

  RenderRequest sent_inline = r;
  sent_inline.scene = std::make_shared<Scene>(*scene);
  sent_inline.scene_held = false;
  const RenderResult cold = engine().render(sent_inline);
  EXPECT_TRUE(cold.reused.empty());
  EXPECT_TRUE(same_bits(second.textures.at(0), cold.textures.at(0)));

  r.filter.pcss.blocker_samples = 8;  // another setting: the light's work runs again
  const RenderResult other = engine().render(r);
  for (const char* rerun : {"atlas.bake", "atlas.visibility", "atlas.soften", "shadow_map"})
    EXPECT_FALSE(has(other.reused, rerun)) << rerun;
  sent_inline.filter = r.filter;
  EXPECT_TRUE(same_bits(other.textures.at(0), engine().render(sent_inline).textures.at(0)));
}

// An idle engine gives its workspaces' buffers back (idle_memory_bytes), but not those of the
// one that keeps results for its held scene: the next request there still continues.
TEST(Sequence, IdleTrimmingSparesTheWarmWorkspace) {
  EngineOptions options;
  options.idle_memory_bytes = 0;
  options.idle_trim_delay_ms = 0;  // as soon as each request ends
  options.max_concurrent = 2;
  Engine trimming(options);
  RenderRequest r = two_lights().base;
  r.scene_held = true;
  trimming.render(r);
  r.camera.eye = {2, 10, 8};
  EXPECT_TRUE(has(trimming.render(r).reused, "light0.shadow_map"));
  r.scene_held = false;  // inline: it keeps nothing, so the trimming then empties both
  trimming.render(r);
  r.scene_held = true;
  EXPECT_FALSE(has(trimming.render(r).reused, "light0.shadow_map"));
}

// A point light's cube: its faces are kept too.
TEST(Sequence, KeepsCubeFaces) {
  SequenceRequest s = two_lights();
  Light point;
  point.type = LightType::kPoint;
  point.position = {0, 5, 0};
  s.base.lights = {point};
  s.base.shadow_map.fit = MapFit::kView;
  s.frames.resize(2);
  const std::vector<RenderResult> frames = run(s);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_TRUE(has_prefix(frames[0].passes, "shadow_map.-y."));
  EXPECT_TRUE(has(frames[1].reused, "shadow_map.-y"));
  EXPECT_FALSE(has_prefix(frames[1].passes, "shadow_map.-y."));
}

std::string refused(const SequenceRequest& s) {
  try {
    run(s);
  } catch (const InvalidArgument& e) {
    return e.field();
  } catch (const ResourceExhausted& e) {
    return "exhausted: " + e.field();
  }
  return "(accepted)";
}

TEST(Sequence, BadFramesAreNamed) {
  SequenceRequest s = two_lights();
  EXPECT_EQ(refused(s), "frames");  // none
  s.frames.resize(3);
  s.frames[1].transforms = {{9, glm::mat4(1.0f)}};
  EXPECT_EQ(refused(s), "frames[1].transforms[0].instance");
  s.frames[1].transforms = {{1, glm::mat4(1.0f)}, {1, glm::mat4(1.0f)}};
  EXPECT_EQ(refused(s), "frames[1].transforms[1].instance");
  s.frames[1].transforms = {{1, glm::mat4(NAN)}};
  EXPECT_EQ(refused(s), "frames[1].transforms[0].transform");
  s.frames[1].transforms.clear();
  s.frames[2].camera = s.base.camera;
  s.frames[2].camera->fov_deg = 0.0f;
  EXPECT_EQ(refused(s), "frames[2].camera.fov_deg");
  s.frames[2].camera.reset();
  s.frames[2].lights = std::vector<Light>(1);
  s.frames[2].lights->at(0).direction = {0, 0, 0};
  EXPECT_EQ(refused(s), "frames[2].lights[0].directional.direction");
  s.frames[2].lights.reset();
  s.base.camera.width = 0;
  EXPECT_EQ(refused(s), "base.camera.width");
  s.base.camera.width = 320;
  const std::vector<Light> lights = s.base.lights;
  s.base.lights.clear();  // an empty list where the products need a light
  EXPECT_EQ(refused(s), "base.lights");
  s.frames[2].lights = lights;  // ... unless every frame that needs one has its own
  EXPECT_EQ(refused(s), "base.lights");
  for (Frame& f : s.frames) f.lights = lights;
  EXPECT_EQ(refused(s), "(accepted)");
  s.base.lights = lights;
  for (Frame& f : s.frames) f.lights.reset();
  s.base.shadow_map.technique = Technique::kPsm;  // a PSM map cannot be fitted to the scene
  EXPECT_EQ(refused(s), "base.shadow_map.fit");
  s.base.shadow_map.technique = Technique::kDefault;
  s.frames.resize(kMaxFrames + 1);
  EXPECT_EQ(refused(s), "exhausted: frames");
}

// A cancelled sequence stops, and the engine serves the next one.
TEST(Sequence, CancelStopsAndTheEngineGoesOn) {
  SequenceRequest s = two_lights();
  s.frames.resize(5);
  int done = 0;
  EXPECT_THROW(engine().render_sequence(
                   s, [&](RenderResult&&) { ++done; }, [&] { return done >= 2; }),
               Cancelled);
  EXPECT_EQ(done, 2);
  s.frames.resize(1);
  EXPECT_EQ(run(s).size(), 1u);
}

}  // namespace
}  // namespace shadow
