#include "engine/plan/validate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "engine/light/cube_fit.hpp"
#include "engine/light/virtual_levels.hpp"
#include "engine/plan/atlas_layout.hpp"
#include "engine/plan/csm_size.hpp"
#include "engine/plan/filter.hpp"
#include "engine/plan/light_request.hpp"
#include "engine/plan/mip_levels.hpp"
#include "engine/plan/plan.hpp"
#include "engine/plan/require.hpp"
#include "engine/plan/technique.hpp"
#include "engine/plan/uv_layouts.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

constexpr uint32_t kMaxImageSide = 16384;
// Largest distance a camera may span: float32's range with room for one matrix product.
constexpr double kMaxWorldReach = 1e37;
constexpr uint64_t kMaxElements = uint64_t{1} << 31;  // 32-bit ids with room to spare
constexpr uint32_t kMaxAtlasGutter = 16;

std::string idx(const char* prefix, size_t i) {
  return prefix + std::to_string(i) + "]";
}

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

// Vectors are measured in double: a float length squares its components, so 1e-30 underflows to
// zero and 1e20 overflows to infinity, though both are fine directions.
double length(const glm::vec3& v) {
  return glm::length(glm::dvec3(v));
}

void validate_camera(const Camera& c) {
  require(finite(c.eye), "camera.eye", "is not finite");
  require(finite(c.target), "camera.target", "is not finite");
  require(finite(c.up), "camera.up", "is not finite");
  const glm::dvec3 forward = glm::dvec3(c.target) - glm::dvec3(c.eye);
  require(glm::length(forward) > 0.0, "camera.target", "equals camera.eye");
  // The camera's matrices reach the kernels as float32: a view spanning more overflows them.
  const double apart = glm::length(forward),
               from_origin = std::max(length(c.eye), length(c.target));
  require(std::max(apart, from_origin) <= kMaxWorldReach,
          length(c.eye) >= length(c.target) ? "camera.eye" : "camera.target",
          "overflows float32: camera.eye and camera.target are " + number(apart) +
              " apart and up to " + number(from_origin) +
              " from the origin; the camera's matrices need both within " + number(kMaxWorldReach));
  require(length(c.up) > 0.0 && glm::length(glm::cross(glm::normalize(forward),
                                                       glm::normalize(glm::dvec3(c.up)))) > 1e-6,
          "camera.up", "is zero or parallel to the view direction");
  require(c.fov_deg > 0.0f && c.fov_deg < 180.0f, "camera.fov_deg",
          "must be in (0, 180), got " + std::to_string(c.fov_deg));
  require(c.width >= 1 && c.width <= kMaxImageSide, "camera.width",
          "must be in [1, 16384], got " + std::to_string(c.width));
  require(c.height >= 1 && c.height <= kMaxImageSide, "camera.height",
          "must be in [1, 16384], got " + std::to_string(c.height));
  // A pixel at the target must be wider than float32 can tell coordinates apart there (with a
  // margin of 4 steps); narrower, every pixel lands on the same few points and a tiny field of
  // view comes back as one texel's shadow, or garbage.
  const double tan_half = std::tan(glm::radians(double(c.fov_deg)) / 2.0);
  const double pixel = 2.0 * apart * tan_half / c.height;
  const double resolvable = std::ldexp(std::max(apart, from_origin), -22);
  if (!(pixel >= resolvable)) {
    const double min_fov = glm::degrees(2.0 * std::atan(resolvable * c.height / (2.0 * apart)));
    throw InvalidArgument("camera.fov_deg",
                          number(c.fov_deg) + " degrees makes a pixel " + number(pixel) +
                              " wide at camera.target, finer than float32 resolves at " +
                              number(std::max(apart, from_origin)) + " from the origin (" +
                              number(resolvable) + "): use at least " + number(min_fov) +
                              " degrees or bring the camera nearer the origin");
  }
  require(std::isfinite(c.near) && c.near > 0.0f, "camera.near",
          "must be finite and > 0, got " + std::to_string(c.near));
  require(std::isfinite(c.far) && c.far > c.near, "camera.far",
          "must be finite and > camera.near, got " + std::to_string(c.far));
  // Float32 depth 1 - near/d rounds to 1, the far plane, for every d beyond 2^24 near planes.
  require(double(c.far) <= std::ldexp(double(c.near), 24), "camera.far",
          number(c.far) + " is more than 2^24 times camera.near (" + number(c.near) +
              "): float32 depth cannot tell surfaces beyond " +
              number(std::ldexp(double(c.near), 24)) + " from the far plane; raise camera.near");
}

// `lf`: the light's field path, "lights[i]".
void validate_light(const Light& l, Technique technique, const std::string& lf) {
  const std::string f = lf + (l.type == LightType::kDirectional ? ".directional"
                              : l.type == LightType::kSpot      ? ".spot"
                                                                : ".point");
  if (l.type != LightType::kPoint) {
    require(finite(l.direction), f + ".direction", "is not finite");
    require(length(l.direction) > 0.0, f + ".direction", "is zero");
  }
  if (l.type != LightType::kDirectional)
    require(finite(l.position), f + ".position", "is not finite");
  if (l.type == LightType::kSpot)
    require(l.cone_angle_deg > 0.0f && l.cone_angle_deg < 180.0f, f + ".cone_angle_deg",
            "must be in (0, 180), got " + std::to_string(l.cone_angle_deg));
  require(std::isfinite(l.size) && l.size >= 0.0f, lf + ".size", "must be finite and >= 0");
  if (!draws(technique, l.type)) {
    const TechniqueFacts& facts = technique_facts(technique);
    throw InvalidArgument(facts.refusal_on_light ? lf + ".point" : "shadow_map.technique",
                          facts.refusal);
  }
}

// Whether the request may be drawn as a cube (which faces, only the fit knows): CUBE, PSM_CUBE,
// and PSM with a point light, which falls back to the cube where no single frustum covers the
// visible receivers (the light inside the view).
bool may_render_cube(const RenderRequest& r) {
  return may_draw_cube(r.shadow_map.technique, r.lights[0].type);
}

// Cube faces carry a guard band as wide as the filter's reach (engine/light/cube_fit.hpp); filters
// whose reach has no bound, and light-space products over one map, are not available.
void validate_cube(const RenderRequest& r) {
  validate_cube_filter(r.filter, r.shadow_map.size);
  for (size_t i = 0; i < r.products.size(); ++i) {
    require(r.products[i] != Product::kShadowMapMips && r.products[i] != Product::kShadowMapSat,
            idx("products[", i),
            "shadow-map mips and summed-area tables are not available for cube maps");
    require(r.products[i] != Product::kCsmBasis && r.products[i] != Product::kBlockerDepth,
            idx("products[", i),
            "the CSM basis and blocker depth are not available for cube maps (a basis and a "
            "depth range per face): ask for the visibility");
  }
}

// The products a TECHNIQUE_VIRTUAL request may not ask for: its pages are drawn only where the
// camera's pixels read them, so no light has a dense map to return, prefilter or bake from.
struct VirtualRefusedProduct {
  Product product;
  const char* name;
  const char* reason;
};
constexpr const char* kNoDenseMap =
    "its maps are pages drawn only where the camera's pixels read them, never a dense map (ask "
    "for the visibility)";
constexpr const char* kNoVirtualDesign =
    "a prefiltered product (mips, SAT, CSM basis) or the atlas has no virtual design";
constexpr VirtualRefusedProduct kVirtualRefusedProducts[] = {
    {Product::kShadowMap, "PRODUCT_SHADOW_MAP", kNoDenseMap},
    {Product::kShadowMapMips, "PRODUCT_SHADOW_MAP_MIPS", kNoVirtualDesign},
    {Product::kShadowMapSat, "PRODUCT_SHADOW_MAP_SAT", kNoVirtualDesign},
    {Product::kCsmBasis, "PRODUCT_CSM_BASIS", kNoVirtualDesign},
    {Product::kBlockerDepth, "PRODUCT_BLOCKER_DEPTH", kNoVirtualDesign},
    {Product::kShadowAtlas, "PRODUCT_SHADOW_ATLAS", kNoVirtualDesign},
    {Product::kShadowAtlasMips, "PRODUCT_SHADOW_ATLAS_MIPS", kNoVirtualDesign},
    {Product::kShadowAtlasSat, "PRODUCT_SHADOW_ATLAS_SAT", kNoVirtualDesign},
    {Product::kAtlasUvs, "PRODUCT_ATLAS_UVS", kNoVirtualDesign},
    {Product::kTexelDensity, "PRODUCT_TEXEL_DENSITY",
     "a pixel's texel is its level's, which marking picks to match the pixel's footprint (not yet "
     "reported per pixel)"},
};

// TECHNIQUE_VIRTUAL's own needs: a level's edge, the filters read through its page table and no
// dense-map product. Its pool and LOD bias are checked with any technique, as the PSM and LiSPSM
// settings are.
void validate_virtual(const RenderRequest& r) {
  const uint32_t size = r.shadow_map.size;
  require(size >= kMinVirtualMapSize && size <= kMaxVirtualMapSize && (size & (size - 1)) == 0,
          "shadow_map.size",
          "must be a power of two from 2048 to 32768 with TECHNIQUE_VIRTUAL (each level's virtual "
          "edge), got " +
              std::to_string(size));
  validate_virtual_filter(r.filter);
  for (size_t i = 0; i < r.products.size(); ++i)
    for (const VirtualRefusedProduct& refused : kVirtualRefusedProducts)
      if (r.products[i] == refused.product)
        throw InvalidArgument(idx("products[", i),
                              std::string(refused.name) +
                                  " is not available with TECHNIQUE_VIRTUAL: " + refused.reason);
  // Slot numbers reach 16384: a half holds integers exactly only to 2048.
  for (size_t i = 0; i < r.products.size(); ++i)
    require(r.products[i] != Product::kVirtualPages || r.output_format == PixelFormat::kFloat32,
            idx("products[", i),
            "PRODUCT_VIRTUAL_PAGES is float32 only (its page tables hold slot numbers up to "
            "16384); ask for OUTPUT_FORMAT_FLOAT32");
}

// The shadow atlas: its settings, a size within the texture and buffer limits, and UVs on every
// receiving instance's mesh (their range and overlaps are checked on the device by the bake).
void validate_atlas(const RenderRequest& r, const Limits& limits) {
  const AtlasSettings& a = r.atlas;
  const bool fixed = a.tile != 0;
  require(!fixed || (a.tile >= kMinAtlasTile && a.tile <= kMaxAtlasTile), "atlas.tile_size",
          "must be in [16, 4096], got " + std::to_string(a.tile));
  require(std::isfinite(a.texel_world_size) && a.texel_world_size >= 0, "atlas.texel_world_size",
          "must be finite and > 0 (absent: the shadow map's texel footprint), got " +
              std::to_string(a.texel_world_size));
  require(!fixed || a.texel_world_size == 0, "atlas.texel_world_size",
          "give atlas.tile_size (one tile for every instance) or atlas.texel_world_size (tiles "
          "sized from the world), not both");
  require(
      a.gutter <= kMaxAtlasGutter && (!fixed || 4 * a.gutter < a.tile), "atlas.gutter",
      "must be in [0, 16] and under a quarter of atlas.tile_size, got " + std::to_string(a.gutter));
  // The atlas's layout reads the receiving meshes through their indices on the host (their
  // areas and UVs here, the generated layouts and charts later), ahead of the device's index
  // check: an index past the vertices is refused here, in the device check's words.
  std::vector<bool> checked(r.scene->meshes.size(), false);
  for (const Instance& inst : r.scene->instances) {
    if (!inst.receives_shadows || checked[inst.mesh]) continue;
    checked[inst.mesh] = true;
    const Mesh& m = r.scene->meshes[inst.mesh];
    const auto bad = std::find_if(m.indices.begin(), m.indices.end(),
                                  [&](uint32_t i) { return i >= m.vertex_count(); });
    if (bad != m.indices.end())
      throw InvalidArgument(
          idx("scene.meshes[", inst.mesh) + ".indices" + idx("[", size_t(bad - m.indices.begin())),
          "index " + std::to_string(*bad) + " is out of range (mesh has " +
              std::to_string(m.vertex_count()) + " vertices)");
  }
  const AtlasLayout layout = atlas_layout(r);
  const AtlasSize& size = layout.size;
  require(size.receivers > 0, "products",
          "PRODUCT_SHADOW_ATLAS needs an instance that receives shadows; none does");
  // The bake's largest buffer, its normals, holds 16 bytes a texel.
  if (size.width > kMaxAtlasEdge || size.height > kMaxAtlasEdge ||
      size.width * size.height * 16 > limits.max_buffer_bytes) {
    const std::string atlas = std::to_string(size.width) + "x" + std::to_string(size.height) +
                              " atlas, over the limit of 16384 texels a side or the device's "
                              "buffer limit (" +
                              std::to_string(limits.max_buffer_bytes / 16) + " texels)";
    if (fixed)
      throw ResourceExhausted("atlas.tile_size",
                              std::to_string(size.receivers) + " receiving instances in tiles of " +
                                  std::to_string(a.tile) + " make a " + atlas + ": smaller tiles");
    throw ResourceExhausted(
        "atlas.texel_world_size",
        std::to_string(size.receivers) + " receiving instances at " +
            (a.texel_world_size > 0 ? std::to_string(a.texel_world_size) + " world units"
                                    : std::string("the shadow map's footprint")) +
            " a texel (tiles of " + std::to_string(layout.cell) + " to " +
            std::to_string(layout.largest) + " texels) make a " + atlas +
            ": a larger texel_world_size (shadowctl: --atlas-density)");
  }
  // The atlas covers every receiver, seen or not: so must the maps. PSM and LiSPSM spend their
  // texels on the camera's view and cannot hold receivers behind the camera at all.
  require(r.shadow_map.fit == MapFit::kScene, "shadow_map.fit",
          "the shadow atlas needs maps fitted to the scene (MAP_FIT_SCENE; shadowctl: --fit "
          "scene): it covers every receiver, not only those in view");
  for (size_t i = 0; i < r.lights.size(); ++i) {
    const Technique t = for_light(r, i).shadow_map.technique;
    require(technique_facts(t).fits_scene, "shadow_map.technique",
            "the shadow atlas takes uniform maps (directional and spot lights) or cubes (point "
            "lights): PSM and LiSPSM warp the map to the camera's view, which cannot hold the "
            "receivers behind the camera (" +
                light_field(i) + ")");
  }
  // A layout whose every UV triangle has no area (every face mapped to one point, as some
  // exporters write) covers no texel: the atlas would be all NaN.
  if (!a.generate_uvs)
    for (const Instance& inst : r.scene->instances)
      if (inst.receives_shadows && uvs_degenerate(r.scene->meshes[inst.mesh]))
        throw InvalidArgument("scene.meshes[" + std::to_string(inst.mesh) + "].uvs",
                              "every UV triangle has zero area (all faces on one point or line): "
                              "the shadow atlas would be empty; give the mesh a layout, or let the "
                              "server make one (atlas.generate_uvs; shadowctl: "
                              "--atlas-generate-uvs)");
  // Receiving meshes without UVs (all of them with generate_uvs) get a generated layout
  // (engine/plan/uv_layouts), up to a size.
  for (uint32_t m : meshes_to_lay_out(*r.scene, a.generate_uvs)) {
    const uint64_t triangles = r.scene->meshes[m].triangle_count();
    if (triangles > kMaxLayoutTriangles)
      throw ResourceExhausted(
          a.generate_uvs ? "atlas.generate_uvs" : "scene.meshes[" + std::to_string(m) + "].uvs",
          std::string(a.generate_uvs ? "mesh " + std::to_string(m) + " receives shadows, and its "
                                     : "absent, and the mesh's ") +
              std::to_string(triangles) + " triangles are over the " +
              std::to_string(kMaxLayoutTriangles) + " a layout is generated for: " +
              (a.generate_uvs ? "give it unique UVs and leave generate_uvs off"
                              : "give the mesh UVs"));
    // The layout is made on the host before the device checks the positions.
    const std::vector<float>& p = r.scene->meshes[m].positions;
    const auto bad = std::find_if(p.begin(), p.end(), [](float x) {
      return !(std::abs(x) <= kMaxLayoutCoordinate);  // NaN too
    });
    if (bad != p.end())
      throw InvalidArgument(
          idx("scene.meshes[", m) + ".positions" + idx("[", size_t(bad - p.begin()) / 3),
          std::isfinite(*bad) ? "a coordinate of " + number(*bad) + " is beyond the " +
                                    number(kMaxLayoutCoordinate) +
                                    " a UV layout is generated for: give the mesh UVs"
                              : "vertex position is not finite (NaN or Inf)");
  }
}

// CSM's products need its settings; its largest buffer (one family of M channels with mips) must
// fit a device buffer.
void validate_csm_request(const RenderRequest& r, const Limits& limits) {
  const bool csm_filter = is_csm(r.filter.kind);
  for (size_t i = 0; i < r.products.size(); ++i)
    if (r.products[i] == Product::kCsmBasis || r.products[i] == Product::kBlockerDepth)
      require(csm_filter, idx("products[", i),
              "the CSM basis and blocker depth need filter csm or pcss_csm (their settings)");
  if (!csm_filter) return;
  const CsmSettings& c = r.filter.csm;
  const bool sat = c.lookup == CsmLookup::kSat, half = c.storage == CsmStorage::kFloat16;
  require(!(sat && half), std::string(filter_facts(r.filter.kind).field) + ".storage",
          "float16 storage is for the mips: the SAT lookup sums float32 basis channels into "
          "float64 tables");
  // As if looked up (the basis product alone has no prefilter).
  const uint64_t family = csm_family_bytes(r.shadow_map.size, c.terms, half,
                                           sat ? CsmPrefilter::kSat : CsmPrefilter::kMips);
  if (family > limits.max_buffer_bytes)
    throw ResourceExhausted(std::string(filter_facts(r.filter.kind).field) + ".terms",
                            std::to_string(r.filter.csm.terms) + " terms of a " +
                                std::to_string(r.shadow_map.size) + "^2 map need " +
                                std::to_string(family) +
                                " bytes per channel family, over the device's buffer limit of " +
                                std::to_string(limits.max_buffer_bytes) +
                                (sat ? ": fewer terms, the mips lookup or a smaller map"
                                     : ": fewer terms, float16 storage or a smaller map"));
}

// A quality goal picks the technique and size (engine/choose/quality_pick.hpp) among single maps.
void validate_quality(const RenderRequest& r) {
  const Quality& q = r.quality;
  if (q.goal == Quality::Goal::kNone) return;
  if (q.goal == Quality::Goal::kMaxError)
    require(std::isfinite(q.value) && q.value > 0 && q.value <= 1, "quality.max_error",
            "must be in (0, 1] (a share of the pixels), got " + std::to_string(q.value));
  else
    require(std::isfinite(q.value) && q.value > 0 && q.value <= 1e7, "quality.max_device_ms",
            "must be in (0, 1e7] ms, got " + std::to_string(q.value));
  const Technique t = r.shadow_map.technique;
  require(t == Technique::kDefault || t == Technique::kAuto, "shadow_map.technique",
          "is picked by the quality goal: leave it unspecified (or AUTO), or drop quality");
  for (size_t i = 0; i < r.lights.size(); ++i)
    require(r.lights[i].type != LightType::kPoint, light_field(i) + ".point",
            "quality goals do not predict cube maps yet: set shadow_map.technique and size");
}

// The bytes of `one` light's products (a request narrowed by for_light), and with `shared` those
// that need no light.
uint64_t one_light_bytes(const RenderRequest& r, bool shared) {
  const uint64_t faces = !shared && may_render_cube(r) ? 6 : 1;             // up to six
  const uint64_t value = r.output_format == PixelFormat::kFloat16 ? 2 : 4;  // SATs: 8 always
  uint64_t map = faces * r.shadow_map.size * r.shadow_map.size * value;
  uint64_t pixels = uint64_t{r.camera.width} * r.camera.height * value;
  uint64_t total = 0;
  const uint64_t size = r.shadow_map.size, w = r.camera.width, h = r.camera.height;
  // The atlas' layout (host work over every receiving mesh's triangles): once for its products.
  std::optional<AtlasSize> atlas_sized;
  const auto atlas = [&] {
    if (!atlas_sized) atlas_sized = atlas_size(r);
    return *atlas_sized;
  };
  for (Product p : r.products) {
    if (per_light(p) == shared) continue;
    switch (p) {
      case Product::kShadowMap:
        total += map;
        break;
      case Product::kVisibility:
      case Product::kTexelDensity:
        total += pixels;
        break;
      case Product::kPosition:
        total += 3 * pixels;
        break;
      case Product::kShadowMapMips:
        total += mip_chain_texels(size, size) * value;
        break;
      case Product::kShadowMapSat:
        total += size * size * sizeof(double);
        break;
      case Product::kVisibilityMips:
        total += mip_chain_texels(w, h) * value;
        break;
      case Product::kVisibilitySat:
        total += w * h * sizeof(double);
        break;
      case Product::kCsmBasis:  // 4M + 1 channels at most
        total += size * size * (4 * uint64_t{r.filter.csm.terms} + 1) * value;
        break;
      case Product::kBlockerDepth:
        total += pixels;
        break;
      case Product::kShadowAtlas: {
        const AtlasSize a = atlas();
        total += a.width * a.height * value;
        break;
      }
      case Product::kShadowAtlasMips: {
        const AtlasSize a = atlas();
        total += mip_chain_texels(a.width, a.height) * value;
        break;
      }
      case Product::kAtlasUvs:  // 3 corners x 2 floats per triangle of each mesh laid out
        for (uint32_t m : meshes_to_lay_out(*r.scene, r.atlas.generate_uvs))
          total += uint64_t{r.scene->meshes[m].triangle_count()} * 6 * value;
        break;
      case Product::kShadowAtlasSat: {  // two channels
        const AtlasSize a = atlas();
        total += a.width * a.height * 2 * sizeof(double);
        break;
      }
      case Product::kVirtualPages: {  // every level's table and window at most, the faces'
        const uint64_t pages = (size / kPageTexels) * (size / kPageTexels);  // matrices, levels
        total += (kMaxLevels * (pages + 4) + 6 * 16) * value + pixels;
        break;
      }
    }
  }
  return total;
}

}  // namespace

void validate_scene(const Scene& scene, const Limits& limits) {
  uint64_t vertices = 0, indices = 0, instance_vertices = 0, instance_triangles = 0;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const Mesh& m = scene.meshes[i];
    std::string f = idx("scene.meshes[", i);
    require(m.positions.size() % 3 == 0, f + ".positions", "must hold xyz triples");
    require(m.indices.size() % 3 == 0, f + ".indices", "must hold index triples");
    require(!m.positions.empty() && !m.indices.empty(), f,
            "mesh is empty (no vertices or no triangles)");
    require(m.normals.empty() || m.normals.size() == m.positions.size(), f + ".normals",
            "must be empty or hold one xyz normal per vertex");
    require(m.uvs.empty() || m.uvs.size() == 2 * m.vertex_count(), f + ".uvs",
            "must be empty or hold one uv pair per vertex");
    vertices += m.vertex_count();
    indices += m.indices.size();
  }
  if (vertices >= kMaxElements || indices >= kMaxElements)
    throw ResourceExhausted("scene.meshes", "more than 2^31 vertices or indices");
  for (size_t j = 0; j < scene.instances.size(); ++j) {
    const Instance& inst = scene.instances[j];
    std::string f = idx("scene.instances[", j);
    require(inst.mesh < scene.meshes.size(), f + ".mesh",
            "names mesh " + std::to_string(inst.mesh) + " but the scene has " +
                std::to_string(scene.meshes.size()));
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        require(std::isfinite(inst.transform[c][r]), f + ".transform", "is not finite");
    require(inst.receiver_class == Instance::kNoClass || inst.receiver_class < 4,
            f + ".receiver_class", "must be 0..3, got " + std::to_string(inst.receiver_class));
    instance_vertices += scene.meshes[inst.mesh].vertex_count();
    instance_triangles += scene.meshes[inst.mesh].triangle_count();
  }
  // Transformed vertices (16 B) and set-up triangles (40 B, plus clipping slack) per pass.
  if (instance_vertices >= kMaxElements || instance_vertices * 16 > limits.max_buffer_bytes ||
      instance_triangles >= kMaxElements || instance_triangles * 48 > limits.max_buffer_bytes)
    throw ResourceExhausted("scene.instances", "the instanced geometry (" +
                                                   std::to_string(instance_triangles) +
                                                   " triangles) exceeds the device's buffer limit");
}

uint64_t output_bytes(const RenderRequest& r) {
  uint64_t total = one_light_bytes(r, true);
  // The virtual pool, once: the request's lights share it.
  if (std::find(r.products.begin(), r.products.end(), Product::kVirtualPages) != r.products.end())
    total += uint64_t{r.shadow_map.virtual_pool_pages} * kPageTexels * kPageTexels * 4;
  for (size_t i = 0; i < r.lights.size(); ++i) total += one_light_bytes(for_light(r, i), false);
  return total;
}

void validate(const RenderRequest& r, const Limits& limits) {
  require(r.scene != nullptr, "scene", "is missing");
  validate_scene(*r.scene, limits);
  validate_camera(r.camera);
  require(!needs_light(r) || !r.lights.empty(), "lights",
          "is empty: every product but POSITION needs a light");
  require(r.lights.size() <= kMaxLights, "lights",
          "has " + std::to_string(r.lights.size()) + " lights, over the limit of " +
              std::to_string(kMaxLights));
  const ShadowMapSettings& s = r.shadow_map;
  if (s.technique == Technique::kVirtual) {
    validate_virtual(r);
  } else {
    require(s.size >= kMinMapSize && s.size <= kMaxMapSize, "shadow_map.size",
            "must be in [256, 8192], got " + std::to_string(s.size));
    for (size_t i = 0; i < r.products.size(); ++i)
      require(r.products[i] != Product::kVirtualPages, idx("products[", i),
              "PRODUCT_VIRTUAL_PAGES needs TECHNIQUE_VIRTUAL (shadow_map.technique)");
  }
  require(std::isfinite(s.bias_constant), "shadow_map.bias_constant", "is not finite");
  require(std::isfinite(s.bias_slope) && s.bias_slope >= 0.0f, "shadow_map.bias_slope",
          "must be finite and >= 0");
  require(std::isfinite(s.bias_world_constant) && s.bias_world_constant >= 0.0f,
          "shadow_map.bias_world_constant", "must be finite and >= 0");
  require(std::isfinite(s.bias_world_texel) && s.bias_world_texel >= 0.0f,
          "shadow_map.bias_world_texel", "must be finite and >= 0");
  // Farther back than 1000 x far the virtual camera's near and far planes merge in double.
  require(std::isfinite(s.psm.virtual_slide) && s.psm.virtual_slide >= 0.0 &&
              s.psm.virtual_slide <= 1e3 * double(r.camera.far),
          "shadow_map.psm_virtual_slide", "must be in [0, 1000 x camera.far]");
  // 0 = n_opt; else a warp between extreme (1e-6 far) and none to speak of (1e6 far).
  const double far = double(r.camera.far);
  require(std::isfinite(s.lispsm.n) &&
              (s.lispsm.n == 0 || (s.lispsm.n >= 1e-6 * far && s.lispsm.n <= 1e6 * far)),
          "shadow_map.lispsm_n", "must be 0 (n_opt) or in [1e-6, 1e6] x camera.far");
  require(std::isfinite(s.virtual_lod_bias) && std::abs(s.virtual_lod_bias) <= kMaxVirtualLodBias,
          "shadow_map.virtual_lod_bias",
          "must be finite and in [-4, 4], got " + std::to_string(s.virtual_lod_bias));
  require(s.virtual_pool_pages >= 1 && s.virtual_pool_pages <= kMaxVirtualPoolPages,
          "shadow_map.virtual_pool_pages",
          "must be in [1, 16384] pages of 128^2 float32 texels (16384 pages = 1 GiB), got " +
              std::to_string(s.virtual_pool_pages));
  for (size_t i = 0; i < r.lights.size(); ++i) {
    // Each light with its own resolved technique; the settings are shared.
    const RenderRequest one = for_light(r, i);
    const Technique t = one.shadow_map.technique;
    validate_light(one.lights[0], t, light_field(i));
    require(s.fit == MapFit::kView || technique_facts(t).fits_scene, "shadow_map.fit",
            "MAP_FIT_SCENE fits uniform maps and cubes only (PSM and LiSPSM warp the map to the "
            "camera's view, virtual maps fit their own levels), and " +
                light_field(i) + " takes another technique");
    if (technique_facts(t).warped)
      require(!needs_uniform_map(r.filter.kind), "shadow_map.technique",
              "PSM and LiSPSM cannot be combined with the pcss or pcss_csm filter: their "
              "penumbra takes similar triangles in the light's own projection, which a warped "
              "map is not (csm filters PSM and LiSPSM maps)");
    validate_filter(r.filter, one.lights[0], light_field(i));
    // A virtual point light's levels are cube faces: the filters that refuse cubes refuse them.
    if (t == Technique::kVirtual && one.lights[0].type == LightType::kPoint &&
        filter_facts(r.filter.kind).cube_refusal)
      throw InvalidArgument(filter_facts(r.filter.kind).field,
                            std::string(filter_facts(r.filter.kind).cube_refusal) +
                                ", a virtual point light's faces too (" + light_field(i) + ")");
    if (may_render_cube(one)) validate_cube(one);
    validate_csm_request(one, limits);
  }
  validate_quality(r);
  require(!r.products.empty(), "products", "is empty: ask for at least one product");
  if (uses_atlas(r)) validate_atlas(r, limits);
  if (std::find(r.products.begin(), r.products.end(), Product::kAtlasUvs) != r.products.end())
    require(uses_atlas(r), "products",
            "PRODUCT_ATLAS_UVS comes with an atlas: ask for PRODUCT_SHADOW_ATLAS (or its mips or "
            "SAT) or filter with atlas_sat or atlas_mip");
  for (size_t i = 0; i < r.products.size(); ++i)
    for (size_t k = 0; k < i; ++k)
      require(r.products[i] != r.products[k], idx("products[", i), "is listed twice");
  uint64_t bytes = output_bytes(r);
  if (bytes > limits.max_output_bytes)
    throw ResourceExhausted("products", "the requested textures need " + std::to_string(bytes) +
                                            " bytes, over the server's limit of " +
                                            std::to_string(limits.max_output_bytes));
}

}  // namespace shadow
