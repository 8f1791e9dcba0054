#include "engine/light/post_perspective.hpp"

namespace shadow {

PostPerspectiveLight post_perspective_light(const Light& light, const glm::dmat4& world_to_clip,
                                            double parallel_tolerance) {
  const bool directional = light.type == LightType::kDirectional;
  // Towards the light: its position, or the opposite of a directional light's travel at w = 0.
  const glm::dvec4 towards = directional
                                 ? glm::dvec4(-glm::normalize(glm::dvec3(light.direction)), 0.0)
                                 : glm::dvec4(glm::dvec3(light.position), 1.0);
  PostPerspectiveLight out;
  out.homogeneous = world_to_clip * towards;
  const glm::dvec3 xyz(out.homogeneous);
  const double w = out.homogeneous.w;
  const std::string source =
      directional ? "directional" : (light.type == LightType::kSpot ? "spot" : "point");

  if (std::abs(w) <= parallel_tolerance * glm::length(xyz)) {
    // At infinity in post-perspective space: rays travel away from the light's direction.
    out.kind = PostPerspectiveCase::kDirectional;
    out.direction = -glm::normalize(xyz);
    out.description = source +
                      (directional ? " parallel to the image plane" : " in the camera plane") +
                      ": directional";
    return out;
  }
  out.position = xyz / w;
  if (w > 0.0) {
    out.kind = PostPerspectiveCase::kPoint;
    out.description = source + " from the front: point light";
  } else {
    out.kind = PostPerspectiveCase::kInvertedPoint;
    out.description = source + " from behind: inverted point light";
  }
  return out;
}

}  // namespace shadow
