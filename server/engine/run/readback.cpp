#include "engine/run/readback.hpp"

#include <algorithm>

#include "engine/plan/light_request.hpp"
#include "wire/huge_pages.hpp"

namespace shadow {

Readback::Readback(cl::Runtime& runtime, HalfPackPass& half_pack, CsmPass& csm, AtlasPass& atlas,
                   VirtualPagesPass& virtual_pages, const cl::Buffer& empty_map)
    : runtime_(runtime),
      half_pack_(half_pack),
      csm_(csm),
      atlas_(atlas),
      virtual_pages_(virtual_pages),
      empty_map_(empty_map) {}

void Readback::read_floats(const cl::Buffer& src, size_t first, size_t count, Texture& t, size_t at,
                           Timeline& timeline) {
  if (t.format == PixelFormat::kFloat16) {
    const cl::Buffer& packed = half_pack_.run(src, uint32_t(first), uint32_t(count), timeline);
    timeline.add("readback", runtime_.read(packed, t.data16.data() + at, count * sizeof(uint16_t)));
  } else {
    timeline.add("readback", runtime_.read(src, t.data.data() + at, count * sizeof(float),
                                           first * sizeof(float)));
  }
}

Texture Readback::float_texture(std::string name, Product kind, uint32_t w, uint32_t h,
                                uint32_t channels, uint32_t faces) const {
  Texture t;
  t.name = std::move(name);
  t.kind = kind;
  t.width = w;
  t.height = h;
  t.channels = channels;
  t.format = half_ ? PixelFormat::kFloat16 : PixelFormat::kFloat32;
  const size_t n = size_t{w} * h * channels * faces;
  half_ ? resize_on_huge_pages(t.data16, n) : resize_on_huge_pages(t.data, n);
  return t;
}

Texture Readback::read_texture(const cl::Buffer& buffer, std::string name, Product kind, uint32_t w,
                               uint32_t h, uint32_t channels, Timeline& timeline) {
  Texture t = float_texture(std::move(name), kind, w, h, channels);
  read_floats(buffer, 0, size_t{w} * h * channels, t, 0, timeline);
  return t;
}

std::vector<Texture> Readback::read_mips(const DeviceTexture& src, const MipChain& chain,
                                         const std::string& name, Product kind,
                                         Timeline& timeline) {
  std::vector<Texture> out;
  out.push_back(read_texture(*src.buffer, name + "_mip0", kind, src.width, src.height, src.channels,
                             timeline));
  for (size_t i = 0; i < chain.levels.size(); ++i) {
    const MipLevel& l = chain.levels[i];
    Texture t = float_texture(name + "_mip" + std::to_string(i + 1), kind, l.width, l.height,
                              chain.channels);
    read_floats(chain.storage, l.offset, size_t{l.width} * l.height * chain.channels, t, 0,
                timeline);
    out.push_back(std::move(t));
  }
  return out;
}

Texture Readback::read_sat(const SummedAreaTable& table, const std::string& name, Product kind,
                           Timeline& timeline) {
  Texture t;
  t.name = name + "_sat";
  t.kind = kind;
  t.width = table.width;
  t.height = table.height;
  t.channels = table.channels;
  t.format = PixelFormat::kFloat64;
  resize_on_huge_pages(t.data64, size_t{table.width} * table.height * table.channels);
  timeline.add("readback", runtime_.read(table.sums, t.data64.data(), t.byte_size()));
  return t;
}

Texture Readback::read_cube(const std::vector<LightMap>& maps, uint32_t size, std::string name,
                            Timeline& timeline) {
  const auto rendered = std::count_if(maps.begin(), maps.end(),
                                      [&](const LightMap& m) { return m.depth != &empty_map_; });
  Texture t =
      float_texture(std::move(name), Product::kShadowMap, size, size, 1, uint32_t(rendered));
  const size_t face_floats = size_t{size} * size;
  for (const LightMap& m : maps) {
    if (m.depth == &empty_map_) continue;  // the faces not rendered
    int k = 0;
    while (!(m.setup.faces.owned & (1u << k))) ++k;
    read_floats(*m.depth, 0, face_floats, t, t.cube_faces.size() * face_floats, timeline);
    t.cube_faces.push_back(
        {kCubeFaceNames[k], glm::mat4(m.setup.world_to_ndc), glm::mat4(m.setup.view)});
  }
  t.faces = uint32_t(t.cube_faces.size());
  return t;
}

// The pool (with the last light: every light's pages drawn), then the light's tables, windows
// and pixels' levels (docs/api.md, "Virtual shadow maps").
std::vector<Texture> Readback::read_virtual_pages(uint32_t light_index, bool last_light,
                                                  const std::string& sfx, const LightPlan& light,
                                                  const ViewSetup& camera, uint32_t w, uint32_t h,
                                                  Timeline& timeline) {
  std::vector<Texture> ts;
  const Product p = Product::kVirtualPages;
  if (last_light)
    ts.push_back(read_texture(virtual_pages_.pool_image(timeline), "virtual_pool", p, kPageTexels,
                              kPageTexels * virtual_pages_.pool_pages(), 1, timeline));
  const VirtualMap& map = virtual_pages_.map(light_index);
  const uint32_t pages = map.pages(), levels = uint32_t(map.layout.levels.size());
  ts.push_back(read_texture(virtual_pages_.table_image(light_index, timeline),
                            "virtual_table" + sfx, p, pages, pages * levels, 1, timeline));
  const VirtualLevels& layout = map.layout;
  Texture windows = float_texture("virtual_windows" + sfx, p, 4, levels, 1);
  for (uint32_t i = 0; i < levels; ++i) {
    const ClipmapLevel& l = layout.levels[i];
    const float row[4] = {float(l.level), float(l.first_page.x), float(l.first_page.y),
                          float(layout.extent(i))};
    std::copy(row, row + 4, windows.data.begin() + 4 * i);
  }
  ts.push_back(std::move(windows));
  if (layout.perspective()) {  // each face's world -> mip 0's texture NDC, column-major
    Texture faces = float_texture("virtual_faces" + sfx, p, 16, uint32_t(layout.faces), 1);
    for (int f = 0; f < layout.faces; ++f) {
      const glm::mat4 m(layout.face_ndc[f]);
      std::copy(&m[0][0], &m[0][0] + 16, faces.data.begin() + 16 * f);
    }
    ts.push_back(std::move(faces));
  }
  for (Texture& t : ts) {  // the light's space: the first level's window and the light's view
    t.world_to_ndc = glm::mat4(light.light.world_to_ndc);
    t.world_to_camera = glm::mat4(light.light.view);
  }
  ts.push_back(read_texture(virtual_pages_.level_image(light_index, w * h, timeline),
                            "virtual_level" + sfx, p, w, h, 1, timeline));
  ts.back().world_to_ndc = glm::mat4(camera.world_to_ndc);
  ts.back().world_to_camera = glm::mat4(camera.view);
  return ts;
}

std::vector<Texture> Readback::products(const RenderRequest& req, uint32_t light_index,
                                        bool last_light, const std::string& sfx,
                                        const ViewSetup& camera, const SharedResources& shared_view,
                                        const LightResources& light_res, const SceneBuffers& scene,
                                        const std::function<DeviceTexture(Resource)>& source,
                                        Timeline& timeline) {
  const LightPlan& light = light_res.fit;
  const std::vector<LightMap>& maps = light_res.maps;
  const cl::Buffer* vis = light_res.visibility;
  const cl::Buffer* density = light_res.density;
  const GBuffer* view = shared_view.view;
  const std::map<Resource, const MipChain*>& chains = light_res.chains;
  const std::map<Resource, const SummedAreaTable*>& tables = light_res.tables;
  const RasterOutput* single_map = light_res.single_map;
  const CsmBasis* csm_basis = light_res.csm_basis;
  const cl::Buffer* atlas_visibility = light_res.atlas;
  const uint32_t size = req.shadow_map.size, w = req.camera.width, h = req.camera.height;
  const bool shared = light_index == 0;
  std::vector<Texture> out;
  for (Product p : req.products) {
    if (!per_light(p) && !shared) continue;
    std::vector<Texture> ts;
    switch (p) {
      case Product::kShadowMap:
        ts.push_back(light.cube ? read_cube(maps, size, "shadowmap_cube" + sfx, timeline)
                                : read_texture(single_map->depth, "shadowmap" + sfx, p, size, size,
                                               1, timeline));
        break;
      case Product::kShadowMapMips:
        ts = read_mips(source(Resource::kLightMaps), *chains.at(Resource::kMapMips),
                       "shadowmap" + sfx, p, timeline);
        break;
      case Product::kShadowMapSat:
        ts.push_back(read_sat(*tables.at(Resource::kMapSat), "shadowmap" + sfx, p, timeline));
        break;
      case Product::kVisibility:
        ts.push_back(read_texture(*vis, "visibility" + sfx, p, w, h, 1, timeline));
        break;
      case Product::kVisibilityMips:
        ts = read_mips(source(Resource::kVisibility), *chains.at(Resource::kVisibilityMips),
                       "visibility" + sfx, p, timeline);
        break;
      case Product::kVisibilitySat:
        ts.push_back(
            read_sat(*tables.at(Resource::kVisibilitySat), "visibility" + sfx, p, timeline));
        break;
      case Product::kTexelDensity:
        ts.push_back(read_texture(*density, "texel_density" + sfx, p, w, h, 1, timeline));
        break;
      case Product::kPosition:
        ts.push_back(read_texture(view->position, "position", p, w, h, 3, timeline));
        break;
      case Product::kCsmBasis: {
        ts.push_back(read_texture(csm_.pack(*csm_basis, timeline), "csm_basis" + sfx, p, size, size,
                                  csm_basis->channels(), timeline));
        ts.back().channel_names = csm_channel_names(csm_basis->terms, csm_basis->blocker);
        ts.back().depth_mapping = csm_depth_mapping_text(csm_basis->depth);
        ts.back().csm_terms = csm_basis->terms;
        ts.back().csm_storage = req.filter.csm.storage;
        break;
      }
      case Product::kBlockerDepth:
        ts.push_back(read_texture(csm_.blocker(), "blocker_depth" + sfx, p, w, h, 1, timeline));
        ts.back().depth_mapping = csm_depth_mapping_text(csm_basis->depth);
        break;
      case Product::kShadowAtlas:  // in UV space: no matrix places it
        ts.push_back(read_texture(*atlas_visibility, "shadow_atlas" + sfx, p, atlas_.width(),
                                  atlas_.height(), 1, timeline));
        break;
      case Product::kShadowAtlasMips:
        ts = read_mips(source(Resource::kAtlas), *chains.at(Resource::kAtlasMips),
                       "shadow_atlas" + sfx, p, timeline);
        break;
      case Product::kAtlasUvs:  // the meshes the engine laid out, one texture each
        for (uint32_t m : req.generated_layouts) {
          const MeshRange& range = scene.meshes()[m];
          ts.push_back(read_texture(atlas_.corner_uvs(scene, range, timeline),
                                    "atlas_uvs_mesh" + std::to_string(m), p, 3,
                                    range.triangle_count, 2, timeline));
          ts.back().channel_names = {"u", "v"};
          ts.back().mesh = m;
        }
        break;
      case Product::kShadowAtlasSat:
        ts.push_back(read_sat(*tables.at(Resource::kAtlasSat), "shadow_atlas" + sfx, p, timeline));
        ts.back().channel_names = {"visibility", "coverage"};
        break;
      case Product::kVirtualPages:
        ts = read_virtual_pages(light_index, last_light, sfx, light, camera, w, h, timeline);
        break;
    }
    const bool light_space = p == Product::kShadowMap || p == Product::kShadowMapMips ||
                             p == Product::kShadowMapSat || p == Product::kCsmBasis;
    const bool in_uv_space = p == Product::kShadowAtlas || p == Product::kShadowAtlasMips ||
                             p == Product::kShadowAtlasSat;
    const bool placed = p == Product::kVirtualPages;  // read_virtual_pages sets its matrices
    for (Texture& t : ts) {
      // No matrix places the atlas: its tiles do (in level-0 texels, so on level 0 only).
      if (in_uv_space && &t == &ts.front()) t.atlas_tiles = atlas_.tiles();
      // A cube's faces carry their own matrices; mip levels keep the source's (NDC x, y run
      // 0..1 across every level).
      if (t.cube_faces.empty() && t.faces != 0 && !in_uv_space && p != Product::kAtlasUvs &&
          !placed) {
        t.world_to_ndc = glm::mat4(light_space ? light.light.world_to_ndc : camera.world_to_ndc);
        t.world_to_camera = glm::mat4(light_space ? light.light.view : camera.view);
      }
      out.push_back(std::move(t));
    }
  }
  return out;
}

void order_products(const RenderRequest& req, std::vector<Texture>& textures) {
  const auto rank = [&](const Texture& t) {
    return std::find(req.products.begin(), req.products.end(), t.kind) - req.products.begin();
  };
  std::stable_sort(textures.begin(), textures.end(),
                   [&](const Texture& a, const Texture& b) { return rank(a) < rank(b); });
}

}  // namespace shadow
