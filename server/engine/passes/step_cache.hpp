// Which results a workspace may take from its last runs instead of running their step again
// (issue 52): the maps and the camera's raster, the G-buffer resolve, the CSM basis, the atlas'
// bake, each light's atlas, its prefilters and its soft atlas.
// - A reusable step has a slot (where its result lives: its pass's buffers) and a key, a hash of
//   exactly its declared inputs: the scene's device copy, the light, the fit, sizes, flags,
//   settings, the kernel build options and the stamps of the results it reads.
// - A step whose slot holds its key's result takes it (a hit: RenderResult::reused names the
//   pass); any other runs, and its slot then holds its key (a slot that held another key's
//   result is a miss: RenderResult::rerun names it).
// - Only sequences and requests that continue the last on a held scene keep results (keep());
//   everything else runs every step.
#pragma once

#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include <glm/glm.hpp>

#include "engine/cl/timeline.hpp"
#include "wire/types.hpp"

namespace shadow {

// A step's key: FNV-1a over its declared inputs, added field by field (padding never enters).
class StepKey {
 public:
  StepKey& bytes(const void* data, size_t size) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) hash_ = (hash_ ^ b[i]) * 1099511628211ull;
    return *this;
  }
  // Numbers, enums and GLM vectors and matrices (no padding): their bits.
  template <class T>
  requires std::is_arithmetic_v<T> || std::is_enum_v<T> StepKey& add(T v) {
    return bytes(&v, sizeof v);
  }
  template <glm::length_t L, class T, glm::qualifier Q>
  StepKey& add(const glm::vec<L, T, Q>& v) {
    return bytes(&v, sizeof v);
  }
  template <glm::length_t C, glm::length_t R, class T, glm::qualifier Q>
  StepKey& add(const glm::mat<C, R, T, Q>& m) {
    return bytes(&m, sizeof m);
  }
  StepKey& add(const std::string& s) { return add(s.size()).bytes(s.data(), s.size()); }
  // A result another step made, named by where it lives and the run that wrote it.
  StepKey& add(const void* where, uint64_t version) {
    return add(reinterpret_cast<uintptr_t>(where)).add(version);
  }
  // The request's fields a step's result depends on.
  StepKey& add(const Light& l) {
    return add(l.type).add(l.position).add(l.direction).add(l.cone_angle_deg).add(l.size);
  }
  StepKey& add(const Filter& f) {
    add(f.kind).add(f.poisson.taps).add(f.poisson.radius).add(f.poisson.rotate);
    add(f.pcss.blocker_samples).add(f.pcss.filter_samples).add(f.pcss.rotate);
    add(f.blur.radius).add(f.blur.passes);
    const CsmSettings& c = f.csm;
    return add(c.terms)
        .add(c.storage)
        .add(c.window)
        .add(c.damping)
        .add(c.depth_offset)
        .add(c.scale)
        .add(c.lookup);
  }
  // What the shadow test reads of the map's settings besides the map (its bias).
  StepKey& add_test(const ShadowMapSettings& s) {
    return add(s.size).add(s.bias_constant).add(s.bias_slope);
  }
  uint64_t value() const { return hash_; }

 private:
  uint64_t hash_ = 1469598103934665603ull;
};

class StepCache {
 public:
  // Whether results are kept for a later frame or request; either way every slot is forgotten.
  void keep(bool on) {
    keeping_ = on;
    slots_.clear();
  }
  bool keeping() const { return keeping_; }

  // While keeping, whether `slot` holds the result of `key`: then the pass `pass` is recorded as
  // kept. Otherwise the slot is forgotten until made(), and if it held another key's result the
  // pass is recorded as run again.
  bool take(const std::string& slot, uint64_t key, const std::string& pass, Timeline& timeline) {
    if (!keeping_) return false;
    const auto it = slots_.find(slot);
    if (it != slots_.end() && it->second == key) {
      timeline.reuse(pass);
      return true;
    }
    if (it != slots_.end()) {
      timeline.rerun(pass);
      slots_.erase(it);
    }
    return false;
  }
  // `slot` holds the result of `key` now (kept only while keeping).
  void made(const std::string& slot, uint64_t key) {
    if (keeping_) slots_[slot] = key;
  }
  // `slot`'s result was overwritten by a step that keeps nothing.
  void forget(const std::string& slot) { slots_.erase(slot); }

 private:
  bool keeping_ = false;
  std::map<std::string, uint64_t> slots_;
};

}  // namespace shadow
