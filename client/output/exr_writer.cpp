#include "output/exr_writer.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <stdexcept>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>

#include "output/exr_parts.hpp"

namespace shadow::output {
namespace {

// OpenEXR's matrices are row-vector (p · M), stored row by row: R[r][c] = M[c][r], which is
// exactly GLM's column-major memory of M.
Imath::M44f row_vector(const glm::mat4& m) {
  Imath::M44f r;
  std::memcpy(&r.x[0][0], &m[0][0], sizeof r.x);
  return r;
}

Imf::Compression compression_of(std::string_view name) {
  if (name == "none") return Imf::NO_COMPRESSION;
  if (name == "rle") return Imf::RLE_COMPRESSION;
  if (name == "zips") return Imf::ZIPS_COMPRESSION;
  if (name == "zip") return Imf::ZIP_COMPRESSION;
  if (name == "piz") return Imf::PIZ_COMPRESSION;
  throw std::invalid_argument("unknown EXR compression '" + std::string(name) + "'");
}

// "YYYY:MM:DD HH:MM:SS", local time, as OpenEXR's capDate has it.
std::string now() {
  const std::time_t t = std::time(nullptr);
  std::tm local{};
  localtime_r(&t, &local);
  char text[32];
  std::strftime(text, sizeof text, "%Y:%m:%d %H:%M:%S", &local);
  return text;
}

}  // namespace

bool known_exr_compression(std::string_view name) {
  return std::find(kExrCompressions.begin(), kExrCompressions.end(), name) !=
         kExrCompressions.end();
}

ExrPart exr_part(const Texture& texture, std::string_view compression, const float* pixels) {
  const int width = int(texture.width), height = int(texture.height);
  ExrPart part{Imf::Header(width, height, 1.0f, Imath::V2f(0, 0), 1.0f, Imf::INCREASING_Y,
                           compression_of(exr_compression_for(texture.kind, compression))),
               {},
               {}};
  Imf::Header& h = part.header;
  h.setType(Imf::SCANLINEIMAGE);  // which a multi-part file needs in each part
  const std::vector<std::string> names = channel_names(texture);
  // Float16 textures keep their precision on disk: HALF channels, from exact float copies of
  // their values (write_products) made half again.
  const bool half16 = texture.format == PixelFormat::kFloat16;
  const Imf::PixelType stored = half16 ? Imf::HALF : Imf::FLOAT;
  const size_t value = half16 ? sizeof(half) : sizeof(float);
  const size_t xstride = names.size() * value, ystride = size_t(width) * xstride;
  char* base = const_cast<char*>(reinterpret_cast<const char*>(pixels));
  if (half16) {
    part.halves =
        std::make_shared<std::vector<half>>(pixels, pixels + size_t(width) * height * names.size());
    base = reinterpret_cast<char*>(part.halves->data());
  }
  for (size_t c = 0; c < names.size(); ++c) {
    h.channels().insert(names[c], Imf::Channel(stored));
    part.pixels.insert(names[c], Imf::Slice(stored, base + c * value, xstride, ystride));
  }
  Imf::addWorldToNDC(h, row_vector(texture.world_to_ndc));
  Imf::addWorldToCamera(h, row_vector(texture.world_to_camera));
  Imf::addCapDate(h, now());
  const auto text = [&](const char* name, const std::string& value) {
    h.insert(name, Imf::StringAttribute(value));
  };
  if (texture.kind == Product::kShadowMap) text("textureformat", "Shadow");
  // Not standard names, so in our own namespace ("prefix:name", as OpenImageIO reads them).
  if (!texture.depth_mapping.empty()) text("shadow:depth_mapping", texture.depth_mapping);
  if (!texture.atlas_tiles.empty()) {  // "instance x y size" per tile, ';'-separated
    std::string tiles;
    for (const AtlasTile& t : texture.atlas_tiles) {
      if (!tiles.empty()) tiles += ';';
      tiles += std::to_string(t.instance) + ' ' + std::to_string(t.x) + ' ' + std::to_string(t.y) +
               ' ' + std::to_string(t.size);
    }
    text("shadow:atlas_tiles", tiles);
    // The world size of a texel on each tile's instance, in the same order.
    std::string sizes;
    for (const AtlasTile& t : texture.atlas_tiles) {
      char size[32];
      std::snprintf(size, sizeof size, "%.6g", t.texel_world_size);
      if (!sizes.empty()) sizes += ';';
      sizes += size;
    }
    text("shadow:atlas_texel_world_sizes", sizes);
  }
  if (texture.csm_terms > 0) {
    h.insert("shadow:csm_terms", Imf::IntAttribute(int(texture.csm_terms)));
    text("shadow:csm_storage", texture.csm_storage == CsmStorage::kFloat16 ? "float16" : "float32");
  }
  return part;
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

  write_exr_parts(file, {exr_part(texture, compression, texture.data.data())});
}

}  // namespace shadow::output
