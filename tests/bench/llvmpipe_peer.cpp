#include "llvmpipe_peer.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include <glm/gtc/type_ptr.hpp>

namespace shadow::bench {

struct LlvmpipePeer::Impl {
  OSMesaContext ctx = nullptr;
  uint32_t size = 0;
  std::vector<uint8_t> color;  // OSMesa needs a colour buffer; colour writes are masked off
  GLuint vbo = 0, ibo = 0;
  GLsizei index_count = 0;
};

LlvmpipePeer::LlvmpipePeer(uint32_t size, int threads) : impl_(std::make_unique<Impl>()) {
  setenv("LP_NUM_THREADS", std::to_string(threads).c_str(), 0);
  setenv("GALLIUM_DRIVER", "llvmpipe", 0);
  impl_->size = size;
  impl_->ctx = OSMesaCreateContextExt(OSMESA_RGBA, 32, 0, 0, nullptr);
  if (!impl_->ctx) throw std::runtime_error("OSMesaCreateContextExt failed");
  impl_->color.resize(size_t{size} * size * 4);
  if (!OSMesaMakeCurrent(impl_->ctx, impl_->color.data(), GL_UNSIGNED_BYTE, GLsizei(size),
                         GLsizei(size)))
    throw std::runtime_error("OSMesaMakeCurrent failed at " + std::to_string(size));
  glViewport(0, 0, GLsizei(size), GLsizei(size));
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glClearDepth(1.0);
  glGenBuffers(1, &impl_->vbo);
  glGenBuffers(1, &impl_->ibo);
}

LlvmpipePeer::~LlvmpipePeer() {
  glDeleteBuffers(1, &impl_->vbo);
  glDeleteBuffers(1, &impl_->ibo);
  OSMesaDestroyContext(impl_->ctx);
}

void LlvmpipePeer::upload(const std::vector<float>& positions,
                          const std::vector<uint32_t>& indices) {
  glBindBuffer(GL_ARRAY_BUFFER, impl_->vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(positions.size() * sizeof(float)), positions.data(),
               GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl_->ibo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(uint32_t)),
               indices.data(), GL_STATIC_DRAW);
  glEnableClientState(GL_VERTEX_ARRAY);
  glVertexPointer(3, GL_FLOAT, 0, nullptr);
  impl_->index_count = GLsizei(indices.size());
}

double LlvmpipePeer::draw(const glm::mat4& world_to_ndc) {
  // Texture NDC (x, y 0..1 from the top-left, z 0..1) to GL clip space (-1..1, y up); the
  // image comes out upside down in GL's bottom-up rows, which depth() undoes.
  const glm::mat4 tex_to_gl(2, 0, 0, 0, 0, -2, 0, 0, 0, 0, 2, 0, -1, 1, -1, 1);
  const glm::mat4 m = tex_to_gl * world_to_ndc;
  glMatrixMode(GL_PROJECTION);
  glLoadMatrixf(glm::value_ptr(m));
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glFinish();
  const auto start = std::chrono::steady_clock::now();
  glClear(GL_DEPTH_BUFFER_BIT);
  glDrawElements(GL_TRIANGLES, impl_->index_count, GL_UNSIGNED_INT, nullptr);
  glFinish();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

std::vector<float> LlvmpipePeer::depth() const {
  const uint32_t n = impl_->size;
  std::vector<float> rows(size_t{n} * n), out(rows.size());
  glReadPixels(0, 0, GLsizei(n), GLsizei(n), GL_DEPTH_COMPONENT, GL_FLOAT, rows.data());
  for (uint32_t y = 0; y < n; ++y)  // GL row 0 is the bottom, which is our last row
    std::copy_n(rows.data() + size_t{y} * n, n, out.data() + size_t{n - 1 - y} * n);
  return out;
}

}  // namespace shadow::bench
