#include "service/uploaded_bytes.hpp"

#include <algorithm>
#include <deque>

#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

namespace shadow::service {

void UploadedBytes::append(const std::string& data) {
  for (size_t at = 0; at < data.size();) {
    if (room_ == 0) {
      const uint64_t segment = std::min(kSegmentBytes, total_ - size_);
      held_.push_back(engine_.reserve(2 * segment, "scene upload"));
      segments_.emplace_back().reserve(segment);
      room_ = segment;
    }
    const size_t n = std::min<uint64_t>(data.size() - at, room_);
    segments_.back().append(data, at, n);
    at += n, size_ += n, room_ -= n;
  }
}

bool UploadedBytes::parse_into(v1::Scene& scene) {
  namespace io = google::protobuf::io;
  std::deque<io::ArrayInputStream> parts;
  std::vector<io::ZeroCopyInputStream*> streams;
  for (const std::string& s : segments_)
    streams.push_back(&parts.emplace_back(s.data(), static_cast<int>(s.size())));
  io::ConcatenatingInputStream in(streams.data(), static_cast<int>(streams.size()));
  const bool parsed = scene.ParseFromZeroCopyStream(&in);
  segments_ = {};
  return parsed;
}

}  // namespace shadow::service
