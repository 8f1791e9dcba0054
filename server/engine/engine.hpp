// The shadow engine: validates a request, plans the passes its products need, runs them as
// OpenCL kernels and returns the textures. Thread-safe: requests are serialized on one queue.
#pragma once

#include <cstdint>
#include <memory>

#include "engine/types.hpp"

namespace shadow {

struct EngineOptions {
  uint64_t max_output_bytes = uint64_t{1} << 30;  // sum of all returned textures
  bool profile = true;                            // per-pass device timings
};

class Engine {
 public:
  explicit Engine(EngineOptions options = {});
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // Throws InvalidArgument / ResourceExhausted for bad requests, cl::Error for device failures.
  RenderResult render(const RenderRequest& request);

  const EngineOptions& options() const;
  std::string device_name() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadow
