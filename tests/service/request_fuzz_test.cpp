// Random mutations of a valid serialized RenderRequest sent as raw bytes to the real server:
// no crash, no call past its deadline, and never INTERNAL or UNKNOWN (bad input is the client's
// fault: INVALID_ARGUMENT, or RESOURCE_EXHAUSTED for a limit; a mutation may also still be a good
// request). SHADOW_FUZZ_COUNT and SHADOW_FUZZ_SEED run it longer (docs/service.md).
#include <cstdlib>
#include <map>
#include <random>
#include <string>

#include <grpcpp/impl/codegen/client_unary_call.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/sync_stream.h>

#include "server_fixture.hpp"
#include "test_scene.hpp"
#include "wire/convert.hpp"

namespace shadow::test {
namespace {

uint64_t env_or(const char* name, uint64_t fallback) {
  const char* value = std::getenv(name);
  return value ? std::strtoull(value, nullptr, 10) : fallback;
}

// One of a few mutations a careless or hostile client makes: flipped bits, random bytes,
// truncation, inserted or repeated bytes, and varints blown up to their longest form.
std::string mutate(std::string bytes, std::mt19937_64& rng) {
  auto pick = [&](size_t n) { return n == 0 ? 0 : size_t(rng() % n); };
  const int mutations = 1 + int(rng() % 4);
  for (int m = 0; m < mutations && !bytes.empty(); ++m) {
    const size_t at = pick(bytes.size());
    switch (rng() % 6) {
      case 0:
        bytes[at] = char(bytes[at] ^ (1 << (rng() % 8)));
        break;
      case 1:
        bytes[at] = char(rng());
        break;
      case 2:
        bytes.resize(at);
        break;
      case 3:
        bytes.insert(at, std::string(1 + pick(8), char(rng())));
        break;
      case 4: {
        const size_t length = std::min<size_t>(1 + pick(64), bytes.size() - at);
        bytes.insert(at, bytes.substr(at, length));
        break;
      }
      case 5:
        for (size_t i = at; i < std::min(bytes.size(), at + 1 + pick(10)); ++i) bytes[i] = '\xff';
        break;
    }
  }
  return bytes;
}

// Sends `bytes` as the request of the server-streaming `rpc` (Render or RenderSequence) and
// reads the whole reply; returns the final status.
grpc::Status render_raw(grpc::Channel& channel, const std::string& bytes,
                        std::chrono::seconds deadline, const char* rpc = "Render") {
  const std::string name = std::string("/shadow.v1.ShadowService/") + rpc;  // the method keeps
  const grpc::internal::RpcMethod method(name.c_str(),                      // a pointer to it
                                         grpc::internal::RpcMethod::SERVER_STREAMING);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + deadline);
  grpc::Slice slice(bytes);
  const grpc::ByteBuffer request(&slice, 1);
  std::unique_ptr<grpc::ClientReader<grpc::ByteBuffer>> reader(
      grpc::internal::ClientReaderFactory<grpc::ByteBuffer>::Create(&channel, method, &context,
                                                                    request));
  grpc::ByteBuffer response;
  while (reader->Read(&response)) {
  }
  return reader->Finish();
}

class RequestFuzzTest : public ServerFixture<> {};

// `count` mutations of `valid_request` against the server at `address`: every answer OK,
// INVALID_ARGUMENT or RESOURCE_EXHAUSTED within the deadline; then the server still renders.
// Returns how many got each code, and in `undecodable` how many did not parse.
std::map<grpc::StatusCode, int> fuzz(const std::string& address,
                                     const v1::RenderRequest& valid_request, uint64_t count,
                                     uint64_t seed, int& undecodable) {
  std::mt19937_64 rng(seed);
  const std::string valid = valid_request.SerializeAsString();
  auto channel = client::ShadowClient::make_channel(address);
  // A deadline far beyond what the tiny request costs: passing it means a hang.
  const auto deadline = std::chrono::seconds(60);
  std::map<grpc::StatusCode, int> codes;
  undecodable = 0;
  for (uint64_t i = 0; i < count; ++i) {
    const std::string bytes = mutate(valid, rng);
    const grpc::Status status = render_raw(*channel, bytes, deadline);
    ++codes[status.error_code()];
    const grpc::StatusCode code = status.error_code();
    EXPECT_TRUE(code == grpc::StatusCode::OK || code == grpc::StatusCode::INVALID_ARGUMENT ||
                code == grpc::StatusCode::RESOURCE_EXHAUSTED)
        << "mutation " << i << " (seed " << seed << "): code " << code << " '"
        << status.error_message() << "'";
    if (code == grpc::StatusCode::UNAVAILABLE) break;  // the server is gone
    if (status.error_message().rfind("request: ", 0) == 0) ++undecodable;
    if (!status.ok()) {
      EXPECT_FALSE(status.error_message().empty()) << "mutation " << i;
    }
  }
  std::string summary;
  for (const auto& [code, n] : codes)
    summary += " code " + std::to_string(code) + ": " + std::to_string(n);
  std::cout << count << " mutations (seed " << seed << "):" << summary << " (" << undecodable
            << " of them undecodable)\n";
  return codes;
}

TEST_F(RequestFuzzTest, MutatedRequestsNeverGetInternalOrUnknownAndNeverHang) {
  int undecodable = 0;
  auto codes = fuzz(server().address(), tiny_proto_request(), env_or("SHADOW_FUZZ_COUNT", 1000),
                    env_or("SHADOW_FUZZ_SEED", 16), undecodable);
  // The mutations reach every kind of answer: undecodable, bad fields and still-good requests.
  EXPECT_GT(undecodable, 0);
  EXPECT_GT(codes[grpc::StatusCode::INVALID_ARGUMENT], undecodable);
  EXPECT_GT(codes[grpc::StatusCode::OK], 0);

  const RenderResult after = client().render(tiny_proto_request());
  EXPECT_EQ(after.textures.size(), 3u);
}

// The same for a shadow atlas, whose checks and generated UV layouts read the meshes through
// their indices on the host: an index past the vertices there once ended the server.
TEST_F(RequestFuzzTest, MutatedAtlasRequestsNeverGetInternalOrUnknownAndNeverHang) {
  RenderRequest atlas = small_request({Product::kShadowAtlas});
  atlas.shadow_map.size = 256;
  atlas.shadow_map.fit = MapFit::kScene;
  atlas.atlas.tile = 32;
  int undecodable = 0;
  auto codes =
      fuzz(server().address(), convert::to_proto(atlas), env_or("SHADOW_FUZZ_COUNT", 1000) / 2,
           env_or("SHADOW_FUZZ_SEED", 16) + 1, undecodable);
  EXPECT_GT(codes[grpc::StatusCode::INVALID_ARGUMENT], undecodable);
  EXPECT_GT(codes[grpc::StatusCode::OK], 0);
  EXPECT_EQ(client().render(atlas).textures.size(), 1u);
}

// The message gRPC C++ gives an unparsable request by default is INTERNAL with no text.
TEST_F(RequestFuzzTest, AnUndecodableRequestIsInvalidArgumentSayingSo) {
  auto channel = client::ShadowClient::make_channel(server().address());
  // Field 1 (scene) as length-delimited with a length far past the end of the message.
  const grpc::Status status =
      render_raw(*channel, std::string("\x0a\xff\xff\x03", 4), std::chrono::seconds(30));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("request: ", 0), 0u) << status.error_message();
  EXPECT_NE(status.error_message().find("shadow.v1.RenderRequest"), std::string::npos);
  // A sequence's request too; and the statistics count both, though no handler saw them.
  const uint64_t before = client().statistics().undecodable_requests();
  const grpc::Status sequence = render_raw(*channel, std::string("\x0a\xff\xff\x03", 4),
                                           std::chrono::seconds(30), "RenderSequence");
  EXPECT_EQ(sequence.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(sequence.error_message().find("shadow.v1.SequenceRequest"), std::string::npos);
  render_raw(*channel, std::string("\x0a\xff\xff\x03", 4), std::chrono::seconds(30));
  EXPECT_EQ(client().statistics().undecodable_requests(), before + 2);
}

}  // namespace
}  // namespace shadow::test
