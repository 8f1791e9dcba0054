// Loads small OBJ / glTF / GLB files written by the test and checks what comes out exactly, and
// feeds the loaders hostile files: each must be refused with an error naming the file and what
// is wrong.
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <glm/gtc/type_ptr.hpp>

#include "scenes/scene_loader.hpp"
#include "temp_dir.hpp"

namespace shadow::scenes {
namespace {

using shadow::testing::TempDir;
using ::testing::HasSubstr;

// The error load_scene throws; anything but a std::runtime_error fails the test.
std::string load_error(const std::filesystem::path& path, const LoadLimits& limits = {}) {
  try {
    load_scene(path, limits);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const size_t at = s.find(from);
  if (at == std::string::npos) throw std::logic_error("fixture has no '" + from + "'");
  return s.replace(at, from.size(), to);
}

glm::vec3 apply(const glm::mat4& m, glm::vec3 p) {
  return glm::vec3(m * glm::vec4(p, 1.0f));
}

// --- OBJ -----------------------------------------------------------------------------------

// A quad with normals and uvs, then a shape whose faces disagree on having normals and uvs.
constexpr const char* kObj = R"(v 0 0 0
v 2 0 0
v 2 0 1
v 0 0 1
v 5 5 5
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 1 0
vn 0 -1 0
o quad
f 1/1/1 4/4/1 3/3/1 2/2/1
o tri
f 1 2 5
f 1/1/2 2/2/2 5/1/2
)";

TEST(LoadObj, OneMeshPerShapeWithReindexedCorners) {
  TempDir dir;
  const Scene scene = load_scene(dir.write("two.obj", kObj));
  ASSERT_EQ(scene.meshes.size(), 2u);
  ASSERT_EQ(scene.instances.size(), 2u);
  EXPECT_EQ(scene.instances[0].mesh, 0u);
  EXPECT_EQ(scene.instances[1].mesh, 1u);
  EXPECT_EQ(scene.instances[1].transform, glm::mat4(1.0f));

  const Mesh& quad = scene.meshes[0];
  ASSERT_EQ(quad.vertex_count(), 4u);  // four distinct corners, each stored once
  ASSERT_EQ(quad.triangle_count(), 2u);
  // tinyobjloader picks the diagonal, so check each vertex against the corner it must be.
  const std::map<std::vector<float>, std::vector<float>> uv_of = {
      {{0, 0, 0}, {0, 0}}, {{0, 0, 1}, {0, 1}}, {{2, 0, 1}, {1, 1}}, {{2, 0, 0}, {1, 0}}};
  std::set<std::vector<float>> seen;
  for (size_t v = 0; v < 4; ++v) {
    const std::vector<float> p(&quad.positions[3 * v], &quad.positions[3 * v + 3]);
    ASSERT_TRUE(uv_of.count(p)) << "vertex " << v << " is not a corner of the quad";
    EXPECT_EQ(std::vector<float>(&quad.uvs[2 * v], &quad.uvs[2 * v + 2]), uv_of.at(p));
    EXPECT_EQ(std::vector<float>(&quad.normals[3 * v], &quad.normals[3 * v + 3]),
              (std::vector<float>{0, 1, 0}));
    seen.insert(p);
  }
  EXPECT_EQ(seen.size(), 4u);
  // Every corner index refers to the right position: triangles cover the quad exactly once.
  float area = 0;
  for (size_t t = 0; t < quad.triangle_count(); ++t) {
    glm::vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = glm::make_vec3(&quad.positions[3 * quad.indices[3 * t + k]]);
    const glm::vec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
    EXPECT_GT(n.y, 0.0f) << "triangle " << t << " lost the face's winding";
    area += n.y / 2;
  }
  EXPECT_FLOAT_EQ(area, 2.0f);

  // Faces disagree on normals / uvs, so the mesh keeps neither and corners collapse to positions.
  const Mesh& tri = scene.meshes[1];
  EXPECT_TRUE(tri.normals.empty());
  EXPECT_TRUE(tri.uvs.empty());
  EXPECT_EQ(tri.positions, (std::vector<float>{0, 0, 0, 2, 0, 0, 5, 5, 5}));
  EXPECT_EQ(tri.indices, (std::vector<uint32_t>{0, 1, 2, 0, 1, 2}));
}

TEST(LoadObj, ExtensionIsCaseInsensitive) {
  TempDir dir;
  EXPECT_EQ(load_scene(dir.write("UPPER.OBJ", kObj)).meshes.size(), 2u);
}

TEST(LoadObj, BadFilesNameTheFileAndTheProblem) {
  TempDir dir;
  const auto missing = dir.path() / "missing.obj";
  EXPECT_THAT(load_error(missing), HasSubstr(missing.string() + ": no such file"));

  const auto range = dir.write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  EXPECT_THAT(load_error(range), HasSubstr(range.string()));
  EXPECT_THAT(load_error(range), HasSubstr("out of range"));

  const auto empty = dir.write("empty.obj", "v 0 0 0\nv 1 0 0\n");
  EXPECT_THAT(load_error(empty), HasSubstr(empty.string() + ": contains no triangles"));

  const auto other = dir.write("scene.fbx", "");
  EXPECT_THAT(load_error(other), HasSubstr("unknown scene format '.fbx'"));
}

// tinyobjloader alone reads "nan" as 0 and an index that overflows atoi as whatever wraps; the
// loader must refuse both, naming file:line and the token.
TEST(LoadObj, BadNumbersNameFileLineAndToken) {
  TempDir dir;
  const auto error = [&](const std::string& name, const std::string& text) {
    return load_error(dir.write(name, text));
  };
  const std::string tri = "f 1 2 3\n";
  const auto at = [&](const std::string& name, int line) {
    return (dir.path() / name).string() + ":" + std::to_string(line) + ": ";
  };

  EXPECT_THAT(error("nan.obj", "v 0 0 0\nv nan 1 0\nv 0 1 0\n" + tri),
              HasSubstr(at("nan.obj", 2) + "coordinate 'nan' is not a finite float"));
  EXPECT_THAT(error("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 -inf\n" + tri),
              HasSubstr(at("inf.obj", 3) + "coordinate '-inf' is not a finite float"));
  EXPECT_THAT(error("big.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\n" + tri),
              HasSubstr(at("big.obj", 2) + "coordinate '1e39' is not a finite float"));
  EXPECT_THAT(error("word.obj", "v 0 0 0\nv 1 0 0\nv 0 one 0\n" + tri),
              HasSubstr(at("word.obj", 3) + "coordinate 'one' is not a number"));
  EXPECT_THAT(error("comma.obj", "v 0 0 0\nv 1,5 0 0\nv 0 1 0\n" + tri),
              HasSubstr(at("comma.obj", 2) + "coordinate '1,5' is not a number"));
  EXPECT_THAT(error("short.obj", "v 0 0 0\nv 1 0\nv 0 1 0\n" + tri),
              HasSubstr(at("short.obj", 2) + "v takes 3 to 7 numbers, got 2"));
  EXPECT_THAT(error("normal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 NaN 1\nf 1//1 2//1 3//1\n"),
              HasSubstr(at("normal.obj", 4) + "normal component 'NaN' is not a finite float"));
  EXPECT_THAT(error("uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 x\nf 1/1 2/1 3/1\n"),
              HasSubstr(at("uv.obj", 4) + "texture coordinate 'x' is not a number"));
}

TEST(LoadObj, BadFacesNameFileLineAndToken) {
  TempDir dir;
  const std::string verts = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const auto error = [&](const std::string& name, const std::string& faces) {
    return load_error(dir.write(name, verts + faces));
  };
  const auto at = [&](const std::string& name, int line) {
    return (dir.path() / name).string() + ":" + std::to_string(line) + ": ";
  };

  EXPECT_THAT(error("zero.obj", "f 1 2 3\nf 0 1 2\n"),
              HasSubstr(at("zero.obj", 5) + "position index '0' is 0; OBJ indices start at 1"));
  EXPECT_THAT(error("overflow.obj", "f 1 2 99999999999999999999\n"),
              HasSubstr(at("overflow.obj", 4) + "position index '99999999999999999999' overflows"));
  EXPECT_THAT(error("int.obj", "f 1 2 2147483648\n"),
              HasSubstr(at("int.obj", 4) + "position index '2147483648' overflows"));
  EXPECT_THAT(error("range.obj", "f 1 2 4\n"),
              HasSubstr(at("range.obj", 4) +
                        "position index '4' is out of range: the file has 3 positions"));
  EXPECT_THAT(error("relative.obj", "f -1 -2 -4\n"),
              HasSubstr(at("relative.obj", 4) + "position index '-4' is out of range: only 3"));
  EXPECT_THAT(error("uvrange.obj", "vt 0 0\nf 1/1 2/2 3/1\n"),
              HasSubstr(at("uvrange.obj", 5) + "texture coordinate index '2' in '2/2' is out of "
                                               "range: the file has 1 texture coordinate"));
  EXPECT_THAT(error("normalzero.obj", "vn 0 0 1\nf 1//1 2//0 3//1\n"),
              HasSubstr(at("normalzero.obj", 5) + "normal index '0' in '2//0' is 0"));
  EXPECT_THAT(error("two.obj", "f 1 2\n"),
              HasSubstr(at("two.obj", 4) + "face has 2 vertices, needs at least 3"));
  EXPECT_THAT(error("one.obj", "f 1\n"), HasSubstr(at("one.obj", 4) + "face has 1 vertex"));
  EXPECT_THAT(error("slash.obj", "f 1/ 2 3\n"),
              HasSubstr(at("slash.obj", 4) + "face vertex '1/' is not i, i/j, i//k or i/j/k"));
  EXPECT_THAT(error("junk.obj", "f 1 2 3x\n"),
              HasSubstr(at("junk.obj", 4) + "position index '3x' is not a whole number"));
  EXPECT_THAT(error("nul.obj", std::string("f 1 2 3\n# \0\n", 12)),
              HasSubstr(at("nul.obj", 5) + "contains a NUL byte"));
  std::string big = "f";
  for (int i = 0; i < 1025; ++i) big += " 1";
  EXPECT_THAT(error("big.obj", big + "\n"),
              HasSubstr(at("big.obj", 4) + "face has 1025 vertices, more than the 1024"));
}

// What the strict scanner must still accept: OBJ's relative indices, forward references, signs,
// exponents, tiny values, trailing comments, CRLF and lone-CR line ends, statements it drops.
TEST(LoadObj, StrictScannerKeepsValidSyntax) {
  TempDir dir;
  const Scene scene = load_scene(dir.write("ok.obj",
                                           "mtllib materials.mtl\r\n"
                                           "f 1/1 2/2 3/1 # a comment\r\n"  // forward references
                                           "v +0 .0 0.\r"
                                           "v 1e0 -0 1E-50\n"
                                           "v\t0 1.0e+0 0 # comment\n"
                                           "vt 0.5\nvt 0 1 0\n"
                                           "usemtl red\ns 1\nl 1 2\np 1\nt crease 2/0/0 1 2\n"
                                           "f -3/-2 -2/-1 -1/-2\n"));
  ASSERT_EQ(scene.meshes.size(), 1u);
  const Mesh& m = scene.meshes[0];
  EXPECT_EQ(m.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  EXPECT_EQ(m.uvs, (std::vector<float>{0.5f, 0, 0, 1, 0.5f, 0}));
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 1, 2}));
}

TEST(LoadObj, FilesPastTheSizeLimitAreNotRead) {
  TempDir dir;
  LoadLimits limits;
  limits.max_file_bytes = 16;
  const auto path = dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_THAT(
      load_error(path, limits),
      HasSubstr(path.string() + " is 32 bytes, more than the 16 bytes a scene file may have"));
  limits = LoadLimits{};
  limits.bytes_per_input_byte = 1;
  limits.slack_bytes = 0;
  EXPECT_THAT(load_error(path, limits), HasSubstr("more than the loader allows"));
}

// --- glTF ----------------------------------------------------------------------------------

template <typename T>
void append(std::string& bytes, std::initializer_list<T> values) {
  for (T v : values) bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// A quad: interleaved position + normal (stride 24) and uint16 indices, in an external .bin.
std::string quad_bin() {
  std::string b;
  append<float>(b, {0,      0, 0,  0, 1, 0, /**/ 1, 0, 0, 0, 1, 0, /**/ 1, 0, -1, 0, 1, 0,
                    /**/ 0, 0, -1, 0, 1, 0});
  append<uint16_t>(b, {0, 1, 2, 0, 2, 3});
  return b;
}

// Node 0 translates its child node 1 (rotation + scale, uses mesh 0); node 2 uses the same mesh
// through a matrix.
constexpr const char* kGltf = R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0, 2]}],
  "nodes": [
    {"translation": [1, 2, 3], "children": [1]},
    {"rotation": [0, 0.7071067811865476, 0, 0.7071067811865476], "scale": [2, 2, 2], "mesh": 0},
    {"matrix": [3,0,0,0, 0,1,0,0, 0,0,1,0, 5,0,-5,1], "mesh": 0}
  ],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
  "buffers": [{"uri": "quad.bin", "byteLength": 108}],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 96, "byteStride": 24},
    {"buffer": 0, "byteOffset": 96, "byteLength": 12}
  ],
  "accessors": [
    {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3",
     "min": [0, 0, -1], "max": [1, 0, 0]},
    {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"},
    {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
  ]
})";

TEST(LoadGltf, StridedAttributesAndNodeHierarchy) {
  TempDir dir;
  dir.write("quad.bin", quad_bin());
  const Scene scene = load_scene(dir.write("quad.gltf", kGltf));

  ASSERT_EQ(scene.meshes.size(), 1u);  // shared by both nodes
  const Mesh& m = scene.meshes[0];
  EXPECT_EQ(m.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 0, -1, 0, 0, -1}));
  EXPECT_EQ(m.normals, (std::vector<float>{0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0}));
  EXPECT_TRUE(m.uvs.empty());
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));

  ASSERT_EQ(scene.instances.size(), 2u);
  EXPECT_EQ(scene.instances[0].mesh, 0u);
  EXPECT_EQ(scene.instances[1].mesh, 0u);
  // Parent translation ∘ child rotation (90° about +y) ∘ child scale 2: (1,0,0) → (0,0,-2) → +t.
  const glm::mat4& child = scene.instances[0].transform;
  const glm::vec3 x = apply(child, {1, 0, 0});
  EXPECT_NEAR(x.x, 1.0f, 1e-6f);
  EXPECT_NEAR(x.y, 2.0f, 1e-6f);
  EXPECT_NEAR(x.z, 1.0f, 1e-6f);
  const glm::vec3 z = apply(child, {0, 0, 1});  // (0,0,2) → (2,0,0) → +t
  EXPECT_NEAR(z.x, 3.0f, 1e-6f);
  EXPECT_NEAR(z.y, 2.0f, 1e-6f);
  EXPECT_NEAR(z.z, 3.0f, 1e-6f);
  // The matrix node is taken column-major, as glTF stores it.
  const glm::mat4& other = scene.instances[1].transform;
  EXPECT_EQ(other[0], glm::vec4(3, 0, 0, 0));
  EXPECT_EQ(other[3], glm::vec4(5, 0, -5, 1));
}

// Wraps a JSON document and a binary chunk into a .glb container.
std::string make_glb(std::string json, std::string bin) {
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  std::string out = "glTF";
  append<uint32_t>(out, {2, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size())});
  append<uint32_t>(out, {static_cast<uint32_t>(json.size()), 0x4E4F534A});  // "JSON"
  out += json;
  append<uint32_t>(out, {static_cast<uint32_t>(bin.size()), 0x004E4942});  // "BIN\0"
  return out + bin;
}

// Four primitives: uint8-indexed triangle, non-indexed pair of triangles, uint32-indexed strip,
// and points (no triangles, dropped).
std::string glb_bin() {
  std::string b;
  append<float>(b, {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 0, 0, 2, 1, 0});  // 6 vertices, @0
  append<uint8_t>(b, {2, 1, 0, 0});                                          // @72, 3 + pad
  append<uint32_t>(b, {0, 1, 2, 3});                                         // @76
  return b;
}

constexpr const char* kGlbJson = R"({
  "asset": {"version": "2.0"},
  "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [
    {"attributes": {"POSITION": 0}, "indices": 1},
    {"attributes": {"POSITION": 0}},
    {"attributes": {"POSITION": 0}, "indices": 2, "mode": 5},
    {"attributes": {"POSITION": 0}, "mode": 0}
  ]}],
  "buffers": [{"byteLength": 92}],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 72},
    {"buffer": 0, "byteOffset": 72, "byteLength": 3},
    {"buffer": 0, "byteOffset": 76, "byteLength": 16}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",
     "min": [0, 0, 0], "max": [2, 1, 0]},
    {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"},
    {"bufferView": 2, "componentType": 5125, "count": 4, "type": "SCALAR"}
  ]
})";

TEST(LoadGltf, BinaryContainerWithEveryIndexFlavour) {
  TempDir dir;
  const Scene scene = load_scene(dir.write("prims.glb", make_glb(kGlbJson, glb_bin())));
  ASSERT_EQ(scene.meshes.size(), 3u);  // the points primitive is dropped
  ASSERT_EQ(scene.instances.size(), 3u);
  for (uint32_t i = 0; i < 3; ++i) {
    EXPECT_EQ(scene.instances[i].mesh, i);
    EXPECT_EQ(scene.instances[i].transform, glm::mat4(1.0f));
    EXPECT_EQ(scene.meshes[i].vertex_count(), 6u);
  }
  EXPECT_EQ(scene.meshes[0].indices, (std::vector<uint32_t>{2, 1, 0}));
  EXPECT_EQ(scene.meshes[1].indices, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
  // Strip 0,1,2,3 → (0,1,2), (1,3,2) as glTF specifies: the second flips to keep the winding.
  EXPECT_EQ(scene.meshes[2].indices, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2}));
  EXPECT_EQ(scene.meshes[0].positions[9], 1.0f);
}

TEST(LoadGltf, SparseAccessorSubstitutesIntoZeros) {
  TempDir dir;
  // POSITION without a bufferView: zeros, except element 2 (first uint8 index) takes the
  // vector at byte 12 of view 0, (1, 0, 0).
  const std::string json =
      replace(kGlbJson, R"({"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",)",
              R"({"componentType": 5126, "count": 6, "type": "VEC3", "sparse": {"count": 1,
          "indices": {"bufferView": 1, "componentType": 5121},
          "values": {"bufferView": 0, "byteOffset": 12}},)");
  const Scene scene = load_scene(dir.write("sparse.glb", make_glb(json, glb_bin())));
  ASSERT_EQ(scene.meshes.size(), 3u);
  EXPECT_EQ(scene.meshes[1].positions,
            (std::vector<float>{0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}));
}

TEST(LoadGltf, BadFilesNameTheFileAndTheProblem) {
  TempDir dir;
  dir.write("quad.bin", quad_bin());

  const auto range = dir.write("range.gltf", replace(kGltf, R"("count": 6)", R"("count": 7)"));
  EXPECT_THAT(load_error(range), HasSubstr(range.string()));
  EXPECT_THAT(load_error(range), HasSubstr("do not fit in bufferView 1"));

  // Index 3 → 9 in the buffer: out of range for four vertices.
  std::string bin = quad_bin();
  bin[96 + 2 * 5] = 9;
  dir.write("bad_index.bin", bin);
  const auto index =
      dir.write("index.gltf", replace(kGltf, R"("uri": "quad.bin")", R"("uri": "bad_index.bin")"));
  EXPECT_THAT(load_error(index),
              HasSubstr("meshes[0].primitives[0]: index 5 is 9, but there are only 4 vertices"));

  const auto nopos =
      dir.write("nopos.gltf", replace(kGltf, R"("POSITION": 0, "NORMAL": 1)", R"("NORMAL": 1)"));
  EXPECT_THAT(load_error(nopos), HasSubstr("has no POSITION attribute"));

  const auto stride =
      dir.write("stride.gltf", replace(kGltf, R"("byteStride": 24)", R"("byteStride": 8)"));
  EXPECT_THAT(load_error(stride), HasSubstr("byteStride"));

  const auto broken = dir.write("broken.gltf", "{ not json");
  EXPECT_THAT(load_error(broken), HasSubstr(broken.string() + ": not a readable glTF 2.0 file"));

  const auto nobin = dir.write("nobin.gltf", replace(kGltf, "quad.bin", "absent.bin"));
  EXPECT_THAT(load_error(nobin), HasSubstr(nobin.string() + ": not a readable glTF 2.0 file"));

  const auto truncated = dir.write("cut.glb", make_glb(kGlbJson, glb_bin()).substr(0, 40));
  EXPECT_THAT(load_error(truncated), HasSubstr(truncated.string()));
}

}  // namespace
}  // namespace shadow::scenes
