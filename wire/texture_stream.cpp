#include "wire/texture_stream.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <string>

#include "wire/convert.hpp"
#include "wire/errors.hpp"
#include "wire/little_endian.hpp"

namespace shadow::convert {
namespace {

constexpr uint64_t kFloatBytes = sizeof(float);

// w * h * c * f * value_bytes; false if that overflows 64 bits.
bool texture_bytes(uint64_t w, uint64_t h, uint64_t c, uint64_t f, uint64_t* out,
                   uint64_t value_bytes = kFloatBytes) {
  uint64_t n = value_bytes;
  for (uint64_t factor : {w, h, c, f}) {
    if (__builtin_mul_overflow(n, factor, &n)) return false;
  }
  *out = n;
  return true;
}

std::string texture_name(size_t i) {
  return "textures[" + std::to_string(i) + "]";
}

// A cube texture has cube_faces or faces != 1 (a cube with no rendered face has neither).
// Returns what is wrong with its faces, starting with `field` (the cube_faces field), or ""
// when they are consistent: one distinct named face per face of data, at most six.
std::string cube_faces_problem(uint32_t faces, const std::vector<std::string>& names,
                               const std::string& field) {
  static const std::vector<std::string> kNames = {"+x", "-x", "+y", "-y", "+z", "-z"};
  if (names.empty() && faces == 1) return "";
  if (names.size() != faces) {
    return field + " holds " + std::to_string(names.size()) + " entries for " +
           std::to_string(faces) + " faces of data";
  }
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string name = field + "[" + std::to_string(i) + "].name '" + names[i] + "'";
    if (std::find(kNames.begin(), kNames.end(), names[i]) == kNames.end())
      return name + " is not +x, -x, +y, -y, +z or -z";
    if (std::find(names.begin(), names.begin() + i, names[i]) != names.begin() + i)
      return name + " appears twice";
  }
  return "";
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

std::vector<std::string> face_names(const std::vector<TextureFace>& faces) {
  std::vector<std::string> names;
  for (const TextureFace& f : faces) names.push_back(f.name);
  return names;
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
  if (info.format() == v1::PIXEL_FORMAT_FLOAT32) {
    t.format = PixelFormat::kFloat32;
  } else if (info.format() == v1::PIXEL_FORMAT_FLOAT64) {
    t.format = PixelFormat::kFloat64;
  } else {
    throw StreamError("bad header: " + where + ".format " + std::to_string(int(info.format())) +
                      " is not supported");
  }
  t.width = info.width();
  t.height = info.height();
  t.channels = info.channels();
  t.faces = info.faces();
  uint64_t expected = 0;
  if (!texture_bytes(t.width, t.height, t.channels, t.faces, &expected, t.value_bytes()) ||
      expected != info.byte_size()) {
    throw StreamError("bad header: " + where + ".byte_size " + std::to_string(info.byte_size()) +
                      " does not match " + std::to_string(t.width) + "x" +
                      std::to_string(t.height) + "x" + std::to_string(t.channels) + "x" +
                      std::to_string(t.faces) +
                      (t.format == PixelFormat::kFloat64 ? " float64" : " float32"));
  }
  const std::string problem =
      cube_faces_problem(t.faces, face_names(t.cube_faces), where + ".cube_faces");
  if (!problem.empty()) throw StreamError("bad header: " + problem);
  return t;
}

}  // namespace

v1::TextureInfo to_proto_info(const Texture& t) {
  uint64_t expected = 0;
  if (!texture_bytes(t.width, t.height, t.channels, t.faces, &expected, t.value_bytes()) ||
      expected != uint64_t(t.byte_size()) ||
      (t.format == PixelFormat::kFloat64 ? !t.data.empty() : !t.data64.empty())) {
    throw std::logic_error("texture " + t.name + " holds " + std::to_string(t.byte_size()) +
                           " bytes, which does not match its dimensions");
  }
  const std::string problem =
      cube_faces_problem(t.faces, face_names(t.cube_faces), "texture " + t.name + " cube_faces");
  if (!problem.empty()) throw std::logic_error(problem);
  v1::TextureInfo info;
  info.set_name(t.name);
  info.set_kind(to_proto(t.kind));
  info.set_width(t.width);
  info.set_height(t.height);
  info.set_channels(t.channels);
  info.set_faces(t.faces);
  info.set_format(t.format == PixelFormat::kFloat64 ? v1::PIXEL_FORMAT_FLOAT64
                                                    : v1::PIXEL_FORMAT_FLOAT32);
  *info.mutable_world_to_ndc() = to_proto(t.world_to_ndc);
  *info.mutable_world_to_camera() = to_proto(t.world_to_camera);
  info.set_byte_size(t.byte_size());
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
  const LightFitReport& fit = result.light_fit;
  header.set_light_case(fit.light_case);
  header.set_psm_virtual_near(fit.virtual_near);
  header.set_psm_virtual_far(fit.virtual_far);
  header.set_psm_slide_back(fit.slide_back);
  header.set_psm_light_near(fit.light_near);
  header.set_psm_light_far(fit.light_far);
  header.set_psm_cube_texel_min(fit.cube_texel_min);
  header.set_psm_cube_texel_max(fit.cube_texel_max);
  for (const CubeFaceReport& face : fit.cube_faces) {
    v1::CubeFaceReport& out = *header.add_cube_faces();
    out.set_face(face.name);
    out.set_rendered(face.rendered);
    out.set_reason(face.reason);
  }
  for (const PassTiming& timing : result.timings) {
    v1::PassTiming* out = header.add_timings();
    out->set_pass(timing.pass);
    out->set_device_ms(timing.device_ms);
  }
  return header;
}

// Whole values per chunk, so a big-endian host can swap each chunk on its own.
template <class T>
bool send_values(const std::vector<T>& data, size_t per_chunk, v1::TextureChunk& chunk,
                 const v1::RenderResponse& response,
                 const std::function<bool(const v1::RenderResponse&)>& write) {
  per_chunk = std::max<size_t>(1, per_chunk);
  for (size_t first = 0; first < data.size(); first += per_chunk) {
    const size_t count = std::min(per_chunk, data.size() - first);
    chunk.set_offset(uint64_t(first) * sizeof(T));
    std::string* bytes = chunk.mutable_data();
    bytes->resize(count * sizeof(T));
    host_to_le(data.data() + first, count, bytes->data());
    if (!write(response)) return false;
  }
  return true;
}

bool stream_result(const RenderResult& result, size_t chunk_bytes,
                   const std::function<bool(const v1::RenderResponse&)>& write) {
  // Whole floats per chunk, so a big-endian host can swap each chunk on its own.
  const size_t floats_per_chunk = std::max<size_t>(1, chunk_bytes / kFloatBytes);
  v1::RenderResponse response;
  *response.mutable_header() = make_header(result);
  if (!write(response)) return false;

  v1::TextureChunk* chunk = response.mutable_chunk();
  for (size_t i = 0; i < result.textures.size(); ++i) {
    chunk->set_texture(uint32_t(i));
    if (!send_values(result.textures[i].data, floats_per_chunk, *chunk, response, write) ||
        !send_values(result.textures[i].data64, floats_per_chunk / 2, *chunk, response, write))
      return false;
  }
  return true;
}

void ResultAssembler::add(const v1::RenderResponse& response) {
  switch (response.payload_case()) {
    case v1::RenderResponse::kHeader:
      add_header(response.header());
      break;
    case v1::RenderResponse::kChunk:
      add_chunk(response.chunk());
      break;
    case v1::RenderResponse::PAYLOAD_NOT_SET:
      throw StreamError("a response carries neither a header nor a chunk");
  }
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
    texture_bytes(t.width, t.height, t.channels, t.faces, &bytes, t.value_bytes());
    if (t.format == PixelFormat::kFloat64)
      t.data64.resize(bytes / sizeof(double));
    else
      t.data.resize(bytes / kFloatBytes);
  }
  received_.assign(result_.textures.size(), 0);
  for (const std::string& pass : header.passes()) result_.passes.push_back(pass);
  LightFitReport& fit = result_.light_fit;
  fit.light_case = header.light_case();
  fit.virtual_near = header.psm_virtual_near();
  fit.virtual_far = header.psm_virtual_far();
  fit.slide_back = header.psm_slide_back();
  fit.light_near = header.psm_light_near();
  fit.light_far = header.psm_light_far();
  fit.cube_texel_min = header.psm_cube_texel_min();
  fit.cube_texel_max = header.psm_cube_texel_max();
  for (const v1::CubeFaceReport& face : header.cube_faces())
    fit.cube_faces.push_back({face.face(), face.rendered(), face.reason()});
  for (const v1::PassTiming& timing : header.timings()) {
    result_.timings.push_back({timing.pass(), timing.device_ms()});
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
  if (chunk.data().size() > size - received) {
    throw StreamError("a chunk of " + where + " ends at byte " +
                      std::to_string(received + chunk.data().size()) + ", past its size " +
                      std::to_string(size));
  }
  char* base = t.format == PixelFormat::kFloat64 ? reinterpret_cast<char*>(t.data64.data())
                                                 : reinterpret_cast<char*>(t.data.data());
  std::copy(chunk.data().begin(), chunk.data().end(), base + received);
  received += chunk.data().size();
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
  if constexpr (std::endian::native == std::endian::big) {
    for (Texture& t : result_.textures) {
      for (float& v : t.data) {
        uint32_t u = std::bit_cast<uint32_t>(v);
        v = std::bit_cast<float>(__builtin_bswap32(u));
      }
      for (double& v : t.data64)
        v = std::bit_cast<double>(__builtin_bswap64(std::bit_cast<uint64_t>(v)));
    }
  }
  have_header_ = false;
  received_.clear();
  return std::move(result_);
}

}  // namespace shadow::convert
