// Filters, receiver classes, mip/SAT products and float64 textures on the wire: round trips,
// documented defaults for absent fields, and float64 streaming.
#include <cstring>

#include <gtest/gtest.h>

#include "wire/convert.hpp"
#include "wire/errors.hpp"
#include "wire/result_assembler.hpp"
#include "wire/result_slicer.hpp"

namespace shadow::convert {
namespace {

Filter round_trip(const Filter& f) {
  v1::Filter wire;
  EXPECT_TRUE(wire.ParseFromString(to_proto(f).SerializeAsString()));
  return from_proto(wire);
}

TEST(FilterConvert, EveryKindRoundTripsWithItsSettings) {
  Filter f;
  f.kind = FilterKind::kPoisson;
  f.poisson = {33, 3.5f, false};
  Filter g = round_trip(f);
  EXPECT_EQ(g.kind, FilterKind::kPoisson);
  EXPECT_EQ(g.poisson.taps, 33u);
  EXPECT_EQ(g.poisson.radius, 3.5f);
  EXPECT_FALSE(g.poisson.rotate);

  f.kind = FilterKind::kPcss;
  f.pcss = {7, 48, false};
  g = round_trip(f);
  EXPECT_EQ(g.kind, FilterKind::kPcss);
  EXPECT_EQ(g.pcss.blocker_samples, 7u);
  EXPECT_EQ(g.pcss.filter_samples, 48u);
  EXPECT_FALSE(g.pcss.rotate);

  f.kind = FilterKind::kBlur;
  f.blur = {9, 3};
  g = round_trip(f);
  EXPECT_EQ(g.kind, FilterKind::kBlur);
  EXPECT_EQ(g.blur.radius, 9u);
  EXPECT_EQ(g.blur.passes, 3u);

  for (FilterKind k : {FilterKind::kHard, FilterKind::kPcf2x2}) {
    f.kind = k;
    EXPECT_EQ(round_trip(f).kind, k);
  }
}

TEST(FilterConvert, AbsentFieldsTakeTheDocumentedDefaults) {
  EXPECT_EQ(from_proto(v1::Filter{}).kind, FilterKind::kHard);
  v1::Filter wire;
  wire.mutable_poisson();
  const Filter p = from_proto(wire);
  EXPECT_EQ(p.kind, FilterKind::kPoisson);
  EXPECT_EQ(p.poisson.taps, 16u);
  EXPECT_EQ(p.poisson.radius, 2.0f);
  EXPECT_TRUE(p.poisson.rotate);
  wire.mutable_pcss();
  const Filter s = from_proto(wire);
  EXPECT_EQ(s.pcss.blocker_samples, 16u);
  EXPECT_EQ(s.pcss.filter_samples, 32u);
  wire.mutable_blur();
  const Filter b = from_proto(wire);
  EXPECT_EQ(b.blur.radius, 4u);
  EXPECT_EQ(b.blur.passes, 2u);
  // Zero is a value, not "absent": validation rejects it later with the field's path.
  wire.mutable_poisson()->set_taps(0);
  EXPECT_EQ(from_proto(wire).poisson.taps, 0u);
}

TEST(FilterConvert, RequestCarriesFilterClassesAndNewProducts) {
  auto scene = std::make_shared<Scene>();
  scene->meshes.push_back(Mesh{{0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2}, {}, {}});
  Instance a, b;
  b.receiver_class = 3;
  scene->instances = {a, b};
  RenderRequest r;
  r.scene = scene;
  r.products = {Product::kShadowMapMips, Product::kShadowMapSat, Product::kVisibilityMips,
                Product::kVisibilitySat};
  r.filter.kind = FilterKind::kBlur;
  r.filter.blur = {5, 1};
  v1::RenderRequest wire;
  ASSERT_TRUE(wire.ParseFromString(to_proto(r).SerializeAsString()));
  EXPECT_FALSE(wire.scene().instances(0).has_receiver_class());
  EXPECT_EQ(wire.products(0), v1::PRODUCT_SHADOW_MAP_MIPS);
  EXPECT_EQ(wire.products(3), v1::PRODUCT_VISIBILITY_SAT);
  const RenderRequest out = from_proto(wire);
  EXPECT_EQ(out.products, r.products);
  EXPECT_EQ(out.scene->instances[0].receiver_class, Instance::kNoClass);
  EXPECT_EQ(out.scene->instances[1].receiver_class, 3u);
  EXPECT_EQ(out.filter.kind, FilterKind::kBlur);
  EXPECT_EQ(out.filter.blur.radius, 5u);
}

TEST(FilterConvert, CsmKindsRoundTripAndDefaultWhenAbsent) {
  Filter f;
  f.kind = FilterKind::kPcssCsm;
  f.csm = {12, CsmStorage::kFloat16, 6.0f, 0.5f, 0.75f, 2.0f, CsmLookup::kSat};
  Filter g = round_trip(f);
  EXPECT_EQ(g.kind, FilterKind::kPcssCsm);
  EXPECT_EQ(g.csm.terms, 12u);
  EXPECT_EQ(g.csm.storage, CsmStorage::kFloat16);
  EXPECT_EQ(g.csm.window, 6.0f);
  EXPECT_EQ(g.csm.damping, 0.5f);
  EXPECT_EQ(g.csm.depth_offset, 0.75f);
  EXPECT_EQ(g.csm.scale, 2.0f);
  EXPECT_EQ(g.csm.lookup, CsmLookup::kSat);
  f.kind = FilterKind::kCsm;
  EXPECT_EQ(round_trip(f).kind, FilterKind::kCsm);
  EXPECT_EQ(round_trip(f).csm.terms, 12u);
  v1::Filter wire;
  wire.mutable_csm();
  const CsmSettings d = from_proto(wire).csm, defaults;
  EXPECT_EQ(d.terms, defaults.terms);
  EXPECT_EQ(d.storage, CsmStorage::kFloat32);
  EXPECT_EQ(d.window, defaults.window);
  EXPECT_EQ(d.damping, defaults.damping);
  EXPECT_EQ(d.depth_offset, defaults.depth_offset);
  EXPECT_EQ(d.scale, defaults.scale);
  EXPECT_EQ(d.lookup, CsmLookup::kMips);
  wire.mutable_csm()->set_lookup(static_cast<v1::CsmLookup>(7));
  try {
    from_proto(wire);
    ADD_FAILURE() << "unknown lookup accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.field(), "filter.csm.lookup");
  }
  wire.mutable_pcss_csm()->set_storage(static_cast<v1::CsmStorage>(9));
  try {
    from_proto(wire);
    ADD_FAILURE() << "unknown storage accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.field(), "filter.pcss_csm.storage");
  }
}

TEST(FilterConvert, CsmBasisInfoStreamsItsChannelsAndMapping) {
  RenderResult r;
  Texture t;
  t.name = "csm_basis";
  t.kind = Product::kCsmBasis;
  t.width = t.height = 2;
  t.channels = 2;
  t.channel_names = {"sin1", "cos1"};
  t.depth_mapping = "linear: z = NDC z";
  t.csm_terms = 1;
  t.csm_storage = CsmStorage::kFloat16;
  t.data.assign(8, 0.25f);
  r.textures = {t};
  ResultAssembler assembler;
  ASSERT_TRUE(stream_result(r, 100, [&](const v1::RenderResponse& m) {
    assembler.add(m);
    return true;
  }));
  const Texture out = assembler.finish().textures.at(0);
  EXPECT_EQ(out.channel_names, t.channel_names);
  EXPECT_EQ(out.depth_mapping, t.depth_mapping);
  EXPECT_EQ(out.csm_terms, 1u);
  EXPECT_EQ(out.csm_storage, CsmStorage::kFloat16);
  EXPECT_EQ(out.data, t.data);
  // A header naming fewer channels than it has is a broken stream.
  v1::RenderResponse header;
  *header.mutable_header()->add_textures() = to_proto_info(t);
  header.mutable_header()->mutable_textures(0)->add_channel_names("extra");
  ResultAssembler broken;
  EXPECT_THROW(broken.add(header), StreamError);
}

TEST(FilterConvert, Float64TexturesStreamExactly) {
  RenderResult r;
  Texture t;
  t.name = "visibility_sat";
  t.kind = Product::kVisibilitySat;
  t.width = 37;
  t.height = 11;
  t.format = PixelFormat::kFloat64;
  for (size_t i = 0; i < 37 * 11; ++i) t.data64.push_back(double(i) * 1.0000001 + 1e-9);
  Texture f;
  f.name = "visibility";
  f.kind = Product::kVisibility;
  f.width = f.height = 3;
  f.data.assign(9, 0.5f);
  r.textures = {t, f};
  EXPECT_EQ(to_proto_info(t).format(), v1::PIXEL_FORMAT_FLOAT64);
  EXPECT_EQ(to_proto_info(t).byte_size(), 37u * 11 * 8);
  ResultAssembler assembler;
  ASSERT_TRUE(stream_result(r, 100, [&](const v1::RenderResponse& m) {
    v1::RenderResponse copy;
    EXPECT_TRUE(copy.ParseFromString(m.SerializeAsString()));
    if (m.has_chunk()) {
      EXPECT_LE(m.chunk().data().size(), 100u);
    }
    assembler.add(copy);
    return true;
  }));
  const RenderResult out = assembler.finish();
  ASSERT_EQ(out.textures.size(), 2u);
  EXPECT_EQ(out.textures[0].format, PixelFormat::kFloat64);
  ASSERT_EQ(out.textures[0].data64.size(), t.data64.size());
  EXPECT_EQ(0, std::memcmp(out.textures[0].data64.data(), t.data64.data(), t.byte_size()));
  EXPECT_EQ(out.textures[1].data, f.data);
}

}  // namespace
}  // namespace shadow::convert
