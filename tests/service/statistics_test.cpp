// GetStatistics against the requests actually sent to a fresh server: calls by status code, the
// time samples, and per-pass device time equal to the sum of the timings the replies carried;
// and the request log's line formats.
#include <map>

#include <gmock/gmock.h>

#include "server_fixture.hpp"
#include "service/request_log.hpp"
#include "test_scene.hpp"

namespace shadow::test {
namespace {

using ::testing::HasSubstr;

std::map<std::string, uint64_t> by_code(const v1::TenantStatistics& t) {
  std::map<std::string, uint64_t> out;
  for (const v1::StatusCount& c : t.requests()) out[c.code()] = c.count();
  return out;
}

void expect_ordered(const v1::Percentiles& p, uint64_t samples) {
  EXPECT_EQ(p.samples(), samples);
  EXPECT_LE(p.p50_ms(), p.p90_ms());
  EXPECT_LE(p.p90_ms(), p.p99_ms());
  EXPECT_LE(p.p99_ms(), p.max_ms());
  EXPECT_GE(p.p50_ms(), 0.0);
}

class StatisticsTest : public ServerFixture<> {};

TEST_F(StatisticsTest, MatchTheRequestsSent) {
  auto c = client();
  const v1::Statistics empty = c.statistics();
  EXPECT_EQ(empty.total().requests_size(), 0);
  EXPECT_EQ(empty.workspaces(), 4u);  // the default --max-concurrent

  std::map<std::string, std::pair<uint64_t, double>> passes;  // from the replies' headers
  for (int i = 0; i < 3; ++i) {
    const RenderResult r = c.render(tiny_proto_request());
    for (const PassTiming& t : r.timings) {
      ++passes[t.pass].first;
      passes[t.pass].second += t.device_ms;
    }
  }
  for (int i = 0; i < 2; ++i) {
    v1::RenderRequest bad = tiny_proto_request();
    bad.mutable_camera()->set_width(0);
    EXPECT_THROW(c.render(bad), client::RpcError);
  }

  const v1::Statistics s = c.statistics();
  const std::map<std::string, uint64_t> want = {{"INVALID_ARGUMENT", 2}, {"OK", 3}};
  EXPECT_EQ(by_code(s.total()), want);
  ASSERT_EQ(s.tenants_size(), 1);  // no tokens: one anonymous tenant
  EXPECT_EQ(s.tenants(0).tenant(), "");
  EXPECT_EQ(by_code(s.tenants(0)), want);
  expect_ordered(s.total().queue_time(), 3);
  expect_ordered(s.total().run_time(), 3);
  EXPECT_GT(s.total().run_time().max_ms(), 0.0);

  ASSERT_EQ(size_t(s.total().passes_size()), passes.size());
  for (const v1::PassStatistics& p : s.total().passes()) {
    ASSERT_TRUE(passes.count(p.pass())) << p.pass();
    EXPECT_EQ(p.runs(), passes[p.pass()].first) << p.pass();
    EXPECT_NEAR(p.device_ms(), passes[p.pass()].second, 1e-9 * (1 + p.device_ms())) << p.pass();
  }
  // Device time charged (issue 51's fair share): every slice and fill, the engine's warm-up
  // included, so at least what the passes' timings add up to; one tenant has all of it.
  double pass_ms = 0;
  for (const auto& [name, runs] : passes) pass_ms += runs.second;
  EXPECT_GE(s.total().device_ms(), pass_ms);
  EXPECT_DOUBLE_EQ(s.tenants(0).device_ms(), s.total().device_ms());
  EXPECT_DOUBLE_EQ(s.tenants(0).device_share(), 1.0);
  EXPECT_EQ(s.workspaces_busy(), 0u);
  EXPECT_EQ(s.requests_waiting(), 0u);
  EXPECT_GT(s.device_memory_budget(), 0u);
  EXPECT_LE(s.device_memory_bytes(), s.device_memory_budget());

  // The device the engine chose (PoCL here; whatever SHADOW_DEVICE names elsewhere).
  const cl::DeviceRecord& device = server().engine().device();
  EXPECT_FALSE(s.device_name().empty());
  EXPECT_EQ(s.device_name(), device.device_name);
  EXPECT_EQ(s.device_platform(), device.platform_name);
  EXPECT_EQ(s.device_type(), cl::type_name(device.type));
  EXPECT_THAT(s.device_type(), ::testing::AnyOf("GPU", "CPU", "ACCELERATOR", "OTHER"));
  EXPECT_EQ(s.device_driver(), device.driver_version);
  EXPECT_FALSE(s.device_driver().empty());
}

TEST(RequestLog, OneLineOfTextOrJson) {
  service::LogLine line;
  line.tenant = "alice";
  line.peer = "ipv4:127.0.0.1:5555";
  line.products = {"shadowmap", "visibility"};
  line.code = grpc::StatusCode::INVALID_ARGUMENT;
  line.message = "camera.width: must be in [1, 16384], got 0 \"quoted\"\n";
  line.queue_ms = 1.5, line.run_ms = 2.25, line.total_ms = 4;
  line.request_bytes = 100;
  const std::string json = service::format_log_line(line, service::LogFormat::kJson);
  EXPECT_EQ(json,
            "{\"event\":\"render\",\"tenant\":\"alice\",\"peer\":\"ipv4:127.0.0.1:5555\","
            "\"products\":[\"shadowmap\",\"visibility\"],\"status\":\"INVALID_ARGUMENT\","
            "\"message\":\"camera.width: must be in [1, 16384], got 0 \\\"quoted\\\"\\u000a\","
            "\"queue_ms\":1.500,\"run_ms\":2.250,\"total_ms\":4.000,\"request_bytes\":100,"
            "\"reply_bytes\":0,\"previous_attempts\":0,\"frames\":0,\"scene_id\":\"\"}");
  const std::string text = service::format_log_line(line, service::LogFormat::kText);
  EXPECT_THAT(text, HasSubstr("render tenant=alice peer=ipv4:127.0.0.1:5555 "
                              "products=shadowmap,visibility status=INVALID_ARGUMENT"));
  EXPECT_EQ(text.find("previous_attempts"), std::string::npos);  // a first attempt says nothing
  EXPECT_EQ(text.find('\n'), std::string::npos);
  line.previous_attempts = 2;
  EXPECT_THAT(service::format_log_line(line, service::LogFormat::kText),
              HasSubstr(" previous_attempts=2"));
  EXPECT_THAT(service::format_log_line(line, service::LogFormat::kJson),
              HasSubstr(",\"previous_attempts\":2,"));
}

}  // namespace
}  // namespace shadow::test
