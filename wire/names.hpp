// One name table per enum of the vocabulary types (wire/types.hpp). A row holds an engine value,
// its proto value and its name: the spelling of shadowctl's flags and of every message that
// names a value. (The JSON of shadowctl --request is protobuf's mapping: it spells the proto
// value, e.g. "TECHNIQUE_PSM".) The flag parser, the request builder and the proto conversion
// look values up here; nothing else spells them.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "shadow/v1/shadow.pb.h"
#include "wire/types.hpp"

namespace shadow::names {

template <class Value, class Proto>
struct Row {
  Value value;
  Proto proto;
  std::string_view name;
  std::string_view alias = {};  // also accepted by parse(), never listed
};

template <class Value, class Proto>
class Table {
 public:
  // `noun` names a value in messages: "unknown <noun> 'x' (expected a, b or c)".
  template <size_t N>
  constexpr Table(std::string_view noun, const Row<Value, Proto> (&rows)[N])
      : noun_(noun), rows_(rows) {}

  std::string_view noun() const { return noun_; }
  std::span<const Row<Value, Proto>> rows() const { return rows_; }

  std::optional<Value> parse(std::string_view name) const {
    for (const auto& row : rows_)
      if (name == row.name || (!row.alias.empty() && name == row.alias)) return row.value;
    return std::nullopt;
  }
  std::optional<Value> from_proto(Proto proto) const {
    for (const auto& row : rows_)
      if (row.proto == proto) return row.value;
    return std::nullopt;
  }
  // Values outside the enum have no row: Proto{} (*_UNSPECIFIED, KIND_NOT_SET) and "".
  Proto to_proto(Value value) const {
    const Row<Value, Proto>* row = find(value);
    return row ? row->proto : Proto{};
  }
  std::string_view name(Value value) const {
    const Row<Value, Proto>* row = find(value);
    return row ? row->name : std::string_view();
  }

  // "uniform, psm, cube, psm_cube, lispsm, auto or virtual"; listing(" | ", " | ") for a flag's
  // help.
  std::string listing(std::string_view separator = ", ", std::string_view last = " or ") const {
    std::string out;
    for (size_t i = 0; i < rows_.size(); ++i) {
      if (i > 0) out += i + 1 == rows_.size() ? last : separator;
      out += rows_[i].name;
    }
    return out;
  }
  // "unknown technique 'x' (expected uniform, psm, cube, psm_cube, lispsm, auto or virtual)".
  std::string unknown_name(std::string_view name) const {
    return "unknown " + std::string(noun_) + " '" + std::string(name) + "' (expected " + listing() +
           ")";
  }
  // "unknown technique 9".
  std::string unknown_proto(Proto proto) const {
    return "unknown " + std::string(noun_) + " " + std::to_string(int(proto));
  }

 private:
  const Row<Value, Proto>* find(Value value) const {
    for (const auto& row : rows_)
      if (row.value == value) return &row;
    return nullptr;
  }

  std::string_view noun_;
  std::span<const Row<Value, Proto>> rows_;
};

extern const Table<Technique, v1::Technique> kTechniques;
extern const Table<PsmCasters, v1::PsmCasterMode> kPsmCasters;
extern const Table<PsmNear, v1::PsmNearMode> kPsmNear;
extern const Table<MapFit, v1::MapFit> kMapFits;
// The proto side of a oneof is its case, which is the member's field number.
extern const Table<LightType, v1::Light::KindCase> kLightTypes;
extern const Table<FilterKind, v1::Filter::KindCase> kFilterKinds;
extern const Table<CsmStorage, v1::CsmStorage> kCsmStorages;
extern const Table<CsmLookup, v1::CsmLookup> kCsmLookups;
extern const Table<Product, v1::Product> kProducts;
extern const Table<PixelFormat, v1::PixelFormat> kPixelFormats;
extern const Table<ChunkCompression, v1::ChunkCompression> kChunkCompressions;

}  // namespace shadow::names
