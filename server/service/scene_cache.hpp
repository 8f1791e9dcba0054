// The scenes clients uploaded (UploadScene), checked and converted, for requests that name them
// by id. Least recently used first out, under a byte budget in all and one per tenant. Each
// tenant has its own set: a tenant can neither render nor learn of another tenant's scenes (an
// id another tenant uploaded is NOT_FOUND, as if never uploaded, so a client re-uploads it).
//
// Tenants do not evict each other within their fair share: min(tenant budget, total budget /
// the tenants holding scenes, the uploader counted). A new scene makes room for the tenant
// budget from the uploader's own least recently used scenes; then for the total budget from the
// least recently used scenes of tenants over their share (the uploader counted with its new
// scene), each only while its tenant is still over it. Were any tenant's scenes evicted below
// that, the sum of the per-tenant budgets (often above the total) would let one busy tenant
// empty everyone else's; instead a scene that still does not fit is refused, and evicts nothing.
#pragma once

#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "engine/cl/runtime.hpp"
#include "wire/types.hpp"

namespace shadow::service {

class SceneCache {
 public:
  struct Limits {
    uint64_t total_bytes = uint64_t{2} << 30;
    uint64_t tenant_bytes = 0;  // 0: as total_bytes
  };
  // Each scene held takes its bytes from `reserve` (the engine's memory budget), so the cache
  // counts inside the budget; empty: counted nowhere.
  using Reserve = std::function<cl::Reservation(uint64_t bytes)>;
  explicit SceneCache(Limits limits, Reserve reserve = {})
      : limits_(limits), reserve_(std::move(reserve)) {}

  // The bytes a scene counts: its arrays and instances.
  static uint64_t bytes_of(const Scene& scene);
  // Whether a scene of `bytes` may be cached for a tenant at all (else ResourceExhausted naming
  // `field`), so an upload over the budget is refused before its bytes arrive.
  void check_fits(uint64_t bytes, const std::string& field) const;

  // The tenant's scene `id` (now the most recently used), or nullptr.
  std::shared_ptr<const Scene> find(const std::string& tenant, const std::string& id);
  // As find, for a request: NotFound naming `field` when absent; counted as a hit or a miss.
  std::shared_ptr<const Scene> get(const std::string& tenant, const std::string& id,
                                   const std::string& field);
  // Holds `scene` for the tenant under `id`, evicting least recently used scenes as the budgets
  // need and the fair share allows (above). False when it held the id already (the new copy is
  // dropped). ResourceExhausted naming `scene_cache` when it cannot fit without evicting
  // another tenant within its share, or naming `memory_budget` when the budget has no room.
  bool put(const std::string& tenant, const std::string& id, std::shared_ptr<const Scene> scene);

  struct Usage {
    uint64_t scenes = 0, bytes = 0, hits = 0, misses = 0, evictions = 0;
  };
  Usage usage(const std::string* tenant = nullptr) const;  // null: all tenants

 private:
  using Key = std::pair<std::string, std::string>;  // tenant, id
  struct Entry {
    std::shared_ptr<const Scene> scene;
    uint64_t bytes;
    std::list<Key>::iterator order;
    cl::Reservation held;  // its bytes of the memory budget
  };
  // The scenes `put` evicts to make room for `bytes` of the tenant's, oldest first; throws
  // when they are not enough. Evicts nothing itself, so a refused scene costs no one a scene.
  std::vector<std::list<Key>::iterator> victims(const std::string& tenant, uint64_t bytes);
  void evict(std::list<Key>::iterator key);
  uint64_t tenant_limit() const;

  Limits limits_;
  Reserve reserve_;
  mutable std::mutex mutex_;
  std::map<Key, Entry> entries_;
  std::list<Key> order_;                // most recently used first
  std::map<std::string, Usage> usage_;  // per tenant
};

}  // namespace shadow::service
