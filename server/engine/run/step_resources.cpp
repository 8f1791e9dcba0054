#include "engine/run/step_resources.hpp"

#include <stdexcept>
#include <string>

namespace shadow {

bool StepLedger::enter(const Step& step) {
  const bool shared = is_shared(step.kind);
  const bool next_light = !shared && step.light != light_;
  if (next_light) {
    light_ = step.light;
    light_written_.reset();
  }
  for (Resource r : step.reads)
    if (!shared_[size_t(r)] && !light_written_[size_t(r)])
      throw std::logic_error("plan: step " + step.name + " reads resource " +
                             std::to_string(int(r)) + " before any step writes it");
  return next_light;
}

void StepLedger::done(const Step& step) {
  auto& set = is_shared(step.kind) ? shared_ : light_written_;
  for (Resource r : step.writes) set.set(size_t(r));
}

bool StepLedger::written(Resource r, bool shared) const {
  return shared ? shared_[size_t(r)] : light_written_[size_t(r)];
}

}  // namespace shadow
