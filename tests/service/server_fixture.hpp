// Starts the real ShadowService (real engine, health, reflection) on 127.0.0.1 with a port the
// kernel picks, once per test suite, and hands out clients of the real client library.
#pragma once

#include <memory>

#include <gtest/gtest.h>

#include "service/server.hpp"
#include "shadow_client.hpp"

namespace shadow::test {

template <uint64_t kMaxOutputBytes = uint64_t{1} << 30>
class ServerFixture : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    service::ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.engine.max_output_bytes = kMaxOutputBytes;
    server_ = std::make_unique<service::ShadowServer>(options);
  }
  static void TearDownTestSuite() { server_.reset(); }

  static service::ShadowServer& server() { return *server_; }
  static client::ShadowClient client() { return client::ShadowClient(server_->address()); }

 private:
  static inline std::unique_ptr<service::ShadowServer> server_;
};

}  // namespace shadow::test
