// shadowctl and virtual shadow maps (issue 53): --technique virtual with its flags (only with
// virtual), the default products without a dense map, the size left to the server, and the
// report's pages line for a render and for every frame of a sequence.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "shadowctl/args.hpp"
#include "shadowctl/report.hpp"
#include "shadowctl/request.hpp"
#include "shadowctl/sequence_to_files.hpp"

namespace shadow::ctl {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;

RequestFlags virtual_demo() {
  RequestFlags f;
  f.scene = kDemoScene;
  f.technique = "virtual";
  return f;
}

// The FlagError's message, or "(accepted)".
std::string flag_error(const RequestFlags& f) {
  try {
    build_request(f);
  } catch (const FlagError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(VirtualFlags, TechniqueAndItsSettings) {
  EXPECT_EQ(parse_technique("virtual", "--technique"), Technique::kVirtual);
  RequestFlags f = virtual_demo();
  v1::RenderRequest r = build_request(f);
  EXPECT_EQ(r.shadow_map().technique(), v1::TECHNIQUE_VIRTUAL);
  // Unset: the server's defaults (16384, bias -0.5, 1024 pages, coarsening allowed), even with the
  // demo, which suggests only biases.
  EXPECT_FALSE(r.shadow_map().has_size());
  EXPECT_FALSE(r.shadow_map().has_virtual_lod_bias());
  EXPECT_FALSE(r.shadow_map().has_virtual_pool_pages());
  EXPECT_FALSE(r.shadow_map().virtual_refuse_coarsening());
  f.map_size = "32768";
  f.virtual_lod_bias = "-1";
  f.virtual_pool_pages = "2048";
  f.virtual_refuse_coarsening = true;
  r = build_request(f);
  EXPECT_EQ(r.shadow_map().size(), 32768u);
  EXPECT_EQ(r.shadow_map().virtual_lod_bias(), -1.0f);
  EXPECT_EQ(r.shadow_map().virtual_pool_pages(), 2048u);
  EXPECT_TRUE(r.shadow_map().virtual_refuse_coarsening());
}

// Ranges are the server's to check (it names the field); the syntax is shadowctl's.
TEST(VirtualFlags, BadValuesNameTheFlag) {
  RequestFlags f = virtual_demo();
  f.virtual_lod_bias = "nan";
  EXPECT_THAT(flag_error(f), HasSubstr("--virtual-lod-bias: expected a finite number"));
  f.virtual_lod_bias = "1x";
  EXPECT_THAT(flag_error(f), HasSubstr("--virtual-lod-bias: expected a finite number"));
  f = virtual_demo();
  f.virtual_pool_pages = "-1";
  EXPECT_THAT(flag_error(f), HasSubstr("--virtual-pool-pages: expected a whole number"));
  f.virtual_pool_pages = "64k";
  EXPECT_THAT(flag_error(f), HasSubstr("--virtual-pool-pages: expected a whole number"));
}

TEST(VirtualFlags, OnlyWithTechniqueVirtual) {
  for (const char* technique : {"uniform", "lispsm", "auto"}) {
    RequestFlags f = virtual_demo();
    f.technique = technique;
    f.virtual_lod_bias = "1";
    EXPECT_THAT(flag_error(f), HasSubstr("--virtual-lod-bias: only with --technique virtual"))
        << technique;
    f.virtual_lod_bias.reset();
    f.virtual_pool_pages = "64";
    EXPECT_THAT(flag_error(f), HasSubstr("--virtual-pool-pages: only with --technique virtual"))
        << technique;
    f.virtual_pool_pages.reset();
    f.virtual_refuse_coarsening = true;
    EXPECT_THAT(flag_error(f),
                HasSubstr("--virtual-refuse-coarsening: only with --technique virtual"))
        << technique;
  }
  RequestFlags none;  // no --technique: each light's default
  none.scene = kDemoScene;
  none.virtual_pool_pages = "64";
  EXPECT_THAT(flag_error(none), HasSubstr("--virtual-pool-pages: only with --technique virtual"));
}

// A virtual map has no dense map to return: without --products it renders visibility and
// position; the other techniques keep the shadow map first.
TEST(VirtualFlags, DefaultProductsWithoutTheDenseMap) {
  RequestFlags f = virtual_demo();
  EXPECT_THAT(build_request(f).products(),
              ElementsAre(v1::PRODUCT_VISIBILITY, v1::PRODUCT_POSITION));
  f.products = "visibility,texel_density";  // a list given is kept
  EXPECT_THAT(build_request(f).products(),
              ElementsAre(v1::PRODUCT_VISIBILITY, v1::PRODUCT_TEXEL_DENSITY));
  f.products = "shadowmap,visibility";  // the server refuses it, by name
  EXPECT_THAT(build_request(f).products(),
              ElementsAre(v1::PRODUCT_SHADOW_MAP, v1::PRODUCT_VISIBILITY));
  for (const char* technique : {"uniform", "lispsm"}) {
    RequestFlags other = virtual_demo();
    other.technique = technique;
    EXPECT_THAT(build_request(other).products(),
                ElementsAre(v1::PRODUCT_SHADOW_MAP, v1::PRODUCT_VISIBILITY, v1::PRODUCT_POSITION))
        << technique;
  }
}

// The demo no longer suggests a size: absent, the server's 2048 for the other techniques (as the
// demo's own 2048 was), and an explicit --map-size still wins.
TEST(VirtualFlags, DemoLeavesTheSizeToTheServer) {
  RequestFlags f;
  f.scene = kDemoScene;
  EXPECT_FALSE(build_request(f).shadow_map().has_size());
  f.map_size = "1024";
  EXPECT_EQ(build_request(f).shadow_map().size(), 1024u);
}

TEST(VirtualReport, PagesLine) {
  VirtualPageCounts v{412, 400, 37, 1234, uint64_t{64} << 20};
  EXPECT_EQ(format_virtual_pages(v),
            "virtual pages: requested 412, resident 400, rendered 37, coarsened 1234 pixels, "
            "pool 64 MiB");
  v.pool_bytes = (uint64_t{64} << 20) + (uint64_t{1} << 19);  // 64.5 MiB: one decimal
  EXPECT_THAT(format_virtual_pages(v), HasSubstr(", pool 64.5 MiB"));
  v.pool_bytes = uint64_t{1} << 16;  // one page
  EXPECT_THAT(format_virtual_pages(v), HasSubstr(", pool 0.1 MiB"));
  v.pool_bytes = uint64_t{1} << 30;
  EXPECT_THAT(format_virtual_pages(v), HasSubstr(", pool 1024 MiB"));

  RenderResult r;
  EXPECT_THAT(format_report(r, {}, Timeline{}), Not(HasSubstr("virtual pages")));
  r.virtual_pages = VirtualPageCounts{412, 412, 412, 0, uint64_t{64} << 20};
  EXPECT_THAT(format_report(r, {}, Timeline{}),
              HasSubstr("\nvirtual pages: requested 412, resident 412, rendered 412, coarsened 0 "
                        "pixels, pool 64 MiB\n"));
}

// Every frame of a sequence prints its own pages line under its frame line.
TEST(VirtualReport, EveryFramesPages) {
  FrameWritten f;
  f.frame = 3;
  f.passes = 4;
  f.reused = {"scene"};
  f.rerun = {"light0.shadow_map"};
  const std::string plain = format_frame(f);
  EXPECT_THAT(plain, Not(HasSubstr("\n")));
  f.virtual_pages = VirtualPageCounts{300, 300, 12, 0, uint64_t{64} << 20};
  EXPECT_EQ(format_frame(f), plain +
                                 "\nvirtual pages: requested 300, resident 300, rendered 12, "
                                 "coarsened 0 pixels, pool 64 MiB");
}

}  // namespace
}  // namespace shadow::ctl
