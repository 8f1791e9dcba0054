// shadow-bench's "edge sampling" section: the spread of log(estimate / measured) per technique
// and the cases measured above kUnexplainedFactor x their estimate.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

#include "edge_estimate.hpp"

namespace shadow::bench {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

Case hard_case(const char* view, const char* variant, size_t misclassified,
               std::optional<double> estimate) {
  Case c;
  c.scene = "street";
  c.view = view;
  c.variant = variant;
  c.error.both_valid = 10000;
  c.error.misclassified = misclassified;
  c.edge_estimate = estimate;
  return c;
}

TEST(BenchEdgeEstimate, SpreadPerTechniqueAndTheCasesSamplingDoesNotExplain) {
  EXPECT_EQ(technique_of("lispsm 2048 slope 4"), "lispsm");
  EXPECT_EQ(technique_of("uniform"), "uniform");
  const std::vector<Case> cases = {
      hard_case("overview", "uniform 512", 100, 0.01),             // log 0
      hard_case("grazing", "uniform 1024", 100, 0.0025),           // log -1.386, 4x under: listed
      hard_case("overview", "psm 2048", 50, 0.005),                // log 0
      hard_case("overview", "pcss 16/32 2048", 50, std::nullopt),  // not a hard test
  };
  std::ostringstream md;
  write_edge_estimate_section(cases, md);
  const std::string s = md.str();
  EXPECT_THAT(s, HasSubstr("| uniform | 2 | -0.69 | 0.69 |"));
  EXPECT_THAT(s, HasSubstr("| psm | 1 | +0.00 | 0.00 |"));
  EXPECT_THAT(s, HasSubstr("| all | 3 | -0.46 | 0.65 |"));
  EXPECT_THAT(s, HasSubstr("(1 cases)"));
  EXPECT_THAT(s, HasSubstr("| street | grazing | uniform 1024 | 1.000% | 0.250% |"));
  EXPECT_THAT(s, Not(HasSubstr("pcss")));

  std::ostringstream none;
  write_edge_estimate_section({hard_case("overview", "pcss 16/32 2048", 5, std::nullopt)}, none);
  EXPECT_EQ(none.str(), "");
}

}  // namespace
}  // namespace shadow::bench
