#include "output/exr_writer.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include <OpenImageIO/imageio.h>

#include "output/exr_parts.hpp"

namespace shadow::output {
namespace {

// OIIO wants the row-vector matrix R = Mᵀ stored row by row: R[r][c] = M[c][r], which is
// exactly GLM's column-major memory of M.
void set_matrix(OIIO::ImageSpec& spec, const char* name, const glm::mat4& m) {
  spec.attribute(name, OIIO::TypeMatrix44, &m[0][0]);
}

}  // namespace

bool known_exr_compression(std::string_view name) {
  return std::find(kExrCompressions.begin(), kExrCompressions.end(), name) !=
         kExrCompressions.end();
}

OIIO::ImageSpec exr_spec(const Texture& texture, std::string_view compression) {
  // Float16 textures keep their precision on disk: HALF channels (written from exact float
  // copies of their values: write_products).
  const OIIO::TypeDesc stored =
      texture.format == PixelFormat::kFloat16 ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;
  OIIO::ImageSpec spec(static_cast<int>(texture.width), static_cast<int>(texture.height),
                       static_cast<int>(texture.channels), stored);
  spec.channelnames = channel_names(texture);
  if (!known_exr_compression(compression))
    throw std::invalid_argument("unknown EXR compression '" + std::string(compression) + "'");
  spec.attribute("compression", compression);
  set_matrix(spec, "worldtoNDC", texture.world_to_ndc);
  set_matrix(spec, "worldtocamera", texture.world_to_camera);
  if (texture.kind == Product::kShadowMap) spec.attribute("textureformat", "Shadow");
  // Not OIIO standard names, so in our own namespace (OIIO's "prefix:name" convention).
  if (!texture.depth_mapping.empty()) spec.attribute("shadow:depth_mapping", texture.depth_mapping);
  if (!texture.atlas_tiles.empty()) {  // "instance x y size" per tile, ';'-separated
    std::string tiles;
    for (const AtlasTile& t : texture.atlas_tiles) {
      if (!tiles.empty()) tiles += ';';
      tiles += std::to_string(t.instance) + ' ' + std::to_string(t.x) + ' ' + std::to_string(t.y) +
               ' ' + std::to_string(t.size);
    }
    spec.attribute("shadow:atlas_tiles", tiles);
    // The world size of a texel on each tile's instance, in the same order.
    std::string sizes;
    for (const AtlasTile& t : texture.atlas_tiles) {
      char size[32];
      std::snprintf(size, sizeof size, "%.6g", t.texel_world_size);
      if (!sizes.empty()) sizes += ';';
      sizes += size;
    }
    spec.attribute("shadow:atlas_texel_world_sizes", sizes);
  }
  if (texture.csm_terms > 0) {
    spec.attribute("shadow:csm_terms", int(texture.csm_terms));
    spec.attribute("shadow:csm_storage",
                   texture.csm_storage == CsmStorage::kFloat16 ? "float16" : "float32");
  }
  return spec;
}

std::vector<std::string> channel_names(const Texture& texture) {
  // Named by the server (CSM bases: sin1.., cos1.., zsin1.., zcos1.., z).
  if (!texture.channel_names.empty() && texture.channel_names.size() == texture.channels)
    return texture.channel_names;
  // Summed-area tables after split_hi_lo: "S.hi", "S.lo" per source channel.
  if (texture.kind == Product::kShadowMapSat || texture.kind == Product::kVisibilitySat) {
    std::vector<std::string> names;
    for (uint32_t c = 0; c < texture.channels / 2; ++c) {
      std::string base = "S";
      if (texture.channels != 2) base += std::to_string(c);
      names.push_back(base + ".hi");
      names.push_back(base + ".lo");
    }
    return names;
  }
  if ((texture.kind == Product::kShadowMap || texture.kind == Product::kShadowMapMips) &&
      texture.channels == 1)
    return {"Z"};
  if ((texture.kind == Product::kVisibilityMips || texture.kind == Product::kShadowAtlas ||
       texture.kind == Product::kShadowAtlasMips) &&
      texture.channels == 1)
    return {"Y"};
  if (texture.kind == Product::kVisibility && texture.channels == 1) return {"Y"};
  if (texture.kind == Product::kTexelDensity && texture.channels == 1) return {"Y"};
  if (texture.channels == 3) return {"R", "G", "B"};
  std::vector<std::string> names;
  for (uint32_t c = 0; c < texture.channels; ++c) {
    names.emplace_back("C");  // not "C" + ...: GCC 12 warns falsely (-Wrestrict) on that
    names.back() += std::to_string(c);
  }
  return names;
}

void write_exr(const Texture& texture, const std::filesystem::path& file,
               std::string_view compression) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error(file.string() + ": " + why);
  };
  if (texture.faces != 1)
    fail("textures with " + std::to_string(texture.faces) + " faces are not supported yet");
  if (texture.width == 0 || texture.height == 0 || texture.channels == 0) fail("empty texture");
  const size_t expected = size_t{texture.width} * texture.height * texture.channels;
  if (texture.data.size() != expected)
    fail("texture holds " + std::to_string(texture.data.size()) + " floats, expected " +
         std::to_string(expected));

  const OIIO::ImageSpec spec = exr_spec(texture, compression);
  auto out = OIIO::ImageOutput::create(file.string());
  if (!out) fail("cannot create an EXR writer: " + OIIO::geterror());
  if (!out->open(file.string(), spec)) fail(out->geterror());
  if (!out->write_image(OIIO::TypeDesc::FLOAT, texture.data.data())) fail(out->geterror());
  if (!out->close()) fail(out->geterror());
}

}  // namespace shadow::output
