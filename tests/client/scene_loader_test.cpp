// Loads small OBJ / glTF / GLB files written by the test and checks what comes out exactly, and
// feeds the loaders hostile files: each must be refused with an error naming the file and what
// is wrong, never read out of bounds, allocate out of proportion or read outside its folder.
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

#include "gltf_bytes.hpp"
#include "scenes/scene_loader.hpp"
#include "temp_dir.hpp"

namespace shadow::scenes {
namespace {

using shadow::testing::append;
using shadow::testing::glb_bin;
using shadow::testing::make_glb;
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

// Four primitives: uint8-indexed triangle, non-indexed pair of triangles, uint32-indexed strip,
// and points (no triangles, dropped).
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

// --- glTF: hostile files -------------------------------------------------------------------

// Offsets near 2^64 wrapped the old bounds checks: the reads landed before the buffer.
TEST(LoadGltfHostile, OffsetsNear2To64DoNotWrapTheBoundsCheck) {
  TempDir dir;
  dir.write("quad.bin", quad_bin());
  // byteOffset + byteLength = 2^64 - 16 + 112 wraps to 96: inside the 108-byte buffer.
  const auto view = dir.write(
      "view.gltf", replace(kGltf, R"("byteOffset": 0, "byteLength": 96, "byteStride": 24)",
                           R"("byteOffset": 18446744073709551600, "byteLength": 112,
                              "byteStride": 24)"));
  EXPECT_THAT(load_error(view),
              HasSubstr(view.string() + ": meshes[0].primitives[0] POSITION accessors[0]: "
                                        "bufferView 0 (byteOffset 18446744073709551600, "
                                        "byteLength 112) runs past the end of buffer 0 (108 "
                                        "bytes)"));
  // byteOffset + 3 * 24 + 12 = 2^64 - 24 + 84 wraps to 60: inside the 96-byte view.
  const auto accessor = dir.write(
      "accessor.gltf", replace(kGltf, R"({"bufferView": 0, "byteOffset": 0,)",
                               R"({"bufferView": 0, "byteOffset": 18446744073709551592,)"));
  EXPECT_THAT(load_error(accessor),
              HasSubstr("meshes[0].primitives[0] POSITION accessors[0]: 4 elements from "
                        "byteOffset 18446744073709551592 do not fit in bufferView 0 (96 bytes)"));
  // The largest offsets and lengths of all.
  const auto huge = dir.write(
      "huge.gltf",
      replace(kGltf, R"("byteOffset": 96, "byteLength": 12)",
              R"("byteOffset": 18446744073709551615, "byteLength": 18446744073709551615)"));
  EXPECT_THAT(load_error(huge), HasSubstr("indices accessors[2]: bufferView 1"));
}

// A huge count allocated (or aborted on) count * components before the bounds check ran. Now a
// count is checked against the bufferView it reads before anything is allocated, and an accessor
// without one (zeros, the base of a sparse accessor) is charged to the budget first.
TEST(LoadGltfHostile, HugeCountsAreRefusedBeforeAllocating) {
  TempDir dir;
  dir.write("quad.bin", quad_bin());
  const std::string position =
      R"({"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4,)";
  const auto count = [&](const std::string& name, const std::string& n, bool view = true) {
    std::string accessor = replace(position, R"("count": 4)", "\"count\": " + n);
    if (!view) accessor = replace(accessor, R"("bufferView": 0, "byteOffset": 0, )", "");
    return dir.write(name, replace(kGltf, position, accessor));
  };
  const auto big = count("big.gltf", "100000000");
  EXPECT_THAT(load_error(big),
              HasSubstr(big.string() + ": meshes[0].primitives[0] POSITION accessors[0]: "
                                       "100000000 elements from byteOffset 0 do not fit in "
                                       "bufferView 0 (96 bytes)"));
  EXPECT_THAT(load_error(count("max.gltf", "18446744073709551615")),
              HasSubstr("POSITION accessors[0]: 18446744073709551615 elements from byteOffset 0 "
                        "do not fit in bufferView 0 (96 bytes)"));
  const auto zeros = count("zeros.gltf", "100000000", false);
  EXPECT_THAT(load_error(zeros),
              HasSubstr(zeros.string() + ": meshes[0].primitives[0] POSITION accessors[0] needs "
                                         "1200000000 bytes, more than the loader allows"));
  EXPECT_THAT(load_error(count("too_many.gltf", "18446744073709551615", false)),
              HasSubstr("POSITION accessors[0]: count 18446744073709551615 is too large"));
  // 2^62 elements of 3 components fit 64 bits; their bytes do not.
  EXPECT_THAT(load_error(count("wrap.gltf", "4611686018427387904", false)),
              HasSubstr("POSITION accessors[0] needs more than 2^64 bytes"));

  // A sparse accessor without a bufferView is count zeros plus the substitutions.
  const auto sparse = dir.write(
      "sparse.glb",
      make_glb(replace(kGlbJson,
                       R"({"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",)",
                       R"({"componentType": 5126, "count": 50000000, "type": "VEC3",
                           "sparse": {"count": 1,
                             "indices": {"bufferView": 1, "componentType": 5121},
                             "values": {"bufferView": 0}},)"),
               glb_bin()));
  EXPECT_THAT(load_error(sparse), HasSubstr("POSITION accessors[0] needs 600000000 bytes"));
}

// Each level of children [n+1, n+1] doubles the paths to the node at the bottom: 2^40 visits.
TEST(LoadGltfHostile, NodeDagsAreBoundedByTheBudget) {
  TempDir dir;
  std::string nodes;
  const int levels = 40;
  for (int i = 0; i < levels; ++i)
    nodes += "{\"children\": [" + std::to_string(i + 1) + ", " + std::to_string(i + 1) + "]},";
  std::string json =
      replace(kGlbJson, R"("nodes": [{"mesh": 0}])", "\"nodes\": [" + nodes + R"({"mesh": 0}])");
  const auto dag = dir.write("dag.glb", make_glb(json, glb_bin()));
  EXPECT_THAT(load_error(dag), HasSubstr(dag.string() + ": the scene's instances needs"));
  EXPECT_THAT(load_error(dag), HasSubstr("more than the loader allows"));
  // Without a mesh nothing is allocated per visit, but the visits are bounded all the same.
  json = replace(kGlbJson, R"("nodes": [{"mesh": 0}])", "\"nodes\": [" + nodes + "{}]");
  const auto empty = dir.write("empty_dag.glb", make_glb(json, glb_bin()));
  EXPECT_THAT(load_error(empty), HasSubstr(empty.string() + ": the node hierarchy (nodes reached "
                                                            "through many parents?) needs"));
  // A tree of the same size is fine.
  nodes.clear();
  for (int i = 0; i < levels; ++i) nodes += "{\"children\": [" + std::to_string(i + 1) + "]},";
  nodes += R"({"mesh": 0, "translation": [1, 2, 3]})";
  json = replace(kGlbJson, R"("nodes": [{"mesh": 0}])", "\"nodes\": [" + nodes + "]");
  EXPECT_EQ(load_scene(dir.write("tree.glb", make_glb(json, glb_bin()))).instances.size(), 3u);
}

// Buffer URIs resolve only to data: URIs or regular files inside the glTF's own folder.
TEST(LoadGltfHostile, BufferUrisStayInsideTheGltfsFolder) {
  TempDir dir;
  const auto folder = dir.path() / "scene";
  std::filesystem::create_directories(folder / "sub");
  const std::string bin = quad_bin();
  dir.write("outside.bin", bin);
  dir.write("scene/sub/quad.bin", bin);
  const auto with_uri = [&](const std::string& name, const std::string& uri) {
    return dir.write("scene/" + name,
                     replace(kGltf, R"("uri": "quad.bin")", "\"uri\": \"" + uri + "\""));
  };
  const auto refused = [&](const std::string& name, const std::string& uri) {
    return load_error(with_uri(name, uri));
  };

  EXPECT_EQ(load_scene(with_uri("ok.gltf", "sub/quad.bin")).meshes.size(), 1u);
  EXPECT_EQ(load_scene(with_uri("dot.gltf", "./sub/./quad.bin")).meshes.size(), 1u);
  EXPECT_EQ(load_scene(with_uri("escaped.gltf", "sub%2Fquad.bin")).meshes.size(), 1u);

  const auto up = with_uri("up.gltf", "../outside.bin");
  EXPECT_THAT(load_error(up), HasSubstr(up.string() + ": not a readable glTF 2.0 file: buffer uri "
                                                      "'../outside.bin' contains '..'"));
  EXPECT_THAT(refused("passwd.gltf", "../../../../../../../../etc/passwd"),
              HasSubstr("contains '..'; only files in the glTF's folder are read"));
  EXPECT_THAT(refused("encoded.gltf", "%2e%2e/outside.bin"), HasSubstr("contains '..'"));
  EXPECT_THAT(refused("inner.gltf", "sub/../../outside.bin"), HasSubstr("contains '..'"));
  EXPECT_THAT(refused("absolute.gltf", (dir.path() / "outside.bin").string()),
              HasSubstr("is an absolute path"));
  EXPECT_THAT(refused("scheme.gltf", "file:///etc/passwd"),
              HasSubstr("is not a data: URI or a relative file name"));
  EXPECT_THAT(refused("dir.gltf", "sub"), HasSubstr("buffer uri 'sub' is not a regular file"));

  // A symlink inside the folder that leads out of it; one that stays inside is fine.
  std::filesystem::create_symlink(dir.path() / "outside.bin", folder / "link.bin");
  EXPECT_THAT(refused("link.gltf", "link.bin"), HasSubstr("outside the glTF's folder"));
  std::filesystem::create_directory_symlink(dir.path(), folder / "root");
  EXPECT_THAT(refused("linkdir.gltf", "root/outside.bin"), HasSubstr("outside the glTF's folder"));
  std::filesystem::create_symlink(folder / "sub" / "quad.bin", folder / "inside.bin");
  EXPECT_EQ(load_scene(with_uri("inside.gltf", "inside.bin")).meshes.size(), 1u);

  // tinygltf also looks in the current directory; that is not the glTF's folder.
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir.path());
  const std::string from_cwd = load_error(with_uri("cwd.gltf", "outside.bin"));
  std::filesystem::current_path(cwd);
  EXPECT_THAT(from_cwd, HasSubstr("buffer uri 'outside.bin' does not exist"));

  // A FIFO would block a plain read.
  ASSERT_EQ(mkfifo((folder / "fifo.bin").c_str(), 0600), 0);
  EXPECT_THAT(refused("fifo.gltf", "fifo.bin"), HasSubstr("is not a regular file"));
}

TEST(LoadGltfHostile, FilesPastTheSizeLimitAreNotRead) {
  TempDir dir;
  // 3 GiB, but sparse: nothing is written, and the loader must not read it either.
  { std::ofstream(dir.path() / "huge.bin"); }
  ASSERT_EQ(truncate((dir.path() / "huge.bin").c_str(), off_t{3} << 30), 0);
  const auto huge =
      dir.write("huge.gltf", replace(replace(kGltf, "quad.bin", "huge.bin"), R"("byteLength": 108)",
                                     R"("byteLength": 3221225472)"));
  EXPECT_THAT(load_error(huge), HasSubstr(huge.string() + ": not a readable glTF 2.0 file: buffer "
                                                          "uri 'huge.bin': "));
  EXPECT_THAT(load_error(huge), HasSubstr("huge.bin is 3221225472 bytes, more than the 2048 MiB"));

  dir.write("quad.bin", quad_bin());
  LoadLimits limits;
  limits.max_total_input_bytes = 1024;  // the .gltf fits, the .gltf and its .bin do not
  const auto quad = dir.write("quad.gltf", kGltf);
  EXPECT_THAT(load_error(quad, limits), HasSubstr("past 1024 bytes"));
  EXPECT_EQ(load_scene(quad).meshes.size(), 1u);
}

// NaN and infinity have no place in POSITION, NORMAL or TEXCOORD_0; the error names the mesh,
// the attribute, the accessor and the element.
TEST(LoadGltfHostile, NonFiniteAttributesNameMeshAccessorAndElement) {
  TempDir dir;
  const auto with_value = [&](const std::string& name, size_t float_index, float value) {
    std::string bin = quad_bin();
    std::memcpy(bin.data() + 4 * float_index, &value, 4);
    dir.write(name + ".bin", bin);
    return dir.write(name + ".gltf",
                     replace(kGltf, R"("uri": "quad.bin")", "\"uri\": \"" + name + ".bin\""));
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const auto position = with_value("position", 6 * 2 + 1, nan);  // vertex 2, y
  EXPECT_THAT(
      load_error(position),
      HasSubstr(position.string() +
                ": meshes[0].primitives[0] POSITION accessors[0]: element 2 is not finite"));
  const auto normal = with_value("normal", 6 * 3 + 5, -inf);  // vertex 3, normal z
  EXPECT_THAT(load_error(normal),
              HasSubstr("meshes[0].primitives[0] NORMAL accessors[1]: element 3 is not finite"));

  // TEXCOORD_0 in the .glb: six uv pairs after the other data, element 4 broken.
  std::string bin = glb_bin();
  append<float>(bin, {0, 0, 1, 0, 0, 1, 1, 1, nan, 0, 1, 0});
  std::string json = replace(kGlbJson, R"({"attributes": {"POSITION": 0}, "indices": 1},)",
                             R"({"attributes": {"POSITION": 0, "TEXCOORD_0": 3}, "indices": 1},)");
  json = replace(json, R"("byteLength": 92)", R"("byteLength": 140)");
  json = replace(json, R"({"buffer": 0, "byteOffset": 76, "byteLength": 16})",
                 R"({"buffer": 0, "byteOffset": 76, "byteLength": 16},
                    {"buffer": 0, "byteOffset": 92, "byteLength": 48})");
  json = replace(json, R"({"bufferView": 2, "componentType": 5125, "count": 4, "type": "SCALAR"})",
                 R"({"bufferView": 2, "componentType": 5125, "count": 4, "type": "SCALAR"},
                    {"bufferView": 3, "componentType": 5126, "count": 6, "type": "VEC2"})");
  const auto uv = dir.write("uv.glb", make_glb(json, bin));
  EXPECT_THAT(
      load_error(uv),
      HasSubstr("meshes[0].primitives[0] TEXCOORD_0 accessors[3]: element 4 is not finite"));

  // A node transform that overflows float is refused too.
  const auto far = dir.write(
      "far.gltf", replace(kGltf, R"("translation": [1, 2, 3])", R"("translation": [1e39, 2, 3])"));
  dir.write("quad.bin", quad_bin());
  EXPECT_THAT(load_error(far), HasSubstr("nodes[1]: the world transform is not finite"));
}

TEST(LoadGltfHostile, ComponentTypesAndStridesAreChecked) {
  TempDir dir;
  dir.write("quad.bin", quad_bin());
  const auto edit = [&](const std::string& name, const std::string& from, const std::string& to) {
    return load_error(dir.write(name, replace(kGltf, from, to)));
  };
  const std::string position = R"("componentType": 5126, "count": 4, "type": "VEC3",
     "min")";
  EXPECT_THAT(edit("double.gltf", position, replace(position, "5126", "5130")),
              HasSubstr("POSITION accessors[0]: has unsupported componentType 5130"));
  EXPECT_THAT(edit("int.gltf", position, replace(position, "5126", "5124")),
              HasSubstr("POSITION accessors[0]: has unsupported componentType 5124"));
  EXPECT_THAT(edit("vec2.gltf", position, replace(position, "VEC3", "VEC2")),
              HasSubstr("POSITION accessors[0]: has 2 components per element, expected 3"));
  EXPECT_THAT(edit("mat4.gltf", position, replace(position, "VEC3", "MAT4")),
              HasSubstr("POSITION accessors[0]: has 16 components per element, expected 3"));
  EXPECT_THAT(edit("findex.gltf", R"("componentType": 5123, "count": 6)",
                   R"("componentType": 5126, "count": 3)"),
              HasSubstr("indices accessors[2]: indices must be unsigned byte, short or int, not "
                        "componentType 5126"));
  EXPECT_THAT(edit("stride.gltf", R"("byteStride": 24)", R"("byteStride": 8)"),
              HasSubstr("POSITION accessors[0]: byteStride 8 is smaller than an element (12 "
                        "bytes)"));
  EXPECT_THAT(edit("odd.gltf", R"("byteStride": 24)", R"("byteStride": 26)"),
              HasSubstr("byteStride"));  // tinygltf: a multiple of 4, at most 252

  // Sparse accessors: index type, offsets, counts and targets.
  const std::string sparse_json =
      replace(kGlbJson, R"({"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",)",
              R"({"componentType": 5126, "count": 6, "type": "VEC3", "sparse": {"count": 1,
          "indices": {"bufferView": 1, "componentType": 5121},
          "values": {"bufferView": 0, "byteOffset": 12}},)");
  const auto sparse = [&](const std::string& name, const std::string& from, const std::string& to) {
    return load_error(dir.write(name, make_glb(replace(sparse_json, from, to), glb_bin())));
  };
  EXPECT_THAT(sparse("s_type.glb", R"("bufferView": 1, "componentType": 5121)",
                     R"("bufferView": 1, "componentType": 5126)"),
              HasSubstr("POSITION accessors[0].sparse.indices: componentType 5126 is not "
                        "unsigned byte, short or int"));
  EXPECT_THAT(sparse("s_offset.glb", R"("bufferView": 0, "byteOffset": 12)",
                     R"("bufferView": 0, "byteOffset": -16)"),
              HasSubstr("POSITION accessors[0].sparse: has a negative byteOffset"));
  EXPECT_THAT(sparse("s_count.glb", R"("sparse": {"count": 1)", R"("sparse": {"count": 7)"),
              HasSubstr("sparse: count 7 is not between 1 and the accessor's 6 elements"));
  EXPECT_THAT(sparse("s_fit.glb", R"("bufferView": 0, "byteOffset": 12)",
                     R"("bufferView": 0, "byteOffset": 64)"),
              HasSubstr("sparse.values: 1 elements from byteOffset 64 do not fit in bufferView 0"));
  std::string bin = glb_bin();
  bin[72] = 6;  // the sparse target index: one past the last element
  EXPECT_THAT(load_error(dir.write("s_target.glb", make_glb(sparse_json, bin))),
              HasSubstr("sparse: index 6 out of range (6 elements)"));
}

// tinygltf 2.7 checks a GLB's BIN chunk against the file minus its 8-byte chunk header, so a
// BIN chunk 8 bytes too long was read past the end of the file's bytes.
TEST(LoadGltfHostile, GlbContainerIsCheckedStrictly) {
  TempDir dir;
  const std::string glb = make_glb(kGlbJson, glb_bin());
  uint32_t json_length;
  std::memcpy(&json_length, glb.data() + 12, 4);
  const size_t bin_header = 20 + json_length;
  const auto with = [&](size_t at, uint32_t value, size_t cut = 0) {
    std::string bytes = glb;
    std::memcpy(bytes.data() + at, &value, 4);
    return bytes.substr(0, bytes.size() - cut);
  };
  const uint32_t bin_length = static_cast<uint32_t>(glb.size() - bin_header - 8);
  const auto over = dir.write("over.glb", with(bin_header, bin_length + 8));
  EXPECT_THAT(load_error(over),
              HasSubstr(over.string() + ": not a valid GLB file: the BIN chunk (" +
                        std::to_string(bin_length + 8) + " bytes) runs past the end"));
  EXPECT_THAT(load_error(dir.write("v1.glb", with(4, 1))), HasSubstr("version 1, not 2"));
  EXPECT_THAT(load_error(dir.write("long.glb", with(8, static_cast<uint32_t>(glb.size() + 1)))),
              HasSubstr("the header says"));
  EXPECT_THAT(load_error(dir.write("json.glb", with(12, 0xfffffff0u))),
              HasSubstr("the JSON chunk (4294967280 bytes) runs past the end"));
  EXPECT_THAT(load_error(dir.write("cut.glb", glb.substr(0, 19))),
              HasSubstr("the header is cut short"));
  // A GLB buffer of 0 bytes made tinygltf throw std::out_of_range.
  const auto empty = dir.write(
      "empty.glb",
      make_glb(replace(kGlbJson, R"("byteLength": 92)", R"("byteLength": 0)"), glb_bin()));
  EXPECT_THAT(load_error(empty), HasSubstr(empty.string() + ": not a readable glTF 2.0 file"));
}

// tinygltf converts "extras" recursively: deep nesting overflowed the stack.
TEST(LoadGltfHostile, DeepJsonIsRefused) {
  TempDir dir;
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  const auto path = dir.write(
      "deep.glb", make_glb(replace(kGlbJson, R"("asset": {"version": "2.0"})",
                                   R"("asset": {"version": "2.0", "extras": )" + deep + "}"),
                           glb_bin()));
  EXPECT_THAT(load_error(path),
              HasSubstr(path.string() + ": JSON nesting is deeper than 64 levels"));
  // A NUL byte in the JSON ends no token early (it once looped the estimate forever).
  const auto nul = dir.write("nul.gltf", std::string("{\"asset\": {\"version\": \0\"2.0\"}}", 27));
  EXPECT_THAT(load_error(nul), HasSubstr(nul.string() + ": not a readable glTF 2.0 file"));
  // Ordinary extras are fine.
  const auto extras = dir.write(
      "extras.glb",
      make_glb(replace(kGlbJson, R"("asset": {"version": "2.0"})",
                       R"("asset": {"version": "2.0", "extras": {"a": [[1], {"b": 2}]}})"),
               glb_bin()));
  EXPECT_EQ(load_scene(extras).meshes.size(), 3u);
  // Thousands of empty materials cost tinygltf ~2 KiB each: estimated and refused up front.
  std::string materials = "{}";
  for (int i = 0; i < 100000; ++i) materials += ",{}";
  const auto many = dir.write(
      "materials.glb",
      make_glb(replace(kGlbJson, R"("scenes")", "\"materials\": [" + materials + "], \"scenes\""),
               glb_bin()));
  EXPECT_THAT(load_error(many), HasSubstr("parsing the glTF JSON needs"));
}

}  // namespace
}  // namespace shadow::scenes
