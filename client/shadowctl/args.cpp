#include "shadowctl/args.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "output/output_options.hpp"
#include "wire/names.hpp"

namespace shadow::ctl {
namespace {

std::vector<std::string_view> split(std::string_view text, char sep) {
  std::vector<std::string_view> parts;
  size_t start = 0;
  for (size_t at; (at = text.find(sep, start)) != std::string_view::npos; start = at + 1)
    parts.push_back(text.substr(start, at - start));
  parts.push_back(text.substr(start));
  return parts;
}

std::string quoted(std::string_view text) {
  return "'" + std::string(text) + "'";
}

// A value by its name in the enum's table (wire/names.hpp); the error lists the table's names.
template <class Value, class Proto>
Value parse_name(const names::Table<Value, Proto>& table, std::string_view text,
                 std::string_view flag) {
  if (const std::optional<Value> value = table.parse(text)) return *value;
  throw FlagError(flag, table.unknown_name(text));
}

}  // namespace

float parse_float(std::string_view text, std::string_view flag) {
  float value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(value))
    throw FlagError(flag, "expected a finite number, got " + quoted(text));
  return value;
}

uint32_t parse_uint(std::string_view text, std::string_view flag) {
  uint32_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end)
    throw FlagError(flag, "expected a whole number, got " + quoted(text));
  return value;
}

glm::vec3 parse_vec3(std::string_view text, std::string_view flag) {
  const auto parts = split(text, ',');
  if (parts.size() != 3) throw FlagError(flag, "expected X,Y,Z, got " + quoted(text));
  glm::vec3 v;
  for (int i = 0; i < 3; ++i) {
    try {
      v[i] = parse_float(parts[i], flag);
    } catch (const FlagError&) {
      throw FlagError(flag, "expected X,Y,Z with three numbers, got " + quoted(text));
    }
  }
  return v;
}

ImageSize parse_size(std::string_view text, std::string_view flag) {
  const size_t x = text.find_first_of("xX");
  if (x == std::string_view::npos) throw FlagError(flag, "expected WxH, got " + quoted(text));
  ImageSize size;
  try {
    size = {parse_uint(text.substr(0, x), flag), parse_uint(text.substr(x + 1), flag)};
  } catch (const FlagError&) {
    size = {};
  }
  // 0 is how the request says "unset": the server's default would replace it.
  if (size.width == 0 || size.height == 0)
    throw FlagError(
        flag, "expected WxH with whole numbers of at least 1, e.g. 1280x720, got " + quoted(text));
  return size;
}

Light parse_light(std::string_view text, std::string_view flag) {
  const auto parts = split(text, ':');
  const std::string_view kind = parts[0];
  const auto expect = [&](size_t n, const char* form) {
    if (parts.size() != n)
      throw FlagError(flag, std::string("expected ") + form + ", got " + quoted(text));
  };
  Light light;
  light.type = parse_name(names::kLightTypes, kind, flag);
  switch (light.type) {
    case LightType::kDirectional:
      expect(2, "directional:DX,DY,DZ");
      light.direction = parse_vec3(parts[1], flag);
      break;
    case LightType::kSpot:
      expect(4, "spot:PX,PY,PZ:DX,DY,DZ:CONE_DEG");
      light.position = parse_vec3(parts[1], flag);
      light.direction = parse_vec3(parts[2], flag);
      light.cone_angle_deg = parse_float(parts[3], flag);
      break;
    case LightType::kPoint:
      expect(2, "point:PX,PY,PZ");
      light.position = parse_vec3(parts[1], flag);
      break;
  }
  return light;
}

std::vector<Product> parse_products(std::string_view text, std::string_view flag) {
  std::vector<Product> products;
  for (std::string_view name : split(text, ',')) {
    const Product p = parse_name(names::kProducts, name, flag);
    if (std::find(products.begin(), products.end(), p) != products.end())
      throw FlagError(flag, quoted(name) + " is listed twice");
    products.push_back(p);
  }
  return products;
}

FilterKind parse_filter(std::string_view text, std::string_view flag) {
  return parse_name(names::kFilterKinds, text, flag);
}

CsmStorage parse_csm_storage(std::string_view text, std::string_view flag) {
  return parse_name(names::kCsmStorages, text, flag);
}

CsmLookup parse_csm_lookup(std::string_view text, std::string_view flag) {
  return parse_name(names::kCsmLookups, text, flag);
}

bool parse_bool(std::string_view text, std::string_view flag) {
  if (text == "on" || text == "true") return true;
  if (text == "off" || text == "false") return false;
  throw FlagError(flag, "expected on or off, got " + quoted(text));
}

ReceiverClass parse_receiver_class(std::string_view text, std::string_view flag) {
  const auto parts = split(text, ':');
  if (parts.size() != 2) throw FlagError(flag, "expected INSTANCE:CLASS, got " + quoted(text));
  try {
    return {parse_uint(parts[0], flag), parse_uint(parts[1], flag)};
  } catch (const FlagError&) {
    throw FlagError(flag,
                    "expected INSTANCE:CLASS with whole numbers, e.g. 0:1, got " + quoted(text));
  }
}

Technique parse_technique(std::string_view text, std::string_view flag) {
  return parse_name(names::kTechniques, text, flag);
}

PsmCasters parse_psm_casters(std::string_view text, std::string_view flag) {
  return parse_name(names::kPsmCasters, text, flag);
}

PixelFormat parse_pixel_format(std::string_view text, std::string_view flag) {
  return parse_name(names::kPixelFormats, text, flag);
}

MapFit parse_map_fit(std::string_view text, std::string_view flag) {
  return parse_name(names::kMapFits, text, flag);
}

PsmNear parse_psm_near(std::string_view text, std::string_view flag) {
  return parse_name(names::kPsmNear, text, flag);
}

ChunkCompression parse_chunk_compression(std::string_view text, std::string_view flag) {
  return parse_name(names::kChunkCompressions, text, flag);
}

std::string parse_exr_compression(std::string_view text, std::string_view flag) {
  if (output::known_exr_compression(text)) return std::string(text);
  std::string names;
  for (std::string_view n : output::kExrCompressions)
    names += (names.empty() ? "" : ", ") + std::string(n);
  throw FlagError(flag, "unknown EXR compression " + quoted(text) + " (expected " + names + ")");
}

output::Preview parse_preview(std::string_view text, std::string_view flag) {
  if (text == "png") return output::Preview::kPng;
  if (text == "full") return output::Preview::kFull;
  if (text == "none") return output::Preview::kNone;
  throw FlagError(flag, "expected png, full or none, got " + quoted(text));
}

}  // namespace shadow::ctl
