#include "wire/result_assembler.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <new>
#include <optional>
#include <string>

#include <zstd.h>

#include "wire/convert.hpp"
#include "wire/errors.hpp"
#include "wire/huge_pages.hpp"
#include "wire/names.hpp"
#include "wire/texture_layout.hpp"

namespace shadow::convert {
namespace {

std::string texture_name(size_t i) {
  return "textures[" + std::to_string(i) + "]";
}

std::vector<TextureFace> faces_from_proto(const v1::TextureInfo& info, const std::string& where) {
  std::vector<TextureFace> faces;
  for (int i = 0; i < info.cube_faces_size(); ++i) {
    const v1::CubeFace& f = info.cube_faces(i);
    const std::string at = where + ".cube_faces[" + std::to_string(i) + "]";
    faces.push_back({f.name(), from_proto(f.world_to_ndc(), at + ".world_to_ndc"),
                     from_proto(f.world_to_camera(), at + ".world_to_camera")});
  }
  return faces;
}

Texture texture_from_info(const v1::TextureInfo& info, const std::string& where) {
  Texture t;
  t.name = info.name();
  try {
    t.kind = from_proto(info.kind(), where + ".kind");
    t.world_to_ndc = from_proto(info.world_to_ndc(), where + ".world_to_ndc");
    t.world_to_camera = from_proto(info.world_to_camera(), where + ".world_to_camera");
    t.cube_faces = faces_from_proto(info, where);
  } catch (const InvalidArgument& e) {
    throw StreamError(std::string("bad header: ") + e.what());
  }
  const std::optional<PixelFormat> format = names::kPixelFormats.from_proto(info.format());
  if (!format) {
    throw StreamError("bad header: " + where + ".format " + std::to_string(int(info.format())) +
                      " is not supported");
  }
  t.format = *format;
  t.width = info.width();
  t.height = info.height();
  t.channels = info.channels();
  t.faces = info.faces();
  if (info.channel_names_size() != 0 && uint32_t(info.channel_names_size()) != t.channels)
    throw StreamError("bad header: " + where + ".channel_names has " +
                      std::to_string(info.channel_names_size()) + " names for " +
                      std::to_string(t.channels) + " channels");
  t.channel_names.assign(info.channel_names().begin(), info.channel_names().end());
  t.depth_mapping = info.depth_mapping();
  t.light = info.light();
  t.mesh = info.mesh();
  for (const v1::AtlasTile& a : info.atlas_tiles()) {
    // A tile must lie inside its texture (a client indexes the data with it).
    if (a.size() == 0 || a.x() > t.width || a.size() > t.width - a.x() || a.y() > t.height ||
        a.size() > t.height - a.y())
      throw StreamError("bad header: " + where + ".atlas_tiles: a tile of instance " +
                        std::to_string(a.instance()) + " lies outside the texture");
    t.atlas_tiles.push_back({a.instance(), a.x(), a.y(), a.size(), a.texel_world_size()});
  }
  t.csm_terms = info.csm_terms();
  if (t.csm_terms > 0) {
    const std::optional<CsmStorage> storage = names::kCsmStorages.from_proto(info.csm_storage());
    if (!storage)
      throw StreamError("bad header: " + where + ".csm_storage " +
                        std::to_string(int(info.csm_storage())) + " is not known");
    t.csm_storage = *storage;
  }
  uint64_t expected = 0;
  if (!texture_bytes(t, &expected) || expected != info.byte_size()) {
    throw StreamError("bad header: " + where + ".byte_size " + std::to_string(info.byte_size()) +
                      " does not match " + std::to_string(t.width) + "x" +
                      std::to_string(t.height) + "x" + std::to_string(t.channels) + "x" +
                      std::to_string(t.faces) + " " +
                      std::string(names::kPixelFormats.name(t.format)));
  }
  const std::string problem = cube_faces_problem(t, where + ".cube_faces");
  if (!problem.empty()) throw StreamError("bad header: " + problem);
  return t;
}

// Bytes [from, to) of `t` arrived in wire order (little-endian): puts the values that are now
// whole into host order. A value split across chunks is swapped when its last byte arrives.
void to_host_order(Texture& t, uint64_t from, uint64_t to) {
  if constexpr (std::endian::native == std::endian::big) {
    const uint64_t size = t.value_bytes();
    for (uint64_t v = from / size; v < to / size; ++v) {  // the values that end in [from, to)
      if (size == 8) {
        double& d = t.data64[v];
        d = std::bit_cast<double>(__builtin_bswap64(std::bit_cast<uint64_t>(d)));
      } else if (size == 2) {
        t.data16[v] = __builtin_bswap16(t.data16[v]);
      } else {
        float& f = t.data[v];
        f = std::bit_cast<float>(__builtin_bswap32(std::bit_cast<uint32_t>(f)));
      }
    }
  } else {
    (void)t, (void)from, (void)to;
  }
}

void free_dctx(ZSTD_DCtx* c) {
  ZSTD_freeDCtx(c);
}

// Decompresses one zstd frame of exactly `raw` bytes into `dst`, which has room for `raw` bytes
// and no more; anything else (not a frame, trailing bytes, another size) throws StreamError.
void unzstd(ZSTD_DCtx* dctx, const std::string& frame, char* dst, uint64_t raw,
            const std::string& where) {
  const unsigned long long declared = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (declared == ZSTD_CONTENTSIZE_ERROR)
    throw StreamError("a compressed chunk of " + where + " is not a zstd frame");
  if (declared == ZSTD_CONTENTSIZE_UNKNOWN)
    throw StreamError("a compressed chunk of " + where + " does not declare its size");
  if (declared != raw)
    throw StreamError("a compressed chunk of " + where + " declares " + std::to_string(declared) +
                      " bytes, but raw_size " + std::to_string(raw));
  if (ZSTD_findFrameCompressedSize(frame.data(), frame.size()) != frame.size())
    throw StreamError("a compressed chunk of " + where + " is not one whole zstd frame");
  const size_t n = ZSTD_decompressDCtx(dctx, dst, raw, frame.data(), frame.size());
  if (ZSTD_isError(n))
    throw StreamError("a compressed chunk of " + where + " does not decompress to its " +
                      std::to_string(raw) + " bytes: " + ZSTD_getErrorName(n));
  if (n != raw)
    throw StreamError("a compressed chunk of " + where + " decompressed to " + std::to_string(n) +
                      " bytes, not its raw_size " + std::to_string(raw));
}

}  // namespace

ResultAssembler::ResultAssembler(uint64_t max_total_bytes)
    : max_total_bytes_(max_total_bytes), zstd_(nullptr, free_dctx) {}

ResultAssembler::~ResultAssembler() = default;

size_t ResultAssembler::add(const v1::RenderResponse& response) {
  switch (response.payload_case()) {
    case v1::RenderResponse::kHeader:
      add_header(response.header());
      return kNoTexture;
    case v1::RenderResponse::kChunk:
      add_chunk(response.chunk());
      return response.chunk().texture();
    case v1::RenderResponse::kProgress:  // the client's to show, not a product's
      throw StreamError("a progress message reached the assembler");
    case v1::RenderResponse::PAYLOAD_NOT_SET:
      break;
  }
  throw StreamError("a response carries neither a header nor a chunk");
}

void ResultAssembler::add_header(const v1::RenderHeader& header) {
  if (have_header_) throw StreamError("a second header arrived");
  have_header_ = true;
  uint64_t total = 0;
  for (int i = 0; i < header.textures_size(); ++i) {
    const v1::TextureInfo& info = header.textures(i);
    result_.textures.push_back(texture_from_info(info, texture_name(i)));
    if (__builtin_add_overflow(total, info.byte_size(), &total) || total > max_total_bytes_) {
      throw StreamError("the textures would take more than " + std::to_string(max_total_bytes_) +
                        " bytes");
    }
  }
  // Allocate only once every size is known to be sane.
  for (Texture& t : result_.textures) {
    uint64_t bytes = 0;
    texture_bytes(t, &bytes);
    if (t.format == PixelFormat::kFloat64)
      resize_on_huge_pages(t.data64, bytes / sizeof(double));
    else if (t.format == PixelFormat::kFloat16)
      resize_on_huge_pages(t.data16, bytes / sizeof(uint16_t));
    else
      resize_on_huge_pages(t.data, bytes / sizeof(float));
  }
  received_.assign(result_.textures.size(), 0);
  for (const std::string& pass : header.passes()) result_.passes.push_back(pass);
  result_.frame = header.frame();
  for (const std::string& pass : header.reused()) result_.reused.push_back(pass);
  for (const std::string& pass : header.rerun()) result_.rerun.push_back(pass);
  for (const v1::LightFit& in : header.light_fits()) {
    LightFitReport& fit = result_.light_fits.emplace_back();
    fit.light_case = in.light_case();
    fit.virtual_near = in.psm_virtual_near();
    fit.virtual_far = in.psm_virtual_far();
    fit.slide_back = in.psm_slide_back();
    fit.light_near = in.psm_light_near();
    fit.light_far = in.psm_light_far();
    fit.cube_texel_min = in.psm_cube_texel_min();
    fit.cube_texel_max = in.psm_cube_texel_max();
    fit.lispsm_n = in.lispsm_n();
    fit.auto_technique = names::kTechniques.from_proto(in.auto_technique());
    fit.auto_reason = in.auto_reason();
    fit.auto_map_size = in.auto_map_size();
    fit.raster_overlaps = in.raster_overlaps();
    fit.raster_box_pixels = in.raster_box_pixels();
    for (const v1::AutoCandidate& c : in.auto_candidates()) {
      const std::optional<Technique> t = names::kTechniques.from_proto(c.technique());
      if (!t)
        throw StreamError("bad header: light_fits.auto_candidates.technique " +
                          std::to_string(int(c.technique())) + " is not a technique");
      fit.auto_candidates.push_back({*t, c.map_size(), c.maps(), c.predicted_error(),
                                     c.mean_footprint_px(), c.trial_map_size(), c.trial_edge()});
    }
    for (const v1::CubeFaceReport& face : in.cube_faces())
      fit.cube_faces.push_back({face.face(), face.rendered(), face.reason()});
  }
  for (const v1::PassTiming& timing : header.timings()) {
    result_.timings.push_back({timing.pass(), timing.device_ms()});
  }
  if (header.has_virtual_pages()) {
    const v1::VirtualPages& v = header.virtual_pages();
    result_.virtual_pages = VirtualPageCounts{v.requested(), v.resident(), v.rendered(),
                                              v.coarsened_pixels(), v.pool_bytes()};
  }
  if (header.has_quality()) {
    const v1::QualityPick& in = header.quality();
    const std::optional<Technique> technique = names::kTechniques.from_proto(in.technique());
    if (!technique)
      throw StreamError("bad header: quality.technique " + std::to_string(int(in.technique())) +
                        " is not known");
    result_.quality = QualityPick{*technique,
                                  in.size(),
                                  in.predicted_error(),
                                  in.predicted_device_ms(),
                                  in.goal_met(),
                                  in.reason(),
                                  {},
                                  {}};
    for (double share : in.boundary_share()) {
      if (!(share >= 0 && share <= 1))
        throw StreamError("bad header: quality.boundary_share " + std::to_string(share) +
                          " is not in [0, 1]");
      result_.quality->boundary_share.push_back(share);
    }
    for (int i = 0; i < in.candidates_size(); ++i) {
      const v1::QualityCandidate& c = in.candidates(i);
      const std::string field = "bad header: quality.candidates[" + std::to_string(i) + "].";
      const std::optional<Technique> t = names::kTechniques.from_proto(c.technique());
      if (!t)
        throw StreamError(field + "technique " + std::to_string(int(c.technique())) +
                          " is not known");
      if (!(c.predicted_error() >= 0 && std::isfinite(c.predicted_error())))
        throw StreamError(field + "predicted_error " + std::to_string(c.predicted_error()) +
                          " is not a finite share >= 0");
      if (!(c.predicted_device_ms() >= 0 && std::isfinite(c.predicted_device_ms())))
        throw StreamError(field + "predicted_device_ms " + std::to_string(c.predicted_device_ms()) +
                          " is not finite and >= 0");
      if (!(c.typical_device_ms() >= 0 && std::isfinite(c.typical_device_ms())))
        throw StreamError(field + "typical_device_ms " + std::to_string(c.typical_device_ms()) +
                          " is not finite and >= 0");
      result_.quality->candidates.push_back({*t, c.size(), c.predicted_error(),
                                             c.predicted_device_ms(), c.typical_device_ms(),
                                             c.raster_load_priced()});
    }
  }
}

void ResultAssembler::add_chunk(const v1::TextureChunk& chunk) {
  if (!have_header_) throw StreamError("a chunk arrived before the header");
  if (chunk.texture() >= result_.textures.size()) {
    throw StreamError("a chunk names texture " + std::to_string(chunk.texture()) + " of " +
                      std::to_string(result_.textures.size()));
  }
  Texture& t = result_.textures[chunk.texture()];
  uint64_t& received = received_[chunk.texture()];
  const uint64_t size = t.byte_size();
  const std::string where = texture_name(chunk.texture()) + " (" + t.name + ")";
  if (chunk.offset() != received) {
    throw StreamError("a chunk of " + where + " starts at byte " + std::to_string(chunk.offset()) +
                      ", expected " + std::to_string(received));
  }
  char* base = t.bytes();
  uint64_t raw = chunk.data().size();
  switch (chunk.compression()) {
    case v1::CHUNK_COMPRESSION_UNSPECIFIED:
    case v1::CHUNK_COMPRESSION_NONE:
      if (chunk.raw_size() != 0)
        throw StreamError("an uncompressed chunk of " + where + " has raw_size " +
                          std::to_string(chunk.raw_size()));
      break;
    case v1::CHUNK_COMPRESSION_ZSTD:
      raw = chunk.raw_size();
      break;
    default:
      throw StreamError("a chunk of " + where + " has unknown compression " +
                        std::to_string(int(chunk.compression())));
  }
  if (raw > size - received) {
    throw StreamError("a chunk of " + where + " ends at byte " + std::to_string(received + raw) +
                      ", past its size " + std::to_string(size));
  }
  if (chunk.compression() == v1::CHUNK_COMPRESSION_ZSTD) {
    if (!zstd_) {
      zstd_.reset(ZSTD_createDCtx());
      if (!zstd_) throw std::bad_alloc();
    }
    unzstd(zstd_.get(), chunk.data(), base + received, raw, where);
  } else if (raw > 0) {
    std::memcpy(base + received, chunk.data().data(), raw);
  }
  to_host_order(t, received, received + raw);
  received += raw;
}

RenderResult ResultAssembler::finish() {
  if (!have_header_) throw StreamError("the stream ended without a header");
  for (size_t i = 0; i < result_.textures.size(); ++i) {
    const Texture& t = result_.textures[i];
    if (received_[i] != t.byte_size()) {
      throw StreamError("the stream ended after " + std::to_string(received_[i]) + " of " +
                        std::to_string(t.byte_size()) + " bytes of " + texture_name(i) + " (" +
                        t.name + ")");
    }
  }
  have_header_ = false;
  received_.clear();
  return std::move(result_);
}

}  // namespace shadow::convert
