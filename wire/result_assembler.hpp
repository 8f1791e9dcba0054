// The client's half of the Render stream: collects the RenderHeader and the TextureChunks that
// wire/result_slicer.hpp sent back into a RenderResult, checking the protocol documented in
// shadow.proto on the way.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "shadow/v1/shadow.pb.h"
#include "wire/types.hpp"

namespace shadow::convert {

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
