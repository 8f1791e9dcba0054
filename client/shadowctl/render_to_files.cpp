#include "shadowctl/render_to_files.hpp"

#include "output/stream_writer.hpp"

namespace shadow::ctl {

RenderedFiles render_to_files(client::ShadowClient& client, const v1::RenderRequest& request,
                              const std::filesystem::path& dir,
                              const output::OutputOptions& options,
                              std::chrono::milliseconds deadline) {
  const auto start = std::chrono::steady_clock::now();
  const auto since = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
  };
  RenderedFiles out;
  output::StreamWriter writer(dir, options);
  out.result =
      client.render(request, deadline, [&](const convert::ResultAssembler& stream, size_t texture) {
        if (texture == convert::ResultAssembler::kNoTexture) {  // also after a restart
          out.timeline.header = since();
          writer.start(stream.partial().textures);
        } else if (texture == client::ShadowClient::kStreamDiscarded) {
          writer.discard();
        } else {
          writer.arrived(texture, stream.received(texture));
        }
      });
  out.timeline.last_chunk = since();
  out.files = writer.finish(out.result.textures);
  out.timeline.exr_rows = writer.streamed_ms() > 0 ? out.timeline.header + writer.streamed_ms() : 0;
  out.timeline.done = since();
  return out;
}

}  // namespace shadow::ctl
