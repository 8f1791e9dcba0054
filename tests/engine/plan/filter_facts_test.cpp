// The filter table (engine/plan/filter.*): a row per filter, and the checks validation, the plan
// and the cost estimate read from it.
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "engine/plan/filter.hpp"
#include "wire/errors.hpp"

namespace shadow {
namespace {

constexpr FilterKind kAll[] = {FilterKind::kHard,    FilterKind::kPcf2x2,   FilterKind::kPoisson,
                               FilterKind::kPcss,    FilterKind::kBlur,     FilterKind::kCsm,
                               FilterKind::kPcssCsm, FilterKind::kAtlasSat, FilterKind::kAtlasMip};

// The field a refusal names, or "" when `check` passes.
template <class Check>
std::string refused_field(Check check) {
  try {
    check();
  } catch (const InvalidArgument& e) {
    return e.field();
  }
  return "";
}

TEST(Filters, EveryFilterHasARowWithItsStepAndCost) {
  std::set<std::string> steps;
  for (FilterKind k : kAll) {
    const FilterFacts& f = filter_facts(k);
    EXPECT_EQ(f.kind, k);
    steps.insert(f.step);
    ASSERT_NE(f.taps, nullptr);
    EXPECT_GE(f.taps(Filter{.kind = k}, 1.0, 0), 1.0);
  }
  EXPECT_EQ(steps, (std::set<std::string>{"visibility.shadow_test", "visibility.pcf",
                                          "visibility.pcss", "visibility.blur", "visibility.csm",
                                          "visibility.pcss_csm", "visibility.atlas"}));
  EXPECT_EQ(filter_facts(FilterKind::kPcss).taps(Filter{.kind = FilterKind::kPcss}, 2.0, 0),
            2.0 * (16 + 32));  // blocker and filter taps, times the miss factor
}

TEST(Filters, SettingsAreCheckedOnTheirOwnField) {
  Light sized;
  sized.size = 1.0f;
  Filter poisson{.kind = FilterKind::kPoisson};
  poisson.poisson.taps = 0;
  EXPECT_EQ(refused_field([&] { validate_filter(poisson, sized, "lights[0]"); }),
            "filter.poisson.taps");
  Filter pcss_csm{.kind = FilterKind::kPcssCsm};
  pcss_csm.csm.terms = 17;
  EXPECT_EQ(refused_field([&] { validate_filter(pcss_csm, sized, "lights[0]"); }),
            "filter.pcss_csm.terms");
  pcss_csm.csm.terms = 8;
  pcss_csm.csm.window = 0;  // PCSS-CSM's window comes from its penumbra
  EXPECT_EQ(refused_field([&] { validate_filter(pcss_csm, sized, "lights[0]"); }), "");
  // The soft filters need a light size, named on the light.
  for (FilterKind k : {FilterKind::kPcss, FilterKind::kPcssCsm, FilterKind::kAtlasSat})
    EXPECT_EQ(refused_field([&] { validate_filter(Filter{.kind = k}, Light{}, "lights[2]"); }),
              "lights[2].size")
        << filter_facts(k).field;
  EXPECT_EQ(refused_field([&] { validate_filter(Filter{}, Light{}, "lights[2]"); }), "");
}

TEST(Filters, CubeFacesTakeTheFiltersWithABoundedReach) {
  for (FilterKind k : kAll) {
    const std::string field = refused_field([&] { validate_cube_filter(Filter{.kind = k}, 1024); });
    EXPECT_EQ(field.empty(), filter_facts(k).auto_cube) << filter_facts(k).field;
  }
  // 1024^2 faces: a guard band of 128 texels.
  Filter poisson{.kind = FilterKind::kPoisson};
  poisson.poisson.radius = 126.0f;
  EXPECT_EQ(filter_reach(poisson), 127u);
  EXPECT_EQ(refused_field([&] { validate_cube_filter(poisson, 1024); }), "");
  poisson.poisson.radius = 127.5f;
  EXPECT_EQ(refused_field([&] { validate_cube_filter(poisson, 1024); }), "filter.poisson.radius");
  Filter csm{.kind = FilterKind::kCsm};
  csm.csm.window = 42.0f;  // reads 3 x 42 + 1 texels
  EXPECT_EQ(filter_reach(csm), 127u);
  EXPECT_EQ(refused_field([&] { validate_cube_filter(csm, 1024); }), "");
  csm.csm.window = 42.5f;
  EXPECT_EQ(refused_field([&] { validate_cube_filter(csm, 1024); }), "filter.csm.window");
}

// TECHNIQUE_VIRTUAL reads its pages through the page table: hard, 2x2, Poisson and PCSS are built
// for that; the others are refused on their own field, each with its reason.
TEST(Filters, VirtualMapsTakeTheFiltersBuiltForTheirPages) {
  std::vector<FilterKind> taken;
  for (FilterKind k : kAll) {
    const std::string field = refused_field([&] { validate_virtual_filter(Filter{.kind = k}); });
    EXPECT_EQ(field, filter_facts(k).virtual_refusal ? filter_facts(k).field : "")
        << filter_facts(k).field;
    if (field.empty()) taken.push_back(k);
  }
  EXPECT_EQ(taken, (std::vector<FilterKind>{FilterKind::kHard, FilterKind::kPcf2x2,
                                            FilterKind::kPoisson, FilterKind::kPcss}));
  const auto why = [](FilterKind k) {
    try {
      validate_virtual_filter(Filter{.kind = k});
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(why(FilterKind::kBlur).find("use pcss for soft shadows with virtual maps"),
            std::string::npos)
      << why(FilterKind::kBlur);
  for (FilterKind k :
       {FilterKind::kCsm, FilterKind::kPcssCsm, FilterKind::kAtlasSat, FilterKind::kAtlasMip})
    EXPECT_NE(why(k).find("a prefiltered product (mips, SAT, CSM basis) or the atlas has no "
                          "virtual design"),
              std::string::npos)
        << why(k);
}

}  // namespace
}  // namespace shadow
