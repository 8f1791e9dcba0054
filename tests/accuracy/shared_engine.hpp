// What the accuracy tests share: one engine per test binary (one OpenCL context and a warm
// program cache for every test) and a product's texture from a result.
#pragma once

#include <algorithm>
#include <stdexcept>

#include "engine/engine.hpp"
#include "engine_fixture.hpp"

namespace shadow::accuracy {

using testing::engine;  // the one shared engine (common/engine_fixture.hpp)

// The first texture of `kind`; throws if the result has none.
inline const Texture& texture(const RenderResult& r, Product kind) {
  auto it = std::find_if(r.textures.begin(), r.textures.end(),
                         [&](const Texture& t) { return t.kind == kind; });
  if (it == r.textures.end()) throw std::runtime_error("product missing from the result");
  return *it;
}

}  // namespace shadow::accuracy
