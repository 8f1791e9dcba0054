#include "service/scene_cache.hpp"

#include <algorithm>
#include <set>

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

std::vector<std::list<SceneCache::Key>::iterator> SceneCache::victims(const std::string& tenant,
                                                                      uint64_t bytes) {
  // What each tenant holding scenes, and the uploader, would hold after the evictions so far.
  std::map<std::string, uint64_t> held;
  uint64_t total = 0;
  for (const auto& [name, u] : usage_)
    if (u.scenes > 0) held[name] = u.bytes, total += u.bytes;
  held.try_emplace(tenant, 0);
  const uint64_t share = std::min(tenant_limit(), limits_.total_bytes / held.size());
  std::vector<std::list<Key>::iterator> out;
  std::set<Key> taken;
  const auto take = [&](std::list<Key>::iterator it) {
    const uint64_t b = entries_.at(*it).bytes;
    held[it->first] -= b;
    total -= b;
    taken.insert(*it);
    out.push_back(it);
  };
  // Oldest first. The tenant's own budget: its own scenes.
  for (auto it = order_.end(); held[tenant] + bytes > tenant_limit() && it != order_.begin();) {
    --it;
    if (it->first == tenant) take(it);
  }
  // The total budget: scenes of tenants over their share, each while it still is.
  const auto over_share = [&](const std::string& name) {
    return held[name] + (name == tenant ? bytes : 0) > share;
  };
  for (auto it = order_.end(); total + bytes > limits_.total_bytes && it != order_.begin();) {
    --it;
    if (!taken.count(*it) && over_share(it->first)) take(it);
  }
  // Then the uploader is over its share with none of its own scenes left to give.
  if (total + bytes > limits_.total_bytes)
    throw ResourceExhausted(
        "scene_cache", "the scene's " + std::to_string(bytes) +
                           " bytes do not fit the server's scene cache (--scene-cache-bytes " +
                           std::to_string(limits_.total_bytes) + " shared by " +
                           std::to_string(held.size()) + " tenants, a fair share of " +
                           std::to_string(share) +
                           " bytes each) without evicting scenes of tenants within their share; "
                           "retry when they hold less, or upload a smaller scene");
  return out;
}

void SceneCache::evict(std::list<Key>::iterator key) {
  const auto entry = entries_.find(*key);
  Usage& u = usage_[key->first];
  u.bytes -= entry->second.bytes;
  --u.scenes;
  ++u.evictions;
  entries_.erase(entry);
  order_.erase(key);
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
  const auto evicted = victims(tenant, bytes);
  // Counted inside the server's memory budget (issue 51): refused, evicting nothing, when the
  // budget has no room for it now.
  cl::Reservation held = reserve_ ? reserve_(bytes) : cl::Reservation();
  for (const auto victim : evicted) evict(victim);
  order_.push_front(key);
  entries_.emplace(key, Entry{std::move(scene), bytes, order_.begin(), std::move(held)});
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
