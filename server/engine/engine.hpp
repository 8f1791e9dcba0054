// The shadow engine: validates a request, plans the passes its products need, runs them as
// OpenCL kernels and returns the textures. Thread-safe: up to `max_concurrent` requests run at
// once, each in a workspace of its own (engine/run/workspace.hpp); up to `max_queue` more wait.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "engine/choose/calibration.hpp"
#include "engine/cl/runtime.hpp"
#include "wire/types.hpp"

namespace shadow {

struct EngineOptions {
  uint64_t max_output_bytes = uint64_t{1} << 30;  // sum of all returned textures
  bool profile = true;                            // per-pass device timings
  // Requests rendering at once, each in its own workspace: 4 measured best on 2 cores (the host
  // work of one request overlaps the kernels of others; docs/benchmarks.md, "Concurrency").
  uint32_t max_concurrent = 4;
  uint32_t max_queue = 16;  // requests waiting for a workspace
  // While the first request in line waits for memory (a workspace is free, the budget is not),
  // those behind it whose buffers fit now and whose cost estimate is at most overtake_max_ms go
  // first, during the first overtake_window_ms of its wait; after that, first come first served
  // until it starts. A preview then does not wait seconds behind heavy frames, and the first in
  // line waits at most about overtake_window_ms + overtake_max_ms longer. 0 ms: strictly in order.
  double overtake_max_ms = 250;
  uint32_t overtake_window_ms = 1000;
  // Requests estimated above this many ms of device time are refused (engine/plan/cost.hpp); 0 =
  // none.
  double max_request_cost_ms = 10000;
  // Sequences whose frames together are estimated above this many ms are refused before any
  // frame runs (issue 51: a farm's sequence is priced as a whole); 0 = none. An hour.
  double max_sequence_cost_ms = 60 * 60e3;
  // A client (a tenant, or a peer) that holds a workspace never takes the last free one: it
  // stays for a client that holds none, so a newcomer waits for no one's request to end, and
  // device turns (cl::DeviceTurns) then share the device between them slice by slice.
  bool spare_workspace = true;
  // Weights of named clients in the device's fair share (cl::DeviceTurns); others weigh 1.
  std::map<std::string, double> client_weights;
  // Bytes of every workspace's device buffers and every reserved request and reply together;
  // 0 = the smaller of the device's global memory and half the host's, less the process'
  // baseline (cl::Device::default_budget).
  uint64_t memory_budget = 0;
  // When the engine has had nothing running or waiting for idle_trim_delay_ms with more memory
  // in use than this, every workspace gives its scratch buffers back, so an idle server holds
  // little: all but the last request's, if it keeps results for the next request on its held
  // scene. The delay spares a client that sends one request after another: trimmed between
  // them, each big request would fault its buffers in again (uniform 4096 and CSM 2048 took
  // 1.6-2.1x as long, docs/benchmarks.md). 0 = as soon as the last request ends.
  uint64_t idle_memory_bytes = uint64_t{256} << 20;
  uint32_t idle_trim_delay_ms = 1000;
  // Device bytes of held scenes (RenderRequest::scene_held: uploaded scenes named by id) kept
  // between requests, so such a request neither uploads nor checks its scene again.
  uint64_t resident_scene_bytes = uint64_t{1} << 30;
  // A quality goal's error predictions (engine/choose/calibration.hpp); null = the built-in table.
  std::shared_ptr<const Calibration> calibration = nullptr;
  // The OpenCL device's SPEC (engine/cl/device_choice.hpp: "P:D" or part of a name); empty:
  // $SHADOW_DEVICE, else a GPU, else a CPU device.
  std::string device;
  // The kernels' shape (engine/cl/device_profile.hpp): cpu, gpu or auto; empty:
  // $SHADOW_KERNEL_PROFILE, else auto (the GPU shape on GPUs).
  std::string kernel_profile;
};

// What admission makes of a request or a sequence, without running it (Engine::quote): a price a
// farm's scheduler can plan with.
struct Quote {
  double ms = 0;              // estimated device time (a quality goal's: its probe's alone)
  uint64_t device_bytes = 0;  // device buffers it waits for (a sequence's: its largest frame's)
  uint64_t reply_bytes = 0;   // its reply (a sequence's: its largest frame's)
  uint32_t frames = 0;        // a sequence's
  bool quality_goal = false;  // the pick adds its candidate's cost, within max_request_ms
  std::string driver;         // the largest term of a request's estimate
  // The limits it is held against: 0 = none.
  double max_request_ms = 0, max_sequence_ms = 0;
  uint64_t budget_bytes = 0;
  // Empty when it would be admitted; else the limit it meets (a ResourceExhausted's field, e.g.
  // "request cost", "max_sequence_cost", "memory_budget") and the refusal's whole message.
  std::string refused_field, refusal;
};

class Engine {
 public:
  using Progress = std::function<void(const RenderProgress&)>;
  explicit Engine(EngineOptions options = {});
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // A request waits, first come first served, for a workspace and for the memory budget its
  // device buffers need (the cost estimate's), so requests that fit one at a time run one after
  // another instead of failing together; small ones may go before one that waits for memory
  // (EngineOptions::overtake_max_ms).
  // Throws InvalidArgument / ResourceExhausted for bad requests, requests over the cost limit or
  // a full queue (all before waiting for a workspace), or buffers that do not fit even with
  // nothing rendering (the budget held by replies, uploads and waiting requests); Cancelled once
  // `cancelled` says so (asked while waiting and before every launch), cl::Error for device
  // failures.
  // With `reply`, the bytes of the reply's textures are reserved there against the memory
  // budget with the request's share, so the caller can hold them while it streams the reply.
  // `held_bytes`: what the caller already holds of the budget for the request (its message),
  // counted when judging whether the request could ever fit.
  // `client` names whose work it is (a tenant or a peer): admission and the device's turns share
  // the device fairly between clients (EngineOptions::spare_workspace, cl::DeviceTurns), and a
  // request whose own device time passes 3x its estimate is stopped (ResourceExhausted).
  // `progress` is told how far it is before every launch and read, on this thread.
  RenderResult render(const RenderRequest& request, std::function<bool()> cancelled = {},
                      cl::Reservation* reply = nullptr, uint64_t held_bytes = 0,
                      const std::string& client = {}, Progress progress = {});

  // Admission's figures for a request or a sequence, without waiting or rendering. Throws
  // InvalidArgument for what render() would refuse as invalid; a limit it meets is in the quote.
  Quote quote(const RenderRequest& request) const;
  Quote quote(const SequenceRequest& sequence) const;

  // Renders the frames of `sequence` in order in one workspace, calling `frame_done` with each
  // frame's result (RenderResult::frame, ::reused) as soon as it is done; the next frame starts
  // when it returns. Every frame is validated and admitted before the first renders (errors name
  // "frames[i]..." or "base..."). Between frames the scene stays on the device and passes whose
  // inputs did not change are not run again: a reused result is bit-identical to a rerun.
  // `frame_done` runs without the workspace (a slow reader holds none); the next frame queues
  // again, and continues from the sequence's state where no other request took it meanwhile.
  // Throws as render(); an exception from `frame_done` ends the sequence and passes through.
  // `progress` as render()'s, with the frames done.
  void render_sequence(const SequenceRequest& sequence,
                       const std::function<void(RenderResult&&)>& frame_done,
                       std::function<bool()> cancelled = {}, const std::string& client = {},
                       Progress progress = {});

  // Every check of a scene kept for later requests (UploadScene): the host's, then the device's
  // per-vertex and per-index ones, in a workspace as a request's (waiting for one likewise).
  // The checked buffers stay resident for the requests that name the scene. Throws as render().
  void check_scene(const std::shared_ptr<const Scene>& scene, std::function<bool()> cancelled = {},
                   const std::string& client = {});
  // Device ms each client has been charged since the start, the most used first.
  std::vector<cl::DeviceTurns::Total> device_time_by_client() const;

  // `bytes` of the memory budget for `what`; ResourceExhausted naming the budget when over.
  cl::Reservation reserve(uint64_t bytes, const std::string& what);

  // Bytes counted against the memory budget now: device buffers and reservations.
  uint64_t device_bytes_in_use() const;
  uint64_t memory_budget_bytes() const;
  // The most bytes of device buffers alone held at once since the last reset (benches and the
  // memory-estimate tests).
  uint64_t buffer_peak_bytes() const;
  void reset_buffer_peak();

  struct Load {
    uint32_t rendering = 0;  // workspaces held by a request
    uint32_t workspaces = 0;
    uint32_t waiting = 0;  // requests waiting for a workspace
  };
  Load load() const;

  const EngineOptions& options() const;
  std::string device_name() const;
  const cl::DeviceRecord& device() const;    // the chosen device: names, type, driver
  const cl::DeviceProfile& profile() const;  // the shape of kernels it runs

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadow
