// The engine wires its units together: pricing (engine/choose/price.hpp) says what a request
// needs and whether it may run, the scheduler (engine/run/scheduler.hpp) gives it a workspace and
// its share of the memory budget, and the workspace (engine/run/workspace.hpp) runs its plan.
#include "engine/engine.hpp"

#include <chrono>
#include <utility>

#include "engine/choose/price.hpp"
#include "engine/plan/atlas_layout.hpp"
#include "engine/plan/sequence.hpp"
#include "engine/plan/uv_layouts.hpp"
#include "engine/run/scheduler.hpp"
#include "engine/run/warm_up.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

SchedulerOptions scheduler_options(const EngineOptions& o) {
  return {o.max_concurrent,  o.max_queue,         o.overtake_max_ms,   o.overtake_window_ms,
          o.spare_workspace, o.idle_memory_bytes, o.idle_trim_delay_ms};
}

}  // namespace

struct Engine::Impl {
  explicit Impl(EngineOptions o)
      : options(std::move(o)),
        device(std::make_shared<const cl::Device>(options.memory_budget, options.device,
                                                  options.kernel_profile)),
        programs(*device),
        resident(options.resident_scene_bytes),
        scheduler(scheduler_options(options), device, programs, resident) {}

  const Calibration& calibration() const {
    return options.calibration ? *options.calibration : Calibration::built_in();
  }
  // What every request and sequence is priced against.
  PriceLimits limits() const {
    return {{options.max_output_bytes, device->max_alloc_bytes()},
            options.max_request_cost_ms,
            options.max_sequence_cost_ms,
            device->budget_bytes(),
            &calibration()};
  }
  // `request` itself, or in `copy` with generated UV layouts where its atlas needs them.
  const RenderRequest& laid_out(const RenderRequest& request, RenderRequest& copy) {
    if (!uses_atlas(request)) return request;
    std::vector<uint32_t> meshes = meshes_to_lay_out(*request.scene, request.atlas.generate_uvs);
    if (meshes.empty()) return request;
    copy = request;
    copy.scene = layouts.apply(request.scene, request.atlas.generate_uvs);
    copy.generated_layouts = std::move(meshes);
    return copy;
  }
  RenderControl control(std::function<bool()> cancelled, const std::string& client,
                        double estimate_ms, CandidateCost candidate_cost = {},
                        Engine::Progress progress = {}) {
    return {options.max_request_cost_ms,
            options.profile,
            std::move(cancelled),
            &resident,
            &calibration(),
            std::move(candidate_cost),
            client,
            estimate_ms,
            cl::Runtime::kGuardSlackMs,
            std::move(progress)};
  }
  // A quote's limits, with a ResourceExhausted from `price` as its refusal.
  template <class Price>
  Quote quote(Price&& price) const {
    Quote q;
    q.max_request_ms = options.max_request_cost_ms;
    q.budget_bytes = device->budget_bytes();
    try {
      price(q);
    } catch (const ResourceExhausted& e) {
      q.refused_field = e.field();
      q.refusal = e.what();
    }
    return q;
  }

  EngineOptions options;
  std::shared_ptr<const cl::Device> device;
  cl::ProgramCache programs;
  ResidentScenes resident;
  UvLayouts layouts;
  Scheduler scheduler;  // last: its workspaces go before what they use
};

Engine::Engine(EngineOptions options) {
  if (options.max_concurrent == 0) throw std::invalid_argument("max_concurrent must be >= 1");
  const std::set<pid_t> threads_before = thread_ids();
  impl_ = std::make_unique<Impl>(std::move(options));
  const EngineOptions& o = impl_->options;
  impl_->device->turns().set_weights(o.client_weights);
  for (uint32_t i = 0; i < o.max_concurrent; ++i) {
    auto ws = std::make_unique<Workspace>(impl_->device, impl_->programs);
    if (i == 0)
      warm_up(*ws);  // the programs build once, engine-wide
    else
      ws->create_kernels();
    impl_->scheduler.add(std::move(ws));
  }
  // The runtime guard counts what they ran, not what other processes kept them waiting.
  if (impl_->device->record().type == cl::DeviceType::kCpu)
    impl_->device->core_share().watch(lower_device_threads(threads_before));
  impl_->scheduler.start();  // its idle trim: not a device thread
}

Engine::~Engine() = default;

Quote Engine::quote(const RenderRequest& request) const {
  return impl_->quote([&](Quote& q) {
    const Price p = price_request(request, impl_->limits(), true, 0);
    q.ms = p.ms, q.device_bytes = p.device_bytes, q.reply_bytes = p.reply_bytes;
    q.driver = p.driver;
    q.quality_goal = request.quality.goal != Quality::Goal::kNone;
  });
}

Quote Engine::quote(const SequenceRequest& sequence) const {
  return impl_->quote([&](Quote& q) {
    q.max_sequence_ms = impl_->options.max_sequence_cost_ms;
    const SequencePrice p = price_sequence(sequence, impl_->limits());
    q.ms = p.ms, q.device_bytes = p.device_bytes, q.reply_bytes = p.reply_bytes;
    q.frames = uint32_t(sequence.frames.size());
  });
}

RenderResult Engine::render(const RenderRequest& request, std::function<bool()> cancelled,
                            cl::Reservation* reply, uint64_t held_bytes, const std::string& client,
                            Progress progress) {
  const PriceLimits limits = impl_->limits();
  const Price price = price_request(request, limits, reply != nullptr, held_bytes);
  const bool goal = request.quality.goal != Quality::Goal::kNone;
  RenderRequest copy;
  const RenderRequest& req = impl_->laid_out(request, copy);
  const Scheduler::AtWork at_work(impl_->scheduler, client);
  const Clock::time_point queued = Clock::now();
  // A goal waits as a request of unknown cost: it never goes before one that waits for memory.
  Scheduler::Lease ws = impl_->scheduler.acquire(
      {client, cancelled, req.scene_held ? req.scene.get() : nullptr, price.device_bytes, 0, reply,
       price.reply_bytes, goal ? Scheduler::kNoEstimate : price.ms});
  const Clock::time_point started = Clock::now();
  // A goal's guard is left to its candidates' admission: its estimate is its pick's.
  RenderResult result =
      ws->render(req, price.plan,
                 impl_->control(std::move(cancelled), client, goal ? 0.0 : price.ms,
                                candidate_cost(price, limits), std::move(progress)));
  ws.release();
  result.queue_ms = ms_between(queued, started);
  result.run_ms = ms_between(started, Clock::now());
  return result;
}

void Engine::render_sequence(const SequenceRequest& sequence,
                             const std::function<void(RenderResult&&)>& frame_done,
                             std::function<bool()> cancelled, const std::string& client,
                             Progress progress) {
  const SequencePrice price = price_sequence(sequence, impl_->limits());
  const Scheduler::AtWork at_work(impl_->scheduler, client);
  uint64_t id = 0;  // the sequence's, in the workspace that holds its state
  for (size_t i = 0; i < sequence.frames.size(); ++i) {
    const Clock::time_point queued = Clock::now();
    // Each frame is admitted as a request is, so other clients' requests run between frames.
    Scheduler::Lease ws = impl_->scheduler.acquire(
        {client, cancelled, nullptr, price.device_bytes, id, nullptr, 0, price.frame_ms[i]});
    // Where another request had the workspace between frames (or the idle trim emptied it), the
    // sequence starts afresh: the same bits, without the reuse.
    if (id == 0 || ws->sequence() != id) id = ws->begin_sequence();
    const Clock::time_point started = Clock::now();
    RenderResult result;
    try {
      // One frame's copy of the scene at a time (frames that move instances).
      const RenderRequest frame = frame_request(sequence, i);
      RenderRequest copy;
      Progress frame_progress;
      if (progress)
        frame_progress = [&](const RenderProgress& p) {
          RenderProgress with_frames = p;
          with_frames.frames_done = uint32_t(i);
          with_frames.frames = uint32_t(sequence.frames.size());
          progress(with_frames);
        };
      result = ws->render(
          impl_->laid_out(frame, copy), price.plans[i],
          impl_->control(cancelled, client, price.frame_ms[i], {}, std::move(frame_progress)));
    } catch (...) {
      ws->end_sequence();
      throw;
    }
    result.frame = uint32_t(i);
    result.queue_ms = ms_between(queued, started);
    result.run_ms = ms_between(started, Clock::now());
    if (i + 1 == sequence.frames.size()) ws->end_sequence();
    // The frame goes to its reader, at the reader's pace, without the workspace: a slow reader
    // holds up no one, and an idle server gives the sequence its own workspace back.
    ws.release();
    frame_done(std::move(result));
  }
}

void Engine::check_scene(const std::shared_ptr<const Scene>& scene, std::function<bool()> cancelled,
                         const std::string& client) {
  validate_scene(*scene, impl_->limits().validation);
  const Scheduler::AtWork at_work(impl_->scheduler, client);
  Scheduler::Lease ws =
      impl_->scheduler.acquire({client, cancelled, nullptr, ResidentScenes::bytes_of(*scene)});
  ws->make_resident(scene, impl_->resident, std::move(cancelled), client);
}

cl::Reservation Engine::reserve(uint64_t bytes, const std::string& what) {
  return impl_->device->reserve(bytes, what);
}

std::vector<cl::DeviceTurns::Total> Engine::device_time_by_client() const {
  return impl_->device->turns().totals();
}

uint64_t Engine::device_bytes_in_use() const {
  return impl_->device->allocated_bytes();
}

uint64_t Engine::buffer_peak_bytes() const {
  return impl_->device->buffer_peak_bytes();
}

void Engine::reset_buffer_peak() {
  impl_->device->reset_buffer_peak();
}

uint64_t Engine::memory_budget_bytes() const {
  return impl_->device->budget_bytes();
}

Engine::Load Engine::load() const {
  const Scheduler::Load l = impl_->scheduler.load();
  return {l.rendering, l.workspaces, l.waiting};
}

const EngineOptions& Engine::options() const {
  return impl_->options;
}
std::string Engine::device_name() const {
  return impl_->device->device_name();
}
const cl::DeviceRecord& Engine::device() const {
  return impl_->device->record();
}
const cl::DeviceProfile& Engine::profile() const {
  return impl_->device->profile();
}

}  // namespace shadow
