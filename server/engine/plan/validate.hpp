// Host-side request checks: every scalar field, array shapes and the limits, before anything
// is allocated. Per-vertex and per-index checks run on the device (SceneBuffers).
#pragma once

#include <cstdint>

#include "wire/types.hpp"

namespace shadow {

// A shadow map's edge in texels (ShadowMapSettings::size; a cube's faces each).
inline constexpr uint32_t kMinMapSize = 256, kMaxMapSize = 8192;
// TECHNIQUE_VIRTUAL: a level's virtual edge (a power of two, whole 128^2 pages) and the pool's
// pages (16384 float32 pages are 1 GiB), and |virtual_lod_bias| at most.
inline constexpr uint32_t kMinVirtualMapSize = 2048, kMaxVirtualMapSize = 32768;
inline constexpr uint32_t kMaxVirtualPoolPages = 16384;
inline constexpr float kMaxVirtualLodBias = 4.0f;

struct Limits {
  uint64_t max_output_bytes;  // all returned textures together
  uint64_t max_buffer_bytes;  // one device buffer
};

// Throws InvalidArgument or ResourceExhausted naming the offending field.
void validate(const RenderRequest& request, const Limits& limits);
// The scene's part of validate(), for scenes checked once and kept (UploadScene).
void validate_scene(const Scene& scene, const Limits& limits);

// Bytes of every texture the request asks for.
uint64_t output_bytes(const RenderRequest& request);

}  // namespace shadow
