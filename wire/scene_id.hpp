// A scene's id: what UploadScene returns, what RenderRequest.scene_id names, and what a client
// sends as "x-scene-id" metadata so a proxy can keep a scene's requests on one replica
// (deploy/nginx.conf: hash $http_x_scene_id consistent). Client and server compute it here.
#pragma once

#include <cstddef>
#include <string>

#include "shadow/v1/shadow.pb.h"

namespace shadow {

inline constexpr const char* kSceneIdHeader = "x-scene-id";

// The most `data` one UploadScene chunk may carry (SceneUpload in shadow.proto); the server
// refuses a larger chunk, so a scene's bytes arrive, and are counted, a bounded step at a time.
inline constexpr size_t kMaxUploadChunkBytes = size_t{4} << 20;

// SHA-256, 64 lowercase hex digits, of the scene's canonical encoding: its deterministic
// protobuf serialization (fields in number order). Unknown fields count, so a server drops them
// before (the Python client computes the same). Costs one serialization and one hash.
std::string scene_id(const v1::Scene& scene);

// 64 lowercase hex digits, as scene_id() writes them.
bool is_scene_id(const std::string& text);

}  // namespace shadow
