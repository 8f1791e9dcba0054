#include "wire/result_slicer.hpp"

#include <algorithm>
#include <bit>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include <zstd.h>

#include "wire/convert.hpp"
#include "wire/little_endian.hpp"
#include "wire/names.hpp"
#include "wire/texture_layout.hpp"

namespace shadow::convert {
namespace {

// Fills `chunk` with `count` values from `values`: raw, or as one zstd frame when that is
// smaller. Raw bytes are copied once (on a little-endian host, straight into the message).
template <class T>
void fill_chunk(const T* values, size_t count, ZSTD_CCtx* zstd, v1::TextureChunk& chunk) {
  const size_t raw = count * sizeof(T);
  std::string* bytes = chunk.mutable_data();
  if (zstd) {
    // The frame needs the bytes in wire order; on a little-endian host they already are.
    std::string le;
    const char* src = reinterpret_cast<const char*>(values);
    if constexpr (std::endian::native != std::endian::little) {
      le.resize(raw);
      host_to_le(values, count, le.data());
      src = le.data();
    }
    bytes->resize(ZSTD_compressBound(raw));
    const size_t packed = ZSTD_compress2(zstd, bytes->data(), bytes->size(), src, raw);
    if (ZSTD_isError(packed))
      throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(packed));
    if (packed < raw) {
      bytes->resize(packed);
      chunk.set_compression(v1::CHUNK_COMPRESSION_ZSTD);
      chunk.set_raw_size(raw);
      return;
    }
  }
  chunk.set_compression(v1::CHUNK_COMPRESSION_NONE);
  chunk.set_raw_size(0);
  if constexpr (std::endian::native == std::endian::little) {
    bytes->assign(reinterpret_cast<const char*>(values), raw);
  } else {
    bytes->resize(raw);
    host_to_le(values, count, bytes->data());
  }
}

// Whole values per chunk, so a big-endian host can swap each chunk on its own.
template <class T>
bool send_values(const std::vector<T>& data, size_t per_chunk, ZSTD_CCtx* zstd,
                 v1::RenderResponse& response,
                 const std::function<bool(const v1::RenderResponse&)>& write) {
  per_chunk = std::max<size_t>(1, per_chunk);
  v1::TextureChunk& chunk = *response.mutable_chunk();
  for (size_t first = 0; first < data.size(); first += per_chunk) {
    const size_t count = std::min(per_chunk, data.size() - first);
    chunk.set_offset(uint64_t(first) * sizeof(T));
    fill_chunk(data.data() + first, count, zstd, chunk);
    if (!write(response)) return false;
  }
  return true;
}

struct ZstdContextFree {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};

}  // namespace

v1::TextureInfo to_proto_info(const Texture& t) {
  uint64_t expected = 0;
  if (!texture_bytes(t, &expected) || expected != uint64_t(t.byte_size()) ||
      t.byte_size() != t.bytes_of_format()) {
    throw std::logic_error("texture " + t.name + " holds " + std::to_string(t.byte_size()) +
                           " bytes, which does not match its dimensions");
  }
  const std::string problem = cube_faces_problem(t, "texture " + t.name + " cube_faces");
  if (!problem.empty()) throw std::logic_error(problem);
  v1::TextureInfo info;
  info.set_name(t.name);
  info.set_kind(to_proto(t.kind));
  info.set_width(t.width);
  info.set_height(t.height);
  info.set_channels(t.channels);
  info.set_faces(t.faces);
  info.set_format(names::kPixelFormats.to_proto(t.format));
  *info.mutable_world_to_ndc() = to_proto(t.world_to_ndc);
  *info.mutable_world_to_camera() = to_proto(t.world_to_camera);
  info.set_byte_size(t.byte_size());
  for (const std::string& c : t.channel_names) info.add_channel_names(c);
  info.set_depth_mapping(t.depth_mapping);
  for (const AtlasTile& a : t.atlas_tiles) {
    v1::AtlasTile& out = *info.add_atlas_tiles();
    out.set_instance(a.instance);
    out.set_x(a.x);
    out.set_y(a.y);
    out.set_size(a.size);
    out.set_texel_world_size(a.texel_world_size);
  }
  info.set_light(t.light);
  info.set_mesh(t.mesh);
  if (t.csm_terms > 0) {
    info.set_csm_terms(t.csm_terms);
    info.set_csm_storage(names::kCsmStorages.to_proto(t.csm_storage));
  }
  for (const TextureFace& face : t.cube_faces) {
    v1::CubeFace& out = *info.add_cube_faces();
    out.set_name(face.name);
    *out.mutable_world_to_ndc() = to_proto(face.world_to_ndc);
    *out.mutable_world_to_camera() = to_proto(face.world_to_camera);
  }
  return info;
}

v1::RenderHeader make_header(const RenderResult& result) {
  v1::RenderHeader header;
  for (const Texture& t : result.textures) *header.add_textures() = to_proto_info(t);
  for (const std::string& pass : result.passes) header.add_passes(pass);
  header.set_frame(result.frame);
  for (const std::string& pass : result.reused) header.add_reused(pass);
  for (const std::string& pass : result.rerun) header.add_rerun(pass);
  for (const LightFitReport& fit : result.light_fits) {
    v1::LightFit& out = *header.add_light_fits();
    out.set_light_case(fit.light_case);
    out.set_psm_virtual_near(fit.virtual_near);
    out.set_psm_virtual_far(fit.virtual_far);
    out.set_psm_slide_back(fit.slide_back);
    out.set_psm_light_near(fit.light_near);
    out.set_psm_light_far(fit.light_far);
    out.set_psm_cube_texel_min(fit.cube_texel_min);
    out.set_psm_cube_texel_max(fit.cube_texel_max);
    out.set_lispsm_n(fit.lispsm_n);
    if (fit.auto_technique)
      out.set_auto_technique(names::kTechniques.to_proto(*fit.auto_technique));
    out.set_auto_reason(fit.auto_reason);
    out.set_auto_map_size(fit.auto_map_size);
    out.set_raster_overlaps(fit.raster_overlaps);
    out.set_raster_box_pixels(fit.raster_box_pixels);
    for (const AutoCandidateReport& c : fit.auto_candidates) {
      v1::AutoCandidate& a = *out.add_auto_candidates();
      a.set_technique(names::kTechniques.to_proto(c.technique));
      a.set_map_size(c.map_size);
      a.set_maps(c.maps);
      a.set_predicted_error(c.predicted_error);
      a.set_mean_footprint_px(c.mean_footprint);
      a.set_trial_map_size(c.trial_map_size);
      a.set_trial_edge(c.trial_edge);
    }
    for (const CubeFaceReport& face : fit.cube_faces) {
      v1::CubeFaceReport& f = *out.add_cube_faces();
      f.set_face(face.name);
      f.set_rendered(face.rendered);
      f.set_reason(face.reason);
    }
  }
  if (const std::optional<QualityPick>& q = result.quality) {
    v1::QualityPick& out = *header.mutable_quality();
    out.set_technique(names::kTechniques.to_proto(q->technique));
    out.set_size(q->size);
    out.set_predicted_error(q->predicted_error);
    out.set_predicted_device_ms(q->predicted_device_ms);
    out.set_goal_met(q->goal_met);
    out.set_reason(q->reason);
    for (double share : q->boundary_share) out.add_boundary_share(share);
    for (const QualityCandidate& c : q->candidates) {
      v1::QualityCandidate& to = *out.add_candidates();
      to.set_technique(names::kTechniques.to_proto(c.technique));
      to.set_size(c.size);
      to.set_predicted_error(c.predicted_error);
      to.set_predicted_device_ms(c.predicted_device_ms);
      to.set_typical_device_ms(c.typical_device_ms);
      to.set_raster_load_priced(c.raster_load_priced);
    }
  }
  if (const std::optional<VirtualPageCounts>& v = result.virtual_pages) {
    v1::VirtualPages& out = *header.mutable_virtual_pages();
    out.set_requested(v->requested);
    out.set_resident(v->resident);
    out.set_rendered(v->rendered);
    out.set_coarsened_pixels(v->coarsened_pixels);
    out.set_pool_bytes(v->pool_bytes);
  }
  for (const PassTiming& timing : result.timings) {
    v1::PassTiming* out = header.add_timings();
    out->set_pass(timing.pass);
    out->set_device_ms(timing.device_ms);
  }
  return header;
}

bool stream_result(const RenderResult& result, size_t chunk_bytes,
                   const std::function<bool(const v1::RenderResponse&)>& write,
                   ChunkCompression compression) {
  const size_t floats_per_chunk = std::max<size_t>(1, chunk_bytes / sizeof(float));
  std::unique_ptr<ZSTD_CCtx, ZstdContextFree> zstd;
  if (compression == ChunkCompression::kZstd) {
    zstd.reset(ZSTD_createCCtx());
    if (!zstd) throw std::bad_alloc();
    ZSTD_CCtx_setParameter(zstd.get(), ZSTD_c_compressionLevel, kZstdLevel);
    ZSTD_CCtx_setParameter(zstd.get(), ZSTD_c_contentSizeFlag, 1);
  }
  v1::RenderResponse response;
  *response.mutable_header() = make_header(result);
  if (!write(response)) return false;

  for (size_t i = 0; i < result.textures.size(); ++i) {
    response.mutable_chunk()->set_texture(uint32_t(i));
    const Texture& t = result.textures[i];
    if (!send_values(t.data, floats_per_chunk, zstd.get(), response, write) ||
        !send_values(t.data16, floats_per_chunk * 2, zstd.get(), response, write) ||
        !send_values(t.data64, floats_per_chunk / 2, zstd.get(), response, write))
      return false;
  }
  return true;
}

}  // namespace shadow::convert
