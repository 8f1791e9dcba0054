// Host mirrors of the records kernels read (kernels/prelude.cl, rasterizer.cl, scene_buffers.cl).
#pragma once

#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

namespace shadow {

inline constexpr uint32_t kDrawReceives = 1u;
// Ping-pong blur: receiver class + 1 (0 = none) in bits 8..15 (DRAW_CLASS_SHIFT in prelude.cl).
inline constexpr uint32_t kDrawClassShift = 8;

// draw_t: one instance of a mesh in one pass.
struct alignas(64) DrawItem {
  glm::mat4 to_clip;
  glm::mat4 to_world;
  uint32_t vertex_base;
  uint32_t index_base;
  uint32_t vertex_count;
  uint32_t triangle_count;
  uint32_t out_vertex_base;
  uint32_t out_triangle_base;
  uint32_t instance;
  uint32_t flags;
  uint32_t pad[8];
};
static_assert(sizeof(DrawItem) == 192, "must match draw_t in kernels/prelude.cl");

// faces_t: how a camera pixel picks its cube face (prelude.cl: cube_face, owns_pixel).
struct alignas(64) FacesItem {
  glm::mat4 space;    // world -> the space in which the cube's faces are axis planes
  glm::vec4 origin;   // the projection centre in that space
  glm::vec4 inv_pos;  // per axis: 1 / distance from the centre to the + face, 0 if unused
  glm::vec4 inv_neg;  // per axis: 1 / distance to the - face, 0 if unused
  uint32_t owned;     // bit k: face k (+x -x +y -y +z -z); 0 = a single map, every pixel
  uint32_t pad[3];
};
static_assert(sizeof(FacesItem) == 128, "must match faces_t in kernels/prelude.cl");

// Light kinds (LIGHT_* in prelude.cl): light_t.kind, for the per-pixel kernels and the
// rasterizer's world-space bias alike.
inline constexpr int32_t kLightDirectional = 0;
inline constexpr int32_t kLightSpot = 1;
inline constexpr int32_t kLightPoint = 2;

// light_t: the light (prelude.cl; transform_vertices and the per-pixel kernels).
struct alignas(16) LightItem {
  glm::vec4 position;   // spot: apex; point: the light; w = 1
  glm::vec4 axis;       // unit direction of travel (directional) or cone axis (spot); w = 0
  float cos_half_cone;  // spot: outside the cone nothing is lit
  int32_t kind;         // kLightDirectional, kLightSpot or kLightPoint
  float disk;           // the area light's disk: tan(angular radius) for a sun, else its radius
  uint32_t pad;
};
static_assert(sizeof(LightItem) == 48, "must match light_t in kernels/prelude.cl");
static_assert(offsetof(LightItem, axis) == 16 && offsetof(LightItem, cos_half_cone) == 32 &&
                  offsetof(LightItem, kind) == 36 && offsetof(LightItem, disk) == 40,
              "must match light_t in kernels/prelude.cl");

// shadow_lookup_t: one shadow-map lookup of the per-pixel kernels (prelude.cl; shadow_test,
// pcf, pcss, blur_visibility).
struct alignas(64) ShadowLookupItem {
  glm::mat4 to_ndc;  // world -> the map's texture NDC
  LightItem light;
  uint32_t map_size;
  float bias_constant;  // NDC-depth bias: constant
  float bias_slope;     // plus this times the receiver's depth slope per texel
  uint32_t pad;
};
static_assert(sizeof(ShadowLookupItem) == 128, "must match shadow_lookup_t in kernels/prelude.cl");
static_assert(offsetof(ShadowLookupItem, light) == 64 &&
                  offsetof(ShadowLookupItem, map_size) == 112 &&
                  offsetof(ShadowLookupItem, bias_constant) == 116 &&
                  offsetof(ShadowLookupItem, bias_slope) == 120,
              "must match shadow_lookup_t in kernels/prelude.cl");

// cube_ndc_t: every face's matrix for a cube tested in one launch (prelude.cl; pcf.cl).
struct alignas(64) CubeNdcItem {
  glm::mat4 to_ndc[6];  // +x -x +y -y +z -z; zero for a face not rendered
};
static_assert(sizeof(CubeNdcItem) == 384, "must match cube_ndc_t in kernels/prelude.cl");

// csm_depth_t (csm.cl): how a map's NDC z becomes linear depth in [0, 1].
struct CsmDepthItem {
  int32_t perspective;  // z_ndc = alpha + beta / d (else z_ndc is taken as it is)
  float alpha, beta;
  float d_near, inv_range;  // d at z_ndc = 0 and 1 / (d_far - d_near) (kStored: 0, 1)
  uint32_t pad[3];
};
static_assert(sizeof(CsmDepthItem) == 32, "must match csm_depth_t in kernels/csm.cl");

// csm_controls_t (csm.cl): ringing controls and the no-blocker threshold.
struct CsmControlsItem {
  float damping, depth_offset, scale, min_occluded;
};
static_assert(sizeof(CsmControlsItem) == 16, "must match csm_controls_t in kernels/csm.cl");

// tri_t: a set-up triangle (rasterizer.cl).
inline constexpr size_t kTriRecordBytes = 48;

// chunk_t: a slice of one mesh's vertices or indices (scene_buffers.cl).
struct ChunkItem {
  uint32_t first;
  uint32_t count;
  uint32_t limit;  // check_indices: the mesh's vertex count
  uint32_t mesh;   // host bookkeeping; the kernels ignore it
};

}  // namespace shadow
