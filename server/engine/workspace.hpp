// One request's share of the device: its own in-order queue (cl::Runtime), its own kernel
// objects, and the passes with the scratch buffers they grow. The engine keeps a few and hands
// each running request one, so concurrent requests share only the compiled programs and the
// device-memory budget.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine/cl/program_cache.hpp"
#include "engine/cube_fit.hpp"
#include "engine/passes/blur.hpp"
#include "engine/passes/depth_range.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/light_distance.hpp"
#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/pcf.hpp"
#include "engine/passes/pcss.hpp"
#include "engine/passes/rasterizer.hpp"
#include "engine/passes/shadow_test.hpp"
#include "engine/passes/summed_area.hpp"
#include "engine/passes/texel_density.hpp"
#include "engine/types.hpp"

namespace shadow {

// What one render may use and when it must stop.
struct RenderControl {
  uint64_t max_output_bytes = UINT64_MAX;  // the client's limit; the start-up warm-up has none
  bool profile = true;                     // per-pass device timings in the result
  // Asked before every launch and read; once it says yes the render throws Cancelled.
  std::function<bool()> cancelled;
};

class Workspace {
 public:
  Workspace(std::shared_ptr<const cl::Device> device, cl::ProgramCache& programs);
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;

  // Validates and renders one request. The queue is drained before any exception leaves.
  RenderResult render(const RenderRequest& request, const RenderControl& control = {});

  // Creates every kernel object of every pass (the programs build once, engine-wide).
  void create_kernels();

 private:
  // One map as the per-pixel passes take it: its set-up (which owns some or all pixels) and its
  // depth. A cube gives one per rendered face and one for the faces not rendered.
  struct LightMap {
    ViewSetup setup;
    const cl::Buffer* depth;
  };
  // How the light is drawn: a cube's faces (rendered by plan_light itself, or only fitted
  // without `need_maps`), or the single map's set-up (rasterized by render).
  struct LightPlan {
    bool cube = false;
    ViewSetup light;             // the single map
    std::vector<LightMap> maps;  // the cube's maps, one per rendered face and one for the rest
    LightFitReport report;
  };

  RenderResult render_validated(const RenderRequest& request, bool profile);
  // `view`: the camera view when PSM measures its near plane from it, else null.
  LightPlan plan_light(const RenderRequest& req, const SceneBuffers& buffers, const GBuffer* view,
                       bool need_maps, Timeline& timeline);
  // Renders the cube faces a point light needs (or none) and says why in `report`.
  std::vector<LightMap> render_cube(const RenderRequest& req, const SceneBuffers& buffers,
                                    const std::vector<InstanceBounds>& bounds, bool need_maps,
                                    LightFitReport& report, Timeline& timeline);
  // Renders the faces a fit chose (only their matrices without `need_maps`), reports all six,
  // and adds one map that decides the pixels of the faces not rendered (all lit).
  std::vector<LightMap> render_faces(const RenderRequest& req, const SceneBuffers& buffers,
                                     const std::array<CubeFaceFit, 6>& faces, bool need_maps,
                                     LightFitReport& report, Timeline& timeline);

  Texture read_texture(const cl::Buffer& buffer, std::string name, Product kind, uint32_t w,
                       uint32_t h, uint32_t channels, Timeline& timeline);
  const cl::Buffer& visibility(const RenderRequest& req, const GBuffer& view, uint32_t pixels,
                               const cl::Buffer& map, const ViewSetup& light, Timeline& timeline);
  // Level 0 (a copy of `src`) .. the 1x1 level, one texture each, named "<name>_mip<i>".
  std::vector<Texture> read_mips(const DeviceTexture& src, const std::string& name, Product kind,
                                 Timeline& timeline);
  Texture read_sat(const DeviceTexture& src, const std::string& name, Product kind,
                   Timeline& timeline);
  // The rendered faces of a cube as one texture ("shadowmap_cube", faces in +x..-z order).
  Texture read_cube(const std::vector<LightMap>& maps, uint32_t size, Timeline& timeline);

  cl::Runtime runtime;
  cl::Kernels kernels;
  Rasterizer rasterizer;
  GBufferPass gbuffer;
  ShadowTestPass shadow_test;
  TexelDensityPass texel_density;
  PcfPass pcf;
  PcssPass pcss;
  MipPyramidPass mips;
  SummedAreaPass sat;
  BlurPass blur;
  LightDistancePass light_distance;
  DepthRangePass depth_range;
  // One float, bound for the cube faces not rendered: every pixel is off such a map (w = 0),
  // so no kernel reads it (PCF skips the taps of strips with nothing to filter).
  cl::Buffer empty_map;
  const cl::Buffer* blurred = nullptr;  // this request's blurred class planes, if any
};

}  // namespace shadow
