#include "engine/run/resident_scenes.hpp"

namespace shadow {

uint64_t ResidentScenes::bytes_of(const Scene& scene) {
  uint64_t bytes = 0;
  for (const Mesh& m : scene.meshes)
    bytes += m.positions.size() * sizeof(float) + m.indices.size() * sizeof(uint32_t);
  return bytes;
}

uint64_t ResidentScenes::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

std::shared_ptr<const SceneBuffers> ResidentScenes::held(
    const std::shared_ptr<const Scene>& scene) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const Entry& e : entries_)
    if (e.scene.lock() == scene) return e.buffers;
  return nullptr;
}

std::shared_ptr<const SceneBuffers> ResidentScenes::get(
    const std::shared_ptr<const Scene>& scene,
    const std::function<std::shared_ptr<const SceneBuffers>()>& upload, bool& held) {
  // The scene's entry, now the most recently used; drops entries whose scene is gone.
  const auto find = [&]() -> const Entry* {
    for (auto it = entries_.begin(); it != entries_.end();) {
      const std::shared_ptr<const Scene> alive = it->scene.lock();
      if (!alive) {  // its scene left the scene cache and every request
        bytes_ -= it->bytes;
        it = entries_.erase(it);
      } else if (alive == scene) {
        entries_.splice(entries_.begin(), entries_, it);
        return &entries_.front();
      } else {
        ++it;
      }
    }
    return nullptr;
  };
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (const Entry* entry = find()) {
      held = true;
      return entry->buffers;
    }
  }
  held = false;
  std::shared_ptr<const SceneBuffers> buffers = upload();  // may throw: nothing is kept
  const uint64_t bytes = bytes_of(*scene);
  std::lock_guard<std::mutex> lock(mutex_);
  if (const Entry* other = find()) return other->buffers;  // another request uploaded it too
  if (bytes > budget_) return buffers;
  while (bytes_ + bytes > budget_) {
    bytes_ -= entries_.back().bytes;
    entries_.pop_back();  // its buffers go when their last request ends
  }
  entries_.push_front({scene, buffers, bytes});
  bytes_ += bytes;
  return buffers;
}

}  // namespace shadow
