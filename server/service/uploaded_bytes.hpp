// A scene's serialization as its upload arrives, counted against the memory budget as it grows:
// each byte twice, for itself and for its parsed copy while the scene is checked. So the budget
// holds what an upload sent, not what it declared. Kept in segments, each reserved when the
// first byte lands in it: growing copies nothing, an upload holds at most one segment more than
// it sent, and a stream of tiny chunks keeps a short list.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/engine.hpp"
#include "shadow/v1/shadow.pb.h"

namespace shadow::service {

class UploadedBytes {
 public:
  static constexpr uint64_t kSegmentBytes = uint64_t{64} << 10;

  // At most `total` bytes (the upload's declared size) on `engine`'s budget.
  UploadedBytes(Engine& engine, uint64_t total) : engine_(engine), total_(total) {}
  uint64_t size() const { return size_; }

  // ResourceExhausted naming the memory budget when the next segment does not fit it.
  void append(const std::string& data);
  // Parses the bytes, then frees them; their reservation stays for the parsed copy.
  bool parse_into(v1::Scene& scene);

 private:
  Engine& engine_;
  const uint64_t total_;
  uint64_t size_ = 0;
  uint64_t room_ = 0;  // left in the last segment
  std::vector<std::string> segments_;
  std::vector<cl::Reservation> held_;
};

}  // namespace shadow::service
