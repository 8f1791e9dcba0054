// The hardware-rasterizer peer for the raster bench: OpenGL through EGL without a window, depth
// only. On a GPU machine EGL gives the GPU's own rasterizer; on a CPU machine Mesa's llvmpipe.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace shadow::bench {

// An OpenGL core context made current on this thread with no default framebuffer: the first
// EGL device (a GPU before Mesa's software device), else Mesa's surfaceless platform.
class EglContext {
 public:
  EglContext();  // throws std::runtime_error naming the step that failed
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  const std::string& platform() const { return platform_; }  // "device" or "surfaceless"
  std::string renderer() const;                              // GL_RENDERER
  // "GL_RENDERER / GL_VENDOR / GL_VERSION", e.g. "llvmpipe (LLVM 15.0.6, 256 bits) / Mesa /
  // 4.5 (Core Profile) Mesa 22.3.6".
  std::string description() const;

 private:
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  std::string platform_;
};

// An N x N GL_DEPTH_COMPONENT32F texture on a framebuffer without colour, and one mesh in
// buffer objects. Needs a current EglContext for its whole life.
class DepthPeer {
 public:
  explicit DepthPeer(uint32_t size);
  ~DepthPeer();
  DepthPeer(const DepthPeer&) = delete;
  DepthPeer& operator=(const DepthPeer&) = delete;

  // World-space positions (xyz) and triangle indices; replaces the previous mesh.
  void upload(const std::vector<float>& positions, const std::vector<uint32_t>& indices);

  struct Timing {
    double wall_ms = 0;  // clear + draw + glFinish, on the host's clock
    double gpu_ms = 0;   // the same commands by a GL_TIME_ELAPSED query
  };
  // Clears depth to 1 and draws every triangle through `world_to_ndc` (x, y 0..1 from the
  // top-left, z 0..1, this project's convention) with depth func LESS.
  Timing draw(const glm::mat4& world_to_ndc);
  // The depth of texel (x, y), row 0 at the top as in the project's maps, z in 0..1.
  std::vector<float> depth() const;

 private:
  uint32_t size_;
  bool zero_to_one_ = false;  // clip z already 0..1 (ARB_clip_control): depth = NDC z exactly
  unsigned program_ = 0, matrix_location_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0, texture_ = 0,
           framebuffer_ = 0, query_ = 0;
  int index_count_ = 0;
};

}  // namespace shadow::bench
