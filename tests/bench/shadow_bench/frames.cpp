#include "frames.hpp"

#include <cmath>
#include <glm/glm.hpp>
#include <map>

#include "oracle/metrics.hpp"

namespace shadow::bench {
namespace {

// v turned by `deg` about the unit axis k (Rodrigues).
glm::dvec3 turned(const glm::dvec3& v, const glm::dvec3& k, double deg) {
  const double a = glm::radians(deg), c = std::cos(a), s = std::sin(a);
  return v * c + glm::cross(k, v) * s + k * glm::dot(k, v) * (1 - c);
}

}  // namespace

std::vector<Light> nudged_lights(const Light& light) {
  std::vector<Light> out(4, light);
  if (light.type == LightType::kPoint) {
    const glm::vec3 steps[] = {
        {kNudgeM, 0, 0}, {-kNudgeM, 0, 0}, {0, 0, kNudgeM}, {0, 0, -kNudgeM}};
    for (int i = 0; i < 4; ++i) out[i].position += steps[i];
    return out;
  }
  const glm::dvec3 d = glm::normalize(glm::dvec3(light.direction));
  // Sideways: about the axis in d's vertical plane across d; up and down: about the horizontal
  // axis across d. A light straight up or down takes z as its vertical.
  const glm::dvec3 vertical = std::abs(d.y) > 0.999 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  const glm::dvec3 across = glm::normalize(glm::cross(d, vertical));
  const glm::dvec3 upright = glm::cross(across, d);
  const std::pair<glm::dvec3, double> turns[] = {
      {upright, kNudgeDeg}, {upright, -kNudgeDeg}, {across, kNudgeDeg}, {across, -kNudgeDeg}};
  for (int i = 0; i < 4; ++i)
    out[i].direction = glm::vec3(glm::normalize(turned(d, turns[i].first, turns[i].second)));
  return out;
}

std::vector<FrameError> run_nudged_frames(
    const std::string& scene, const std::string& view, const Light& light,
    const std::vector<std::string>& variants, const RenderVisibility& render,
    const std::function<std::vector<float>(const Light&)>& reference,
    const std::vector<double>& distance) {
  std::vector<FrameError> out;
  int frame = 0;
  for (const Light& nudged : nudged_lights(light)) {
    ++frame;
    std::vector<float> ref;  // cast once a variant ran
    for (const std::string& variant : variants) {
      const std::optional<std::vector<float>> vis = render(variant, nudged);
      if (!vis) continue;
      if (ref.empty()) ref = reference(nudged);
      out.push_back({scene, view, variant, frame, nudged, oracle::compare_visibility(*vis, ref),
                     oracle::compare_visibility_by_distance(*vis, ref, distance,
                                                            oracle::kStandardDistanceEdges)});
    }
  }
  return out;
}

std::function<double(const Case&)> frame_mean_rate(const std::vector<FrameError>& frames) {
  // Per scene, view and variant: the nudged frames' rates summed, and how many.
  std::map<std::string, std::pair<double, int>> nudged;
  for (const FrameError& f : frames) {
    auto& [sum, n] = nudged[f.scene + "/" + f.view + "/" + f.variant];
    sum += f.error.misclassified_rate(), ++n;
  }
  return [nudged = std::move(nudged)](const Case& c) {
    double sum = c.error.misclassified_rate();
    int n = 1;
    if (const auto it = nudged.find(c.scene + "/" + c.view + "/" + c.variant); it != nudged.end())
      sum += it->second.first, n += it->second.second;
    return sum / n;
  };
}

}  // namespace shadow::bench
