// Scenes by reference and sequences over gRPC: UploadScene's ids (same content, same id; one bit
// changes it), the cache's LRU budget (eviction, NOT_FOUND naming scene_id, the client's
// transparent re-upload), hostile upload streams (an idle one holds no memory and is cancelled
// after the stall timeout, an oversized chunk is refused, uploads take a tenant slot), and
// RenderSequence: frames in order, each bit-identical to the same frame rendered alone, with
// what was reused in each header.
#include <chrono>
#include <cstring>
#include <thread>

#include <gmock/gmock.h>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/plan/sequence.hpp"
#include "service/scene_cache.hpp"
#include "service/server.hpp"
#include "shadow_client.hpp"
#include "test_scene.hpp"
#include "wire/convert.hpp"
#include "wire/scene_id.hpp"

namespace shadow::test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

v1::Scene scene_proto(float box_height = 1.0f) {
  std::shared_ptr<Scene> scene = ground_and_box();
  scene->instances[1].transform =
      glm::translate(glm::mat4(1.0f), glm::vec3(0, box_height - 1.0f, 0));
  return convert::to_proto(*scene);
}

uint64_t cached_bytes(const v1::Scene& scene) {
  return service::SceneCache::bytes_of(*convert::from_proto(scene));
}

v1::SceneUpload upload_chunk(uint64_t total, const std::string& data) {
  v1::SceneUpload c;
  c.set_total_bytes(total);
  c.set_data(data);
  return c;
}

// Sends raw upload chunks; the status and the reply.
grpc::Status upload_chunks(const std::string& address, const std::vector<v1::SceneUpload>& chunks,
                           v1::SceneRef* reply = nullptr) {
  auto stub = v1::ShadowService::NewStub(client::ShadowClient::make_channel(address));
  grpc::ClientContext context;
  v1::SceneRef ref;
  auto writer = stub->UploadScene(&context, reply ? reply : &ref);
  for (const v1::SceneUpload& c : chunks)
    if (!writer->Write(c)) break;
  writer->WritesDone();
  return writer->Finish();
}

// An UploadScene stream that sends `chunks` and then nothing, as a client that went quiet; its
// deadline bounds a test run against a server that never ends it.
class OpenUpload {
 public:
  OpenUpload(const std::string& address, const std::vector<v1::SceneUpload>& chunks)
      : stub_(v1::ShadowService::NewStub(client::ShadowClient::make_channel(address))) {
    context_.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    writer_ = stub_->UploadScene(&context_, &reply_);
    for (const v1::SceneUpload& c : chunks) writer_->Write(c);
  }
  ~OpenUpload() {
    if (finished_) return;
    context_.TryCancel();
    writer_->Finish();
  }
  // Waits for the server to end the call, still sending nothing.
  grpc::Status wait() {
    finished_ = true;
    return writer_->Finish();
  }
  // Says it has sent all.
  grpc::Status close() {
    writer_->WritesDone();
    return wait();
  }

 private:
  std::unique_ptr<v1::ShadowService::Stub> stub_;
  grpc::ClientContext context_;
  v1::SceneRef reply_;
  std::unique_ptr<grpc::ClientWriter<v1::SceneUpload>> writer_;
  bool finished_ = false;
};

// A server whose scene cache holds two of the test scenes.
class SceneUploadTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    service::ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.scene_cache.total_bytes = 2 * cached_bytes(scene_proto()) + 100;
    server_ = std::make_unique<service::ShadowServer>(options);
  }
  static void TearDownTestSuite() { server_.reset(); }
  static client::ShadowClient client() { return client::ShadowClient(server_->address()); }

  static grpc::Status upload_raw(const std::vector<v1::SceneUpload>& chunks,
                                 v1::SceneRef* reply = nullptr) {
    return upload_chunks(server_->address(), chunks, reply);
  }

  static inline std::unique_ptr<service::ShadowServer> server_;
};

v1::RenderRequest by_id(const std::string& id) {
  v1::RenderRequest request = tiny_proto_request();
  request.set_scene_id(id);  // the oneof drops the inline scene
  return request;
}

bool same_bits(const Texture& a, const Texture& b) {
  return a.name == b.name && a.data.size() == b.data.size() &&
         std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0 &&
         a.data64 == b.data64 && a.world_to_ndc == b.world_to_ndc;
}

TEST_F(SceneUploadTest, SameContentSameIdOneBitChangesIt) {
  auto c = client();
  const v1::Scene scene = scene_proto();
  const std::string id = c.upload_scene(scene);
  EXPECT_EQ(id, scene_id(scene));
  EXPECT_TRUE(is_scene_id(id));
  v1::SceneRef again;
  v1::SceneUpload whole;
  whole.set_total_bytes(scene.SerializeAsString().size());
  whole.set_data(scene.SerializeAsString());
  ASSERT_TRUE(upload_raw({whole}, &again).ok());
  EXPECT_EQ(again.scene_id(), id);
  EXPECT_TRUE(again.already_held());  // the second upload cost a hash
  EXPECT_EQ(again.cached_bytes(), cached_bytes(scene));
  // One bit of one vertex.
  v1::Scene flipped = scene;
  std::string positions = flipped.meshes(0).positions();
  positions[5] ^= 1;
  flipped.mutable_meshes(0)->set_positions(positions);
  EXPECT_NE(c.upload_scene(flipped), id);
}

// By id as inline, bit for bit; from the second request on, without uploading the scene, and
// continuing the last request by id with the same settings (here the same view: all of it kept).
TEST_F(SceneUploadTest, RenderByIdEqualsInline) {
  auto c = client();
  const v1::Scene scene = scene_proto();
  const std::string id = c.upload_scene(scene);
  v1::RenderRequest inline_request = tiny_proto_request();
  *inline_request.mutable_scene() = scene;
  const RenderResult inline_result = c.render(inline_request);
  EXPECT_THAT(c.render(inline_request).reused, ::testing::IsEmpty());  // inline: uploaded each time
  c.render(by_id(id));
  // The scene stays on the device between the requests that name it.
  const RenderResult by_reference = c.render(by_id(id));
  EXPECT_THAT(by_reference.reused,
              ::testing::ElementsAre("scene", "shadow_map", "gbuffer", "gbuffer.resolve"));
  EXPECT_THAT(by_reference.passes, ::testing::Not(::testing::Contains("scene.upload")));
  ASSERT_EQ(by_reference.textures.size(), inline_result.textures.size());
  for (size_t i = 0; i < inline_result.textures.size(); ++i)
    EXPECT_TRUE(same_bits(by_reference.textures[i], inline_result.textures[i]));
}

TEST_F(SceneUploadTest, EvictedThenNotFoundThenReuploaded) {
  auto uploader = client();
  const v1::SceneCacheStatistics before = uploader.statistics().total().scene_cache();
  const std::string first = uploader.upload_scene(scene_proto(1.25f));
  uploader.upload_scene(scene_proto(1.5f));
  uploader.upload_scene(scene_proto(1.75f));  // the budget holds two: the first goes
  // A client that never uploaded it cannot: NOT_FOUND naming the field and the id.
  auto other = client();
  try {
    other.render(by_id(first));
    ADD_FAILURE() << "rendered an evicted scene";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_THAT(e.what(), StartsWith("scene_id: "));
    EXPECT_THAT(e.what(), HasSubstr(first));
  }
  EXPECT_EQ(other.scene_reuploads(), 0u);
  // The client that uploaded it uploads it again and retries.
  EXPECT_NO_THROW(uploader.render(by_id(first)));
  EXPECT_EQ(uploader.scene_reuploads(), 1u);
  EXPECT_NO_THROW(uploader.render(by_id(first)));  // held again now
  EXPECT_EQ(uploader.scene_reuploads(), 1u);
  // The statistics count it: two misses (the other client's, the uploader's first try), two
  // hits, at least two evictions (the first scene, then another for its re-upload), and a full
  // cache (every test scene has the same size).
  const v1::SceneCacheStatistics after = uploader.statistics().total().scene_cache();
  EXPECT_EQ(after.misses() - before.misses(), 2u);
  EXPECT_EQ(after.hits() - before.hits(), 2u);
  EXPECT_GE(after.evictions() - before.evictions(), 2u);
  EXPECT_EQ(after.scenes(), 2u);
  EXPECT_EQ(after.bytes(), 2 * cached_bytes(scene_proto()));
}

TEST_F(SceneUploadTest, HostileUploadsNameTheField) {
  const std::string bytes = scene_proto().SerializeAsString();
  const auto chunk = [](uint64_t total, const std::string& data) {
    v1::SceneUpload c;
    c.set_total_bytes(total);
    c.set_data(data);
    return c;
  };
  const auto code_and_message = [&](const std::vector<v1::SceneUpload>& chunks) {
    const grpc::Status s = upload_raw(chunks);
    return std::to_string(int(s.error_code())) + " " + s.error_message();
  };
  const std::string invalid = std::to_string(int(grpc::StatusCode::INVALID_ARGUMENT)) + " ";
  EXPECT_THAT(code_and_message({}), StartsWith(invalid + "total_bytes: "));
  EXPECT_THAT(code_and_message({chunk(0, bytes)}), StartsWith(invalid + "total_bytes: "));
  EXPECT_THAT(code_and_message({chunk(bytes.size() - 1, bytes)}), StartsWith(invalid + "data: "));
  EXPECT_THAT(code_and_message({chunk(bytes.size() + 1, bytes)}), StartsWith(invalid + "data: "));
  EXPECT_THAT(code_and_message({chunk(bytes.size(), bytes.substr(0, 10)),
                                chunk(bytes.size(), bytes.substr(10))}),
              StartsWith(invalid + "total_bytes: "));
  EXPECT_THAT(code_and_message({chunk(5, "\xff\xff\xff\xff\xff")}), StartsWith(invalid + "data: "));
  // Over the budget: refused from the first chunk's total, before the bytes.
  EXPECT_THAT(
      code_and_message({chunk(uint64_t{1} << 40, "x")}),
      StartsWith(std::to_string(int(grpc::StatusCode::RESOURCE_EXHAUSTED)) + " total_bytes: "));
  // A scene that parses but is bad names the scene's field.
  v1::Scene bad = scene_proto();
  bad.mutable_instances(1)->set_mesh(7);
  const std::string bad_bytes = bad.SerializeAsString();
  EXPECT_THAT(code_and_message({chunk(bad_bytes.size(), bad_bytes)}),
              StartsWith(invalid + "scene.instances[1].mesh: "));
  // Per-index checks run on the device at upload too, not first when a request renders it.
  Scene past = *small_request().scene;
  past.meshes[1].indices[4] = 8;  // the box has 8 vertices
  const std::string past_bytes = convert::to_proto(past).SerializeAsString();
  EXPECT_THAT(code_and_message({chunk(past_bytes.size(), past_bytes)}),
              StartsWith(invalid + "scene.meshes[1].indices[4]: "));
  // A malformed id; and the server still serves.
  EXPECT_THROW(client().render(by_id("not-an-id")), client::RpcError);
  EXPECT_NO_THROW(client().render(tiny_proto_request()));
}

TEST_F(SceneUploadTest, SequenceFramesMatchFramesAlone) {
  auto c = client();
  SequenceRequest sequence;
  sequence.base = small_request({Product::kShadowMap, Product::kVisibility});
  sequence.base.camera.width = 96, sequence.base.camera.height = 64;
  sequence.base.shadow_map.size = 256;
  sequence.base.shadow_map.fit = MapFit::kScene;
  sequence.frames.resize(3);
  sequence.frames[1].camera = sequence.base.camera;
  sequence.frames[1].camera->eye.x += 1.0f;
  sequence.frames[2].transforms = {{1, glm::translate(glm::mat4(1.0f), glm::vec3(0.5f, 0, 0))}};
  v1::SequenceRequest request = convert::to_proto(sequence);
  const std::string id = c.upload_scene(request.base().scene());
  request.mutable_base()->set_scene_id(id);
  std::vector<RenderResult> frames;
  c.render_sequence(request, [&](RenderResult&& f) { frames.push_back(std::move(f)); });
  ASSERT_EQ(frames.size(), 3u);
  for (uint32_t i = 0; i < 3; ++i) {
    EXPECT_EQ(frames[i].frame, i);
    const RenderResult alone = c.render(frame_request(sequence, i));
    ASSERT_EQ(frames[i].textures.size(), alone.textures.size());
    for (size_t t = 0; t < alone.textures.size(); ++t)
      EXPECT_TRUE(same_bits(frames[i].textures[t], alone.textures[t])) << i << " " << t;
  }
  // The upload checked the scene on the device and left it there: frame 0 takes it, nothing else.
  EXPECT_EQ(frames[0].reused, std::vector<std::string>{"scene"});
  EXPECT_THAT(frames[1].reused, ::testing::Contains("shadow_map"));         // the camera moved
  EXPECT_THAT(frames[2].passes, ::testing::Contains("shadow_map.raster"));  // the box moved
  // Errors name the sequence's fields.
  request.mutable_frames(2)->mutable_transforms(0)->set_instance(9);
  try {
    c.render_sequence(request, [](RenderResult&&) {});
    ADD_FAILURE();
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(e.what(), StartsWith("frames[2].transforms[0].instance: "));
  }
  request.mutable_base()->set_scene_id(std::string(64, 'a'));
  try {
    c.render_sequence(request, [](RenderResult&&) {});
    ADD_FAILURE();
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_THAT(e.what(), StartsWith("base.scene_id: "));
  }
}

// A server with a 1 GiB memory budget, a short stall timeout and two requests per tenant (all
// calls here are tenant "": no tokens). It never trims, so the budget in use stays put.
class UploadLimitsTest : public ::testing::Test {
 protected:
  static constexpr uint64_t kBudget = uint64_t{1} << 30;
  static constexpr std::chrono::seconds kStall{3};

  static void SetUpTestSuite() {
    service::ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.engine.memory_budget = kBudget;
    options.engine.idle_memory_bytes = kBudget;
    options.stall_timeout = kStall;
    options.tenant_max_concurrent = 2;
    server_ = std::make_unique<service::ShadowServer>(options);
  }
  static void TearDownTestSuite() { server_.reset(); }
  static client::ShadowClient client() { return client::ShadowClient(server_->address()); }
  static const std::string& address() { return server_->address(); }

  static inline std::unique_ptr<service::ShadowServer> server_;
};

// The case: an upload declaring nearly all the free budget (with its parsed copy) and
// sending nothing held it, and a bystander's render was RESOURCE_EXHAUSTED. Memory is reserved as
// bytes arrive now, so the render succeeds; the idle upload is then cancelled by the stall
// timeout.
TEST_F(UploadLimitsTest, IdleUploadLeavesTheBudgetToABystander) {
  RenderRequest bystander = small_request();
  bystander.camera.width = 640, bystander.camera.height = 480;  // a reply of over 1 MiB
  const auto deadline = std::chrono::seconds(20);
  auto c = client();
  ASSERT_NO_THROW(c.render(bystander, deadline));  // a workspace's buffers for it stay
  const uint64_t in_use = c.statistics().device_memory_bytes();
  ASSERT_LT(in_use, kBudget / 2);
  OpenUpload idle(address(), {upload_chunk((kBudget - in_use) / 2 - (256 << 10), "")});
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the server reads the chunk
  EXPECT_NO_THROW(c.render(bystander, deadline));
  EXPECT_EQ(idle.wait().error_code(), grpc::StatusCode::CANCELLED);
}

// A stream that sends no chunk at all, and one that stops after its first, are cancelled after
// the stall timeout; their tenant slots are free again.
TEST_F(UploadLimitsTest, StalledUploadIsCancelled) {
  const auto start = std::chrono::steady_clock::now();
  OpenUpload silent(address(), {});
  OpenUpload stopped(address(), {upload_chunk(1000, std::string(10, '\n'))});
  EXPECT_EQ(silent.wait().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_EQ(stopped.wait().error_code(), grpc::StatusCode::CANCELLED);
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_GE(waited, kStall / 2);
  EXPECT_LT(waited, std::chrono::seconds(25));
  EXPECT_NO_THROW(client().upload_scene(scene_proto()));
}

// --tenant-max-concurrent counts uploads: two open ones leave the tenant no slot for a third.
TEST_F(UploadLimitsTest, UploadsTakeATenantSlot) {
  const std::string bytes = scene_proto(1.25f).SerializeAsString();
  {
    OpenUpload first(address(), {upload_chunk(bytes.size(), bytes.substr(0, 10))});
    OpenUpload second(address(), {upload_chunk(bytes.size(), bytes.substr(0, 10))});
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // both handlers are running
    const grpc::Status third = upload_chunks(address(), {upload_chunk(bytes.size(), bytes)});
    EXPECT_EQ(third.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(third.error_message(), StartsWith("tenant: "));
    // Short of their declared bytes.
    EXPECT_EQ(first.close().error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(second.close().error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  }
  EXPECT_TRUE(upload_chunks(address(), {upload_chunk(bytes.size(), bytes)}).ok());
}

// SceneUpload's `data` carries at most 4 MiB (shadow.proto); a bigger chunk is refused as it
// arrives, not kept.
TEST_F(UploadLimitsTest, ChunkOverTheLimitIsRefusedNamingData) {
  const std::string over(kMaxUploadChunkBytes + 1, '\0');
  const grpc::Status s = upload_chunks(address(), {upload_chunk(over.size(), over)});
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), StartsWith("data: "));
  EXPECT_THAT(s.error_message(), HasSubstr("at most " + std::to_string(kMaxUploadChunkBytes)));
  // At the limit the chunk is taken (these bytes are then no Scene).
  const grpc::Status at_limit = upload_chunks(address(), {upload_chunk(over.size(), over.substr(1)),
                                                          upload_chunk(0, std::string(1, '\0'))});
  EXPECT_EQ(at_limit.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(at_limit.error_message(), HasSubstr("is not a serialized"));
}

}  // namespace
}  // namespace shadow::test
