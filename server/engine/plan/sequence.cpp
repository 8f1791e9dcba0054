#include "engine/plan/sequence.hpp"

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "wire/errors.hpp"

namespace shadow {

void validate_frames(const SequenceRequest& sequence) {
  const size_t n = sequence.frames.size();
  if (n == 0) throw InvalidArgument("frames", "is empty: a sequence needs at least one frame");
  if (n > kMaxFrames)
    throw ResourceExhausted("frames", std::to_string(n) + " frames, over the limit of " +
                                          std::to_string(kMaxFrames) + " per sequence");
  const size_t instances = sequence.base.scene ? sequence.base.scene->instances.size() : 0;
  for (size_t i = 0; i < n; ++i) {
    const std::vector<InstanceTransform>& moved = sequence.frames[i].transforms;
    std::vector<bool> seen(instances, false);
    for (size_t k = 0; k < moved.size(); ++k) {
      const std::string f =
          "frames[" + std::to_string(i) + "].transforms[" + std::to_string(k) + "]";
      const uint32_t j = moved[k].instance;
      if (j >= instances)
        throw InvalidArgument(f + ".instance", "names instance " + std::to_string(j) +
                                                   " but the scene has " +
                                                   std::to_string(instances));
      if (seen[j])
        throw InvalidArgument(f + ".instance",
                              "instance " + std::to_string(j) + " is moved twice in one frame");
      seen[j] = true;
      const glm::mat4& m = moved[k].transform;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
          if (!std::isfinite(m[c][r])) throw InvalidArgument(f + ".transform", "must be finite");
    }
  }
}

RenderRequest frame_request(const SequenceRequest& sequence, size_t i) {
  const Frame& frame = sequence.frames.at(i);
  RenderRequest r = sequence.base;
  if (frame.camera) r.camera = *frame.camera;
  if (frame.lights) r.lights = *frame.lights;
  if (!frame.transforms.empty()) {
    auto moved = std::make_shared<Scene>(*sequence.base.scene);
    for (const InstanceTransform& t : frame.transforms)
      moved->instances.at(t.instance).transform = t.transform;
    r.scene = std::move(moved);
    r.scene_held = false;  // the frame's own copy
  }
  return r;
}

bool same_settings(const RenderRequest& a, const RenderRequest& b) {
  return a.quality.goal == Quality::Goal::kNone && b.quality.goal == Quality::Goal::kNone &&
         a.products == b.products && a.shadow_map == b.shadow_map && a.filter == b.filter &&
         a.atlas == b.atlas && a.output_format == b.output_format &&
         a.generated_layouts == b.generated_layouts;
}

std::string frame_field(const SequenceRequest& sequence, size_t i, const std::string& field) {
  const Frame& frame = sequence.frames.at(i);
  const auto under = [&](const char* name) {
    const std::string n = name;
    return field.compare(0, n.size(), n) == 0 &&
           (field.size() == n.size() || field[n.size()] == '.' || field[n.size()] == '[');
  };
  if ((frame.camera && under("camera")) || (frame.lights && under("lights")))
    return "frames[" + std::to_string(i) + "]." + field;
  return "base." + field;
}

}  // namespace shadow
