// How gRPC decodes the service's request messages. gRPC C++'s protobuf serializer answers a
// message it cannot parse with INTERNAL and an empty message, so monitoring would count a
// client's garbage as a server fault. These specializations parse the same way but answer
// INVALID_ARGUMENT saying what could not be decoded. The generated shadow.grpc.pb.h includes this
// file right after the messages (protoc's grpc plugin, additional_header_includes), so every
// translation unit that uses the service sees these instead of the generic protobuf traits.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include <grpcpp/impl/codegen/proto_utils.h>

#include "shadow/v1/shadow.pb.h"

namespace shadow::v1::detail {

// Requests that did not decode, since the process started: they never reach a handler, so the
// statistics read this count (Statistics.undecodable_requests).
inline std::atomic<uint64_t> undecodable_requests{0};

template <class Message>
grpc::Status decode_request(grpc::ByteBuffer* buffer, grpc::protobuf::MessageLite* message) {
  const size_t bytes = buffer == nullptr ? 0 : buffer->Length();
  const grpc::Status status =
      grpc::GenericDeserialize<grpc::ProtoBufferReader, Message>(buffer, message);
  if (status.ok()) return status;
  ++undecodable_requests;
  // The protobuf parser says no more than that it failed (proto3 has no required fields).
  return {grpc::StatusCode::INVALID_ARGUMENT,
          "request: " + std::to_string(bytes) + " bytes do not decode as a " +
              Message::descriptor()->full_name() + " (malformed protobuf wire format)"};
}

}  // namespace shadow::v1::detail

// One line per request message the service takes.
#define SHADOW_DECODE_AS_INVALID_ARGUMENT(Message)                                                \
  template <>                                                                                     \
  class grpc::SerializationTraits<shadow::v1::Message, void> {                                    \
   public:                                                                                        \
    static grpc::Status Serialize(const grpc::protobuf::MessageLite& msg, grpc::ByteBuffer* bb,   \
                                  bool* own_buffer) {                                             \
      return grpc::GenericSerialize<grpc::ProtoBufferWriter, shadow::v1::Message>(msg, bb,        \
                                                                                  own_buffer);    \
    }                                                                                             \
    static grpc::Status Deserialize(grpc::ByteBuffer* buffer, grpc::protobuf::MessageLite* msg) { \
      return shadow::v1::detail::decode_request<shadow::v1::Message>(buffer, msg);                \
    }                                                                                             \
  }

SHADOW_DECODE_AS_INVALID_ARGUMENT(RenderRequest);
SHADOW_DECODE_AS_INVALID_ARGUMENT(StatisticsRequest);
SHADOW_DECODE_AS_INVALID_ARGUMENT(SequenceRequest);
SHADOW_DECODE_AS_INVALID_ARGUMENT(SceneUpload);
