// Bytes of small glTF binaries for the loader tests: little-endian values, the .glb container,
// and a buffer with every index flavour the GLB tests use.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>

namespace shadow::testing {

template <typename T>
void append(std::string& bytes, std::initializer_list<T> values) {
  for (T v : values) bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// Wraps a JSON document and a binary chunk into a .glb container.
inline std::string make_glb(std::string json, std::string bin) {
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  std::string out = "glTF";
  append<uint32_t>(out, {2, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size())});
  append<uint32_t>(out, {static_cast<uint32_t>(json.size()), 0x4E4F534A});  // "JSON"
  out += json;
  append<uint32_t>(out, {static_cast<uint32_t>(bin.size()), 0x004E4942});  // "BIN\0"
  return out + bin;
}

// Six float3 positions @0, three uint8 indices (+ pad) @72, four uint32 indices @76.
inline std::string glb_bin() {
  std::string b;
  append<float>(b, {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 0, 0, 2, 1, 0});
  append<uint8_t>(b, {2, 1, 0, 0});
  append<uint32_t>(b, {0, 1, 2, 3});
  return b;
}

}  // namespace shadow::testing
