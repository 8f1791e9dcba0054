// OBJ through tinyobjloader, behind a strict scanner. OBJ indexes positions, normals and UVs
// separately; the engine wants one index per vertex, so every distinct (position, normal, uv)
// corner becomes one vertex.
//
// tinyobjloader reads what it cannot parse as 0 ("v nan 1 0", a face index that overflows
// atoi), so the file is first read here (size-bounded) and every v / vn / vt / f line is checked
// by a small scanner that names file:line and the token. Only the statements the engine uses
// (v, vn, vt, f, o, g) are then handed to tinyobjloader, as a string: no mtllib or other file is
// ever opened, so the loader reads exactly the one file the user pointed at.
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <tiny_obj_loader.h>

#include "scenes/load_budget.hpp"
#include "scenes/scene_loader.hpp"

namespace shadow::scenes {
namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& why) {
  throw std::runtime_error(path.string() + ": " + why);
}

// A face with more corners than this is rejected: tinyobjloader's ear clipping is quadratic to
// cubic in the corner count.
constexpr size_t kMaxFaceVertices = 1024;

bool is_space(char c) {
  return c == ' ' || c == '\t';
}

// Splits like tinyobjloader's safeGetline: "\n", "\r\n" or a lone "\r" ends a line, and a final
// line break does not start another line.
template <typename F>
void for_each_line(std::string_view text, F&& f) {
  size_t number = 0;
  for (size_t i = 0; i < text.size();) {
    size_t end = i;
    while (end < text.size() && text[end] != '\n' && text[end] != '\r') ++end;
    f(++number, text.substr(i, end - i));
    i = (end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n') ? end + 2 : end + 1;
  }
}

// Whitespace-separated tokens after the statement keyword, up to a '#' comment, into `out`
// (reused line after line: no allocation per line).
void tokens_after(std::string_view rest, std::vector<std::string_view>& out) {
  out.clear();
  size_t i = 0;
  while (i < rest.size()) {
    while (i < rest.size() && is_space(rest[i])) ++i;
    if (i == rest.size() || rest[i] == '#') break;
    size_t end = i;
    while (end < rest.size() && !is_space(rest[end])) ++end;
    out.push_back(rest.substr(i, end - i));
    i = end;
  }
}

enum class Statement { kOther, kPosition, kNormal, kUv, kFace, kObject, kGroup };

// The statement as tinyobjloader recognizes it (after leading blanks: keyword then a blank);
// `rest` is what follows the keyword.
Statement classify(std::string_view line, std::string_view& rest) {
  size_t i = 0;
  while (i < line.size() && is_space(line[i])) ++i;
  const std::string_view t = line.substr(i);
  const auto starts = [&](std::string_view keyword) {
    return t.size() > keyword.size() && t.substr(0, keyword.size()) == keyword &&
           is_space(t[keyword.size()]);
  };
  const std::pair<std::string_view, Statement> keywords[] = {
      {"v", Statement::kPosition}, {"vn", Statement::kNormal}, {"vt", Statement::kUv},
      {"f", Statement::kFace},     {"o", Statement::kObject},  {"g", Statement::kGroup}};
  for (const auto& [keyword, statement] : keywords) {
    if (starts(keyword)) {
      rest = t.substr(keyword.size());
      return statement;
    }
  }
  return Statement::kOther;
}

struct Counts {
  uint64_t positions = 0, normals = 0, uvs = 0;
};

class Scanner {
 public:
  Scanner(const std::filesystem::path& path, LoadBudget& budget) : path_(path), budget_(budget) {}

  // The statements tinyobjloader needs, one output line per input line (so its line numbers
  // match), every number and index checked.
  std::string scan(std::string_view text) {
    if (const size_t nul = text.find('\0'); nul != std::string_view::npos) {
      size_t line = 1;
      for (size_t i = 0; i < nul; ++i)
        if (text[i] == '\n' || (text[i] == '\r' && (i + 1 >= nul || text[i + 1] != '\n'))) ++line;
      fail_at(line, "contains a NUL byte (not a text OBJ file)");
    }
    // First pass: totals, since a positive index may refer to a vertex defined further down.
    for_each_line(text, [&](size_t, std::string_view line) {
      std::string_view rest;
      switch (classify(line, rest)) {
        case Statement::kPosition:
          ++total_.positions;
          break;
        case Statement::kNormal:
          ++total_.normals;
          break;
        case Statement::kUv:
          ++total_.uvs;
          break;
        default:
          break;
      }
    });

    std::string out;
    out.reserve(text.size());
    for_each_line(text, [&](size_t number, std::string_view line) {
      line_ = number;
      std::string_view rest;
      const Statement statement = classify(line, rest);
      switch (statement) {
        case Statement::kPosition:
          numbers(out, "v", rest, 3, 7, "coordinate");
          ++seen_.positions;
          budget_.charge(24, "the OBJ positions");
          break;
        case Statement::kNormal:
          numbers(out, "vn", rest, 3, 3, "normal component");
          ++seen_.normals;
          budget_.charge(12, "the OBJ normals");
          break;
        case Statement::kUv:
          numbers(out, "vt", rest, 1, 3, "texture coordinate");
          ++seen_.uvs;
          budget_.charge(8, "the OBJ texture coordinates");
          break;
        case Statement::kFace:
          face(out, rest);
          break;
        case Statement::kObject:
        case Statement::kGroup:
          budget_.charge(2, line.size(), "the OBJ object names");
          out.append(line);
          break;
        case Statement::kOther:  // comments, mtllib, usemtl, s, l, p, t, ...: not needed
          break;
      }
      out += '\n';
    });
    return out;
  }

 private:
  [[noreturn]] void fail_at(size_t line, const std::string& why) const {
    fail(path_.string() + ":" + std::to_string(line), why);
  }
  [[noreturn]] void fail_here(const std::string& why) const { fail_at(line_, why); }

  // "v x y z": between `min` and `max` finite numbers, each within float range.
  void numbers(std::string& out, std::string_view keyword, std::string_view rest, size_t min,
               size_t max, const char* what) {
    tokens_after(rest, tokens_);
    const std::vector<std::string_view>& tokens = tokens_;
    if (tokens.size() < min || tokens.size() > max) {
      const std::string range =
          min == max ? std::to_string(min) : std::to_string(min) + " to " + std::to_string(max);
      fail_here(std::string(keyword) + " takes " + range + " numbers, got " +
                std::to_string(tokens.size()));
    }
    out.append(keyword);
    for (const std::string_view token : tokens) {
      number(token, what);
      out += ' ';
      out.append(token);
    }
  }

  void number(std::string_view token, const char* what) const {
    std::string_view digits = token;
    if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-') digits.remove_prefix(1);
    double value = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (end != digits.data() + digits.size() || ec == std::errc::invalid_argument)
      fail_here(std::string(what) + " " + quote_token(token) + " is not a number");
    if (ec == std::errc::result_out_of_range) {
      // Underflow is fine (a tiny value is 0); overflow is not.
      value = std::strtod(std::string(digits).c_str(), nullptr);
    }
    if (!std::isfinite(value) || std::fabs(value) > std::numeric_limits<float>::max())
      fail_here(std::string(what) + " " + quote_token(token) + " is not a finite float");
  }

  // "f v1 v2 v3 ...", each vertex "i", "i/j", "i//k" or "i/j/k".
  void face(std::string& out, std::string_view rest) {
    tokens_after(rest, tokens_);
    const std::vector<std::string_view>& tokens = tokens_;
    if (tokens.size() < 3)
      fail_here("face has " + std::to_string(tokens.size()) +
                (tokens.size() == 1 ? " vertex" : " vertices") + ", needs at least 3");
    if (tokens.size() > kMaxFaceVertices)
      fail_here("face has " + std::to_string(tokens.size()) + " vertices, more than the " +
                std::to_string(kMaxFaceVertices) + " supported");
    // tinyobjloader keeps the face (12 bytes a corner) and its triangles (3 corners of 12 bytes
    // plus 9 bytes of per-face data each), once as it parses and once in the shape it returns.
    const uint64_t n = tokens.size();
    budget_.charge(2 * (32 + 12 * n + 45 * (n - 2)), "the OBJ faces");
    out += 'f';
    for (const std::string_view token : tokens) {
      std::string_view parts[3];
      size_t count = 0;
      size_t start = 0;
      for (size_t i = 0; i <= token.size(); ++i) {
        if (i == token.size() || token[i] == '/') {
          if (count == 3) fail_here("face vertex " + quote_token(token) + " has too many '/'");
          parts[count++] = token.substr(start, i - start);
          start = i + 1;
        }
      }
      // i, i/j, i//k, i/j/k: the position is required, an empty uv only in i//k.
      const bool ok = !parts[0].empty() && (count == 1 || !parts[1].empty() || count == 3) &&
                      (count < 3 || !parts[2].empty());
      if (!ok) fail_here("face vertex " + quote_token(token) + " is not i, i/j, i//k or i/j/k");
      index(parts[0], token, "position", seen_.positions, total_.positions);
      if (count >= 2 && !parts[1].empty())
        index(parts[1], token, "texture coordinate", seen_.uvs, total_.uvs);
      if (count == 3) index(parts[2], token, "normal", seen_.normals, total_.normals);
      out += ' ';
      out.append(token);
    }
  }

  // One OBJ index: 1-based, or negative relative to the elements defined so far.
  void index(std::string_view text, std::string_view token, const char* kind, uint64_t so_far,
             uint64_t total) const {
    std::string_view digits = text;
    if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-') digits.remove_prefix(1);
    int64_t value = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    // Named only on failure: building it for every index was a tenth of the loading time.
    const auto where = [&] {
      return std::string(kind) + " index " + quote_token(text) +
             (text == token ? "" : " in " + quote_token(token));
    };
    if (ec == std::errc::result_out_of_range && end == digits.data() + digits.size())
      fail_here(where() + " overflows");
    if (ec != std::errc() || end != digits.data() + digits.size())
      fail_here(where() + " is not a whole number");
    if (value == 0) fail_here(where() + " is 0; OBJ indices start at 1");
    if (value > INT_MAX || value < -INT_MAX) fail_here(where() + " overflows");
    if (value > 0 && static_cast<uint64_t>(value) > total)
      fail_here(where() + " is out of range: the file has " + std::to_string(total) + " " + kind +
                (total == 1 ? "" : "s"));
    if (value < 0 && static_cast<uint64_t>(-value) > so_far)
      fail_here(where() + " is out of range: only " + std::to_string(so_far) + " " + kind +
                (so_far == 1 ? " is" : "s are") + " defined before this line");
  }

  const std::filesystem::path& path_;
  LoadBudget& budget_;
  Counts total_, seen_;
  size_t line_ = 0;
  std::vector<std::string_view> tokens_;
};

Mesh convert_shape(const std::filesystem::path& path, const tinyobj::attrib_t& attrib,
                   const tinyobj::shape_t& shape, LoadBudget& budget) {
  const auto& corners = shape.mesh.indices;
  const int vertex_count = static_cast<int>(attrib.vertices.size() / 3);
  const int normal_count = static_cast<int>(attrib.normals.size() / 3);
  const int uv_count = static_cast<int>(attrib.texcoords.size() / 2);

  // The scanner checked every index; this is the net under it.
  bool has_normals = true, has_uvs = true;
  for (size_t i = 0; i < corners.size(); ++i) {
    const auto& c = corners[i];
    const auto where = [&] { return "shape '" + shape.name + "' face " + std::to_string(i / 3); };
    if (c.vertex_index < 0 || c.vertex_index >= vertex_count)
      fail(path, where() + ": position index " + std::to_string(c.vertex_index + 1) +
                     " out of range (file has " + std::to_string(vertex_count) + ")");
    if (c.normal_index >= normal_count)
      fail(path,
           where() + ": normal index " + std::to_string(c.normal_index + 1) + " out of range");
    if (c.texcoord_index >= uv_count)
      fail(path, where() + ": uv index " + std::to_string(c.texcoord_index + 1) + " out of range");
    has_normals = has_normals && c.normal_index >= 0;
    has_uvs = has_uvs && c.texcoord_index >= 0;
  }

  Mesh mesh;
  grow(mesh.indices, corners.size(), budget, "the OBJ triangles");
  std::map<std::tuple<int, int, int>, uint32_t> vertex_of;
  for (const auto& c : corners) {
    const int n = has_normals ? c.normal_index : -1;
    const int t = has_uvs ? c.texcoord_index : -1;
    auto [it, inserted] =
        vertex_of.try_emplace({c.vertex_index, n, t}, static_cast<uint32_t>(mesh.vertex_count()));
    if (inserted) {
      // The distinct corner's map node, then its position, normal and uv.
      budget.charge(96, "the OBJ vertices");
      grow(mesh.positions, 3, budget, "the OBJ vertices");
      if (has_normals) grow(mesh.normals, 3, budget, "the OBJ vertices");
      if (has_uvs) grow(mesh.uvs, 2, budget, "the OBJ vertices");
      for (int k = 0; k < 3; ++k) mesh.positions.push_back(attrib.vertices[3 * c.vertex_index + k]);
      if (has_normals)
        for (int k = 0; k < 3; ++k) mesh.normals.push_back(attrib.normals[3 * n + k]);
      if (has_uvs)
        for (int k = 0; k < 2; ++k) mesh.uvs.push_back(attrib.texcoords[2 * t + k]);
    }
    mesh.indices.push_back(it->second);
  }
  for (const auto* values : {&mesh.positions, &mesh.normals, &mesh.uvs})
    for (const float value : *values)
      if (!std::isfinite(value))
        fail(path, "shape '" + shape.name + "' has a value that does not fit a float");
  return mesh;
}

}  // namespace

Scene load_obj(const std::filesystem::path& path, const LoadLimits& limits) {
  if (!std::filesystem::is_regular_file(path)) fail(path, "no such file");
  LoadBudget budget(path, limits);
  std::string text = read_file_bounded(path, budget);
  budget.charge(2, text.size(), "the OBJ text");  // the checked copy, and tinyobjloader's
  std::string checked = Scanner(path, budget).scan(text);
  text = std::string();

  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(checked, "", config)) {
    std::string why = reader.Error();
    while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
    fail(path, "not a readable OBJ file: " + (why.empty() ? std::string("parse failed") : why));
  }
  checked = std::string();

  Scene scene;
  for (const auto& shape : reader.GetShapes()) {
    if (shape.mesh.indices.empty()) continue;  // lines or points only
    for (unsigned char n : shape.mesh.num_face_vertices)
      if (n != 3) fail(path, "shape '" + shape.name + "' has a face that did not triangulate");
    grow(scene.meshes, 1, budget, "the OBJ shapes");
    grow(scene.instances, 1, budget, "the OBJ shapes");
    scene.meshes.push_back(convert_shape(path, reader.GetAttrib(), shape, budget));
    Instance instance;
    instance.mesh = static_cast<uint32_t>(scene.meshes.size() - 1);
    scene.instances.push_back(instance);
  }
  if (scene.meshes.empty()) fail(path, "contains no triangles");
  return scene;
}

}  // namespace shadow::scenes
