// A bounded, deterministic fuzz test of the scene loaders: small valid OBJ, .gltf (data: URI and
// external .bin) and .glb files, mutated by a seeded generator (byte flips, inserted digits,
// huge numbers, truncations, duplicated or deleted spans, hostile JSON values and OBJ lines).
// Every load must return a well-formed scene or throw std::runtime_error, never crash or throw
// anything else, and the heap it allocates at its peak must stay within a fixed multiple of the
// bytes of the files it was given. A counting global operator new/delete measures that peak.
//
// SCENE_FUZZ_ITERATIONS=N overrides the iterations per seed file (e.g. for a longer run).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <random>
#include <string>
#include <typeinfo>
#include <vector>

#include <gtest/gtest.h>

#include "gltf_bytes.hpp"
#include "scenes/scene_loader.hpp"
#include "temp_dir.hpp"

// --- a counting heap ---------------------------------------------------------------------------

namespace {

size_t g_current = 0;  // bytes allocated through operator new and not yet freed
size_t g_peak = 0;     // the largest g_current (requested, even if refused) since reset
size_t g_refused = 0;  // requests refused for being larger than kLargest
constexpr size_t kLargest = size_t{1} << 30;  // the test never really allocates more at once

// The block's size and header length sit just before the pointer handed out.
void* counted_alloc(size_t size, size_t align) noexcept {
  const size_t header = align > 16 ? align : 16;
  if (g_current + size > g_peak) g_peak = g_current + size;
  if (size > kLargest) {
    ++g_refused;
    return nullptr;
  }
  void* raw = align > 16 ? std::aligned_alloc(align, (size + header + align - 1) / align * align)
                         : std::malloc(size + header);
  if (!raw) return nullptr;
  char* p = static_cast<char*>(raw) + header;
  reinterpret_cast<size_t*>(p)[-1] = size;
  reinterpret_cast<size_t*>(p)[-2] = header;
  g_current += size;
  return p;
}

void counted_free(void* p) noexcept {
  if (!p) return;
  const size_t size = static_cast<size_t*>(p)[-1];
  const size_t header = static_cast<size_t*>(p)[-2];
  g_current -= size;
  std::free(static_cast<char*>(p) - header);
}

void* counted_new(size_t size, size_t align) {
  if (void* p = counted_alloc(size, align)) return p;
  throw std::bad_alloc();
}

}  // namespace

// Not inlined or cloned anywhere, so a tool that replaces these symbols (valgrind) replaces every
// call.
#if defined(__clang__)
#define NOINLINE __attribute__((noinline))
#else
#define NOINLINE __attribute__((noipa))
#endif

NOINLINE void* operator new(size_t n) {
  return counted_new(n, 16);
}
NOINLINE void* operator new[](size_t n) {
  return counted_new(n, 16);
}
NOINLINE void* operator new(size_t n, std::align_val_t a) {
  return counted_new(n, size_t(a));
}
NOINLINE void* operator new[](size_t n, std::align_val_t a) {
  return counted_new(n, size_t(a));
}
NOINLINE void* operator new(size_t n, const std::nothrow_t&) noexcept {
  return counted_alloc(n, 16);
}
NOINLINE void* operator new[](size_t n, const std::nothrow_t&) noexcept {
  return counted_alloc(n, 16);
}
NOINLINE void* operator new(size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_alloc(n, size_t(a));
}
NOINLINE void* operator new[](size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_alloc(n, size_t(a));
}
// Every other delete forwards to the plain ones, so that a tool that replaces operator new and
// the plain deletes (valgrind 3.19 does, but not the sized ones) sees matching pairs; under such a
// tool the counts stay 0 and only the native run checks the peaks.
NOINLINE void operator delete(void* p) noexcept {
  counted_free(p);
}
NOINLINE void operator delete[](void* p) noexcept {
  counted_free(p);
}
NOINLINE void operator delete(void* p, std::align_val_t) noexcept {
  counted_free(p);
}
NOINLINE void operator delete[](void* p, std::align_val_t) noexcept {
  counted_free(p);
}
NOINLINE void operator delete(void* p, size_t) noexcept {
  ::operator delete(p);
}
NOINLINE void operator delete[](void* p, size_t) noexcept {
  ::operator delete[](p);
}
NOINLINE void operator delete(void* p, size_t, std::align_val_t a) noexcept {
  ::operator delete(p, a);
}
NOINLINE void operator delete[](void* p, size_t, std::align_val_t a) noexcept {
  ::operator delete[](p, a);
}
NOINLINE void operator delete(void* p, const std::nothrow_t&) noexcept {
  ::operator delete(p);
}
NOINLINE void operator delete[](void* p, const std::nothrow_t&) noexcept {
  ::operator delete[](p);
}
NOINLINE void operator delete(void* p, std::align_val_t a, const std::nothrow_t&) noexcept {
  ::operator delete(p, a);
}
NOINLINE void operator delete[](void* p, std::align_val_t a, const std::nothrow_t&) noexcept {
  ::operator delete[](p, a);
}

namespace shadow::scenes {
namespace {

using shadow::testing::append;
using shadow::testing::glb_bin;
using shadow::testing::make_glb;
using shadow::testing::TempDir;

// Writes a fresh file each time: rewriting one in place makes ext4 flush it on close (its
// replace-by-truncate heuristic), which costs more than the load itself.
std::filesystem::path write_fresh(const TempDir& dir, const std::string& name,
                                  const std::string& bytes) {
  std::filesystem::remove(dir.path() / name);
  return dir.write(name, bytes);
}

// The bound every load must keep: peak heap <= kPerInputByte * input bytes + kConstant, i.e. the
// loader's own default budget (LoadLimits: 128 bytes per byte read + 1 MiB) plus 256 KiB for
// what it does not charge (tinygltf's JSON tree, error strings). Measured over 25000 iterations
// per seed file (Release): the largest peak was 0.8 MB, for a 1.3 KB .glb whose sparse accessor's
// count became ~66000 (zeros, admitted by the 1 MiB slack: peak - 128 * input = 620 KiB); every
// other load stayed within 128 * input + 650 bytes. peak / input itself reaches ~620 only there
// and for inputs of a few bytes (the error message). Each test prints these figures.
const double kPerInputByte = static_cast<double>(LoadLimits{}.bytes_per_input_byte);
const double kConstant = static_cast<double>(LoadLimits{}.slack_bytes) + 256 * 1024;

// --- seed files ----------------------------------------------------------------------------------

std::string base64(const std::string& in) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t v = uint8_t(in[i]) << 16 | uint8_t(in[i + 1]) << 8 | uint8_t(in[i + 2]);
    for (int k = 3; k >= 0; --k) out += digits[(v >> (6 * k)) & 63];
  }
  if (i + 1 == in.size()) {
    const uint32_t v = uint8_t(in[i]) << 16;
    out += std::string{digits[v >> 18], digits[(v >> 12) & 63]} + "==";
  } else if (i + 2 == in.size()) {
    const uint32_t v = uint8_t(in[i]) << 16 | uint8_t(in[i + 1]) << 8;
    out += std::string{digits[v >> 18], digits[(v >> 12) & 63], digits[(v >> 6) & 63]} + "=";
  }
  return out;
}

constexpr const char* kObj = R"(# a cube corner and a quad
mtllib scene.mtl
o corner
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
vn 0 1 0
vn 1 0 0
usemtl red
f 1/1/1 2/2/1 3/3/1 4/4/1
f -5/1/2 -4/2/2 -1/3/2
g strip
s 1
f 1//3 4//3 5//3
f 2 3 5
o line
l 1 2
)";

// A quad (interleaved position + normal, stride 24), uv, uint16 indices; a node tree.
std::string quad_bin() {
  std::string b;
  append<float>(b, {0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1, 0, 1, 0, -1, 0, 1, 0, 0, 0, -1, 0, 1, 0});
  append<uint16_t>(b, {0, 1, 2, 0, 2, 3});
  append<float>(b, {0, 0, 1, 0, 1, 1, 0, 1});  // @108
  return b;
}

std::string gltf_json(const std::string& uri) {
  return R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0, 2]}],
  "nodes": [
    {"translation": [1, 2, 3], "children": [1]},
    {"rotation": [0, 0.7071067811865476, 0, 0.7071067811865476], "scale": [2, 2, 2], "mesh": 0},
    {"matrix": [3,0,0,0, 0,1,0,0, 0,0,1,0, 5,0,-5,1], "mesh": 0}
  ],
  "meshes": [{"primitives": [
    {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 3}, "indices": 2},
    {"attributes": {"POSITION": 0}, "mode": 5, "indices": 2}
  ]}],
  "buffers": [{"uri": ")" +
         uri + R"(", "byteLength": 140}],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 96, "byteStride": 24},
    {"buffer": 0, "byteOffset": 96, "byteLength": 12},
    {"buffer": 0, "byteOffset": 108, "byteLength": 32}
  ],
  "accessors": [
    {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3",
     "min": [0, 0, -1], "max": [1, 0, 0]},
    {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"},
    {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
    {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}
  ]
})";
}

constexpr const char* kGlbJson = R"({
  "asset": {"version": "2.0", "extras": {"note": [1, {"a": null}]}},
  "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0}, {"mesh": 1, "scale": [1, 2, 1]}],
  "meshes": [{"primitives": [
    {"attributes": {"POSITION": 0}, "indices": 1},
    {"attributes": {"POSITION": 0}},
    {"attributes": {"POSITION": 0}, "indices": 2, "mode": 6},
    {"attributes": {"POSITION": 0}, "mode": 0}
  ]}, {"primitives": [{"attributes": {"POSITION": 3}, "indices": 2, "mode": 5}]}],
  "buffers": [{"byteLength": 92}],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 72},
    {"buffer": 0, "byteOffset": 72, "byteLength": 3},
    {"buffer": 0, "byteOffset": 76, "byteLength": 16}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3"},
    {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"},
    {"bufferView": 2, "componentType": 5125, "count": 4, "type": "SCALAR"},
    {"componentType": 5126, "count": 6, "type": "VEC3", "sparse": {"count": 1,
      "indices": {"bufferView": 1, "componentType": 5121},
      "values": {"bufferView": 0, "byteOffset": 12}}}
  ]
})";

// --- mutations -----------------------------------------------------------------------------------

class Mutator {
 public:
  explicit Mutator(uint64_t seed) : rng_(seed) {}

  size_t below(size_t n) { return n == 0 ? 0 : static_cast<size_t>(rng_() % n); }
  bool chance(int percent) { return below(100) < static_cast<size_t>(percent); }
  template <typename T>
  const T& pick(const std::vector<T>& items) {
    return items[below(items.size())];
  }

  // One to four random edits of `s`; `json` adds JSON field edits, `obj` OBJ line edits.
  void mutate(std::string& s, bool json, bool obj) {
    const size_t edits = chance(70) ? 1 : 2 + below(3);
    for (size_t e = 0; e < edits; ++e) {
      switch (below(json || obj ? 9 : 7)) {
        case 0:
          flip(s);
          break;
        case 1:
          insert_digits(s);
          break;
        case 2:
          huge_number(s);
          break;
        case 3:
          truncate(s);
          break;
        case 4:
          duplicate(s);
          break;
        case 5:
          erase(s);
          break;
        case 6:
          set_byte(s);
          break;
        default:
          json ? json_field(s) : obj_line(s);
          break;
      }
    }
  }

 private:
  void flip(std::string& s) {
    if (!s.empty()) s[below(s.size())] ^= static_cast<char>(1 << below(8));
  }
  void set_byte(std::string& s) {
    static const std::vector<char> bytes = {'\0', '\n', '\r', '"', '\\', '/', '-', '.',   'e',
                                            '[',  '{',  ']',  '}', ',',  ':', ' ', '\xff'};
    if (!s.empty()) s[below(s.size())] = chance(50) ? pick(bytes) : static_cast<char>(below(256));
  }
  void insert_digits(std::string& s) {
    std::string digits;
    const size_t n = 1 + below(20);
    for (size_t i = 0; i < n; ++i) digits += static_cast<char>('0' + below(10));
    s.insert(digit_position(s), digits);
  }
  // Somewhere in a number if there is one, else anywhere.
  size_t digit_position(const std::string& s) {
    for (int tries = 0; tries < 8; ++tries) {
      const size_t at = below(s.size() + 1);
      if (at < s.size() && s[at] >= '0' && s[at] <= '9') return at;
    }
    return below(s.size() + 1);
  }
  void huge_number(std::string& s) {
    static const std::vector<std::string> numbers = {"4294967295",
                                                     "4294967296",
                                                     "18446744073709551615",
                                                     "18446744073709551600",
                                                     "9223372036854775807",
                                                     "99999999999999999999",
                                                     "-1",
                                                     "-2147483648",
                                                     "2147483647",
                                                     "2147483648",
                                                     "65535",
                                                     "65536",
                                                     "1000000",
                                                     "100000000",
                                                     "0",
                                                     "1e308",
                                                     "1e39",
                                                     "-1e39",
                                                     "nan",
                                                     "inf",
                                                     "-0",
                                                     "3.4028235e38",
                                                     "1e-45",
                                                     "4611686018427387904"};
    const size_t at = digit_position(s);
    size_t end = at;
    while (end < s.size() && ((s[end] >= '0' && s[end] <= '9') || s[end] == '.')) ++end;
    s.replace(at, end - at, pick(numbers));
  }
  void truncate(std::string& s) { s.resize(below(s.size() + 1)); }
  void duplicate(std::string& s) {
    if (s.empty()) return;
    const size_t a = below(s.size()), n = 1 + below(std::min<size_t>(64, s.size() - a));
    const std::string span = s.substr(a, n);
    const size_t copies = chance(10) ? 1 + below(200) : 1;
    std::string repeated;
    for (size_t i = 0; i < copies; ++i) repeated += span;
    s.insert(below(s.size() + 1), repeated);
  }
  void erase(std::string& s) {
    if (s.empty()) return;
    const size_t a = below(s.size());
    s.erase(a, 1 + below(std::min<size_t>(32, s.size() - a)));
  }
  // Replaces the value of a random occurrence of a glTF key with a hostile value.
  void json_field(std::string& s) {
    static const std::vector<std::string> keys = {
        "count",         "byteOffset",  "byteLength", "byteStride",  "bufferView", "buffer",
        "componentType", "type",        "mode",       "indices",     "POSITION",   "NORMAL",
        "TEXCOORD_0",    "children",    "mesh",       "nodes",       "scene",      "uri",
        "matrix",        "translation", "rotation",   "scale",       "sparse",     "values",
        "extras",        "primitives",  "accessors",  "bufferViews", "buffers",    "meshes"};
    static const std::vector<std::string> values = {
        "0",
        "-1",
        "1",
        "2",
        "3",
        "6",
        "7",
        "100",
        "255",
        "5120",
        "5121",
        "5122",
        "5123",
        "5124",
        "5125",
        "5126",
        "5130",
        "4294967295",
        "18446744073709551615",
        "18446744073709551600",
        "9223372036854775807",
        "1e308",
        "-1e308",
        "1.5",
        "null",
        "true",
        "[]",
        "{}",
        "[0]",
        "[0, 0]",
        "[0, 1, 1, 1]",
        "[1e39, 0, 0]",
        "\"VEC3\"",
        "\"SCALAR\"",
        "\"MAT4\"",
        "\"quad.bin\"",
        "\"../quad.bin\"",
        "\"/etc/passwd\"",
        "\"../../../../etc/passwd\"",
        "\"data:application/octet-stream;base64,AAAA\"",
        "\"%2e%2e/quad.bin\"",
        "\"\"",
        "{\"count\": 2147483647, \"indices\": {\"bufferView\": 1, \"componentType\": 5121}, "
        "\"values\": {\"bufferView\": 0}}",
        "[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]",
        "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[]]]]]]]]]]]]]]]]]]"
        "]]]]"
        "]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]"};
    const std::string key = "\"" + pick(keys) + "\"";
    std::vector<size_t> hits;
    for (size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + 1))
      hits.push_back(at);
    if (hits.empty()) return;
    const size_t colon = s.find(':', pick(hits));
    if (colon == std::string::npos) return;
    size_t start = colon + 1;
    while (start < s.size() && s[start] == ' ') ++start;
    // The value ends at the matching close for [ / {, the closing quote for a string, or the
    // next , } ] otherwise.
    size_t end = start;
    if (end < s.size() && (s[end] == '[' || s[end] == '{')) {
      int depth = 0;
      do {
        if (s[end] == '[' || s[end] == '{') ++depth;
        if (s[end] == ']' || s[end] == '}') --depth;
        ++end;
      } while (end < s.size() && depth > 0);
    } else if (end < s.size() && s[end] == '"') {
      end = s.find('"', end + 1);
      end = end == std::string::npos ? s.size() : end + 1;
    } else {
      while (end < s.size() && s[end] != ',' && s[end] != '}' && s[end] != ']') ++end;
    }
    s.replace(start, end - start, pick(values));
  }
  void obj_line(std::string& s) {
    static const std::vector<std::string> lines = {"v nan 0 0",
                                                   "v 1e39 0 0",
                                                   "v 1 2",
                                                   "vn 0 0",
                                                   "vt",
                                                   "vt 1 2 3 4",
                                                   "f 0 1 2",
                                                   "f 1 2",
                                                   "f -99 1 2",
                                                   "f 1 2 99999999999999999999",
                                                   "f 1/1/1 2//2 3/3",
                                                   "f 1/ 2 3",
                                                   "f 1//1 2/2/ 3",
                                                   "f 2147483647 1 2",
                                                   "f -2147483648 1 2",
                                                   "g",
                                                   "o",
                                                   "o x",
                                                   "mtllib /etc/passwd",
                                                   "usemtl x",
                                                   "t crease 8192/8192/8192",
                                                   "l 1 99",
                                                   "p 0",
                                                   "vw 1 2 3",
                                                   "s off",
                                                   "f 1 2 3 4 5 6 7 8 9 10 11 12",
                                                   "v 1 2 3 4 5 6 7 8",
                                                   "v 0x10 0 0",
                                                   "v +-1 0 0"};
    size_t at = below(s.size() + 1);
    while (at > 0 && at <= s.size() && s[at - 1] != '\n') --at;
    s.insert(at, pick(lines) + (chance(80) ? "\n" : ""));
  }

  std::mt19937_64 rng_;
};

// --- the check ----------------------------------------------------------------------------------

struct Stats {
  size_t loads = 0, scenes = 0, errors = 0;
  size_t largest_peak = 0, largest_peak_input = 0;  // the largest peak, and its input's size
  double largest_ratio = 0;                         // the largest peak / input
  double largest_excess = 0;                        // the largest peak - kPerInputByte * input
  size_t largest_ratio_peak = 0, largest_ratio_input = 0;
};

// A returned scene must be usable as is: every index in range, every value finite.
void expect_well_formed(const Scene& scene, const std::string& where) {
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const Mesh& mesh = scene.meshes[m];
    const size_t vertices = mesh.vertex_count();
    ASSERT_EQ(mesh.positions.size() % 3, 0u) << where;
    ASSERT_TRUE(mesh.normals.empty() || mesh.normals.size() == mesh.positions.size()) << where;
    ASSERT_TRUE(mesh.uvs.empty() || mesh.uvs.size() == 2 * vertices) << where;
    ASSERT_EQ(mesh.indices.size() % 3, 0u) << where;
    for (uint32_t i : mesh.indices) ASSERT_LT(i, vertices) << where << " mesh " << m;
    for (const auto* values : {&mesh.positions, &mesh.normals, &mesh.uvs})
      for (float v : *values) ASSERT_TRUE(std::isfinite(v)) << where << " mesh " << m;
  }
  for (const Instance& instance : scene.instances) {
    ASSERT_LT(instance.mesh, scene.meshes.size()) << where;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) ASSERT_TRUE(std::isfinite(instance.transform[c][r])) << where;
  }
}

// Loads `path` (whose files total `input` bytes) and checks the outcome and the peak heap.
void check_load(const std::filesystem::path& path, size_t input, const std::string& where,
                Stats& stats) {
  const size_t baseline = g_current;
  g_peak = g_current;
  const size_t refused = g_refused;
  bool loaded = false;
  try {
    const Scene scene = load_scene(path);
    loaded = true;
    expect_well_formed(scene, where);
  } catch (const std::runtime_error&) {
    // the expected way to refuse a file
  } catch (const std::exception& e) {
    ADD_FAILURE() << where << ": threw a " << typeid(e).name()
                  << ", not std::runtime_error: " << e.what();
  }
  const size_t peak = g_peak - baseline;
  if (static_cast<double>(peak) > kPerInputByte * input + kConstant || g_refused != refused ||
      ::testing::Test::HasFailure()) {
    // Keep the input for a rerun, outside the test's own temporary folder, which goes away.
    const auto kept =
        std::filesystem::temp_directory_path() / ("scene-fuzz-failure" + path.extension().string());
    std::filesystem::copy_file(path, kept, std::filesystem::copy_options::overwrite_existing);
    std::printf("%s: input kept as %s\n", where.c_str(), kept.c_str());
  }
  ++stats.loads;
  ++(loaded ? stats.scenes : stats.errors);
  EXPECT_EQ(g_refused, refused) << where << ": asked for more than " << kLargest
                                << " bytes at once";
  EXPECT_LE(static_cast<double>(peak), kPerInputByte * input + kConstant)
      << where << ": peak heap " << peak << " bytes for " << input << " bytes of input";
  stats.largest_excess =
      std::max(stats.largest_excess, static_cast<double>(peak) - kPerInputByte * input);
  if (peak > stats.largest_peak) {
    stats.largest_peak = peak;
    stats.largest_peak_input = input;
  }
  const double ratio = static_cast<double>(peak) / static_cast<double>(std::max<size_t>(input, 1));
  if (ratio > stats.largest_ratio) {
    stats.largest_ratio = ratio;
    stats.largest_ratio_peak = peak;
    stats.largest_ratio_input = input;
  }
}

size_t iterations(size_t default_count) {
  if (const char* env = std::getenv("SCENE_FUZZ_ITERATIONS"))
    return std::strtoull(env, nullptr, 10);
  return default_count;
}

void report(const char* name, const Stats& stats) {
  std::printf(
      "%s: %zu loads (%zu scenes, %zu refused); largest peak heap %zu bytes (input %zu bytes); "
      "largest peak / input %.1f (%zu / %zu bytes); largest peak - %.0f * input %.0f bytes\n",
      name, stats.loads, stats.scenes, stats.errors, stats.largest_peak, stats.largest_peak_input,
      stats.largest_ratio, stats.largest_ratio_peak, stats.largest_ratio_input, kPerInputByte,
      stats.largest_excess);
}

TEST(SceneFuzz, Obj) {
  TempDir dir;
  Mutator m(0x5eed0b1);
  Stats stats;
  const size_t n = iterations(4000);
  for (size_t i = 0; i < n; ++i) {
    std::string text = kObj;
    m.mutate(text, false, true);
    const auto path = write_fresh(dir, "scene.obj", text);
    check_load(path, text.size(), "obj iteration " + std::to_string(i), stats);
    if (::testing::Test::HasFailure()) break;
  }
  report("obj", stats);
}

TEST(SceneFuzz, GltfWithDataUri) {
  TempDir dir;
  Mutator m(0x5eed6175);
  Stats stats;
  const std::string seed = gltf_json("data:application/octet-stream;base64," + base64(quad_bin()));
  const size_t n = iterations(4000);
  for (size_t i = 0; i < n; ++i) {
    std::string json = seed;
    m.mutate(json, true, false);
    const auto path = write_fresh(dir, "scene.gltf", json);
    check_load(path, json.size(), "gltf (data: uri) iteration " + std::to_string(i), stats);
    if (::testing::Test::HasFailure()) break;
  }
  report("gltf with data: uri", stats);
}

TEST(SceneFuzz, GltfWithExternalBin) {
  TempDir dir;
  Mutator m(0x5eedb1);
  Stats stats;
  const size_t n = iterations(4000);
  for (size_t i = 0; i < n; ++i) {
    std::string json = gltf_json("quad.bin");
    std::string bin = quad_bin();
    if (m.chance(25))
      m.mutate(bin, false, false);
    else
      m.mutate(json, true, false);
    write_fresh(dir, "quad.bin", bin);
    const auto path = write_fresh(dir, "scene.gltf", json);
    check_load(path, json.size() + bin.size(), "gltf (.bin) iteration " + std::to_string(i), stats);
    if (::testing::Test::HasFailure()) break;
  }
  report("gltf with .bin", stats);
}

TEST(SceneFuzz, Glb) {
  TempDir dir;
  Mutator m(0x5eed61b);
  Stats stats;
  const size_t n = iterations(4000);
  for (size_t i = 0; i < n; ++i) {
    std::string glb;
    if (m.chance(50)) {  // edit the JSON and pack it into a well-formed container
      std::string json = kGlbJson;
      m.mutate(json, true, false);
      std::string bin = glb_bin();
      if (m.chance(20)) m.mutate(bin, false, false);
      glb = make_glb(json, bin);
    } else {  // edit the container's bytes
      glb = make_glb(kGlbJson, glb_bin());
      m.mutate(glb, false, false);
    }
    const auto path = write_fresh(dir, "scene.glb", glb);
    check_load(path, glb.size(), "glb iteration " + std::to_string(i), stats);
    if (::testing::Test::HasFailure()) break;
  }
  report("glb", stats);
}

// The hostile files of issue 10, whose counts made the old loader allocate up to 1.3 GB before
// (or instead of) refusing them: now each is refused within the bound, and under 2 MiB.
TEST(SceneFuzz, HostileCountsAllocateLittle) {
  TempDir dir;
  Stats stats;
  const std::string data_uri = "data:application/octet-stream;base64," + base64(quad_bin());
  const std::string seed = gltf_json(data_uri);
  const std::string position =
      R"({"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4,)";
  const auto replaced = [](std::string s, const std::string& from, const std::string& to) {
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? s : s.replace(at, from.size(), to);
  };
  std::vector<std::pair<std::string, std::string>> files = {
      {"count.gltf",
       replaced(seed, position, replaced(position, "\"count\": 4", "\"count\": 100000000"))},
      {"zeros.gltf", replaced(seed, position, R"({"componentType": 5126, "count": 100000000,)")},
      {"max.gltf", replaced(seed, position,
                            replaced(position, "\"count\": 4", "\"count\": 18446744073709551615"))},
      {"sparse.glb", make_glb(replaced(kGlbJson, R"({"componentType": 5126, "count": 6,)",
                                       R"({"componentType": 5126, "count": 2147483647,)"),
                              glb_bin())}};
  std::string nodes;
  for (int i = 0; i < 40; ++i)
    nodes += "{\"children\": [" + std::to_string(i + 1) + ", " + std::to_string(i + 1) + "]},";
  files.emplace_back("dag.glb", make_glb(replaced(kGlbJson, R"("nodes": [{"mesh": 0}, )",
                                                  "\"nodes\": [" + nodes + R"({"mesh": 0}, )"),
                                         glb_bin()));
  for (const auto& [name, bytes] : files) {
    const size_t before = stats.errors;
    check_load(dir.write(name, bytes), bytes.size(), name, stats);
    EXPECT_EQ(stats.errors, before + 1) << name << " was not refused";
  }
  EXPECT_LT(stats.largest_peak, size_t{2} << 20);
  report("hostile counts", stats);
}

}  // namespace
}  // namespace shadow::scenes
