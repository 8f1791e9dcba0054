#include "shadowctl/sequence_to_files.hpp"

#include <cstdio>

#include "output/write_products.hpp"
#include "shadowctl/args.hpp"
#include "shadowctl/report.hpp"
#include "shadowctl/request.hpp"

namespace shadow::ctl {

std::vector<v1::Frame> read_frames_json(const std::filesystem::path& file) {
  v1::SequenceRequest sequence;
  read_json(file, "--frames", sequence, "{\"frames\": [...]}");
  if (sequence.has_base())
    throw FlagError("--frames", file.string() + ": holds a base request; the flags give it");
  if (sequence.frames_size() == 0) throw FlagError("--frames", file.string() + ": no frames");
  return {sequence.frames().begin(), sequence.frames().end()};
}

std::string format_frame(const FrameWritten& f) {
  char head[160];
  std::snprintf(head, sizeof head, "frame %04u  device %8.2f ms  wall %8.2f ms  %2zu passes run",
                f.frame, f.device_ms, f.wall_ms, f.passes);
  std::string out = head;
  if (!f.reused.empty()) {
    out += ", kept:";
    for (const std::string& p : f.reused) out += " " + p;
  }
  if (!f.rerun.empty()) {
    out += ", ran again:";
    for (const std::string& p : f.rerun) out += " " + p;
  }
  if (f.virtual_pages) out += "\n" + format_virtual_pages(*f.virtual_pages);
  return out;
}

std::string sequence_to_files(client::ShadowClient& client, v1::RenderRequest base,
                              const std::vector<v1::Frame>& frames,
                              const std::filesystem::path& dir,
                              const output::OutputOptions& options,
                              const std::function<void(const FrameWritten&)>& written,
                              std::chrono::milliseconds deadline) {
  // A scene by id is already on the server (shadowctl upload).
  const std::string id =
      base.has_scene() ? client.upload_scene(base.scene(), deadline) : base.scene_id();
  v1::SequenceRequest request;
  *request.mutable_base() = std::move(base);
  request.mutable_base()->set_scene_id(id);
  for (const v1::Frame& f : frames) *request.add_frames() = f;
  auto last = std::chrono::steady_clock::now();
  client.render_sequence(
      request,
      [&](RenderResult&& result) {
        FrameWritten f;
        f.frame = result.frame;
        char name[32];
        std::snprintf(name, sizeof name, "frame_%04u", result.frame);
        f.dir = dir / name;
        output::write_products(result.textures, f.dir, options);
        for (const PassTiming& t : result.timings) f.device_ms += t.device_ms;
        for (const Texture& t : result.textures) f.bytes += t.byte_size();
        f.passes = result.passes.size();
        f.reused = result.reused;
        f.rerun = result.rerun;
        f.virtual_pages = result.virtual_pages;
        const auto now = std::chrono::steady_clock::now();
        f.wall_ms = std::chrono::duration<double, std::milli>(now - last).count();
        last = now;
        written(f);
      },
      deadline);
  return id;
}

}  // namespace shadow::ctl
