// Engine RenderResult <-> the Render stream: a RenderHeader, then each texture's bytes as
// TextureChunks of bounded size (an 8192^2 float map is 256 MiB; gRPC messages should stay
// a few MiB). The server slices, the client reassembles and checks.
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <vector>

#include "shadow/v1/shadow.pb.h"
#include "wire/types.hpp"

namespace shadow::convert {

inline constexpr size_t kDefaultChunkBytes = size_t{2} << 20;

v1::TextureInfo to_proto_info(const Texture& texture);
v1::RenderHeader make_header(const RenderResult& result);

// Sends the header, then every texture's bytes in order, in chunks of at most `chunk_bytes`.
// `write` returns false when the peer is gone; streaming stops and this returns false.
// Throws std::logic_error if a texture's data does not match its dimensions.
bool stream_result(const RenderResult& result, size_t chunk_bytes,
                   const std::function<bool(const v1::RenderResponse&)>& write);

// The stream broke the protocol documented in shadow.proto (chunk before header, gap, overlap,
// out of range, inconsistent sizes, missing bytes).
class StreamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Collects a Render stream into a RenderResult. Allocates each texture once, from the header,
// after checking its size for overflow and against `max_total_bytes`.
class ResultAssembler {
 public:
  explicit ResultAssembler(uint64_t max_total_bytes = uint64_t{8} << 30)
      : max_total_bytes_(max_total_bytes) {}

  void add(const v1::RenderResponse& response);  // throws StreamError
  RenderResult finish();                         // throws StreamError if bytes are missing

 private:
  void add_header(const v1::RenderHeader& header);
  void add_chunk(const v1::TextureChunk& chunk);

  uint64_t max_total_bytes_;
  bool have_header_ = false;
  RenderResult result_;
  std::vector<uint64_t> received_;  // bytes so far, per texture
};

}  // namespace shadow::convert
