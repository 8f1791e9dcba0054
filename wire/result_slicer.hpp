// The server's half of the Render stream: a RenderResult as a RenderHeader, then each
// texture's bytes as TextureChunks of bounded size (an 8192^2 float map is 256 MiB; gRPC
// messages should stay a few MiB). The client's half is wire/result_assembler.hpp.
#pragma once

#include <cstddef>
#include <functional>

#include "shadow/v1/shadow.pb.h"
#include "wire/types.hpp"

namespace shadow::convert {

inline constexpr size_t kDefaultChunkBytes = size_t{2} << 20;
// zstd's level for compressed chunks: the fastest that still shrinks empty regions well
// (docs/benchmarks.md, "End to end").
inline constexpr int kZstdLevel = 1;

// Throws std::logic_error if a texture's data does not match its dimensions or cube faces.
v1::TextureInfo to_proto_info(const Texture& texture);
v1::RenderHeader make_header(const RenderResult& result);

// Sends the header, then every texture's bytes in order, in chunks of at most `chunk_bytes`
// raw bytes; with kZstd each chunk that shrinks goes as a zstd frame. `write` returns false
// when the peer is gone; streaming stops and this returns false. Throws std::logic_error if a
// texture's data does not match its dimensions.
bool stream_result(const RenderResult& result, size_t chunk_bytes,
                   const std::function<bool(const v1::RenderResponse&)>& write,
                   ChunkCompression compression = ChunkCompression::kNone);

}  // namespace shadow::convert
