// grpc.health.v1 through the client library: SERVING while up, not healthy when nobody listens;
// and --max-connection-age, which Kubernetes deployments use so that clients re-resolve.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "server_fixture.hpp"

namespace shadow::test {
namespace {

class HealthTest : public ServerFixture<> {};

// A loopback port that was free a moment ago.
int unused_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  close(fd);
  return ntohs(addr.sin_port);
}

TEST_F(HealthTest, ServingWhileUp) {
  EXPECT_TRUE(client().healthy());
}

TEST_F(HealthTest, NotHealthyWhenNothingListens) {
  client::ShadowClient nobody("127.0.0.1:" + std::to_string(unused_port()));
  EXPECT_FALSE(nobody.healthy(std::chrono::milliseconds(500)));
}

TEST(MaxConnectionAge, TheServerClosesOldConnectionsAndClientsReconnect) {
  service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  options.max_connection_age = std::chrono::milliseconds(300);
  options.max_connection_age_grace = std::chrono::milliseconds(300);
  service::ShadowServer server(options);
  const auto channel = client::ShadowClient::make_channel(server.address());
  client::ShadowClient client(channel);
  ASSERT_TRUE(client.healthy());
  ASSERT_EQ(channel->GetState(false), GRPC_CHANNEL_READY);
  // Waits for the event, not for a time: without the age limit the connection stays READY and
  // this fails at the deadline.
  EXPECT_TRUE(channel->WaitForStateChange(
      GRPC_CHANNEL_READY, std::chrono::system_clock::now() + std::chrono::seconds(60)));
  EXPECT_TRUE(client.healthy());  // on a new connection
}

}  // namespace
}  // namespace shadow::test
