// shadowctl's render: the request, the reply and the files, pipelined. Plain textures are written
// as their chunks arrive (output::StreamWriter); the timeline says when each stage ended.
#pragma once

#include <chrono>
#include <filesystem>
#include <vector>

#include "output/output_options.hpp"
#include "output/write_products.hpp"
#include "shadow_client.hpp"

namespace shadow::ctl {

// Milliseconds after the request was sent.
struct Timeline {
  double header = 0;      // the header arrived: the server's queue, render and readback
  double last_chunk = 0;  // the reply is complete
  double exr_rows = 0;    // the streamed EXR rows were written
  double done = 0;        // every file is written and closed
};

struct RenderedFiles {
  RenderResult result;
  std::vector<output::WrittenFile> files;  // pointing into result.textures
  Timeline timeline;
};

// Throws client::RpcError for the call, std::runtime_error naming a file that failed.
RenderedFiles render_to_files(client::ShadowClient& client, const v1::RenderRequest& request,
                              const std::filesystem::path& dir,
                              const output::OutputOptions& options,
                              std::chrono::milliseconds deadline = std::chrono::minutes(5));

}  // namespace shadow::ctl
