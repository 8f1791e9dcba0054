#include "service/shadow_service.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <map>
#include <memory>
#include <optional>

#include "service/status.hpp"
#include "service/uploaded_bytes.hpp"
#include "wire/convert.hpp"
#include "wire/errors.hpp"
#include "wire/names.hpp"
#include "wire/scene_id.hpp"

namespace shadow::service {
namespace {

// gRPC's retry policy numbers its attempts in this header (gRFC A6); absent on a first attempt.
unsigned previous_attempts(const grpc::ServerContext& context) {
  const auto& metadata = context.client_metadata();
  const auto found = metadata.find("grpc-previous-rpc-attempts");
  if (found == metadata.end()) return 0;
  unsigned n = 0;
  const grpc::string_ref value = found->second;
  const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), n);
  return error == std::errc() && end == value.data() + value.size() ? n : 0;
}

// A call's log line as far as its request tells.
LogLine log_line(const char* event, const v1::RenderRequest& request) {
  LogLine line;
  line.event = event;
  line.request_bytes = request.ByteSizeLong();
  line.scene_id = request.scene_id();
  for (int i = 0; i < request.products_size(); ++i) {
    const auto product = names::kProducts.from_proto(request.products(i));
    line.products.emplace_back(product ? names::kProducts.name(*product) : "?");
  }
  return line;
}

// Whose work a call is, for the engine's fair share of the device: its tenant with tokens, else
// its peer (address and port: a client's connection). Without tokens a client that opens many
// connections counts as many; tenants are how a farm shares the device by team.
std::string client_of(const grpc::ServerContext& context, const std::string& tenant) {
  return tenant.empty() ? context.peer() : tenant;
}

// Thrown out of a sequence's frame callback when the client stopped reading.
struct StreamStopped {
  grpc::Status status;
};

}  // namespace

grpc::Status ShadowServiceImpl::stopped_status(const grpc::ServerContext& context,
                                               int64_t frames_sent) const {
  try {
    throw;
  } catch (const Cancelled&) {
    if (!context.IsCancelled() && stopping())
      return {grpc::StatusCode::UNAVAILABLE,
              frames_sent >= 0
                  ? "the server is shutting down (its --shutdown-grace ended) after sending " +
                        std::to_string(frames_sent) + " frames; resume the sequence from frame " +
                        std::to_string(frames_sent) + " on another replica"
                  : std::string("the server is shutting down (its --shutdown-grace ended) before "
                                "the render finished; retry on another replica")};
    if (std::chrono::system_clock::now() >= context.deadline())
      return {grpc::StatusCode::DEADLINE_EXCEEDED, "the deadline passed; the render was stopped"};
    return {grpc::StatusCode::CANCELLED, "cancelled by the client; the render was stopped"};
  } catch (...) {
    return status_from_current_exception();
  }
}

template <class Work>
grpc::Status ShadowServiceImpl::served(grpc::ServerContext* context, LogLine line, Work work) {
  const InFlight in_flight(*this);
  if (draining_) return draining_status();
  const auto start = std::chrono::steady_clock::now();
  CallRecord call;
  call.tenant = tenant_of(*context);
  const grpc::Status status = work(call, line);
  call.code = status.error_code();
  statistics_.record(call);
  line.tenant = call.tenant;
  line.peer = context->peer();
  line.previous_attempts = previous_attempts(*context);
  line.code = call.code;
  line.message = status.error_message();
  line.queue_ms = call.queue_ms, line.run_ms = call.run_ms;
  line.total_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  log_.write(line);
  return status;
}

grpc::Status ShadowServiceImpl::Render(grpc::ServerContext* context,
                                       const v1::RenderRequest* request,
                                       grpc::ServerWriter<v1::RenderResponse>* writer) {
  return served(context, log_line("render", *request), [&](CallRecord& call, LogLine& line) {
    return render(context, *request, writer, call, line);
  });
}

grpc::Status ShadowServiceImpl::RenderSequence(grpc::ServerContext* context,
                                               const v1::SequenceRequest* request,
                                               grpc::ServerWriter<v1::RenderResponse>* writer) {
  LogLine line = log_line("sequence", request->base());
  line.request_bytes = request->ByteSizeLong();
  return served(context, std::move(line), [&](CallRecord& call, LogLine& line) {
    return render_sequence(context, *request, writer, call, line);
  });
}

grpc::Status ShadowServiceImpl::UploadScene(grpc::ServerContext* context,
                                            grpc::ServerReader<v1::SceneUpload>* reader,
                                            v1::SceneRef* reply) {
  LogLine line;
  line.event = "upload";
  return served(context, std::move(line), [&](CallRecord& call, LogLine& line) {
    return upload(context, reader, *reply, call.tenant, line);
  });
}

grpc::Status ShadowServiceImpl::GetStatistics(grpc::ServerContext* context,
                                              const v1::StatisticsRequest*, v1::Statistics* reply) {
  const InFlight in_flight(*this);
  if (draining_) return draining_status();
  // With tokens a tenant sees its own work only.
  const std::string tenant = tenant_of(*context);
  *reply = statistics_.snapshot(tenant.empty() ? nullptr : &tenant);
  const auto cache = [](const SceneCache::Usage& u, v1::SceneCacheStatistics& out) {
    out.set_scenes(u.scenes);
    out.set_bytes(u.bytes);
    out.set_hits(u.hits);
    out.set_misses(u.misses);
    out.set_evictions(u.evictions);
  };
  cache(scenes_.usage(tenant.empty() ? nullptr : &tenant),
        *reply->mutable_total()->mutable_scene_cache());
  for (v1::TenantStatistics& t : *reply->mutable_tenants())
    cache(scenes_.usage(&t.tenant()), *t.mutable_scene_cache());
  // Device time by client: a tenant's own, or without tokens every peer's under tenant "".
  double all_ms = 0;
  std::map<std::string, double> by_tenant;
  const bool tokens = !tenant.empty();
  for (const cl::DeviceTurns::Total& t : engine_.device_time_by_client()) {
    all_ms += t.ms;
    by_tenant[tokens ? t.client : std::string()] += t.ms;
  }
  const auto device_time = [&](v1::TenantStatistics& out, double ms) {
    out.set_device_ms(ms);
    out.set_device_share(all_ms > 0 ? ms / all_ms : 0);
  };
  device_time(*reply->mutable_total(), tokens ? by_tenant[tenant] : all_ms);
  for (v1::TenantStatistics& t : *reply->mutable_tenants()) device_time(t, by_tenant[t.tenant()]);
  const Engine::Load load = engine_.load();
  reply->set_workspaces_busy(load.rendering);
  reply->set_workspaces(load.workspaces);
  reply->set_requests_waiting(load.waiting);
  reply->set_device_memory_bytes(engine_.device_bytes_in_use());
  reply->set_device_memory_budget(engine_.memory_budget_bytes());
  const cl::DeviceRecord& device = engine_.device();
  reply->set_device_name(device.device_name);
  reply->set_device_platform(device.platform_name);
  reply->set_device_type(cl::type_name(device.type));
  reply->set_device_driver(device.driver_version);
  reply->set_kernel_profile(cl::shape_name(engine_.profile().shape));
  if (tenant.empty()) reply->set_undecodable_requests(v1::detail::undecodable_requests);
  return grpc::Status::OK;
}

grpc::Status ShadowServiceImpl::Estimate(grpc::ServerContext* context,
                                         const v1::EstimateRequest* request, v1::Price* reply) {
  const InFlight in_flight(*this);
  if (draining_) return draining_status();
  try {
    const std::string tenant = tenant_of(*context);
    Quote q;
    switch (request->work_case()) {
      case v1::EstimateRequest::kRender:
        q = engine_.quote(convert::from_proto(request->render(), scene_lookup(tenant)));
        break;
      case v1::EstimateRequest::kSequence:
        q = engine_.quote(convert::from_proto(request->sequence(), scene_lookup(tenant)));
        break;
      default:
        throw InvalidArgument("work", "required: a render or a sequence to price");
    }
    reply->set_device_ms(q.ms);
    reply->set_device_bytes(q.device_bytes);
    reply->set_reply_bytes(q.reply_bytes);
    reply->set_frames(q.frames);
    reply->set_quality_goal(q.quality_goal);
    reply->set_largest_term(q.driver);
    reply->set_max_request_cost_ms(q.max_request_ms);
    reply->set_max_sequence_cost_ms(q.max_sequence_ms);
    reply->set_memory_budget(q.budget_bytes);
    reply->set_admitted(q.refusal.empty());
    reply->set_refused_field(q.refused_field);
    reply->set_refusal(q.refusal);
    return grpc::Status::OK;
  } catch (...) {
    return status_from_current_exception();
  }
}

convert::SceneLookup ShadowServiceImpl::scene_lookup(const std::string& tenant) {
  return [this, tenant](const std::string& id) {
    if (!is_scene_id(id))
      throw InvalidArgument("scene_id", "must be 64 lowercase hex digits (SceneRef.scene_id)");
    return scenes_.get(tenant, id, "scene_id");
  };
}

grpc::Status ShadowServiceImpl::send(grpc::ServerContext* context, const RenderResult& result,
                                     ChunkCompression compression,
                                     grpc::ServerWriter<v1::RenderResponse>* writer) {
  // Streaming holds no workspace: a slow reader does not hold up other requests, and one that
  // stops reading is cancelled by the watchdog.
  StallWatchdog::Watch watch(watchdog_, context);
  const bool sent = convert::stream_result(
      result, chunk_bytes_,
      [&](const v1::RenderResponse& r) {
        const bool ok = writer->Write(r);
        if (ok) watch.progress();
        return ok;
      },
      compression);
  if (!sent && watch.stalled())
    return {grpc::StatusCode::CANCELLED, "the client read nothing for the stall timeout"};
  if (!sent) return {grpc::StatusCode::CANCELLED, "the client went away during streaming"};
  return grpc::Status::OK;
}

Engine::Progress ShadowServiceImpl::progress_writer(grpc::ServerContext* context,
                                                    grpc::ServerWriter<v1::RenderResponse>* writer,
                                                    bool asked) {
  if (!asked) return {};
  using Clock = std::chrono::steady_clock;
  return [this, context, writer, start = Clock::now(),
          last = std::optional<Clock::time_point>()](const RenderProgress& p) mutable {
    const Clock::time_point now = Clock::now();
    const auto ms = [](Clock::duration d) {
      return std::chrono::duration<double, std::milli>(d).count();
    };
    if (p.estimate_ms < kProgressAfterMs && ms(now - start) < kProgressAfterMs) return;
    if (last && ms(now - *last) < kProgressEveryMs) return;
    last = now;
    // Below 1 until the work is done: an estimate may be low.
    const double own = p.estimate_ms > 0 ? std::min(p.device_ms / p.estimate_ms, 0.99) : 0.0;
    v1::RenderResponse message;
    v1::Progress& out = *message.mutable_progress();
    out.set_phase(p.phase);
    out.set_fraction(p.frames > 0 ? (p.frames_done + own) / p.frames : own);
    out.set_device_ms(p.device_ms);
    out.set_estimate_ms(p.estimate_ms);
    out.set_frames_done(p.frames_done);
    out.set_frames(p.frames);
    StallWatchdog::Watch watch(watchdog_, context);
    if (writer->Write(message)) watch.progress();  // a failed write: the cancel check says why
  };
}

grpc::Status ShadowServiceImpl::render(grpc::ServerContext* context, const v1::RenderRequest& proto,
                                       grpc::ServerWriter<v1::RenderResponse>* writer,
                                       CallRecord& call, LogLine& line) {
  const v1::RenderRequest* request = &proto;
  try {
    const TenantLimiter::Slot slot = tenants_.acquire(call.tenant);
    // The request's message and its engine copy count against the memory budget while it
    // waits and renders; the reply's textures while they are streamed.
    const cl::Reservation request_memory =
        engine_.reserve(2 * uint64_t{request->ByteSizeLong()}, "request");
    const RenderRequest engine_request = convert::from_proto(*request, scene_lookup(call.tenant));
    const ChunkCompression compression =
        convert::from_proto(request->chunk_compression(), "chunk_compression");
    cl::Reservation reply_memory;
    // IsCancelled() covers both the client's cancel and its deadline; the engine asks it while
    // the request waits for a workspace and before every launch.
    const RenderResult result = engine_.render(
        engine_request, cancel_check(context), &reply_memory, request_memory.bytes(),
        client_of(*context, call.tenant), progress_writer(context, writer, request->progress()));
    call.rendered = true;
    call.queue_ms = result.queue_ms, call.run_ms = result.run_ms;
    call.timings = result.timings;
    for (const Texture& t : result.textures) line.reply_bytes += t.byte_size();
    return send(context, result, compression, writer);
  } catch (...) {
    return stopped_status(*context);
  }
}

grpc::Status ShadowServiceImpl::render_sequence(grpc::ServerContext* context,
                                                const v1::SequenceRequest& request,
                                                grpc::ServerWriter<v1::RenderResponse>* writer,
                                                CallRecord& call, LogLine& line) {
  try {
    const TenantLimiter::Slot slot = tenants_.acquire(call.tenant);
    const cl::Reservation request_memory =
        engine_.reserve(2 * uint64_t{request.ByteSizeLong()}, "request");
    const SequenceRequest sequence = convert::from_proto(request, scene_lookup(call.tenant));
    const ChunkCompression compression =
        convert::from_proto(request.base().chunk_compression(), "base.chunk_compression");
    const auto done = [&](RenderResult&& result) {
      // Each frame's reply counts against the memory budget while it is streamed.
      uint64_t bytes = 0;
      for (const Texture& t : result.textures) bytes += t.byte_size();
      const cl::Reservation reply_memory = engine_.reserve(bytes, "reply");
      call.rendered = true;
      call.queue_ms += result.queue_ms, call.run_ms += result.run_ms;
      call.timings.insert(call.timings.end(), result.timings.begin(), result.timings.end());
      line.reply_bytes += bytes;
      ++line.frames;
      const grpc::Status sent = send(context, result, compression, writer);
      if (!sent.ok()) throw StreamStopped{sent};
    };
    engine_.render_sequence(sequence, done, cancel_check(context), client_of(*context, call.tenant),
                            progress_writer(context, writer, request.base().progress()));
    return grpc::Status::OK;
  } catch (const StreamStopped& stopped) {
    return stopped.status;
  } catch (...) {
    return stopped_status(*context, line.frames);
  }
}

grpc::Status ShadowServiceImpl::upload(grpc::ServerContext* context,
                                       grpc::ServerReader<v1::SceneUpload>* reader,
                                       v1::SceneRef& reply, const std::string& tenant,
                                       LogLine& line) {
  try {
    // An upload holds a thread and memory while it lasts, as a render does.
    const TenantLimiter::Slot slot = tenants_.acquire(tenant);
    uint64_t total = 0;  // from the first chunk
    std::optional<UploadedBytes> bytes;
    {
      // A stream that sends no chunk for the stall timeout is cancelled (the blocked Read
      // returns false). There is no minimum rate beyond that: a stream that trickles bytes holds
      // only the budget for what it sent (reserved as it arrives), a thread and one of its
      // tenant's slots (--tenant-max-concurrent), as an honest client on a slow link does; a
      // rate floor would refuse such clients while an attacker just sends at the floor. The
      // client's deadline bounds the whole upload.
      StallWatchdog::Watch watch(watchdog_, context);
      v1::SceneUpload chunk;
      for (uint64_t i = 0; reader->Read(&chunk); ++i) {
        watch.progress();
        if (i == 0) {
          total = chunk.total_bytes();
          if (total == 0) throw InvalidArgument("total_bytes", "required (> 0) in the first chunk");
          // Refused before a byte is kept when it could never be held: over the cache's budget,
          // or over the memory budget with its parsed copy (reserved as the bytes arrive).
          scenes_.check_fits(total, "total_bytes");
          const uint64_t budget = engine_.memory_budget_bytes();
          if (total > budget / 2)
            throw ResourceExhausted(
                "total_bytes", "the scene's " + std::to_string(total) +
                                   " bytes and their parsed copy need more than the server's " +
                                   std::to_string(budget) +
                                   "-byte memory budget (--memory-budget)");
          bytes.emplace(engine_, total);
        } else if (chunk.total_bytes() != 0) {
          throw InvalidArgument("total_bytes", "only in the first chunk (chunk " +
                                                   std::to_string(i) + " has it too)");
        }
        if (chunk.data().size() > kMaxUploadChunkBytes)
          throw InvalidArgument("data", "chunk " + std::to_string(i) + " carries " +
                                            std::to_string(chunk.data().size()) +
                                            " bytes; a chunk carries at most " +
                                            std::to_string(kMaxUploadChunkBytes));
        if (chunk.data().size() > total - bytes->size())
          throw InvalidArgument("data", "more bytes than total_bytes = " + std::to_string(total));
        bytes->append(chunk.data());
        line.request_bytes = bytes->size();
      }
      if (watch.stalled())
        return {grpc::StatusCode::CANCELLED,
                "no upload data for the stall timeout (--stall-timeout): the upload was cancelled"};
      if (context->IsCancelled())
        return {grpc::StatusCode::CANCELLED,
                "the client cancelled the upload, or its deadline passed"};
    }
    if (!bytes)
      throw InvalidArgument("total_bytes",
                            "the upload has no chunk: the first carries total_bytes");
    if (bytes->size() != total)
      throw InvalidArgument("data",
                            std::to_string(bytes->size()) +
                                " bytes arrived, but total_bytes = " + std::to_string(total));
    v1::Scene scene;
    if (!bytes->parse_into(scene))
      throw InvalidArgument("data", "is not a serialized shadow.v1.Scene message");
    scene.DiscardUnknownFields();  // the id is of the content the server understands
    const std::string id = scene_id(scene);
    line.scene_id = id;
    reply.set_scene_id(id);
    std::shared_ptr<const Scene> held = scenes_.find(tenant, id);
    reply.set_already_held(held != nullptr);
    if (!held) {
      std::shared_ptr<const Scene> converted = convert::from_proto(scene);
      engine_.check_scene(converted, cancel_check(context), client_of(*context, tenant));
      scenes_.put(tenant, id, converted);
      held = std::move(converted);
    }
    reply.set_cached_bytes(SceneCache::bytes_of(*held));
    return grpc::Status::OK;
  } catch (...) {
    return status_from_current_exception();
  }
}

}  // namespace shadow::service
