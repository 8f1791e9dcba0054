#include "engine/engine.hpp"

#include <sys/resource.h>
#include <sys/types.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "engine/choose/quality_pick.hpp"
#include "engine/plan/atlas_layout.hpp"
#include "engine/plan/cost.hpp"
#include "engine/plan/plan.hpp"
#include "engine/plan/sequence.hpp"
#include "engine/plan/uv_layouts.hpp"
#include "engine/plan/validate.hpp"
#include "engine/run/workspace.hpp"
#include "wire/errors.hpp"
#include "wire/units.hpp"

namespace shadow {
namespace {

constexpr int kDeviceThreadNice = 10;

// A one-triangle scene that runs every pass once, so no request pays for a compile.
RenderRequest warm_up_request() {
  auto scene = std::make_shared<Scene>();
  Mesh m;
  m.positions = {-1,    0,    -1,    1,    0,    -1,    0, 0,    1,
                 -0.2f, 0.5f, -0.2f, 0.2f, 0.5f, -0.2f, 0, 0.5f, 0.2f};
  m.indices = {0, 1, 2, 3, 4, 5};
  m.uvs = {0, 0, 0.5f, 0, 0, 0.5f, 0.6f, 0.6f, 1, 0.6f, 0.6f, 1};  // for the atlas
  scene->meshes.push_back(m);
  scene->instances.push_back(Instance{});
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {0, 3, 3};
  r.camera.width = 64;
  r.camera.height = 64;
  r.shadow_map.size = 256;
  r.products = {Product::kShadowMap,      Product::kVisibility,    Product::kPosition,
                Product::kTexelDensity,   Product::kShadowMapMips, Product::kShadowMapSat,
                Product::kVisibilityMips, Product::kVisibilitySat};
  return r;
}

// The process' threads now (Linux: /proc/self/task), to tell the ones the device starts.
std::set<pid_t> thread_ids() {
  std::set<pid_t> ids;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/task", ec))
    ids.insert(pid_t(std::atoi(entry.path().filename().c_str())));
  return ids;
}

// A CPU device's worker threads (PoCL's, started while the engine warmed up) run kernels at a
// lower priority than the threads that take calls, stream replies and do requests' host work:
// under heavy kernels a small request's host work and its client on the same machine would
// otherwise get a third of a core (a bystander's 1024x768 render waited 0.5-0.9 s beside six
// heavy requests, 0.45-0.6 s with this). The kernels lose nothing while the host is idle.
void lower_device_threads(const std::set<pid_t>& before) {
  for (pid_t id : thread_ids())
    if (!before.count(id)) setpriority(PRIO_PROCESS, id_t(id), kDeviceThreadNice);
}

}  // namespace

struct Engine::Impl {
  explicit Impl(EngineOptions o)
      : options(o),
        device(std::make_shared<const cl::Device>(o.memory_budget, o.device, o.kernel_profile)),
        programs(*device),
        resident(o.resident_scene_bytes) {}

  // Waits, first come first served, until a workspace is free and `device_bytes` (the cost
  // estimate's device buffers) of the memory budget can be pledged to it (Workspace::pledge).
  // Picks the workspace that kept its last results for `scene` if free, else one that kept
  // none and holds no sequence, else the one idle longest. Throws ResourceExhausted when the queue
  // is full, or when the buffers do not fit even with nothing rendering and every idle workspace
  // emptied (the budget is held by replies, uploads and waiting requests); Cancelled once
  // `cancelled` says so. A sequence between frames names itself (`sequence`) to get back the
  // workspace that holds its state if still idle; whoever gets a workspace holding another
  // sequence's state ends it.
  // With `reply`, its `reply_bytes` are reserved there with the pledge, under the same wait.
  // `estimated_ms`: the request's cost estimate, for going before one that waits for memory
  // (may_overtake); infinity for what has none.
  // Between clients (`client`: a tenant or a peer), the first in line is not the first to come
  // but the waiter whose client has used the least device time (cl::DeviceTurns' usage; first
  // come first served among equals), and a client that holds a workspace never takes the last
  // free one (EngineOptions::spare_workspace).
  std::unique_ptr<Workspace> acquire(const std::string& client,
                                     const std::function<bool()>& cancelled, const Scene* scene,
                                     uint64_t device_bytes, uint64_t sequence = 0,
                                     cl::Reservation* reply = nullptr, uint64_t reply_bytes = 0,
                                     double estimated_ms = kNoEstimate);
  static constexpr double kNoEstimate = std::numeric_limits<double>::infinity();
  // With the mutex held: whether `client` may take a free workspace now (the spare one is for a
  // client that holds none).
  bool may_take(const std::string& client) const;
  // With the mutex held: the ticket of the waiter that goes next when a workspace is free, among
  // those that may take one; none if none may.
  std::optional<uint64_t> first_in_line() const;
  // With the mutex held: whether waiter `ticket` may go before the first in line, which waits
  // for memory alone (a workspace is free) and has done so for less than the window.
  bool may_overtake(uint64_t ticket, double estimated_ms) const;
  void release(std::unique_ptr<Workspace> ws, const std::string& client);
  // A client's work in the engine, from admission to its end: its device usage orders turns
  // and admission while it lasts (cl::DeviceTurns::enter).
  struct AtWork {
    AtWork(cl::DeviceTurns& turns, std::string client) : turns(turns), client(std::move(client)) {
      turns.enter(this->client);
    }
    ~AtWork() { turns.leave(client); }
    AtWork(const AtWork&) = delete;
    AtWork& operator=(const AtWork&) = delete;
    cl::DeviceTurns& turns;
    std::string client;
  };
  // With the mutex held: if nothing runs or waits and more than idle_memory_bytes are in use,
  // empty_idle(spare).
  std::vector<std::unique_ptr<Workspace>> trim(const Workspace* spare);
  // With the mutex held: every idle workspace but `spare` (when it keeps a held scene's results)
  // starts over empty; the emptied ones are returned, to be destroyed outside the lock.
  std::vector<std::unique_ptr<Workspace>> empty_idle(const Workspace* spare);
  // A request's share of the budget: the pledge for its device buffers and its reply's bytes.
  struct Share {
    cl::Reservation pledge, reply;
  };
  // That share, if free now.
  std::optional<Share> share(uint64_t device_bytes, uint64_t reply_bytes);
  // The pledge for `device_bytes` of estimated buffers: as the workspace will allocate them,
  // with the runtime's headroom, within the budget.
  uint64_t pledged_bytes(uint64_t device_bytes) const {
    return std::min(cl::Runtime::grown(device_bytes), device->budget_bytes());
  }
  // The trimming thread's loop (idle_trim_delay_ms > 0): trims once trim_at has passed.
  void trim_when_due();
  // `request` itself, or in `copy` with generated UV layouts where its atlas needs them.
  const RenderRequest& laid_out(const RenderRequest& request, RenderRequest& copy);
  // What admission knows of a request before it waits: validated, planned, priced and checked
  // against the limits (ResourceExhausted naming the one it meets). The device buffers it waits
  // for (a goal's: its probe's, the least it needs) and, `with_reply`, its reply's bytes (a
  // goal's largest candidate's); `held_bytes` as render()'s.
  struct Price {
    Plan plan;
    double ms = 0;  // a goal's: its probe's
    std::string driver;
    uint64_t device_bytes = 0, reply_bytes = 0;
    double probe_ms = 0;  // a goal's probe, added to each candidate's
    PredictedTime probe_predicted;
  };
  Price price(const RenderRequest& request, bool with_reply, uint64_t held_bytes) const;
  // A sequence's: every frame's plan and estimate, their sum against max_sequence_cost_ms, and
  // the largest frame's buffers (what each frame waits for) and reply.
  struct SequencePrice {
    std::vector<Plan> plans;
    std::vector<double> frame_ms;
    double ms = 0;
    uint64_t device_bytes = 0, reply_bytes = 0;
  };
  SequencePrice price(const SequenceRequest& sequence) const;
  const Calibration& calibration() const {
    return options.calibration ? *options.calibration : Calibration::built_in();
  }
  // What validation holds every request to: the reply's bytes and the device's buffer size.
  Limits limits() const { return {options.max_output_bytes, device->max_alloc_bytes()}; }

  EngineOptions options;
  std::shared_ptr<const cl::Device> device;
  cl::ProgramCache programs;
  ResidentScenes resident;
  UvLayouts layouts;
  std::mutex mutex;
  std::condition_variable freed;
  std::vector<std::unique_ptr<Workspace>> idle;  // workspaces no request holds
  struct Waiter {
    uint64_t ticket;
    std::string client;
  };
  std::deque<Waiter> waiting;               // the requests waiting, in the order they came
  std::map<std::string, uint32_t> holding;  // workspaces each client holds
  uint64_t next_ticket = 0;
  // The first in line's ticket and since when it has found a workspace free but not its memory.
  std::optional<std::pair<uint64_t, std::chrono::steady_clock::time_point>> short_of_memory;
  // When to trim: set as the last request ends (the trim then checks the memory), reset when one
  // starts.
  std::optional<std::chrono::steady_clock::time_point> trim_at;
  const Workspace* trim_spare = nullptr;  // the workspace released last
  bool stopping = false;
  std::condition_variable trim_wake;
  std::thread trimmer;  // runs trim_when_due; joined by ~Engine
};

std::vector<std::unique_ptr<Workspace>> Engine::Impl::trim(const Workspace* spare) {
  if (idle.size() != options.max_concurrent || !waiting.empty() ||
      device->allocated_bytes() <= options.idle_memory_bytes + resident.bytes())
    return {};
  return empty_idle(spare);
}

std::vector<std::unique_ptr<Workspace>> Engine::Impl::empty_idle(const Workspace* spare) {
  std::vector<std::unique_ptr<Workspace>> emptied;
  for (std::unique_ptr<Workspace>& w : idle) {
    if (w.get() == spare && (w->warm_scene() || w->sequence())) continue;
    // A fresh workspace takes a few bytes of the budget; when even those are not free (uploads
    // and replies can hold it all), this workspace keeps its buffers: a trim is only a saving.
    std::unique_ptr<Workspace> fresh;
    try {
      fresh = std::make_unique<Workspace>(device, programs);
    } catch (const std::exception&) {
      break;
    }
    emptied.push_back(std::exchange(w, std::move(fresh)));
  }
  return emptied;
}

void Engine::Impl::trim_when_due() {
  std::unique_lock<std::mutex> lock(mutex);
  while (!stopping) {
    if (!trim_at) {
      trim_wake.wait(lock);
    } else if (std::chrono::steady_clock::now() < *trim_at) {
      trim_wake.wait_until(lock, *trim_at);
    } else {
      trim_at.reset();
      std::vector<std::unique_ptr<Workspace>> emptied;
      try {
        emptied = trim(trim_spare);
      } catch (const std::exception& e) {
        // Nothing may escape this thread (std::terminate would end every request); a trim is
        // only a saving, so the next one tries again.
        std::cerr << "shadow-engine: the idle trim failed: " << e.what() << '\n';
      }
      lock.unlock();
      emptied.clear();  // their buffers go back outside the lock
      lock.lock();
    }
  }
}

const RenderRequest& Engine::Impl::laid_out(const RenderRequest& request, RenderRequest& copy) {
  if (!uses_atlas(request)) return request;
  std::vector<uint32_t> meshes = meshes_to_lay_out(*request.scene, request.atlas.generate_uvs);
  if (meshes.empty()) return request;
  copy = request;
  copy.scene = layouts.apply(request.scene, request.atlas.generate_uvs);
  copy.generated_layouts = std::move(meshes);
  return copy;
}

std::optional<Engine::Impl::Share> Engine::Impl::share(uint64_t device_bytes,
                                                       uint64_t reply_bytes) {
  try {
    Share s;
    s.pledge = device->reserve(pledged_bytes(device_bytes), "request's device buffers");
    s.reply = device->reserve(reply_bytes, "reply");
    return s;
  } catch (const ResourceExhausted&) {
    return std::nullopt;  // what was reserved goes back
  }
}

bool Engine::Impl::may_take(const std::string& client) const {
  if (!options.spare_workspace || options.max_concurrent == 1 || idle.size() > 1) return true;
  const auto held = holding.find(client);
  return held == holding.end() || held->second == 0;
}

std::optional<uint64_t> Engine::Impl::first_in_line() const {
  std::optional<uint64_t> first;
  double least = 0;
  for (const Waiter& w : waiting) {
    if (!may_take(w.client)) continue;
    const double usage = device->turns().usage(w.client);
    if (!first || usage < least) first = w.ticket, least = usage;  // earlier tickets win ties
  }
  return first;
}

bool Engine::Impl::may_overtake(uint64_t ticket, double estimated_ms) const {
  const std::optional<uint64_t> first = first_in_line();
  return first != ticket && estimated_ms <= options.overtake_max_ms && short_of_memory &&
         short_of_memory->first == first &&
         std::chrono::steady_clock::now() - short_of_memory->second <
             std::chrono::milliseconds(options.overtake_window_ms);
}

std::unique_ptr<Workspace> Engine::Impl::acquire(const std::string& client,
                                                 const std::function<bool()>& cancelled,
                                                 const Scene* scene, uint64_t device_bytes,
                                                 uint64_t sequence, cl::Reservation* reply,
                                                 uint64_t reply_bytes, double estimated_ms) {
  std::unique_lock<std::mutex> lock(mutex);
  std::optional<Share> shared;
  // Those already waiting go first (but see may_overtake).
  if (idle.empty() || !waiting.empty() || !may_take(client) ||
      !(shared = share(device_bytes, reply_bytes))) {
    // Waiters about to take a workspace just freed are not in the queue any more.
    const size_t queued = waiting.size() - std::min(waiting.size(), idle.size());
    if (queued >= options.max_queue)
      throw ResourceExhausted("server queue",
                              "the queue is full: " + std::to_string(options.max_concurrent) +
                                  " requests are rendering and " + std::to_string(queued) +
                                  " are waiting (--max-queue " + std::to_string(options.max_queue) +
                                  "); retry later");
    const uint64_t ticket = next_ticket++;
    waiting.push_back({ticket, client});
    const auto erase = [&] {
      waiting.erase(std::find_if(waiting.begin(), waiting.end(),
                                 [&](const Waiter& w) { return w.ticket == ticket; }));
    };
    const auto leave = [&] {
      erase();
      freed.notify_all();  // the next in line may be first now
    };
    bool emptied_idle = false;
    for (;;) {
      if (!idle.empty() && first_in_line() == ticket) {
        if ((shared = share(device_bytes, reply_bytes))) break;
        if (!short_of_memory || short_of_memory->first != ticket) {
          short_of_memory.emplace(ticket, std::chrono::steady_clock::now());
          freed.notify_all();  // small requests behind may go first now
        }
        // Nothing renders, so nothing that runs will give memory back: empty the idle
        // workspaces' scratch once; if that is not enough, the budget is held by replies,
        // uploads and requests waiting, and waiting here would hold up everyone behind.
        if (idle.size() == options.max_concurrent) {
          if (!emptied_idle) {
            std::vector<std::unique_ptr<Workspace>> emptied = empty_idle(nullptr);
            lock.unlock();
            emptied.clear();  // their buffers go back outside the lock
            lock.lock();
            emptied_idle = true;
            continue;
          }
          leave();
          throw ResourceExhausted(
              "memory_budget",
              "the request's " + std::to_string(device_bytes) + " bytes of device buffers and " +
                  std::to_string(reply_bytes) + "-byte reply do not fit beside the " +
                  std::to_string(device->allocated_bytes()) +
                  " bytes that replies being streamed, scene uploads, held scenes and waiting "
                  "requests hold of the server's " +
                  std::to_string(device->budget_bytes()) +
                  "-byte memory budget (--memory-budget); retry later");
        }
      }
      if (!idle.empty() && may_take(client) && may_overtake(ticket, estimated_ms) &&
          (shared = share(device_bytes, reply_bytes)))
        break;
      // Poll the caller's cancellation while waiting: a gRPC deadline has no callback here.
      // Memory that replies and uploads give back wakes no one either.
      freed.wait_for(lock, std::chrono::milliseconds(20));
      if (cancelled && cancelled()) {
        leave();
        throw Cancelled();
      }
    }
    erase();
    if (idle.size() > 1 && !waiting.empty()) freed.notify_all();
  }
  auto pick = std::find_if(idle.rbegin(), idle.rend(), [&](const auto& w) {
    return sequence ? w->sequence() == sequence : scene && w->warm_scene() == scene;
  });
  if (pick == idle.rend())
    pick = std::find_if(idle.rbegin(), idle.rend(), [](const auto& w) {
      return w->warm_scene() == nullptr && w->sequence() == 0;
    });
  if (pick == idle.rend()) pick = std::prev(idle.rend());  // released first
  std::unique_ptr<Workspace> ws = std::move(*pick);
  idle.erase(std::next(pick).base());
  // Another sequence's, between its frames: its state goes.
  if (ws->sequence() != 0 && ws->sequence() != sequence) ws->end_sequence();
  trim_at.reset();  // busy again
  ++holding[client];
  ws->pledge(std::move(shared->pledge));
  if (reply) *reply = std::move(shared->reply);
  return ws;
}

void Engine::Impl::release(std::unique_ptr<Workspace> ws, const std::string& client) {
  ws->pledge({});                                   // what its request did not draw goes back
  std::vector<std::unique_ptr<Workspace>> emptied;  // released outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto held = holding.find(client); held != holding.end() && --held->second == 0)
      holding.erase(held);
    const Workspace* last = ws.get();
    idle.push_back(std::move(ws));
    // Workspaces keep the buffers they grew while requests keep coming (fresh buffers cost page
    // faults, ~1 ms per 4 MB); an idle engine gives them back (EngineOptions::idle_memory_bytes).
    // The one just released stays if it keeps results for its held scene
    // (Workspace::warm_scene): a client's next request on that scene continues from them.
    if (options.idle_trim_delay_ms == 0) {
      emptied = trim(last);
    } else if (idle.size() == options.max_concurrent && waiting.empty()) {
      trim_at =
          std::chrono::steady_clock::now() + std::chrono::milliseconds(options.idle_trim_delay_ms);
      trim_spare = last;
      trim_wake.notify_one();
    }
  }
  freed.notify_all();
}

Engine::Engine(EngineOptions options) {
  if (options.max_concurrent == 0) throw std::invalid_argument("max_concurrent must be >= 1");
  const std::set<pid_t> threads_before = thread_ids();
  impl_ = std::make_unique<Impl>(options);
  impl_->device->turns().set_weights(options.client_weights);
  auto first = std::make_unique<Workspace>(impl_->device, impl_->programs);
  first->create_kernels();
  // The warm-up asks for every product; the client's output limit is not for it.
  const RenderRequest warm = warm_up_request();
  first->render(warm, make_plan(warm));
  // Each filter's visibility kernels once more (launch-time compiles); blur with a class.
  RenderRequest filtered = warm;
  filtered.products = {Product::kVisibility};
  filtered.lights[0].size = 1.0f;
  auto classed = std::make_shared<Scene>(*warm.scene);
  classed->instances[0].receiver_class = 0;
  filtered.scene = classed;
  for (FilterKind kind :
       {FilterKind::kPcf2x2, FilterKind::kPoisson, FilterKind::kPcss, FilterKind::kBlur}) {
    filtered.filter.kind = kind;
    first->render(filtered, make_plan(filtered));
  }
  // CSM in both storages: the basis, its mips, the lookups and the packed basis.
  RenderRequest csm = filtered;
  csm.filter.kind = FilterKind::kPcssCsm;
  csm.filter.csm.terms = 2;
  csm.products = {Product::kVisibility, Product::kBlockerDepth, Product::kCsmBasis};
  for (CsmStorage storage : {CsmStorage::kFloat32, CsmStorage::kFloat16}) {
    csm.filter.csm.storage = storage;
    first->render(csm, make_plan(csm));
  }
  // A cube around a point light: the light-distance pass and the per-face launches.
  RenderRequest cube = warm;
  cube.lights[0].type = LightType::kPoint;
  cube.lights[0].position = {0.0f, 2.0f, 0.0f};
  cube.shadow_map.technique = Technique::kCube;
  cube.products = {Product::kShadowMap, Product::kVisibility, Product::kTexelDensity};
  first->render(cube, make_plan(cube));
  // PSM with the measured near plane (depth_range.reduce) and the world-space caster bias.
  RenderRequest psm = warm;
  psm.products = {Product::kShadowMap};
  psm.shadow_map.technique = Technique::kPsm;
  psm.shadow_map.bias_world_texel = 1.0f;
  first->render(psm, make_plan(psm));
  // A shadow atlas of the one-triangle scene.
  RenderRequest atlas = warm;
  atlas.products = {Product::kShadowAtlas};
  atlas.atlas.tile = 16;
  first->render(atlas, make_plan(atlas));
  impl_->idle.push_back(std::move(first));
  for (uint32_t i = 1; i < options.max_concurrent; ++i) {
    auto ws = std::make_unique<Workspace>(impl_->device, impl_->programs);
    ws->create_kernels();
    impl_->idle.push_back(std::move(ws));
  }
  if (impl_->device->record().type == cl::DeviceType::kCpu) lower_device_threads(threads_before);
  if (options.idle_trim_delay_ms > 0)
    impl_->trimmer = std::thread([impl = impl_.get()] { impl->trim_when_due(); });
}

Engine::~Engine() {
  if (impl_->trimmer.joinable()) {
    {
      std::lock_guard<std::mutex> lock(impl_->mutex);
      impl_->stopping = true;
    }
    impl_->trim_wake.notify_one();
    impl_->trimmer.join();
  }
}

Engine::Impl::Price Engine::Impl::price(const RenderRequest& request, bool with_reply,
                                        uint64_t held_bytes) const {
  validate(request, limits());
  Price p;
  p.plan = make_plan(request);
  // A quality goal's candidates are admitted one by one (pick_quality); the reply is reserved
  // for the largest.
  const bool goal = request.quality.goal != Quality::Goal::kNone;
  const uint64_t budget = device->budget_bytes();
  if (!goal) {
    const CostEstimate cost = estimate_cost(request, p.plan);
    p.ms = cost.ms, p.driver = cost.driver;
    p.device_bytes = cost.device_bytes;
    admit(cost, options.max_request_cost_ms, budget);
  }
  if (with_reply) {
    RenderRequest largest = request;
    largest.shadow_map.size = kQualitySizes.back();
    p.reply_bytes = output_bytes(goal ? largest : request);
  }
  // A goal's probe runs before any candidate: admitted first, its time added to each
  // candidate's. Admission prices at its own rates, the camera view counted twice (on the high
  // side) and the probe's own buffers, a 512^2 map per light, left out; the pick predicts at the
  // calibration's typical rates, without the probe's camera view, which the run takes over.
  if (goal) {
    const RenderRequest probe = quality_probe(request);
    const Plan probe_plan = make_plan(probe);
    try {
      // Admitted as if it set up every candidate technique's map per light to measure their
      // raster loads; the pick counts the measures it takes (pick_quality).
      const double load_maps = double(quality_techniques(request).size() * request.lights.size());
      CostEstimate e = estimate_cost(probe, probe_plan);
      e.ms += load_passes_ms(request, load_maps);
      admit(e, options.max_request_cost_ms, budget);
      p.probe_ms = p.ms = e.ms;
      p.driver = e.driver;
      p.device_bytes = e.device_bytes;
      Plan beyond_view = probe_plan;
      std::erase_if(beyond_view.steps,
                    [](const Step& step) { return step.kind == StepKind::kCameraView; });
      p.probe_predicted = calibration().predict_time(probe, beyond_view);
    } catch (const ResourceExhausted& e) {
      throw ResourceExhausted("quality", "even the goal's probe (the hard test against a " +
                                             std::to_string(kQualityProbeSize) +
                                             "^2 uniform map) is over a limit: " + e.what());
    }
  }
  // What can never fit is refused before it waits; the rest waits for its share.
  const uint64_t need = cl::Runtime::grown(p.device_bytes);
  const uint64_t pledge = pledged_bytes(p.device_bytes);
  if (p.reply_bytes > budget - pledge ||
      held_bytes > budget - pledge - p.reply_bytes)  // pledge <= budget
    throw ResourceExhausted(
        "memory_budget", "the request needs " + bytes_text(need) + " of device buffers, " +
                             bytes_text(p.reply_bytes) + " for its reply and " +
                             bytes_text(held_bytes) + " for its message: more than the server's " +
                             bytes_text(budget) + " memory budget (--memory-budget); ask for less");
  return p;
}

Quote Engine::quote(const RenderRequest& request) const {
  Quote q;
  q.max_request_ms = impl_->options.max_request_cost_ms;
  q.budget_bytes = impl_->device->budget_bytes();
  try {
    const Impl::Price p = impl_->price(request, true, 0);
    q.ms = p.ms, q.device_bytes = p.device_bytes, q.reply_bytes = p.reply_bytes;
    q.driver = p.driver;
    q.quality_goal = request.quality.goal != Quality::Goal::kNone;
  } catch (const ResourceExhausted& e) {
    q.refused_field = e.field();
    q.refusal = e.what();
  }
  return q;
}

RenderResult Engine::render(const RenderRequest& request, std::function<bool()> cancelled,
                            cl::Reservation* reply, uint64_t held_bytes,
                            const std::string& client) {
  const EngineOptions& o = impl_->options;
  const Impl::Price price = impl_->price(request, reply != nullptr, held_bytes);
  const bool goal = request.quality.goal != Quality::Goal::kNone;
  const Calibration& calibration = impl_->calibration();
  RenderRequest copy;
  const RenderRequest& req = impl_->laid_out(request, copy);
  const Limits limits = impl_->limits();
  const CandidateCost candidate_cost = [&](const RenderRequest& c,
                                           const MapLoads& loads) -> std::optional<PredictedTime> {
    try {
      validate(c, limits);
      const Plan candidate_plan = make_plan(c);
      CostEstimate e = estimate_cost(c, candidate_plan);
      e.ms += price.probe_ms;
      admit(e, o.max_request_cost_ms, impl_->device->budget_bytes());
      Plan to_run = candidate_plan;  // without what it takes from the probe
      std::erase_if(to_run.steps, [&](const Step& step) {
        return taken_from_probe(c, candidate_plan, step.kind);
      });
      return calibration.predict_time(c, to_run, loads) += price.probe_predicted;
    } catch (const InvalidArgument&) {
      return std::nullopt;
    } catch (const ResourceExhausted&) {
      return std::nullopt;
    }
  };
  using Clock = std::chrono::steady_clock;
  const Impl::AtWork at_work(impl_->device->turns(), client);
  const Clock::time_point queued = Clock::now();
  // A goal waits as a request of unknown cost: it never goes before one that waits for memory.
  std::unique_ptr<Workspace> ws = impl_->acquire(
      client, cancelled, req.scene_held ? req.scene.get() : nullptr, price.device_bytes, 0, reply,
      price.reply_bytes, goal ? Impl::kNoEstimate : price.ms);
  const Clock::time_point started = Clock::now();
  // Back to the idle set however the render ends.
  try {
    // A goal's guard is left to its candidates' admission: its estimate is its pick's.
    RenderResult result =
        ws->render(req, price.plan,
                   {o.max_request_cost_ms, o.profile, std::move(cancelled), &impl_->resident,
                    &calibration, candidate_cost, client, goal ? 0.0 : price.ms});
    impl_->release(std::move(ws), client);
    result.queue_ms = std::chrono::duration<double, std::milli>(started - queued).count();
    result.run_ms = std::chrono::duration<double, std::milli>(Clock::now() - started).count();
    return result;
  } catch (...) {
    impl_->release(std::move(ws), client);
    throw;
  }
}

Engine::Impl::SequencePrice Engine::Impl::price(const SequenceRequest& sequence) const {
  if (sequence.base.quality.goal != Quality::Goal::kNone)
    throw InvalidArgument("quality",
                          "is not available in sequences (each frame would pick its own map): "
                          "set shadow_map.technique and size");
  validate_frames(sequence);
  SequencePrice p;
  size_t dearest = 0;
  for (size_t i = 0; i < sequence.frames.size(); ++i) {
    const RenderRequest frame = frame_request(sequence, i);
    with_field_renamed(
        [&] {
          validate(frame, limits());
          p.plans.push_back(make_plan(frame));
          const CostEstimate cost = estimate_cost(frame, p.plans.back());
          admit(cost, options.max_request_cost_ms, device->budget_bytes());
          p.frame_ms.push_back(cost.ms);
          p.ms += cost.ms;
          if (cost.ms > p.frame_ms[dearest]) dearest = i;
          p.device_bytes = std::max(p.device_bytes, cost.device_bytes);
          p.reply_bytes = std::max(p.reply_bytes, output_bytes(frame));
        },
        [&](const std::string& field) { return frame_field(sequence, i, field); });
  }
  // The whole sequence, priced before any frame runs: frames one at a time would each pass the
  // per-request limit while the sequence held a workspace for an hour.
  const double max_ms = options.max_sequence_cost_ms;
  if (max_ms > 0 && p.ms > max_ms)
    throw ResourceExhausted(
        "max_sequence_cost",
        "the sequence's " + std::to_string(sequence.frames.size()) + " frames are estimated at " +
            ms_text(p.ms) + " of device time in all (the dearest, frame " +
            std::to_string(dearest) + ": " + ms_text(p.frame_ms[dearest]) +
            "), over the server's limit of " + ms_text(max_ms) +
            " for a sequence (--max-sequence-cost); send fewer frames per call, or lighter ones");
  return p;
}

Quote Engine::quote(const SequenceRequest& sequence) const {
  Quote q;
  q.max_request_ms = impl_->options.max_request_cost_ms;
  q.max_sequence_ms = impl_->options.max_sequence_cost_ms;
  q.budget_bytes = impl_->device->budget_bytes();
  try {
    const Impl::SequencePrice p = impl_->price(sequence);
    q.ms = p.ms, q.device_bytes = p.device_bytes, q.reply_bytes = p.reply_bytes;
    q.frames = uint32_t(sequence.frames.size());
  } catch (const ResourceExhausted& e) {
    q.refused_field = e.field();
    q.refusal = e.what();
  }
  return q;
}

void Engine::render_sequence(const SequenceRequest& sequence,
                             const std::function<void(RenderResult&&)>& frame_done,
                             std::function<bool()> cancelled, const std::string& client) {
  const EngineOptions& o = impl_->options;
  const Impl::SequencePrice price = impl_->price(sequence);
  // AUTO predicts with it as a single request does.
  const Calibration& calibration = impl_->calibration();
  using Clock = std::chrono::steady_clock;
  const Impl::AtWork at_work(impl_->device->turns(), client);
  uint64_t id = 0;  // the sequence's, in the workspace that holds its state
  for (size_t i = 0; i < sequence.frames.size(); ++i) {
    const Clock::time_point queued = Clock::now();
    // Each frame is admitted as a request is, so other clients' requests run between frames.
    std::unique_ptr<Workspace> ws = impl_->acquire(client, cancelled, nullptr, price.device_bytes,
                                                   id, nullptr, 0, price.frame_ms[i]);
    // Where another request had the workspace between frames (or the idle trim emptied it), the
    // sequence starts afresh: the same bits, without the reuse.
    if (id == 0 || ws->sequence() != id) id = ws->begin_sequence();
    const Clock::time_point started = Clock::now();
    RenderResult result;
    try {
      // One frame's copy of the scene at a time (frames that move instances).
      const RenderRequest frame = frame_request(sequence, i);
      RenderRequest copy;
      result = ws->render(impl_->laid_out(frame, copy), price.plans[i],
                          {o.max_request_cost_ms,
                           o.profile,
                           cancelled,
                           &impl_->resident,
                           &calibration,
                           {},
                           client,
                           price.frame_ms[i]});
    } catch (...) {
      ws->end_sequence();
      impl_->release(std::move(ws), client);
      throw;
    }
    result.frame = uint32_t(i);
    result.queue_ms = std::chrono::duration<double, std::milli>(started - queued).count();
    result.run_ms = std::chrono::duration<double, std::milli>(Clock::now() - started).count();
    if (i + 1 == sequence.frames.size()) ws->end_sequence();
    // The frame goes to its reader, at the reader's pace, without the workspace: a slow reader
    // holds up no one, and an idle server gives the sequence its own workspace back.
    impl_->release(std::move(ws), client);
    frame_done(std::move(result));
  }
}

void Engine::check_scene(const std::shared_ptr<const Scene>& scene, std::function<bool()> cancelled,
                         const std::string& client) {
  validate_scene(*scene, impl_->limits());
  const Impl::AtWork at_work(impl_->device->turns(), client);
  std::unique_ptr<Workspace> ws =
      impl_->acquire(client, cancelled, nullptr, ResidentScenes::bytes_of(*scene));
  try {
    ws->make_resident(scene, impl_->resident, std::move(cancelled), client);
  } catch (...) {
    impl_->release(std::move(ws), client);
    throw;
  }
  impl_->release(std::move(ws), client);
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
  std::lock_guard<std::mutex> lock(impl_->mutex);
  const uint32_t all = impl_->options.max_concurrent;
  return {all - std::min<uint32_t>(all, uint32_t(impl_->idle.size())), all,
          uint32_t(impl_->waiting.size())};
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
