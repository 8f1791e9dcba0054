// shadowctl sequence: uploads the scene once, renders a list of frames over it with
// RenderSequence, and writes each frame's textures to DIR/frame_NNNN/ as the frame arrives.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "output/output_options.hpp"
#include "shadow_client.hpp"

namespace shadow::ctl {

// The frames of --frames FILE: a SequenceRequest in protobuf's canonical JSON holding only
// `frames` (the base request comes from the flags). Throws FlagError("--frames").
std::vector<v1::Frame> read_frames_json(const std::filesystem::path& file);

// One frame as it was written.
struct FrameWritten {
  uint32_t frame = 0;
  std::filesystem::path dir;
  double device_ms = 0;  // the frame's passes
  double wall_ms = 0;    // since the previous frame arrived (the first: since the request)
  size_t passes = 0;     // run
  std::vector<std::string> reused, rerun;  // kept from an earlier frame; run again
  uint64_t bytes = 0;                      // of its textures
  // TECHNIQUE_VIRTUAL's pages (RenderResult::virtual_pages).
  std::optional<VirtualPageCounts> virtual_pages;
};

// "frame 0003  device 12.3 ms  wall 45.6 ms  4 passes run, kept: scene gbuffer shadow_map", and
// with virtual pages a second line, format_virtual_pages'.
std::string format_frame(const FrameWritten& frame);

// Uploads `base`'s scene (upload_scene), renders `frames` over it by id and writes each frame,
// calling `written` after each. Returns the scene id. Throws client::RpcError for the calls,
// std::runtime_error naming a file that failed.
std::string sequence_to_files(client::ShadowClient& client, v1::RenderRequest base,
                              const std::vector<v1::Frame>& frames,
                              const std::filesystem::path& dir,
                              const output::OutputOptions& options,
                              const std::function<void(const FrameWritten&)>& written,
                              std::chrono::milliseconds deadline = std::chrono::minutes(30));

}  // namespace shadow::ctl
