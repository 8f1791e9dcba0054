#include "service/scene_cache.hpp"

#include <algorithm>

#include "wire/errors.hpp"

namespace shadow::service {

uint64_t SceneCache::bytes_of(const Scene& scene) {
  uint64_t bytes = scene.instances.size() * sizeof(Instance) + scene.meshes.size() * sizeof(Mesh);
  for (const Mesh& m : scene.meshes)
    bytes += (m.positions.size() + m.normals.size() + m.uvs.size()) * sizeof(float) +
             m.indices.size() * sizeof(uint32_t);
  return bytes;
}

uint64_t SceneCache::tenant_limit() const {
  return limits_.tenant_bytes == 0 ? limits_.total_bytes
                                   : std::min(limits_.tenant_bytes, limits_.total_bytes);
}

void SceneCache::check_fits(uint64_t bytes, const std::string& field) const {
  if (bytes > tenant_limit())
    throw ResourceExhausted(field, "the scene needs " + std::to_string(bytes) +
                                       " bytes, over the server's scene cache budget of " +
                                       std::to_string(tenant_limit()) + " per tenant");
}

std::shared_ptr<const Scene> SceneCache::find(const std::string& tenant, const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = entries_.find({tenant, id});
  if (it == entries_.end()) return nullptr;
  order_.splice(order_.begin(), order_, it->second.order);
  return it->second.scene;
}

std::shared_ptr<const Scene> SceneCache::get(const std::string& tenant, const std::string& id,
                                             const std::string& field) {
  std::shared_ptr<const Scene> scene = find(tenant, id);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++(scene ? usage_[tenant].hits : usage_[tenant].misses);
  }
  if (!scene)
    throw NotFound(field, "the server holds no scene '" + id +
                              "' (never uploaded, or evicted): upload it with UploadScene and ask "
                              "again");
  return scene;
}

void SceneCache::evict_until(const std::string* tenant, uint64_t free_bytes) {
  const uint64_t limit = tenant ? tenant_limit() : limits_.total_bytes;
  const auto used = [&] {
    if (tenant) return usage_[*tenant].bytes;
    uint64_t all = 0;
    for (const auto& [name, u] : usage_) all += u.bytes;
    return all;
  };
  // Oldest first; only the tenant's own scenes for its own budget.
  for (auto it = order_.end(); used() + free_bytes > limit && it != order_.begin();) {
    --it;
    if (tenant && it->first != *tenant) continue;
    const auto entry = entries_.find(*it);
    Usage& u = usage_[it->first];
    u.bytes -= entry->second.bytes;
    --u.scenes;
    ++u.evictions;
    entries_.erase(entry);
    it = order_.erase(it);
  }
}

bool SceneCache::put(const std::string& tenant, const std::string& id,
                     std::shared_ptr<const Scene> scene) {
  const uint64_t bytes = bytes_of(*scene);
  check_fits(bytes, "scene");
  std::lock_guard<std::mutex> lock(mutex_);
  const Key key{tenant, id};
  if (const auto it = entries_.find(key); it != entries_.end()) {
    order_.splice(order_.begin(), order_, it->second.order);
    return false;
  }
  evict_until(&tenant, bytes);
  evict_until(nullptr, bytes);
  order_.push_front(key);
  entries_.emplace(key, Entry{std::move(scene), bytes, order_.begin()});
  Usage& u = usage_[tenant];
  u.bytes += bytes;
  ++u.scenes;
  return true;
}

SceneCache::Usage SceneCache::usage(const std::string* tenant) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (tenant) {
    const auto it = usage_.find(*tenant);
    return it == usage_.end() ? Usage{} : it->second;
  }
  Usage all;
  for (const auto& [name, u] : usage_) {
    all.scenes += u.scenes, all.bytes += u.bytes, all.hits += u.hits, all.misses += u.misses;
    all.evictions += u.evictions;
  }
  return all;
}

}  // namespace shadow::service
