// The products' reads: a light's textures from the device buffers its steps wrote, in the order
// the request asks for them, each with the matrices that place it, as float32 or as halves packed
// on the device (PixelFormat::kFloat16).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "engine/cl/runtime.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/passes/atlas.hpp"
#include "engine/passes/csm.hpp"
#include "engine/passes/device_texture.hpp"
#include "engine/passes/half_pack.hpp"
#include "engine/run/step_resources.hpp"
#include "wire/types.hpp"

namespace shadow {

class Readback {
 public:
  // `empty_map`: the buffer of the cube faces not rendered, which have no texture.
  Readback(cl::Runtime& runtime, HalfPackPass& half_pack, CsmPass& csm, AtlasPass& atlas,
           VirtualPagesPass& virtual_pages, const cl::Buffer& empty_map);

  // The request's output format: halves or floats from here on.
  void set_format(PixelFormat format) { half_ = format == PixelFormat::kFloat16; }

  // Light `light_index`'s products in the order `req` asks for them, with its matrices, named
  // with the light's suffix `sfx`; with the first light, also the products that need no light,
  // and with the last, the virtual pool its lights share. `source`: the texture a mip chain or
  // SAT filtered.
  std::vector<Texture> products(const RenderRequest& req, uint32_t light_index, bool last_light,
                                const std::string& sfx, const ViewSetup& camera,
                                const SharedResources& view, const LightResources& light,
                                const SceneBuffers& scene,
                                const std::function<DeviceTexture(Resource)>& source,
                                Timeline& timeline);

  // A float texture of the output format, sized, with nothing read yet.
  Texture float_texture(std::string name, Product kind, uint32_t w, uint32_t h, uint32_t channels,
                        uint32_t faces = 1) const;

 private:
  // `count` floats of `src` from float `first` on, into `t`'s values from `at` on: as they are,
  // or converted to halves on the device first.
  void read_floats(const cl::Buffer& src, size_t first, size_t count, Texture& t, size_t at,
                   Timeline& timeline);
  Texture read_texture(const cl::Buffer& buffer, std::string name, Product kind, uint32_t w,
                       uint32_t h, uint32_t channels, Timeline& timeline);
  // Level 0 (a copy of `src`) .. the 1x1 level, one texture each, named "<name>_mip<i>".
  std::vector<Texture> read_mips(const DeviceTexture& src, const MipChain& chain,
                                 const std::string& name, Product kind, Timeline& timeline);
  Texture read_sat(const SummedAreaTable& table, const std::string& name, Product kind,
                   Timeline& timeline);
  std::vector<Texture> read_virtual_pages(uint32_t light_index, bool last_light,
                                          const std::string& sfx, const LightPlan& light,
                                          const ViewSetup& camera, uint32_t w, uint32_t h,
                                          Timeline& timeline);
  // The rendered faces of a cube as one texture (`name`, faces in +x..-z order).
  Texture read_cube(const std::vector<LightMap>& maps, uint32_t size, std::string name,
                    Timeline& timeline);

  cl::Runtime& runtime_;
  HalfPackPass& half_pack_;
  CsmPass& csm_;
  AtlasPass& atlas_;
  VirtualPagesPass& virtual_pages_;
  const cl::Buffer& empty_map_;
  bool half_ = false;
};

// The textures of a request's lights in the order its products are asked for, each product's
// lights in order (stable: mips stay by level).
void order_products(const RenderRequest& req, std::vector<Texture>& textures);

}  // namespace shadow
