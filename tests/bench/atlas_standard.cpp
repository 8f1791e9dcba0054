#include "atlas_standard.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>

#include "oracle/area_light.hpp"
#include "oracle/metrics.hpp"
#include "oracle/standard_scenes.hpp"
#include "sphere_field.hpp"

namespace shadow::bench {
namespace {

const Texture* find(const RenderResult& r, Product kind, const std::string& name = "") {
  for (const Texture& t : r.textures)
    if (t.kind == kind && (name.empty() || t.name == name)) return &t;
  return nullptr;
}

// Per camera pixel: the continuous atlas texel (x, y) of its point in its instance's tile, NaN
// where it has none. From the oracle's hit (triangle, barycentrics in double) and its corners'
// UVs: the mesh's own, or the layout the server generated (PRODUCT_ATLAS_UVS, which keeps the
// triangles' order).
std::vector<glm::dvec2> atlas_texels(const Scene& scene, const oracle::CameraHits& hits,
                                     const RenderResult& baked) {
  const Texture& atlas = *find(baked, Product::kShadowAtlas);
  std::vector<glm::dvec2> out(hits.size(), glm::dvec2(NAN));
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
    out[p] = glm::dvec2(tile->x, tile->y) + glm::clamp(t, 0.0, 1.0 - 1e-9) * double(tile->size);
  }
  return out;
}

// Per camera pixel: whether an empty texel of `atlas` (baked without a gutter) lies within
// `texels` of the pixel's atlas texel in its tile: near a chart's border.
std::vector<uint8_t> near_chart_borders(const std::vector<glm::dvec2>& q, const Texture& atlas,
                                        int texels) {
  std::vector<uint8_t> out(q.size(), 0);
  for (size_t p = 0; p < q.size(); ++p) {
    if (std::isnan(q[p].x)) continue;
    const int qx = int(q[p].x), qy = int(q[p].y);
    const auto tile =
        std::find_if(atlas.atlas_tiles.begin(), atlas.atlas_tiles.end(), [&](const AtlasTile& t) {
          return qx >= int(t.x) && qx < int(t.x + t.size) && qy >= int(t.y) &&
                 qy < int(t.y + t.size);
        });
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

struct Figures {
  double frame = 0, bake = 0, mae = 0, penumbra = 0, lit = 0, near = 0, away = 0;
  int views = 0;
  void add(const Figures& f) {
    frame += f.frame, bake += f.bake, mae += f.mae, penumbra += f.penumbra, lit += f.lit,
        near += f.near, away += f.away, ++views;
  }
};

void print_row(const std::string& name, const char* technique, const Figures& f, double n) {
  std::printf("| %s | %s | %.1f | %.0f | %.4f | %.3f | %.4f | %.4f | %.4f |\n", name.c_str(),
              technique, f.frame / n, f.bake / n, f.mae / n, f.penumbra / n, f.lit / n, f.near / n,
              f.away / n);
}

}  // namespace

void standard_scenes_table(Engine& engine, const StandardOptions& o) {
  std::printf(
      "\nstandard scenes, 640x360, %u map fitted to the scene, %u-texel tiles (0: sized from the "
      "world, AtlasSettings::texel_world_size %g, 0: the map's footprint), every receiving "
      "mesh laid out by the server (generate_uvs); one render each (frame: G-buffer and "
      "visibility, right after the bake); lit: mean |error| over the pixels the oracle sees fully "
      "lit\n\n| scene / view | technique | frame ms | bake ms | mean err | penumbra err | lit err "
      "| near chart borders | elsewhere |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- "
      "|\n",
      o.map, o.tile, o.density);
  const std::pair<const char*, FilterKind> kinds[] = {{"hard", FilterKind::kHard},
                                                      {"pcss", FilterKind::kPcss},
                                                      {"atlas_sat", FilterKind::kAtlasSat},
                                                      {"atlas_mip", FilterKind::kAtlasMip}};
  if (!o.images.empty()) std::filesystem::create_directories(o.images);
  for (const scenes::StandardScene& s : scenes::standard_scenes()) {
    if (!o.scenes.empty() && std::find(o.scenes.begin(), o.scenes.end(), s.name) == o.scenes.end())
      continue;
    const oracle::RayOracle rays(*s.scene);
    std::map<std::string, Figures> means;
    for (const scenes::View& v : s.views) {
      if (v.light.type == LightType::kPoint || v.light.size <= 0) continue;
      const std::string name = s.name + " / " + v.name;
      RenderRequest r;
      r.scene = s.scene;
      r.camera = v.camera;
      r.lights = {v.light};
      r.shadow_map.size = o.map;
      r.shadow_map.fit = MapFit::kScene;
      r.atlas.tile = o.tile;
      r.atlas.texel_world_size = o.tile ? 0.0 : o.density;
      r.atlas.generate_uvs = true;  // the scenes' own UVs tile their textures
      RenderRequest borders = r;
      borders.products = {Product::kShadowAtlas, Product::kAtlasUvs};
      borders.atlas.gutter = 0;
      RenderResult baked;
      try {
        baked = engine.render(borders);
      } catch (const std::exception& e) {
        std::printf("| %s | refused: %s | | | | | | | |\n", name.c_str(), e.what());
        continue;
      }
      const std::vector<glm::dvec2> q = atlas_texels(*s.scene, rays.cast_camera(r.camera), baked);
      const std::vector<uint8_t> near =
          near_chart_borders(q, *find(baked, Product::kShadowAtlas), 4);
      const oracle::AreaVisibility truth =
          oracle::camera_area_visibility(rays, r.camera, r.lights[0]);
      std::vector<uint8_t> lit(truth.visibility.size());
      for (size_t p = 0; p < lit.size(); ++p) lit[p] = truth.visibility[p] == 1.0f;
      if (!o.images.empty()) {
        write_floats(o.images, s.name + "_" + v.name + "_oracle", truth.visibility);
        std::vector<float> qx(q.size()), qy(q.size());
        for (size_t p = 0; p < q.size(); ++p) qx[p] = float(q[p].x), qy[p] = float(q[p].y);
        write_floats(o.images, s.name + "_" + v.name + "_qx", qx);
        write_floats(o.images, s.name + "_" + v.name + "_qy", qy);
        const Texture& bare = *find(baked, Product::kShadowAtlas);
        write_floats(o.images, s.name + "_" + v.name + "_atlas_bare", bare.data);
      }
      {
        const Texture& bare = *find(baked, Product::kShadowAtlas);
        uint32_t lo = UINT32_MAX, hi = 0;
        for (const AtlasTile& t : bare.atlas_tiles)
          lo = std::min(lo, t.size), hi = std::max(hi, t.size);
        std::printf("(%s: atlas %ux%u, %zu tiles of %u..%u texels)\n", name.c_str(), bare.width,
                    bare.height, bare.atlas_tiles.size(), lo, hi);
      }
      for (const auto& [technique, kind] : kinds) {
        r.filter.kind = kind;
        r.products = {Product::kVisibility};
        if (kind == FilterKind::kHard && !o.images.empty())
          r.products.push_back(Product::kShadowAtlas);
        const RenderResult got = engine.render(r);
        const std::vector<float>& vis = got.textures.at(0).data;
        const oracle::VisibilityError e = oracle::compare_visibility(vis, truth.visibility);
        size_t count = 0;
        Figures f;
        f.mae = e.mae, f.penumbra = e.penumbra_mae;
        f.lit = mean_error(vis, truth.visibility, lit, 1, count);
        f.near = mean_error(vis, truth.visibility, near, 1, count);
        f.away = mean_error(vis, truth.visibility, near, 0, count);
        std::tie(f.frame, f.bake) = frame_and_bake(got);
        print_row(name, technique, f, 1);
        means[technique].add(f);
        if (!o.images.empty()) {
          write_floats(o.images, s.name + "_" + v.name + "_" + technique, vis);
          if (kind == FilterKind::kHard)
            write_floats(o.images, s.name + "_" + v.name + "_atlas",
                         find(got, Product::kShadowAtlas)->data);
        }
      }
      std::fflush(stdout);
    }
    for (const auto& [technique, kind] : kinds)
      if (means[technique].views)
        print_row(s.name + " (mean of " + std::to_string(means[technique].views) + ")", technique,
                  means[technique], means[technique].views);
  }
}

}  // namespace shadow::bench
