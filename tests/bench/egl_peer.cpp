#include "egl_peer.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES  // GLVND's libOpenGL exports every core entry point
#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include <glm/gtc/type_ptr.hpp>

namespace shadow::bench {
namespace {

bool has_extension(const char* list, std::string_view name) {
  std::istringstream words(list ? list : "");
  for (std::string word; words >> word;)
    if (word == name) return true;
  return false;
}

[[noreturn]] void egl_fail(const std::string& step) {
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", unsigned(eglGetError()));
  throw std::runtime_error("EGL: " + step + " failed (" + code + ")");
}

template <class Fn>
Fn egl_proc(const char* name) {
  auto fn = reinterpret_cast<Fn>(eglGetProcAddress(name));
  if (!fn) throw std::runtime_error(std::string("EGL: no ") + name);
  return fn;
}

// Mesa lists its software device beside the GPUs; a GPU is the rasterizer worth comparing.
bool is_software(EGLDeviceEXT device) {
  auto query = egl_proc<PFNEGLQUERYDEVICESTRINGEXTPROC>("eglQueryDeviceStringEXT");
  return has_extension(query(device, EGL_EXTENSIONS), "EGL_MESA_device_software");
}

EGLDisplay open_display(std::string& platform) {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_display = egl_proc<PFNEGLGETPLATFORMDISPLAYEXTPROC>("eglGetPlatformDisplayEXT");
  if (has_extension(client, "EGL_EXT_platform_device")) {
    auto query_devices = egl_proc<PFNEGLQUERYDEVICESEXTPROC>("eglQueryDevicesEXT");
    EGLDeviceEXT devices[16];
    EGLint count = 0;
    if (query_devices(16, devices, &count) && count > 0) {
      std::stable_partition(devices, devices + count, [](auto d) { return !is_software(d); });
      for (EGLint i = 0; i < count; ++i) {
        EGLDisplay d = get_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
          platform = "device";
          return d;
        }
      }
    }
  }
  if (has_extension(client, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
      platform = "surfaceless";
      return d;
    }
  }
  egl_fail("no EGL device or surfaceless display could be initialized");
}

EGLContext create_context(EGLDisplay display) {
  if (!has_extension(eglQueryString(display, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context"))
    throw std::runtime_error("EGL: the display lacks EGL_KHR_surfaceless_context");
  if (!eglBindAPI(EGL_OPENGL_API)) egl_fail("eglBindAPI(EGL_OPENGL_API)");
  EGLConfig config = EGL_NO_CONFIG_KHR;
  if (!has_extension(eglQueryString(display, EGL_EXTENSIONS), "EGL_KHR_no_config_context")) {
    const EGLint want[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT,
                           EGL_NONE};
    EGLint found = 0;
    if (!eglChooseConfig(display, want, &config, 1, &found) || found == 0)
      egl_fail("eglChooseConfig");
  }
  for (const auto& [major, minor] : {std::pair{4, 5}, std::pair{3, 3}}) {
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 major,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 minor,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    EGLContext c = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes);
    if (c != EGL_NO_CONTEXT) return c;
  }
  egl_fail("eglCreateContext (OpenGL 4.5 or 3.3 core)");
}

std::string gl_string(GLenum name) {
  const auto* s = reinterpret_cast<const char*>(glGetString(name));
  return s ? s : "?";
}

GLuint compile(GLenum type, const char* source) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    throw std::runtime_error(std::string("GL: shader: ") + log);
  }
  return shader;
}

// Depth only: the fragment stage writes nothing, the depth test does the work.
constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
uniform mat4 world_to_clip;
void main() { gl_Position = world_to_clip * vec4(position, 1.0); }
)";
constexpr const char* kFragmentShader = "#version 330 core\nvoid main() {}\n";

GLuint link_program() {
  const GLuint program = glCreateProgram();
  const GLuint vs = compile(GL_VERTEX_SHADER, kVertexShader);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, kFragmentShader);
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) throw std::runtime_error("GL: the depth program does not link");
  return program;
}

bool has_clip_control() {
  GLint major = 0, minor = 0, count = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major > 4 || (major == 4 && minor >= 5)) return true;
  glGetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint i = 0; i < count; ++i) {
    const auto* e = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, GLuint(i)));
    if (e && std::string_view(e) == "GL_ARB_clip_control") return true;
  }
  return false;
}

}  // namespace

EglContext::EglContext() {
  EGLDisplay display = open_display(platform_);
  display_ = display;
  try {
    EGLContext context = create_context(display);
    context_ = context;
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context))
      egl_fail("eglMakeCurrent without a surface");
  } catch (...) {
    if (context_) eglDestroyContext(display, context_);
    eglTerminate(display);
    throw;
  }
}

EglContext::~EglContext() {
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
  eglTerminate(display_);
  eglReleaseThread();
}

std::string EglContext::renderer() const {
  return gl_string(GL_RENDERER);
}

std::string EglContext::description() const {
  return renderer() + " / " + gl_string(GL_VENDOR) + " / " + gl_string(GL_VERSION);
}

DepthPeer::DepthPeer(uint32_t size) : size_(size) {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (GLint(size) > max_size)
    throw std::runtime_error("GL: " + std::to_string(size) + "^2 exceeds GL_MAX_TEXTURE_SIZE " +
                             std::to_string(max_size));
  program_ = link_program();
  matrix_location_ = GLuint(glGetUniformLocation(program_, "world_to_clip"));
  // With clip z in 0..1 the stored depth is the NDC z the engine writes, not (2z - 1 + 1) / 2.
  zero_to_one_ = has_clip_control();
  if (zero_to_one_) glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);

  glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, GLsizei(size), GLsizei(size), 0,
               GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glGenFramebuffers(1, &framebuffer_);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, texture_, 0);
  glDrawBuffer(GL_NONE);
  glReadBuffer(GL_NONE);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("GL: the depth-only framebuffer is incomplete");

  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(1, &vbo_);
  glGenBuffers(1, &ibo_);
  glGenQueries(1, &query_);
  glViewport(0, 0, GLsizei(size), GLsizei(size));
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  glClearDepth(1.0);
}

DepthPeer::~DepthPeer() {
  glDeleteQueries(1, &query_);
  glDeleteBuffers(1, &vbo_);
  glDeleteBuffers(1, &ibo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteFramebuffers(1, &framebuffer_);
  glDeleteTextures(1, &texture_);
  glDeleteProgram(program_);
}

void DepthPeer::upload(const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(positions.size() * sizeof(float)), positions.data(),
               GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);  // recorded in the vertex array
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(uint32_t)),
               indices.data(), GL_STATIC_DRAW);
  index_count_ = int(indices.size());
  glFinish();  // the upload is not part of any timed draw
}

DepthPeer::Timing DepthPeer::draw(const glm::mat4& world_to_ndc) {
  // Texture NDC (x, y 0..1 from the top-left) to GL clip space (-1..1, y up); the image comes
  // out upside down in GL's bottom-up rows, which depth() undoes. z stays 0..1 under clip
  // control, else goes to -1..1.
  const glm::mat4 to_clip = zero_to_one_
                                ? glm::mat4(2, 0, 0, 0, 0, -2, 0, 0, 0, 0, 1, 0, -1, 1, 0, 1)
                                : glm::mat4(2, 0, 0, 0, 0, -2, 0, 0, 0, 0, 2, 0, -1, 1, -1, 1);
  const glm::mat4 m = to_clip * world_to_ndc;
  glUseProgram(program_);
  glUniformMatrix4fv(GLint(matrix_location_), 1, GL_FALSE, glm::value_ptr(m));
  glBindVertexArray(vao_);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  glFinish();
  const auto start = std::chrono::steady_clock::now();
  glBeginQuery(GL_TIME_ELAPSED, query_);
  glClear(GL_DEPTH_BUFFER_BIT);
  glDrawElements(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr);
  glEndQuery(GL_TIME_ELAPSED);
  glFinish();
  Timing t;
  t.wall_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  GLuint64 ns = 0;
  glGetQueryObjectui64v(query_, GL_QUERY_RESULT, &ns);
  t.gpu_ms = double(ns) / 1e6;
  return t;
}

std::vector<float> DepthPeer::depth() const {
  const uint32_t n = size_;
  std::vector<float> rows(size_t{n} * n), out(rows.size());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer_);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, GLsizei(n), GLsizei(n), GL_DEPTH_COMPONENT, GL_FLOAT, rows.data());
  for (uint32_t y = 0; y < n; ++y)  // GL row 0 is the bottom, which is our last row
    std::copy_n(rows.data() + size_t{y} * n, n, out.data() + size_t{n - 1 - y} * n);
  return out;
}

}  // namespace shadow::bench
