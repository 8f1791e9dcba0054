#include "atlas_standard.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>

#include "oracle/area_light.hpp"
#include "oracle/metrics.hpp"
#include "oracle/standard_scenes.hpp"

namespace shadow::bench {
namespace {

const Texture* find(const RenderResult& r, Product kind, const std::string& name = "") {
  for (const Texture& t : r.textures)
    if (t.kind == kind && (name.empty() || t.name == name)) return &t;
  return nullptr;
}

// Per camera pixel: whether an empty texel of `atlas` (baked without a gutter) lies within
// `texels` of the pixel's point in its instance's tile: near a chart's border. The point's UV
// from the oracle's hit (triangle, barycentrics in double) and its corners' UVs: the mesh's own,
// or the layout the server generated (PRODUCT_ATLAS_UVS, which keeps the triangles' order).
std::vector<uint8_t> near_chart_borders(const Scene& scene, const oracle::CameraHits& hits,
                                        const RenderResult& baked, int texels) {
  const Texture& atlas = *find(baked, Product::kShadowAtlas);
  std::vector<uint8_t> out(hits.size(), 0);
  for (size_t p = 0; p < hits.size(); ++p) {
    if (!hits.hit(p)) continue;
    const uint32_t instance = uint32_t(hits.instance[p]);
    const auto tile = std::find_if(atlas.atlas_tiles.begin(), atlas.atlas_tiles.end(),
                                   [&](const AtlasTile& t) { return t.instance == instance; });
    if (tile == atlas.atlas_tiles.end()) continue;  // receives no shadow: no tile
    const Instance& inst = scene.instances[instance];
    const Mesh& m = scene.meshes[inst.mesh];
    const Texture* generated =
        find(baked, Product::kAtlasUvs, "atlas_uvs_mesh" + std::to_string(inst.mesh));
    const size_t tri = size_t(hits.triangle[p]);
    const glm::dmat4 to_world(inst.transform);
    glm::dvec3 v[3];
    glm::dvec2 uv[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = m.indices[3 * tri + k];
      v[k] = glm::dvec3(to_world * glm::dvec4(m.positions[3 * i], m.positions[3 * i + 1],
                                              m.positions[3 * i + 2], 1.0));
      uv[k] = generated ? glm::dvec2(generated->data[(3 * tri + k) * 2],
                                     generated->data[(3 * tri + k) * 2 + 1])
                        : glm::dvec2(m.uvs[2 * i], m.uvs[2 * i + 1]);
    }
    const glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]), x = hits.position[p] - v[0];
    const double b = glm::dot(glm::cross(x, v[2] - v[0]), n) / glm::dot(n, n);
    const double c = glm::dot(glm::cross(v[1] - v[0], x), n) / glm::dot(n, n);
    const glm::dvec2 t = uv[0] + b * (uv[1] - uv[0]) + c * (uv[2] - uv[0]);
    const int qx = int(tile->x + t.x * tile->size), qy = int(tile->y + t.y * tile->size);
    const int lo_x = int(tile->x), lo_y = int(tile->y), hi = int(tile->size) - 1;
    bool near = false;
    for (int j = std::max(qy - texels, lo_y); j <= std::min(qy + texels, lo_y + hi) && !near; ++j)
      for (int i = std::max(qx - texels, lo_x); i <= std::min(qx + texels, lo_x + hi); ++i)
        near |= std::isnan(atlas.data[size_t(j) * atlas.width + i]);
    out[p] = near;
  }
  return out;
}

// Device ms of the camera's passes (frame) and of the rest (bake), scene upload excluded.
std::pair<double, double> frame_and_bake(const RenderResult& r) {
  double frame = 0, bake = 0;
  for (const PassTiming& t : r.timings) {
    if (t.pass.starts_with("scene") || t.pass.starts_with("readback")) continue;
    (t.pass.starts_with("gbuffer") || t.pass.starts_with("visibility.") ? frame : bake) +=
        t.device_ms;
  }
  return {frame, bake};
}

}  // namespace

void standard_scenes_table(Engine& engine, uint32_t map, uint32_t tile) {
  std::printf(
      "\nstandard scenes, 640x360, %u map fitted to the scene, %u-texel tiles, every receiving "
      "mesh laid out by the server (generate_uvs); one render each (frame: G-buffer and "
      "visibility, right after "
      "the bake)\n\n| scene / view | technique | frame ms | bake ms | mean err | penumbra err "
      "| near chart borders | elsewhere |\n| --- | --- | --- | --- | --- | --- | --- | --- |\n",
      map, tile);
  const std::pair<const char*, FilterKind> kinds[] = {{"pcss", FilterKind::kPcss},
                                                      {"atlas_sat", FilterKind::kAtlasSat},
                                                      {"atlas_mip", FilterKind::kAtlasMip}};
  for (const scenes::StandardScene& s : scenes::standard_scenes()) {
    const oracle::RayOracle rays(*s.scene);
    for (const scenes::View& v : s.views) {
      if (v.light.type == LightType::kPoint || v.light.size <= 0) continue;
      const std::string name = s.name + " / " + v.name;
      RenderRequest r;
      r.scene = s.scene;
      r.camera = v.camera;
      r.lights = {v.light};
      r.shadow_map.size = map;
      r.shadow_map.fit = MapFit::kScene;
      r.atlas.tile = tile;
      r.atlas.generate_uvs = true;  // the scenes' own UVs tile their textures
      RenderRequest borders = r;
      borders.products = {Product::kShadowAtlas, Product::kAtlasUvs};
      borders.atlas.gutter = 0;
      RenderResult baked;
      try {
        baked = engine.render(borders);
      } catch (const std::exception& e) {
        std::printf("| %s | refused: %s | | | | | | |\n", name.c_str(), e.what());
        continue;
      }
      const std::vector<uint8_t> near =
          near_chart_borders(*s.scene, rays.cast_camera(r.camera), baked, 4);
      const oracle::AreaVisibility truth =
          oracle::camera_area_visibility(rays, r.camera, r.lights[0]);
      r.products = {Product::kVisibility};
      for (const auto& [technique, kind] : kinds) {
        r.filter.kind = kind;
        const RenderResult got = engine.render(r);
        const std::vector<float>& vis = got.textures.at(0).data;
        const oracle::VisibilityError e = oracle::compare_visibility(vis, truth.visibility);
        size_t at = 0, away = 0;
        const double at_err = mean_error(vis, truth.visibility, near, 1, at);
        const double away_err = mean_error(vis, truth.visibility, near, 0, away);
        const auto [frame, bake] = frame_and_bake(got);
        std::printf("| %s | %s | %.1f | %.1f | %.4f | %.4f | %.4f (%zu px) | %.4f |\n",
                    name.c_str(), technique, frame, bake, e.mae, e.penumbra_mae, at_err, at,
                    away_err);
      }
    }
  }
}

}  // namespace shadow::bench
