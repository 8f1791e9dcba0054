// glTF 2.0 (.gltf with external or embedded buffers, and .glb) through tinygltf. Geometry only:
// images are skipped so a missing texture never stops a shadow render.
//
// The file is read here, size-bounded, and handed to tinygltf from memory. Before tinygltf sees
// it: the GLB container is checked (tinygltf 2.7 lets the BIN chunk run 8 bytes past the file),
// and the JSON's nesting depth is bounded and what tinygltf will build from it is estimated and
// charged to the budget. tinygltf reaches the file system only through the callbacks below,
// which resolve a buffer URI only to a regular file inside the glTF's own folder.
#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include <tiny_gltf.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "scenes/gltf_accessor.hpp"
#include "scenes/load_budget.hpp"
#include "scenes/scene_loader.hpp"

namespace shadow::scenes {
namespace {

namespace fs = std::filesystem;

bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                const unsigned char*, int, void*) {
  return true;
}

// --- the file system, as tinygltf may see it ---------------------------------------------------

struct FsContext {
  fs::path folder;       // canonical folder of the glTF file
  std::string base_dir;  // folder as handed to tinygltf, which joins base_dir + "/" + uri
  LoadBudget* budget = nullptr;
  // Files refused or failed to read: the (decoded) URI tinygltf names in its error, and why.
  std::vector<std::pair<std::string, std::string>> refusals;
};

// Why tinygltf's `joined` (base_dir + "/" + decoded URI) may not be read; empty if it may, with
// the file in `file`. `uri` receives the URI part (empty when `joined` is not under base_dir at
// all: tinygltf also tries "./" + uri, the current directory, which is never allowed).
std::string check_path(const FsContext& ctx, const std::string& joined, fs::path& file,
                       std::string& uri) {
  const std::string prefix = ctx.base_dir.back() == '/' ? ctx.base_dir : ctx.base_dir + "/";
  uri.clear();
  if (joined.compare(0, prefix.size(), prefix) != 0) return "is not in the glTF's folder";
  uri = joined.substr(prefix.size());
  if (uri.empty()) return "is empty";
  if (uri.find('\0') != std::string::npos) return "contains a NUL byte";
  if (uri.front() == '/') return "is an absolute path; only files in the glTF's folder are read";
  const std::string first = uri.substr(0, uri.find('/'));
  if (first.find(':') != std::string::npos) return "is not a data: URI or a relative file name";
  for (const auto& part : fs::path(uri))
    if (part == "..") return "contains '..'; only files in the glTF's folder are read";
  std::error_code ec;
  file = fs::canonical(ctx.folder / uri, ec);
  if (ec) return "does not exist";
  const fs::path inside = file.lexically_relative(ctx.folder);
  if (inside.empty() || *inside.begin() == ".." || *inside.begin() == ".")
    return "resolves to " + file.string() + ", outside the glTF's folder";
  if (!fs::is_regular_file(file, ec)) return "is not a regular file";
  return "";
}

std::string expand_path(const std::string& path, void*) {
  return path;
}

bool file_exists(const std::string& joined, void* user) {
  auto& ctx = *static_cast<FsContext*>(user);
  try {
    fs::path file;
    std::string uri;
    const std::string why = check_path(ctx, joined, file, uri);
    if (why.empty()) return true;
    if (!uri.empty()) ctx.refusals.emplace_back(uri, quote_token(uri) + " " + why);
  } catch (const std::exception&) {  // e.g. bad_alloc: refuse, never throw into tinygltf
  }
  return false;
}

bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& joined,
                     void* user) {
  auto& ctx = *static_cast<FsContext*>(user);
  std::string uri;
  try {
    fs::path file;
    const std::string why = check_path(ctx, joined, file, uri);
    if (!why.empty()) {
      if (err) *err = why;
      if (!uri.empty()) ctx.refusals.emplace_back(uri, quote_token(uri) + " " + why);
      return false;
    }
    read_file_bounded(file, *ctx.budget, *out);
    return true;
  } catch (const std::exception& e) {
    if (err) *err = e.what();
    if (!uri.empty()) ctx.refusals.emplace_back(uri, quote_token(uri) + ": " + e.what());
    return false;
  }
}

bool write_whole_file(std::string*, const std::string&, const std::vector<unsigned char>&, void*) {
  return false;
}

// --- what tinygltf gets to parse -----------------------------------------------------------------

constexpr size_t kMaxJsonDepth = 64;  // glTF itself needs about 8; tinygltf recurses on extras

// What tinygltf 2.7 builds from a JSON text, estimated from its tokens: a JSON DOM node per value
// and a map node per member, its own struct per element of the arrays it keeps (nodes,
// materials, ...; twice, for vector growth), a tinygltf::Value per value under "extras" and
// "extensions", and strings copied a few times (a data: URI is decoded from a copy). Throws if
// the nesting is deeper than kMaxJsonDepth.
uint64_t estimate_json(std::string_view json, const std::string& file) {
  constexpr uint64_t kValue = 32, kMember = 96, kTreeValue = sizeof(tinygltf::Value) + 64;
  constexpr uint64_t kStringFactor = 4;
  const auto element_bytes = [](std::string_view key) -> uint64_t {
    static const std::map<std::string_view, uint64_t> sizes = {
        {"accessors", sizeof(tinygltf::Accessor)},
        {"animations", sizeof(tinygltf::Animation)},
        {"buffers", sizeof(tinygltf::Buffer)},
        {"bufferViews", sizeof(tinygltf::BufferView)},
        {"cameras", sizeof(tinygltf::Camera)},
        {"channels", sizeof(tinygltf::AnimationChannel)},
        {"images", sizeof(tinygltf::Image)},
        {"lights", sizeof(tinygltf::Light)},
        {"materials", sizeof(tinygltf::Material)},
        {"meshes", sizeof(tinygltf::Mesh)},
        {"nodes", sizeof(tinygltf::Node)},
        {"primitives", sizeof(tinygltf::Primitive)},
        {"samplers", std::max(sizeof(tinygltf::Sampler), sizeof(tinygltf::AnimationSampler))},
        {"scenes", sizeof(tinygltf::Scene)},
        {"skins", sizeof(tinygltf::Skin)},
        {"textures", sizeof(tinygltf::Texture)},
    };
    const auto it = sizes.find(key);
    return it == sizes.end() ? 0 : 2 * it->second;
  };
  struct Frame {
    bool object;
    uint64_t element;  // bytes per element of this array, 0 if none
    bool tree;         // under "extras" or "extensions"
  };
  std::vector<Frame> stack;
  std::string_view key;  // the member name just read, in an object
  uint64_t bytes = 0;
  const auto value = [&](uint64_t extra) {
    bytes += kValue + extra;
    if (!stack.empty()) {
      if (stack.back().tree) bytes += kTreeValue;
      if (!stack.back().object) bytes += stack.back().element;
    }
  };
  const size_t n = json.size();
  for (size_t i = 0; i < n;) {
    const char c = json[i];
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == ',' || c == ':') {
      ++i;
    } else if (c == '"') {
      size_t end = i + 1;
      while (end < n && json[end] != '"') end += json[end] == '\\' ? 2 : 1;
      const std::string_view text = json.substr(i + 1, std::min(end, n) - i - 1);
      i = end + 1;
      size_t next = i;
      while (next < n &&
             (json[next] == ' ' || json[next] == '\t' || json[next] == '\n' || json[next] == '\r'))
        ++next;
      const uint64_t copies = text.size() > 15 ? kStringFactor * text.size() : 0;
      if (!stack.empty() && stack.back().object && next < n && json[next] == ':') {
        key = text;
        bytes += kMember + copies;
      } else {
        value(copies);
      }
    } else if (c == '{' || c == '[') {
      value(0);
      if (stack.size() >= kMaxJsonDepth)
        throw std::runtime_error(file + ": JSON nesting is deeper than " +
                                 std::to_string(kMaxJsonDepth) + " levels");
      const bool parent_object = !stack.empty() && stack.back().object;
      const bool tree = (!stack.empty() && stack.back().tree) ||
                        (parent_object && (key == "extras" || key == "extensions"));
      stack.push_back({c == '{', (c == '[' && parent_object) ? element_bytes(key) : 0, tree});
      key = {};
      ++i;
    } else if (c == '}' || c == ']') {
      if (!stack.empty()) stack.pop_back();
      ++i;
    } else {  // a number, true, false, null or junk (a NUL byte too): one token, at least a byte
      constexpr std::string_view kEnds = ",:]}\"{[ \t\r\n";
      do {
        ++i;
      } while (i < n && kEnds.find(json[i]) == std::string_view::npos);
      value(0);
    }
  }
  return bytes;
}

uint32_t le32(std::string_view bytes, size_t at) {
  uint32_t v;
  std::memcpy(&v, bytes.data() + at, 4);
  return v;  // GLB is little-endian, as is every machine this builds on
}

// The GLB container, checked strictly; returns the JSON chunk and sets `length` to the bytes
// tinygltf may look at.
std::string_view check_glb(std::string_view bytes, const std::string& file, uint32_t& length) {
  const auto fail = [&](const std::string& why) -> std::string_view {
    throw std::runtime_error(file + ": not a valid GLB file: " + why);
  };
  if (bytes.size() < 20) return fail("the header is cut short");
  if (le32(bytes, 4) != 2) return fail("version " + std::to_string(le32(bytes, 4)) + ", not 2");
  length = le32(bytes, 8);
  if (length > bytes.size())
    return fail("the header says " + std::to_string(length) + " bytes, the file has " +
                std::to_string(bytes.size()));
  const uint64_t json_bytes = le32(bytes, 12);
  if (le32(bytes, 16) != 0x4E4F534A) return fail("the first chunk is not JSON");
  const uint64_t json_end = 20 + json_bytes;
  if (json_end > length)
    return fail("the JSON chunk (" + std::to_string(json_bytes) + " bytes) runs past the end");
  if (json_end < length) {
    if (json_end + 8 > length) return fail("the BIN chunk's header is cut short");
    const uint64_t bin_bytes = le32(bytes, json_end);
    if (json_end + 8 + bin_bytes > length)
      return fail("the BIN chunk (" + std::to_string(bin_bytes) + " bytes) runs past the end");
  }
  return bytes.substr(20, json_bytes);
}

// --- the scene
// ------------------------------------------------------------------------------------

glm::dmat4 local_transform(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) return glm::make_mat4(node.matrix.data());  // column-major
  glm::dmat4 t(1.0), r(1.0), s(1.0);
  if (node.translation.size() == 3)
    t = glm::translate(glm::dmat4(1.0), glm::make_vec3(node.translation.data()));
  if (node.rotation.size() == 4) {
    const auto& q = node.rotation;  // glTF stores x, y, z, w
    r = glm::mat4_cast(glm::dquat(q[3], q[0], q[1], q[2]));
  }
  if (node.scale.size() == 3) s = glm::scale(glm::dmat4(1.0), glm::make_vec3(node.scale.data()));
  return t * r * s;
}

// Triangle list from the primitive's index stream, whatever its topology.
std::vector<uint32_t> triangle_list(int mode, const std::vector<uint32_t>& idx, LoadBudget& budget,
                                    const std::string& what) {
  std::vector<uint32_t> out;
  const size_t n = idx.size();
  const size_t triangles = mode == TINYGLTF_MODE_TRIANGLES ? n / 3 : (n >= 3 ? n - 2 : 0);
  budget.charge(triangles, 3 * sizeof(uint32_t), what + " triangles");
  out.reserve(3 * triangles);
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    out.assign(idx.begin(), idx.begin() + n / 3 * 3);
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 0; i + 2 < n; ++i) {  // alternate winding so every triangle faces the same way
      const size_t odd = i % 2;
      out.insert(out.end(), {idx[i], idx[i + 1 + odd], idx[i + 2 - odd]});
    }
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t i = 1; i + 1 < n; ++i) out.insert(out.end(), {idx[i], idx[i + 1], idx[0]});
  }
  return out;
}

class Builder {
 public:
  Builder(const fs::path& path, const tinygltf::Model& model, LoadBudget& budget)
      : path_(path), model_(model), budget_(budget) {}

  Scene build() {
    std::vector<int> roots;
    const int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
    if (scene < static_cast<int>(model_.scenes.size())) {
      roots = model_.scenes[scene].nodes;
    } else {  // no scenes: every node that is nobody's child is a root
      std::vector<bool> child(model_.nodes.size(), false);
      for (const auto& n : model_.nodes)
        for (int c : n.children)
          if (c >= 0 && c < static_cast<int>(child.size())) child[c] = true;
      for (size_t i = 0; i < child.size(); ++i)
        if (!child[i]) roots.push_back(static_cast<int>(i));
    }
    for (int root : roots) visit(root, glm::dmat4(1.0), 0);
    if (scene_.instances.empty()) fail("the scene contains no triangle primitives");
    return std::move(scene_);
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(path_.string() + ": " + why);
  }

  void visit(int index, const glm::dmat4& parent, int depth) {
    if (index < 0 || index >= static_cast<int>(model_.nodes.size()))
      fail("nodes[" + std::to_string(index) + "] does not exist");
    if (depth > 256) fail("node hierarchy is deeper than 256 levels (a cycle?)");
    // A node listed as the child of several nodes is visited once per path (a DAG doubles with
    // every level), so every visit is charged like the instance it may become.
    budget_.charge(sizeof(Instance), "the node hierarchy (nodes reached through many parents?)");
    const auto& node = model_.nodes[index];
    const glm::dmat4 world = parent * local_transform(node);
    if (node.mesh >= 0) {
      if (node.mesh >= static_cast<int>(model_.meshes.size()))
        fail("nodes[" + std::to_string(index) + "].mesh " + std::to_string(node.mesh) +
             " does not exist");
      const glm::mat4 transform(world);
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
          if (!std::isfinite(transform[c][r]))
            fail("nodes[" + std::to_string(index) + "]: the world transform is not finite");
      const auto& prims = model_.meshes[node.mesh].primitives;
      for (size_t p = 0; p < prims.size(); ++p) {
        const int mesh = mesh_for(node.mesh, static_cast<int>(p));
        if (mesh < 0) continue;
        grow(scene_.instances, 1, budget_, "the scene's instances");
        Instance instance;
        instance.mesh = static_cast<uint32_t>(mesh);
        instance.transform = transform;
        scene_.instances.push_back(instance);
      }
    }
    for (int child : node.children) visit(child, world, depth + 1);
  }

  // Engine mesh index for a primitive, converted once; -1 if it has no triangles.
  int mesh_for(int gltf_mesh, int primitive) {
    auto [it, inserted] = cache_.try_emplace({gltf_mesh, primitive}, -1);
    if (!inserted) return it->second;
    const std::string where =
        "meshes[" + std::to_string(gltf_mesh) + "].primitives[" + std::to_string(primitive) + "]";
    try {
      Mesh mesh = convert(model_.meshes[gltf_mesh].primitives[primitive], where);
      if (mesh.indices.empty()) return -1;
      grow(scene_.meshes, 1, budget_, "the scene's meshes");
      scene_.meshes.push_back(std::move(mesh));
      it->second = static_cast<int>(scene_.meshes.size() - 1);
    } catch (const BudgetExceeded&) {
      throw;  // names the file already
    } catch (const std::runtime_error& e) {
      fail(e.what());
    }
    return it->second;
  }

  Mesh convert(const tinygltf::Primitive& prim, const std::string& where) const {
    Mesh mesh;
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        prim.mode != TINYGLTF_MODE_TRIANGLE_FAN)
      return mesh;  // points and lines cast no shadows
    const auto attr = [&](const char* name) {
      auto it = prim.attributes.find(name);
      return it == prim.attributes.end() ? -1 : it->second;
    };
    const auto error = [&](const std::string& why) {
      return std::runtime_error(where + ": " + why);
    };
    const int position = attr("POSITION");
    if (position < 0) throw error("has no POSITION attribute");
    mesh.positions = read_float_accessor(model_, position, 3, budget_, where + " POSITION");
    const size_t vertices = mesh.vertex_count();
    if (const int normal = attr("NORMAL"); normal >= 0) {
      mesh.normals = read_float_accessor(model_, normal, 3, budget_, where + " NORMAL");
      if (mesh.normals.size() != mesh.positions.size())
        throw error("NORMAL count differs from POSITION count");
    }
    if (const int uv = attr("TEXCOORD_0"); uv >= 0) {
      mesh.uvs = read_float_accessor(model_, uv, 2, budget_, where + " TEXCOORD_0");
      if (mesh.uvs.size() / 2 != vertices)
        throw error("TEXCOORD_0 count differs from POSITION count");
    }
    std::vector<uint32_t> indices;
    if (prim.indices >= 0) {
      indices = read_index_accessor(model_, prim.indices, budget_, where + " indices");
    } else {
      budget_.charge(vertices, sizeof(uint32_t), where + " indices");
      indices.resize(vertices);
      for (size_t i = 0; i < vertices; ++i) indices[i] = static_cast<uint32_t>(i);
    }
    for (size_t i = 0; i < indices.size(); ++i)
      if (indices[i] >= vertices)
        throw error("index " + std::to_string(i) + " is " + std::to_string(indices[i]) +
                    ", but there are only " + std::to_string(vertices) + " vertices");
    mesh.indices = triangle_list(prim.mode, indices, budget_, where);
    return mesh;
  }

  const fs::path& path_;
  const tinygltf::Model& model_;
  LoadBudget& budget_;
  Scene scene_;
  std::map<std::pair<int, int>, int> cache_;
};

}  // namespace

Scene load_gltf(const fs::path& path, const LoadLimits& limits) {
  const std::string file = path.string();
  if (!fs::is_regular_file(path)) throw std::runtime_error(file + ": no such file");
  LoadBudget budget(path, limits);
  const std::string bytes = read_file_bounded(path, budget);

  FsContext ctx;
  std::error_code ec;
  ctx.folder = fs::canonical(path, ec).parent_path();
  if (ec) throw std::runtime_error(file + ": cannot resolve its folder: " + ec.message());
  ctx.base_dir = ctx.folder.string();
  ctx.budget = &budget;

  const bool glb = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
  uint32_t glb_length = 0;
  const std::string_view json = glb ? check_glb(bytes, file, glb_length) : std::string_view(bytes);
  if (!glb && bytes.size() > UINT32_MAX)
    throw std::runtime_error(file + ": a .gltf JSON file of 4 GiB or more is not supported");
  budget.charge(estimate_json(json, file), "parsing the glTF JSON");

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  loader.SetFsCallbacks({file_exists, expand_path, read_whole_file, write_whole_file, &ctx});
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    ok = glb ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                           reinterpret_cast<const unsigned char*>(bytes.data()),
                                           glb_length, ctx.base_dir)
             : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(),
                                          static_cast<unsigned int>(bytes.size()), ctx.base_dir);
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(file + ": not a readable glTF 2.0 file: out of memory while parsing");
  } catch (const std::exception& e) {  // e.g. std::out_of_range from a GLB buffer of 0 bytes
    throw std::runtime_error(file + ": not a readable glTF 2.0 file: " + e.what());
  }
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
    // tinygltf says "File not found : <uri>"; say why the file was refused.
    for (const auto& [uri, why] : ctx.refusals)
      if (err.find(uri) != std::string::npos) {
        err = "buffer uri " + why;
        break;
      }
    throw std::runtime_error(file + ": not a readable glTF 2.0 file: " +
                             (err.empty() ? std::string("parse failed") : err));
  }
  return Builder(path, model, budget).build();
}

}  // namespace shadow::scenes
