// Virtual shadow maps on the wire (issue 53): the technique's name and settings both ways, its
// default map size (absent = 16384 with virtual only), and the reply's page counts through
// make_header and the assembler, in a single reply and in every frame of a sequence.
#include <gtest/gtest.h>

#include "stream_helpers.hpp"
#include "wire/convert.hpp"
#include "wire/names.hpp"
#include "wire/result_assembler.hpp"
#include "wire/result_slicer.hpp"

namespace shadow::convert {
namespace {

ShadowMapSettings round_trip(const ShadowMapSettings& s) {
  v1::ShadowMapSettings wire;
  EXPECT_TRUE(wire.ParseFromString(to_proto(s).SerializeAsString()));
  return from_proto(wire);
}

TEST(VirtualConvert, TechniqueName) {
  EXPECT_EQ(names::kTechniques.parse("virtual"), Technique::kVirtual);
  EXPECT_EQ(names::kTechniques.name(Technique::kVirtual), "virtual");
  EXPECT_EQ(to_proto(Technique::kVirtual), v1::TECHNIQUE_VIRTUAL);
  EXPECT_EQ(names::kTechniques.from_proto(v1::TECHNIQUE_VIRTUAL), Technique::kVirtual);
  EXPECT_EQ(int(v1::TECHNIQUE_VIRTUAL), 7);
}

TEST(VirtualConvert, SettingsRoundTrip) {
  ShadowMapSettings s;
  s.technique = Technique::kVirtual;
  s.size = 32768;
  s.virtual_lod_bias = -1.5f;
  s.virtual_pool_pages = 4096;
  s.virtual_refuse_coarsening = true;
  const v1::ShadowMapSettings wire = to_proto(s);
  EXPECT_EQ(wire.technique(), v1::TECHNIQUE_VIRTUAL);
  EXPECT_EQ(wire.virtual_lod_bias(), -1.5f);
  EXPECT_EQ(wire.virtual_pool_pages(), 4096u);
  EXPECT_TRUE(wire.virtual_refuse_coarsening());
  EXPECT_EQ(round_trip(s), s);
  // The defaults travel too.
  s.virtual_lod_bias = -0.5f;
  s.virtual_pool_pages = 1024;
  s.virtual_refuse_coarsening = false;
  EXPECT_EQ(round_trip(s), s);
}

// Read only with virtual: another technique neither writes them nor depends on them.
TEST(VirtualConvert, OtherTechniquesLeaveTheVirtualFieldsUnset) {
  ShadowMapSettings s;
  s.technique = Technique::kUniform;
  s.virtual_lod_bias = 2;
  s.virtual_pool_pages = 7;
  s.virtual_refuse_coarsening = true;
  const v1::ShadowMapSettings wire = to_proto(s);
  EXPECT_FALSE(wire.has_virtual_lod_bias());
  EXPECT_FALSE(wire.has_virtual_pool_pages());
  EXPECT_FALSE(wire.virtual_refuse_coarsening());
  ShadowMapSettings uniform;
  uniform.technique = Technique::kUniform;
  EXPECT_EQ(round_trip(s), uniform);
}

// Absent fields are the proto's documented defaults.
TEST(VirtualConvert, AbsentFieldsAreTheDefaults) {
  v1::ShadowMapSettings wire;
  wire.set_technique(v1::TECHNIQUE_VIRTUAL);
  ShadowMapSettings s = from_proto(wire);
  EXPECT_EQ(s.size, 16384u);
  EXPECT_EQ(s.size, kDefaultVirtualMapSize);
  EXPECT_EQ(s.virtual_lod_bias, -0.5f);
  EXPECT_EQ(s.virtual_pool_pages, 1024u);
  EXPECT_FALSE(s.virtual_refuse_coarsening);
  wire.set_size(2048);  // a size given is kept
  EXPECT_EQ(from_proto(wire).size, 2048u);
  // The other techniques keep 2048 for an absent size.
  for (v1::Technique t :
       {v1::TECHNIQUE_UNSPECIFIED, v1::TECHNIQUE_UNIFORM, v1::TECHNIQUE_PSM, v1::TECHNIQUE_CUBE,
        v1::TECHNIQUE_PSM_CUBE, v1::TECHNIQUE_LISPSM, v1::TECHNIQUE_AUTO}) {
    v1::ShadowMapSettings other;
    other.set_technique(t);
    EXPECT_EQ(from_proto(other).size, 2048u) << v1::Technique_Name(t);
  }
  // Through a whole request too.
  RenderRequest plain;
  plain.products = {Product::kVisibility};
  v1::RenderRequest request = to_proto(plain);
  request.mutable_shadow_map()->clear_size();
  request.mutable_shadow_map()->set_technique(v1::TECHNIQUE_VIRTUAL);
  EXPECT_EQ(from_proto(request).shadow_map.size, 16384u);
  request.mutable_shadow_map()->set_technique(v1::TECHNIQUE_UNIFORM);
  EXPECT_EQ(from_proto(request).shadow_map.size, 2048u);
}

TEST(VirtualConvert, PageCountsReachTheClient) {
  RenderResult r;
  r.virtual_pages = VirtualPageCounts{412, 400, 37, 1234, uint64_t{64} << 20};
  const v1::RenderHeader header = make_header(r);
  ASSERT_TRUE(header.has_virtual_pages());
  EXPECT_EQ(header.virtual_pages().requested(), 412u);
  EXPECT_EQ(header.virtual_pages().resident(), 400u);
  EXPECT_EQ(header.virtual_pages().rendered(), 37u);
  EXPECT_EQ(header.virtual_pages().coarsened_pixels(), 1234u);
  EXPECT_EQ(header.virtual_pages().pool_bytes(), uint64_t{64} << 20);
  EXPECT_EQ(assemble(stream(r, kDefaultChunkBytes)).virtual_pages, r.virtual_pages);
  // Without virtual: no counts on the wire, none assembled.
  RenderResult plain;
  EXPECT_FALSE(make_header(plain).has_virtual_pages());
  EXPECT_FALSE(assemble(stream(plain, kDefaultChunkBytes)).virtual_pages.has_value());
  // Zero counts are still counts (a view that marked nothing).
  plain.virtual_pages = VirtualPageCounts{};
  EXPECT_TRUE(make_header(plain).has_virtual_pages());
  EXPECT_EQ(assemble(stream(plain, kDefaultChunkBytes)).virtual_pages, VirtualPageCounts{});
}

// A sequence's frames are each a header and its chunks: every frame carries its own counts.
TEST(VirtualConvert, EveryFrameOfASequenceCarriesItsCounts) {
  for (uint32_t frame = 0; frame < 3; ++frame) {
    RenderResult r;
    r.frame = frame;
    r.rerun = {"light0.virtual_pages"};
    r.virtual_pages = VirtualPageCounts{300 + frame, 300 + frame, frame == 0 ? 300u : frame, 0,
                                        uint64_t{64} << 20};
    const RenderResult back = assemble(stream(r, kDefaultChunkBytes));
    EXPECT_EQ(back.frame, frame);
    EXPECT_EQ(back.rerun, r.rerun);
    EXPECT_EQ(back.virtual_pages, r.virtual_pages) << frame;
  }
}

}  // namespace
}  // namespace shadow::convert
