#include "wire/texture_layout.hpp"

#include <algorithm>
#include <vector>

namespace shadow::convert {

bool texture_bytes(const Texture& t, uint64_t* out) {
  uint64_t n = t.value_bytes();
  for (uint64_t factor :
       {uint64_t{t.width}, uint64_t{t.height}, uint64_t{t.channels}, uint64_t{t.faces}}) {
    if (__builtin_mul_overflow(n, factor, &n)) return false;
  }
  *out = n;
  return true;
}

std::string cube_faces_problem(const Texture& t, const std::string& field) {
  static const std::vector<std::string> kNames = {"+x", "-x", "+y", "-y", "+z", "-z"};
  if (t.cube_faces.empty() && t.faces == 1) return "";
  if (t.cube_faces.size() != t.faces) {
    return field + " holds " + std::to_string(t.cube_faces.size()) + " entries for " +
           std::to_string(t.faces) + " faces of data";
  }
  for (size_t i = 0; i < t.cube_faces.size(); ++i) {
    const std::string& name = t.cube_faces[i].name;
    const std::string at = field + "[" + std::to_string(i) + "].name '" + name + "'";
    if (std::find(kNames.begin(), kNames.end(), name) == kNames.end())
      return at + " is not +x, -x, +y, -y, +z or -z";
    const auto before = t.cube_faces.begin() + i;
    if (std::any_of(t.cube_faces.begin(), before,
                    [&](const TextureFace& f) { return f.name == name; }))
      return at + " appears twice";
  }
  return "";
}

}  // namespace shadow::convert
