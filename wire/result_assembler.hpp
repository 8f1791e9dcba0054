// The client's half of the Render stream: collects the RenderHeader and the TextureChunks that
// wire/result_slicer.hpp sent back into a RenderResult, checking the protocol documented in
// shadow.proto on the way.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "shadow/v1/shadow.pb.h"
#include "wire/types.hpp"

struct ZSTD_DCtx_s;

namespace shadow::convert {

// The stream broke the protocol documented in shadow.proto (chunk before header, gap, overlap,
// out of range, inconsistent sizes, missing bytes, a compressed chunk that is not a zstd frame
// of its declared size).
class StreamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Collects a Render stream into a RenderResult. Allocates each texture once, from the header,
// after checking its size for overflow and against `max_total_bytes`. A zstd chunk is
// decompressed straight into its texture, never past the raw size it declares, which must fit
// in what the texture still lacks.
class ResultAssembler {
 public:
  explicit ResultAssembler(uint64_t max_total_bytes = uint64_t{8} << 30);
  ~ResultAssembler();

  // Returns the texture the message added bytes to, or kNoTexture (the header).
  static constexpr size_t kNoTexture = size_t(-1);
  size_t add(const v1::RenderResponse& response);  // throws StreamError
  RenderResult finish();                           // throws StreamError if bytes are missing

  // While streaming: every texture at its full size, as the header described it. The first
  // received(i) bytes of texture i are final and in host order; their storage does not move,
  // not even into finish()'s result.
  const RenderResult& partial() const { return result_; }
  uint64_t received(size_t texture) const { return received_.at(texture); }

 private:
  void add_header(const v1::RenderHeader& header);
  void add_chunk(const v1::TextureChunk& chunk);

  uint64_t max_total_bytes_;
  bool have_header_ = false;
  RenderResult result_;
  std::vector<uint64_t> received_;  // bytes so far, per texture
  std::unique_ptr<ZSTD_DCtx_s, void (*)(ZSTD_DCtx_s*)> zstd_;
};

}  // namespace shadow::convert
