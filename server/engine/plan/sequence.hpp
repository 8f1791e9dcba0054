// A sequence's frames as requests: frame i is the base request with the frame's camera, lights
// and moved instances (wire/types.hpp, SequenceRequest). Pure host code, no OpenCL.
#pragma once

#include <cstddef>
#include <string>

#include "wire/types.hpp"

namespace shadow {

// Frames per sequence: each frame is admitted against the per-request cost limit, so this
// bounds a sequence's work too.
constexpr size_t kMaxFrames = 1000;

// Checks the frame list's shape (count, instance indices, duplicate or non-finite transforms),
// naming "frames[i]..." fields; the frames' requests are validated as requests by the engine.
void validate_frames(const SequenceRequest& sequence);

// Frame i's request. A frame that moves instances gets its own copy of the scene (its meshes
// included: Scene holds them by value); the others share the base scene.
RenderRequest frame_request(const SequenceRequest& sequence, size_t i);

// Whether two requests ask for the same products with the same settings: over one held scene
// they then differ at most where a sequence's frames may (camera, lights, instance transforms),
// and a workspace continues the second from the first's results as a sequence's next frame
// (engine/run/workspace.hpp). Requests with a quality goal never do (each picks its own map).
bool same_settings(const RenderRequest& a, const RenderRequest& b);

// The path of a field of frame i's request as the sequence names it: "frames[i].camera..." and
// "frames[i].lights..." where the frame gives them, "base...." for what it takes from the base.
std::string frame_field(const SequenceRequest& sequence, size_t i, const std::string& field);

}  // namespace shadow
