#include "engine/run/warm_up.hpp"

#include <sys/resource.h>

#include <cstdlib>
#include <filesystem>
#include <memory>

#include "engine/choose/price.hpp"

namespace shadow {
namespace {

constexpr int kDeviceThreadNice = 10;

// A one-triangle scene that runs every pass once.
RenderRequest warm_up_request() {
  auto scene = std::make_shared<Scene>();
  Mesh m;
  m.positions = {-1,    0,    -1,    1,    0,    -1,    0, 0,    1,
                 -0.2f, 0.5f, -0.2f, 0.2f, 0.5f, -0.2f, 0, 0.5f, 0.2f};
  m.indices = {0, 1, 2, 3, 4, 5};
  m.uvs = {0, 0, 0.5f, 0, 0, 0.5f, 0.6f, 0.6f, 1, 0.6f, 0.6f, 1};  // for the atlas
  scene->meshes.push_back(m);
  scene->instances.push_back(Instance{});
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 3, 3};
  r.camera.width = 64;
  r.camera.height = 64;
  r.shadow_map.size = 256;
  r.products = {Product::kShadowMap,      Product::kVisibility,    Product::kPosition,
                Product::kTexelDensity,   Product::kShadowMapMips, Product::kShadowMapSat,
                Product::kVisibilityMips, Product::kVisibilitySat};
  return r;
}

// The warm-up asks for every product; the client's output limit is not for it.
void render(Workspace& ws, const RenderRequest& request) {
  ws.render(request, plan_unlimited(request));
}

}  // namespace

void warm_up(Workspace& ws) {
  ws.create_kernels();
  const RenderRequest warm = warm_up_request();
  render(ws, warm);
  // Each filter's visibility kernels once more (launch-time compiles); blur with a class.
  RenderRequest filtered = warm;
  filtered.products = {Product::kVisibility};
  filtered.lights[0].size = 1.0f;
  auto classed = std::make_shared<Scene>(*warm.scene);
  classed->instances[0].receiver_class = 0;
  filtered.scene = classed;
  for (FilterKind kind :
       {FilterKind::kPcf2x2, FilterKind::kPoisson, FilterKind::kPcss, FilterKind::kBlur}) {
    filtered.filter.kind = kind;
    render(ws, filtered);
  }
  // CSM in both storages: the basis, its mips, the lookups and the packed basis.
  RenderRequest csm = filtered;
  csm.filter.kind = FilterKind::kPcssCsm;
  csm.filter.csm.terms = 2;
  csm.products = {Product::kVisibility, Product::kBlockerDepth, Product::kCsmBasis};
  for (CsmStorage storage : {CsmStorage::kFloat32, CsmStorage::kFloat16}) {
    csm.filter.csm.storage = storage;
    render(ws, csm);
  }
  // A cube around a point light: the light-distance pass and the per-face launches.
  RenderRequest cube = warm;
  cube.lights[0].type = LightType::kPoint;
  cube.lights[0].position = {0.0f, 2.0f, 0.0f};
  cube.shadow_map.technique = Technique::kCube;
  cube.products = {Product::kShadowMap, Product::kVisibility, Product::kTexelDensity};
  render(ws, cube);
  // PSM with the measured near plane (depth_range.reduce) and the world-space caster bias.
  RenderRequest psm = warm;
  psm.products = {Product::kShadowMap};
  psm.shadow_map.technique = Technique::kPsm;
  psm.shadow_map.bias_world_texel = 1.0f;
  render(ws, psm);
  // A shadow atlas of the one-triangle scene.
  RenderRequest atlas = warm;
  atlas.products = {Product::kShadowAtlas};
  atlas.atlas.tile = 16;
  render(ws, atlas);
}

std::set<pid_t> thread_ids() {
  std::set<pid_t> ids;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/task", ec))
    ids.insert(pid_t(std::atoi(entry.path().filename().c_str())));
  return ids;
}

std::set<pid_t> lower_device_threads(const std::set<pid_t>& before) {
  std::set<pid_t> device;
  for (pid_t id : thread_ids())
    if (!before.count(id)) {
      setpriority(PRIO_PROCESS, id_t(id), kDeviceThreadNice);
      device.insert(id);
    }
  return device;
}

}  // namespace shadow
