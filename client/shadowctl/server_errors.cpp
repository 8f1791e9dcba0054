#include "shadowctl/server_errors.hpp"

#include <algorithm>
#include <cctype>
#include <map>
#include <vector>

#include "shadow/v1/shadow.pb.h"
#include "wire/names.hpp"

namespace shadow::ctl {
namespace {

// Proto field paths (indices written "[]") and the shadowctl flag that sets each. The longest
// path that is a prefix of an error's field decides, so "scene" covers every scene field that no
// longer row names. Fields with no row (atlas_sat.blocker_samples) have no flag.
struct FieldRow {
  std::string_view path;
  std::string_view flag;
};
constexpr FieldRow kFieldFlags[] = {
    {"scene", "--scene"},
    {"scene_id", "--scene-id"},
    {"scene.instances[].receiver_class", "--receiver-class"},
    {"camera", "--eye, --target"},
    {"camera.eye", "--eye"},
    {"camera.target", "--target"},
    {"camera.up", "--up"},
    {"camera.fov_deg", "--fov"},
    {"camera.width", "--size"},
    {"camera.height", "--size"},
    {"camera.near", "--near"},
    {"camera.far", "--far"},
    {"lights", "--light"},
    {"lights[]", "--light"},
    {"lights[].size", "--light-size"},
    {"lights[].directional", "--light directional:DX,DY,DZ"},
    {"lights[].spot", "--light spot:PX,PY,PZ:DX,DY,DZ:CONE_DEG"},
    {"lights[].point", "--light point:PX,PY,PZ"},
    {"shadow_map.size", "--map-size"},
    {"shadow_map.technique", "--technique"},
    {"shadow_map.fit", "--fit"},
    {"shadow_map.bias_constant", "--bias-constant"},
    {"shadow_map.bias_slope", "--bias-slope"},
    {"shadow_map.bias_world_constant", "--bias-world-constant"},
    {"shadow_map.bias_world_texel", "--bias-world-texel"},
    {"shadow_map.psm_casters", "--psm-casters"},
    {"shadow_map.psm_near", "--psm-near"},
    {"shadow_map.psm_virtual_slide", "--psm-virtual-slide"},
    {"shadow_map.lispsm_n", "--lispsm-n"},
    {"shadow_map.virtual_lod_bias", "--virtual-lod-bias"},
    {"shadow_map.virtual_pool_pages", "--virtual-pool-pages"},
    {"shadow_map.virtual_refuse_coarsening", "--virtual-refuse-coarsening"},
    {"filter", "--filter"},
    {"filter.poisson", "--filter poisson"},
    {"filter.poisson.taps", "--pcf-taps"},
    {"filter.poisson.radius", "--pcf-radius"},
    {"filter.poisson.rotate", "--pcf-rotate"},
    {"filter.pcss", "--filter pcss"},
    {"filter.pcss.blocker_samples", "--pcss-blocker-samples"},
    {"filter.pcss.filter_samples", "--pcss-filter-samples"},
    {"filter.pcss.rotate", "--pcss-rotate"},
    {"filter.blur", "--filter blur"},
    {"filter.blur.radius", "--blur-radius"},
    {"filter.blur.passes", "--blur-passes"},
    {"filter.csm", "--filter csm"},
    {"filter.pcss_csm", "--filter pcss_csm"},
    {"filter.csm.terms", "--csm-terms"},
    {"filter.pcss_csm.terms", "--csm-terms"},
    {"filter.csm.storage", "--csm-storage"},
    {"filter.pcss_csm.storage", "--csm-storage"},
    {"filter.csm.lookup", "--csm-lookup"},
    {"filter.pcss_csm.lookup", "--csm-lookup"},
    {"filter.csm.window", "--csm-window"},
    {"filter.csm.damping", "--csm-damping"},
    {"filter.pcss_csm.damping", "--csm-damping"},
    {"filter.csm.depth_offset", "--csm-depth-offset"},
    {"filter.pcss_csm.depth_offset", "--csm-depth-offset"},
    {"filter.csm.scale", "--csm-scale"},
    {"filter.pcss_csm.scale", "--csm-scale"},
    {"filter.atlas_sat", "--filter atlas_sat"},
    {"filter.atlas_mip", "--filter atlas_mip"},
    // A share on the wire, a percentage on the command line.
    {"quality", "--max-error or --max-device-ms"},
    {"quality.max_error", "--max-error (a percentage: 100 x the share)"},
    {"quality.max_device_ms", "--max-device-ms"},
    {"products", "--products"},
    {"pixel_format", "--pixel-format"},
    {"chunk_compression", "--chunk-compression"},
    {"atlas.tile_size", "--atlas-tile"},
    {"atlas.texel_world_size", "--atlas-density"},
    {"atlas.gutter", "--atlas-gutter"},
    {"atlas.generate_uvs", "--atlas-generate-uvs"},
};

bool is_path_char(char c) {
  return std::islower(static_cast<unsigned char>(c)) ||
         std::isdigit(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '[' ||
         c == ']';
}

// "scene.meshes[3].uvs" -> "scene.meshes[].uvs".
std::string without_indices(std::string_view path) {
  std::string out;
  for (size_t i = 0; i < path.size(); ++i) {
    out += path[i];
    if (path[i] != '[') continue;
    size_t close = path.find(']', i);
    if (close == std::string_view::npos) break;
    i = close - 1;
  }
  return out;
}

// Whether `path` is `prefix` or lies under it.
bool under(std::string_view path, std::string_view prefix) {
  return path.substr(0, prefix.size()) == prefix &&
         (path.size() == prefix.size() || path[prefix.size()] == '.' || path[prefix.size()] == '[');
}

// The number in "NAME[N]" at the start of `path` (after `name`), or -1.
long index_after(std::string_view path, std::string_view name) {
  if (path.substr(0, name.size() + 1) != std::string(name) + "[") return -1;
  const size_t close = path.find(']');
  if (close == std::string_view::npos) return -1;
  try {
    return std::stol(std::string(path.substr(name.size() + 1, close - name.size() - 1)));
  } catch (const std::exception&) {
    return -1;
  }
}

// Proto enum value names ("TECHNIQUE_LISPSM") -> "--technique lispsm", from the name tables.
template <class Value, class Proto, class NameOf>
void add_values(std::map<std::string, std::string>& out, const names::Table<Value, Proto>& table,
                std::string_view flag, NameOf proto_name) {
  for (const auto& row : table.rows())
    out[std::string(proto_name(row.proto))] = std::string(flag) + " " + std::string(row.name);
}

const std::map<std::string, std::string>& enum_flags() {
  static const std::map<std::string, std::string> flags = [] {
    std::map<std::string, std::string> m;
    add_values(m, names::kTechniques, "--technique",
               [](v1::Technique p) { return v1::Technique_Name(p); });
    add_values(m, names::kMapFits, "--fit", [](v1::MapFit p) { return v1::MapFit_Name(p); });
    add_values(m, names::kPsmCasters, "--psm-casters",
               [](v1::PsmCasterMode p) { return v1::PsmCasterMode_Name(p); });
    add_values(m, names::kPsmNear, "--psm-near",
               [](v1::PsmNearMode p) { return v1::PsmNearMode_Name(p); });
    add_values(m, names::kCsmStorages, "--csm-storage",
               [](v1::CsmStorage p) { return v1::CsmStorage_Name(p); });
    add_values(m, names::kCsmLookups, "--csm-lookup",
               [](v1::CsmLookup p) { return v1::CsmLookup_Name(p); });
    add_values(m, names::kProducts, "--products",
               [](v1::Product p) { return v1::Product_Name(p); });
    add_values(m, names::kPixelFormats, "--pixel-format",
               [](v1::PixelFormat p) { return v1::PixelFormat_Name(p); });
    add_values(m, names::kChunkCompressions, "--chunk-compression",
               [](v1::ChunkCompression p) { return v1::ChunkCompression_Name(p); });
    return m;
  }();
  return flags;
}

}  // namespace

std::string flag_for_field(std::string_view field) {
  if (field.substr(0, 5) == "base.") field.remove_prefix(5);  // a sequence's base: the flags
  if (const long frame = index_after(field, "frames"); frame >= 0)
    return "frame " + std::to_string(frame) + " of --frames";
  const std::string path = without_indices(field);
  const FieldRow* best = nullptr;
  for (const FieldRow& row : kFieldFlags)
    if (under(path, row.path) && (!best || row.path.size() > best->path.size())) best = &row;
  if (!best) return "";
  std::string flag(best->flag);
  // With several lights, which one: lights[i] is the (i+1)-th --light (the first goes unsaid).
  if (const long light = index_after(field, "lights");
      light >= 1 && flag.rfind("--light", 0) == 0 && flag.rfind("--light-size", 0) != 0)
    flag += " (--light number " + std::to_string(light + 1) + ")";
  return flag;
}

std::string flag_for_enum_value(std::string_view name) {
  const auto& flags = enum_flags();
  const auto it = flags.find(std::string(name));
  return it == flags.end() ? "" : it->second;
}

std::string flag_note(grpc::StatusCode code, std::string_view message) {
  if (code != grpc::StatusCode::INVALID_ARGUMENT && code != grpc::StatusCode::RESOURCE_EXHAUSTED)
    return "";
  std::vector<std::string> parts;
  const auto mentioned = [&](const std::string& flag) {
    // The flag itself, before any explanation in parentheses.
    return message.find(flag.substr(0, flag.find(" ("))) != std::string_view::npos;
  };
  // The leading field: "path: why".
  std::string field;
  if (const size_t colon = message.find(": "); colon != std::string_view::npos && colon > 0) {
    const std::string_view head = message.substr(0, colon);
    bool path = true;
    for (char c : head) path = path && is_path_char(c);
    if (path) field = std::string(head);
  }
  if (!field.empty())
    if (const std::string flag = flag_for_field(field); !flag.empty() && !mentioned(flag))
      parts.push_back(field + " is " + flag);
  // Enum value names: runs of capitals, digits and underscores.
  std::vector<std::string> seen;
  for (size_t i = 0; i < message.size();) {
    if (!std::isupper(static_cast<unsigned char>(message[i]))) {
      ++i;
      continue;
    }
    size_t end = i;
    while (end < message.size() &&
           (std::isupper(static_cast<unsigned char>(message[end])) ||
            std::isdigit(static_cast<unsigned char>(message[end])) || message[end] == '_'))
      ++end;
    const bool word_start = i == 0 || !std::isalnum(static_cast<unsigned char>(message[i - 1]));
    const std::string name(message.substr(i, end - i));
    i = end;
    if (!word_start || std::find(seen.begin(), seen.end(), name) != seen.end()) continue;
    seen.push_back(name);
    if (const std::string flag = flag_for_enum_value(name); !flag.empty() && !mentioned(flag))
      parts.push_back(name + " is " + flag);
  }
  // A mesh's own UVs the atlas cannot use (outside [0, 1], overlapping, all on one point): the
  // server can lay the mesh out instead.
  const std::string path = without_indices(field);
  if (code == grpc::StatusCode::INVALID_ARGUMENT && under(path, "scene.meshes[].uvs") &&
      !mentioned("--atlas-generate-uvs"))
    parts.push_back("--atlas-generate-uvs has the server lay out every receiving mesh instead");
  if (parts.empty()) return "";
  std::string note = " (shadowctl: ";
  for (size_t i = 0; i < parts.size(); ++i) note += (i ? "; " : "") + parts[i];
  return note + ")";
}

}  // namespace shadow::ctl
