#include "engine/passes/light_distance.hpp"

#include <algorithm>
#include <cmath>

#include "engine/passes/pixel_shape.hpp"

namespace shadow {

cl_kernel LightDistancePass::kernel() {
  return kernels_.kernel("light_distance.cl", "min_triangle_distance",
                         group_option(chunk_group(runtime_)));
}

double LightDistancePass::run(const SceneBuffers& scene, const std::vector<DrawItem>& draws,
                              const glm::vec3& point, Timeline& timeline) {
  constexpr uint32_t kChunk = 1024;  // TRIANGLE_CHUNK in light_distance.cl
  const uint32_t triangles =
      draws.empty() ? 0 : draws.back().out_triangle_base + draws.back().triangle_count;
  if (triangles == 0) return INFINITY;
  const uint32_t chunks = (triangles + kChunk - 1) / kChunk;
  runtime_.ensure(draws_, draws.size() * sizeof(DrawItem));
  runtime_.ensure(partial_, size_t{chunks} * sizeof(float));
  timeline.add("cube.light_distance",
               runtime_.write(draws_, draws.data(), draws.size() * sizeof(DrawItem)));
  cl_kernel k = kernel();
  cl::set_args(k, scene.positions(), scene.indices(), draws_, uint32_t(draws.size()), triangles,
               glm::vec4(point, 1.0f), partial_);
  const size_t group = chunk_group(runtime_);
  timeline.add("cube.light_distance", runtime_.launch(k, chunks * group, group));
  mins_.resize(chunks);
  timeline.add("cube.light_distance",
               runtime_.read(partial_, mins_.data(), chunks * sizeof(float)));
  runtime_.finish();
  return *std::min_element(mins_.begin(), mins_.end());
}

}  // namespace shadow
