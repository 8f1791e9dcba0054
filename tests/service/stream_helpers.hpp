// Test helpers for the Render stream: slice a result into messages as they would arrive
// (through serialized bytes), and reassemble messages into a result.
#pragma once

#include <vector>

#include <gtest/gtest.h>

#include "wire/result_assembler.hpp"
#include "wire/result_slicer.hpp"

namespace shadow::convert {

inline std::vector<v1::RenderResponse> stream(const RenderResult& r, size_t chunk_bytes) {
  std::vector<v1::RenderResponse> out;
  EXPECT_TRUE(stream_result(r, chunk_bytes, [&](const v1::RenderResponse& m) {
    v1::RenderResponse wire;
    EXPECT_TRUE(wire.ParseFromString(m.SerializeAsString()));
    out.push_back(wire);
    return true;
  }));
  return out;
}

// Throws StreamError as the assembler does.
inline RenderResult assemble(const std::vector<v1::RenderResponse>& messages) {
  ResultAssembler assembler;
  for (const auto& m : messages) assembler.add(m);
  return assembler.finish();
}

}  // namespace shadow::convert
