// Scenes kept on the device between requests: the scene cache's scenes (UploadScene), so a
// request by scene id neither uploads nor checks its scene again. Shared by every workspace
// (buffers of one context serve any queue once written); least recently used out first under a
// byte budget of device memory. Keyed by the Scene object: the service hands every request by
// one id the same shared Scene, and an entry whose Scene is gone is dropped.
#pragma once

#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>

#include "engine/passes/scene_buffers.hpp"

namespace shadow {

class ResidentScenes {
 public:
  explicit ResidentScenes(uint64_t budget_bytes) : budget_(budget_bytes) {}

  // The scene's buffers, made by `upload` (outside the lock) unless held; `held` says which.
  // A scene over the whole budget is uploaded and not kept.
  std::shared_ptr<const SceneBuffers> get(
      const std::shared_ptr<const Scene>& scene,
      const std::function<std::shared_ptr<const SceneBuffers>()>& upload, bool& held);

  // The scene's buffers if held, else null (no upload, no change of order).
  std::shared_ptr<const SceneBuffers> held(const std::shared_ptr<const Scene>& scene) const;

  uint64_t bytes() const;
  static uint64_t bytes_of(const Scene& scene);  // its positions and indices on the device

 private:
  struct Entry {
    std::weak_ptr<const Scene> scene;
    std::shared_ptr<const SceneBuffers> buffers;
    uint64_t bytes;
  };
  uint64_t budget_;
  mutable std::mutex mutex_;
  std::list<Entry> entries_;  // most recently used first
  uint64_t bytes_ = 0;
};

}  // namespace shadow
