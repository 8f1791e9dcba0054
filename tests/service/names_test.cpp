// The name tables (wire/names.hpp): one row per value of each enum, on both sides, and names
// that round-trip.
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "wire/names.hpp"

namespace shadow::names {
namespace {

// Every row's value, proto value and names are distinct, each round-trips, and the proto side
// has exactly `proto_values` known values (all but *_UNSPECIFIED / KIND_NOT_SET). The engine's
// values are 0 .. engine_values - 1 but for `not_rows` (kDefault: no value on the wire).
template <class Value, class Proto>
void expect_one_row_per_value(const Table<Value, Proto>& table, int engine_values, int proto_values,
                              const std::set<int>& not_rows = {}) {
  SCOPED_TRACE(std::string(table.noun()));
  EXPECT_EQ(int(table.rows().size()), engine_values - int(not_rows.size()));
  EXPECT_EQ(int(table.rows().size()), proto_values);
  std::set<int> values, protos;
  std::set<std::string_view> spellings;
  for (const auto& row : table.rows()) {
    EXPECT_TRUE(values.insert(int(row.value)).second) << row.name;
    EXPECT_TRUE(protos.insert(int(row.proto)).second) << row.name;
    EXPECT_NE(int(row.proto), 0) << row.name;
    EXPECT_TRUE(spellings.insert(row.name).second) << row.name;
    EXPECT_EQ(table.parse(row.name), row.value);
    if (!row.alias.empty()) {
      EXPECT_TRUE(spellings.insert(row.alias).second) << row.alias;
      EXPECT_EQ(table.parse(row.alias), row.value);
    }
    EXPECT_EQ(table.from_proto(row.proto), row.value);
    EXPECT_EQ(table.to_proto(row.value), row.proto);
    EXPECT_EQ(table.name(row.value), row.name);
  }
  for (int v = 0; v < engine_values; ++v) EXPECT_EQ(values.count(v), !not_rows.count(v)) << v;
}

// Known values of a proto enum, without its zero (unspecified) value.
int known_values(const google::protobuf::EnumDescriptor* e) {
  return e->value_count() - 1;
}
int oneof_members(const google::protobuf::Descriptor* message) {
  return message->FindOneofByName("kind")->field_count();
}

TEST(Names, OneRowPerValueOnBothSides) {
  expect_one_row_per_value(kTechniques, 8, known_values(v1::Technique_descriptor()),
                           {int(Technique::kDefault)});
  expect_one_row_per_value(kPsmCasters, 2, known_values(v1::PsmCasterMode_descriptor()));
  expect_one_row_per_value(kPsmNear, 3, known_values(v1::PsmNearMode_descriptor()));
  expect_one_row_per_value(kLightTypes, 3, oneof_members(v1::Light::descriptor()));
  expect_one_row_per_value(kFilterKinds, 9, oneof_members(v1::Filter::descriptor()));
  expect_one_row_per_value(kCsmStorages, 2, known_values(v1::CsmStorage_descriptor()));
  expect_one_row_per_value(kProducts, 15, known_values(v1::Product_descriptor()));
  expect_one_row_per_value(kPixelFormats, 3, known_values(v1::PixelFormat_descriptor()));
  expect_one_row_per_value(kMapFits, 2, known_values(v1::MapFit_descriptor()));
  expect_one_row_per_value(kChunkCompressions, 2, known_values(v1::ChunkCompression_descriptor()));
}

// A oneof's case is its member's field number: the filter and light rows name the right member.
TEST(Names, OneofCasesAreTheMembers) {
  for (const auto& row : kFilterKinds.rows())
    EXPECT_EQ(v1::Filter::descriptor()->FindFieldByNumber(row.proto)->name(), row.name);
  for (const auto& row : kLightTypes.rows())
    EXPECT_EQ(v1::Light::descriptor()->FindFieldByNumber(row.proto)->name(), row.name);
}

TEST(Names, UnknownNamesListTheTable) {
  EXPECT_EQ(kTechniques.unknown_name("tsm"),
            "unknown technique 'tsm' (expected uniform, psm, cube, psm_cube, lispsm, auto or "
            "virtual)");
  EXPECT_EQ(kPsmCasters.unknown_name("x"),
            "unknown mode 'x' (expected inverse-projection or slide-back)");
  EXPECT_EQ(kProducts.unknown_proto(v1::Product(99)), "unknown product 99");
  EXPECT_FALSE(kProducts.parse("depth"));
  EXPECT_EQ(kProducts.parse("shadow_map"), Product::kShadowMap);
}

}  // namespace
}  // namespace shadow::names
