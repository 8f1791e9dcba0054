// The key a scene's requests carry as "x-scene-id" metadata, so that a proxy can keep a scene on
// one replica (deploy/nginx: hash $http_x_scene_id consistent).
#pragma once

#include <string>

#include "shadow/v1/shadow.pb.h"

namespace shadow::client {

inline constexpr const char* kSceneIdHeader = "x-scene-id";

// SHA-256, 64 lowercase hex digits, of the scene's deterministic protobuf serialization (the
// Python client computes the same). Costs one serialization and one hash of the scene.
std::string scene_key(const v1::Scene& scene);

}  // namespace shadow::client
