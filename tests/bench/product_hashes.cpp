// product-hashes: renders a fixed sweep of requests in-process (every standard scene view with
// each technique and filter, and the demo scene) asking for every product, and prints one line
// per texture: case, texture name and a 64-bit FNV-1a hash of its bytes, matrices and passes.
// Refactors that must not change results are checked by diffing this output against a build of
// the commit before (docs/architecture.md says how). Requests the engine refuses print the error.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "engine/engine.hpp"
#include "sweep.hpp"

namespace {

using namespace shadow;

struct Fnv {
  uint64_t h = 1469598103934665603ull;
  void add(const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
};

uint64_t hash(const Texture& t) {
  Fnv f;
  f.add(t.data.data(), t.data.size() * sizeof(float));
  f.add(t.data64.data(), t.data64.size() * sizeof(double));
  f.add(&t.world_to_ndc, sizeof t.world_to_ndc);
  f.add(&t.world_to_camera, sizeof t.world_to_camera);
  for (const TextureFace& face : t.cube_faces) {
    f.add(face.name.data(), face.name.size());
    f.add(&face.world_to_ndc, sizeof face.world_to_ndc);
  }
  const uint32_t shape[] = {t.width, t.height, t.channels, t.faces};
  f.add(shape, sizeof shape);
  return f.h;
}

void run(Engine& engine, const std::string& name, const RenderRequest& req) {
  try {
    const RenderResult r = engine.render(req);
    Fnv passes;
    for (const std::string& p : r.passes) passes.add(p.data(), p.size() + 1);
    std::printf("%s | passes %016llx | %s\n", name.c_str(),
                static_cast<unsigned long long>(passes.h), r.light_fits[0].light_case.c_str());
    for (const Texture& t : r.textures)
      std::printf("%s | %s %ux%ux%u | %016llx\n", name.c_str(), t.name.c_str(), t.width, t.height,
                  t.channels, static_cast<unsigned long long>(hash(t)));
  } catch (const std::exception& e) {
    std::printf("%s | refused: %s\n", name.c_str(), e.what());
  }
}

}  // namespace

int main() {
  EngineOptions options;
  options.max_request_cost_ms = 0;  // the sweep's few large cases are the point
  Engine engine(options);
  bench::for_each_sweep_case(
      [&](const std::string& name, const RenderRequest& req) { run(engine, name, req); });
  return 0;
}
