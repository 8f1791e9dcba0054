// Reading the matrices OpenImageIO stores in an EXR (worldtoNDC, worldtocamera) back in tests.
#pragma once

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include <OpenImageIO/imageio.h>
#include <glm/glm.hpp>

namespace shadow::testing {

// The stored matrix as OIIO hands it out: 16 floats, row by row, for p · M.
inline std::array<float, 16> matrix(const OIIO::ImageSpec& spec, const char* name) {
  const OIIO::ParamValue* p = spec.find_attribute(name);  // case-insensitive
  if (!p || p->type() != OIIO::TypeMatrix44) throw std::runtime_error(std::string("no ") + name);
  std::array<float, 16> m;
  std::copy_n(static_cast<const float*>(p->data()), 16, m.begin());
  return m;
}

// p · M for a stored (row-vector) matrix.
inline glm::vec4 row_times(glm::vec4 p, const std::array<float, 16>& m) {
  glm::vec4 out(0.0f);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out[c] += p[r] * m[4 * r + c];
  return out;
}

}  // namespace shadow::testing
