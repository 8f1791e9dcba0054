// Bad input through the real server: each request gets INVALID_ARGUMENT (RESOURCE_EXHAUSTED
// for limits) whose message starts with the offending field's path, and the server goes on
// serving good requests.
#include <cstring>
#include <functional>
#include <limits>

#include "server_fixture.hpp"
#include "test_scene.hpp"

namespace shadow::test {
namespace {

using grpc::StatusCode;

// Overwrites one float of a packed float32 [n][3] array.
void set_float(std::string* bytes, size_t vertex, int component, float value) {
  std::memcpy(bytes->data() + (3 * vertex + component) * 4, &value, 4);  // little-endian host
}

void set_uint(std::string* bytes, size_t index, uint32_t value) {
  std::memcpy(bytes->data() + 4 * index, &value, 4);
}

v1::Mesh* mesh(v1::RenderRequest& r, int i) {
  return r.mutable_scene()->mutable_meshes(i);
}
v1::Camera* camera(v1::RenderRequest& r) {
  return r.mutable_camera();
}

void make_spot(v1::RenderRequest& r, float dx, float dy, float dz) {
  v1::SpotLight* spot = r.mutable_lights(0)->mutable_spot();
  spot->mutable_position()->set_y(10);
  spot->mutable_direction()->set_x(dx);
  spot->mutable_direction()->set_y(dy);
  spot->mutable_direction()->set_z(dz);
  spot->set_cone_angle_deg(60);
}

struct BadRequest {
  const char* name;
  std::function<void(v1::RenderRequest&)> mutate;
  StatusCode code;
  const char* field;  // the status message must start with "<field>: "
};

void expect_rejected(client::ShadowClient& client, const v1::RenderRequest& request,
                     StatusCode code, const std::string& field) {
  try {
    client.render(request);
    ADD_FAILURE() << "accepted";
  } catch (const client::RpcError& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(field + ": ", 0), 0u)
        << "expected the message to start with '" << field << ": ', got: " << e.what();
  }
}

void expect_still_serving(client::ShadowClient& client) {
  const RenderResult good = client.render(tiny_proto_request());
  EXPECT_EQ(good.textures.size(), 3u);
}

class BadInputTest : public ServerFixture<>, public ::testing::WithParamInterface<BadRequest> {};

TEST_P(BadInputTest, IsRejectedNamingTheFieldAndTheServerKeepsServing) {
  v1::RenderRequest request = tiny_proto_request();
  GetParam().mutate(request);
  auto c = client();
  expect_rejected(c, request, GetParam().code, GetParam().field);
  expect_still_serving(c);
}

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr auto kInvalid = StatusCode::INVALID_ARGUMENT;

INSTANTIATE_TEST_SUITE_P(
    Service, BadInputTest,
    ::testing::Values(
        BadRequest{"nan_position",
                   [](auto& r) { set_float(mesh(r, 1)->mutable_positions(), 2, 0, kNaN); },
                   kInvalid, "scene.meshes[1].positions[2]"},
        BadRequest{"inf_position",
                   [](auto& r) { set_float(mesh(r, 0)->mutable_positions(), 3, 1, kInf); },
                   kInvalid, "scene.meshes[0].positions[3]"},
        BadRequest{"index_out_of_range",
                   [](auto& r) { set_uint(mesh(r, 1)->mutable_indices(), 7, 1000); }, kInvalid,
                   "scene.meshes[1].indices[7]"},
        BadRequest{"empty_mesh",
                   [](auto& r) {
                     r.mutable_scene()->add_meshes();
                     r.mutable_scene()->add_instances()->set_mesh(2);
                   },
                   kInvalid, "scene.meshes[2]"},
        BadRequest{"instance_mesh_out_of_range",
                   [](auto& r) { r.mutable_scene()->mutable_instances(1)->set_mesh(5); }, kInvalid,
                   "scene.instances[1].mesh"},
        BadRequest{"positions_not_a_multiple_of_12",
                   [](auto& r) { mesh(r, 0)->mutable_positions()->append(4, '\0'); }, kInvalid,
                   "scene.meshes[0].positions"},
        BadRequest{"zero_directional_direction",
                   [](auto& r) {
                     r.mutable_lights(0)->mutable_directional()->mutable_direction()->Clear();
                   },
                   kInvalid, "lights[0].directional.direction"},
        BadRequest{"zero_spot_direction", [](auto& r) { make_spot(r, 0, 0, 0); }, kInvalid,
                   "lights[0].spot.direction"},
        BadRequest{"near_zero", [](auto& r) { camera(r)->set_near(0); }, kInvalid, "camera.near"},
        BadRequest{"near_negative", [](auto& r) { camera(r)->set_near(-1); }, kInvalid,
                   "camera.near"},
        BadRequest{"near_equals_far",
                   [](auto& r) {
                     camera(r)->set_near(10);
                     camera(r)->set_far(10);
                   },
                   kInvalid, "camera.far"},
        BadRequest{"near_beyond_far",
                   [](auto& r) {
                     camera(r)->set_near(50);
                     camera(r)->set_far(10);
                   },
                   kInvalid, "camera.far"},
        BadRequest{"fov_zero", [](auto& r) { camera(r)->set_fov_deg(0); }, kInvalid,
                   "camera.fov_deg"},
        BadRequest{"fov_180", [](auto& r) { camera(r)->set_fov_deg(180); }, kInvalid,
                   "camera.fov_deg"},
        BadRequest{"fov_negative", [](auto& r) { camera(r)->set_fov_deg(-30); }, kInvalid,
                   "camera.fov_deg"},
        BadRequest{"zero_width", [](auto& r) { camera(r)->set_width(0); }, kInvalid,
                   "camera.width"},
        BadRequest{"zero_height", [](auto& r) { camera(r)->set_height(0); }, kInvalid,
                   "camera.height"},
        BadRequest{"absurd_camera",
                   [](auto& r) {
                     camera(r)->set_width(1000000);
                     camera(r)->set_height(1000000);
                   },
                   kInvalid, "camera.width"},
        BadRequest{"absurd_map_size", [](auto& r) { r.mutable_shadow_map()->set_size(100000); },
                   kInvalid, "shadow_map.size"},
        BadRequest{"zero_map_size", [](auto& r) { r.mutable_shadow_map()->set_size(0); }, kInvalid,
                   "shadow_map.size"},
        BadRequest{"no_products", [](auto& r) { r.clear_products(); }, kInvalid, "products"},
        BadRequest{"unspecified_product", [](auto& r) { r.add_products(v1::PRODUCT_UNSPECIFIED); },
                   kInvalid, "products[3]"},
        BadRequest{"no_camera", [](auto& r) { r.clear_camera(); }, kInvalid, "camera"},
        BadRequest{"unknown_chunk_compression",
                   [](auto& r) { r.set_chunk_compression(v1::ChunkCompression(7)); }, kInvalid,
                   "chunk_compression"},
        BadRequest{"no_light", [](auto& r) { r.clear_lights(); }, kInvalid, "lights"}),
    [](const auto& info) { return std::string(info.param.name); });

// A server whose reply limit is 1 MiB: a 1024^2 float map (4 MiB) is over it.
class OutputLimitTest : public ServerFixture<uint64_t{1} << 20> {};

TEST_F(OutputLimitTest, OverTheByteLimitIsResourceExhaustedAndTheServerKeepsServing) {
  v1::RenderRequest request = tiny_proto_request();
  request.mutable_shadow_map()->set_size(1024);
  auto c = client();
  expect_rejected(c, request, StatusCode::RESOURCE_EXHAUSTED, "products");
  expect_still_serving(c);  // 256^2 map + 64x48 pixels fit in 1 MiB
}

}  // namespace
}  // namespace shadow::test
