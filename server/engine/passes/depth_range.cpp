#include "engine/passes/depth_range.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/passes/pixel_shape.hpp"

namespace shadow {

namespace {

// The camera's eye and unit forward axis, each rounded to float once from double.
std::pair<glm::vec4, glm::vec4> axes(const Camera& camera) {
  const glm::dvec3 eye(camera.eye), fwd = glm::normalize(glm::dvec3(camera.target) - eye);
  return {glm::vec4(glm::vec3(eye), 1.0f), glm::vec4(glm::vec3(fwd), 0.0f)};
}

}  // namespace

cl_kernel DepthRangePass::partials_kernel() {
  const size_t group = chunk_group(runtime_);
  if (group == 1) return kernels_.kernel("depth_range.cl", "view_depth_partials");
  return kernels_.kernel("depth_range.cl", "view_depth_partials_gpu", group_option(group));
}

std::optional<DepthRange> DepthRangePass::run(const GBuffer& g, const Camera& camera,
                                              Timeline& timeline) {
  const uint32_t pixels = camera.width * camera.height;
  const uint32_t chunks = (pixels + kChunk - 1) / kChunk;
  runtime_.ensure(partials_, size_t{chunks} * 2 * sizeof(float));
  const auto [eye, fwd] = axes(camera);
  cl_kernel k = partials_kernel();
  cl::set_args(k, g.position, g.normal, pixels, eye, fwd, partials_);
  const size_t group = chunk_group(runtime_);
  timeline.add("depth_range.reduce", runtime_.launch(k, size_t{chunks} * group, group));
  return combine(partials_, chunks, "depth_range.reduce", timeline);
}

ViewDepthOut DepthRangePass::out(const Camera& camera, uint32_t count) {
  runtime_.ensure(strips_, size_t{count} * 2 * sizeof(float));
  const auto [eye, fwd] = axes(camera);
  return {eye, fwd, &strips_};
}

std::optional<DepthRange> DepthRangePass::read(uint32_t count, Timeline& timeline) {
  return combine(strips_, count, "depth_range.read", timeline);
}

std::optional<DepthRange> DepthRangePass::combine(const cl::Buffer& buffer, uint32_t count,
                                                  const std::string& pass, Timeline& timeline) {
  std::vector<float> partials(size_t{count} * 2);
  timeline.add(pass, runtime_.read(buffer, partials.data(), partials.size() * sizeof(float)));
  DepthRange r{INFINITY, -INFINITY};
  for (uint32_t c = 0; c < count; ++c) {
    r.min = std::min(r.min, double(partials[2 * c]));
    r.max = std::max(r.max, double(partials[2 * c + 1]));
  }
  if (!(r.min <= r.max)) return std::nullopt;
  return r;
}

}  // namespace shadow
