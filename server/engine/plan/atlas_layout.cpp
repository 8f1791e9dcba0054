#include "engine/plan/atlas_layout.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

#include "engine/light/light_space.hpp"
#include "engine/plan/filter.hpp"
#include "engine/plan/uv_layouts.hpp"

namespace shadow {

namespace {

// The smallest power of two >= x (>= 1).
uint32_t power_of_two_at_least(double x) {
  uint32_t p = 1;
  // 1e-9: a size that is a power of two up to rounding stays that power.
  while (p < kMaxAtlasTile * 2u && double(p) < x * (1 - 1e-9)) p *= 2;
  return p;
}

// The smallest tile a density gives: over four gutters (validate()'s rule for a fixed tile).
uint32_t min_density_tile(uint32_t gutter) {
  uint32_t t = kMinAtlasTile;
  while (t <= 4 * gutter) t *= 2;
  return t;
}

Bounds mesh_bounds(const Mesh& m) {
  Bounds b;
  for (size_t i = 0; i + 2 < m.positions.size(); i += 3)
    b.extend(glm::dvec3(m.positions[i], m.positions[i + 1], m.positions[i + 2]));
  return b;
}

// Sum of the triangles' areas: in object space (positions) and in UV space.
struct MeshAreas {
  double world = 0, uv = 0;
};
MeshAreas mesh_areas(const Mesh& m) {
  MeshAreas a;
  const bool uv = !m.uvs.empty();
  for (size_t i = 0; i + 2 < m.indices.size(); i += 3) {
    const uint32_t k[3] = {m.indices[i], m.indices[i + 1], m.indices[i + 2]};
    if (3 * (size_t{std::max({k[0], k[1], k[2]})} + 1) > m.positions.size()) continue;
    glm::dvec3 p[3];
    for (int c = 0; c < 3; ++c)
      p[c] = glm::dvec3(m.positions[3 * size_t{k[c]}], m.positions[3 * size_t{k[c]} + 1],
                        m.positions[3 * size_t{k[c]} + 2]);
    a.world += 0.5 * glm::length(glm::cross(p[1] - p[0], p[2] - p[0]));
    if (uv && 2 * (size_t{std::max({k[0], k[1], k[2]})} + 1) <= m.uvs.size()) {
      const float* q[3] = {&m.uvs[2 * size_t{k[0]}], &m.uvs[2 * size_t{k[1]}],
                           &m.uvs[2 * size_t{k[2]}]};
      a.uv += 0.5 * std::abs((double(q[1][0]) - q[0][0]) * (double(q[2][1]) - q[0][1]) -
                             (double(q[1][1]) - q[0][1]) * (double(q[2][0]) - q[0][0]));
    }
  }
  return a;
}

// Interleaved bits of a Z-order index: its even bits (x) or odd bits (y).
uint32_t even_bits(uint64_t z) {
  uint32_t v = 0;
  for (int b = 0; b < 32; ++b) v |= uint32_t((z >> (2 * b)) & 1u) << b;
  return v;
}

}  // namespace

std::vector<double> world_per_uv(const RenderRequest& r) {
  const Scene& scene = *r.scene;
  // The meshes the server lays out (before or after it has): their UVs are not the client's.
  std::vector<bool> generated(scene.meshes.size(), false);
  for (uint32_t m : meshes_to_lay_out(scene, r.atlas.generate_uvs)) generated[m] = true;
  for (uint32_t m : r.generated_layouts)
    if (m < generated.size()) generated[m] = true;
  std::vector<std::optional<MeshAreas>> areas(scene.meshes.size());
  std::vector<double> out(scene.instances.size(), 0.0);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const Instance& inst = scene.instances[i];
    if (!inst.receives_shadows || inst.mesh >= scene.meshes.size()) continue;
    if (!areas[inst.mesh]) areas[inst.mesh] = mesh_areas(scene.meshes[inst.mesh]);
    const MeshAreas& a = *areas[inst.mesh];
    const double uv =
        generated[inst.mesh] ? kGeneratedUvCoverage : (a.uv > 0 ? std::min(a.uv, 1.0) : 1.0);
    const double det = std::abs(glm::determinant(glm::dmat3(glm::dmat4(inst.transform))));
    out[i] = std::sqrt(a.world * std::cbrt(det * det) / uv);
  }
  return out;
}

std::vector<double> map_texel_world_size(const RenderRequest& r) {
  const Scene& scene = *r.scene;
  std::vector<Bounds> meshes(scene.meshes.size());
  std::vector<InstanceBounds> bounds;
  for (const Instance& inst : scene.instances) {
    if (inst.mesh < meshes.size() && meshes[inst.mesh].empty())
      meshes[inst.mesh] = mesh_bounds(scene.meshes[inst.mesh]);
    bounds.push_back({inst.mesh < meshes.size()
                          ? transform_bounds(meshes[inst.mesh], glm::dmat4(inst.transform))
                          : Bounds{},
                      inst.casts_shadows, inst.receives_shadows});
  }
  const double size = double(r.shadow_map.size);
  std::vector<double> out(scene.instances.size(), INFINITY);
  for (const Light& light : r.lights) {
    if (light.type == LightType::kDirectional) {
      // Orthographic: one texel size everywhere, from the rows of x and y of the fitted map.
      const glm::dmat4 m = fit_uniform_light(light, r.camera, bounds, MapFit::kScene).world_to_ndc;
      const double gu = glm::length(glm::dvec3(m[0][0], m[1][0], m[2][0]));
      const double gv = glm::length(glm::dvec3(m[0][1], m[1][1], m[2][1]));
      const double texel = 1.0 / (std::sqrt(gu * gv) * size);
      if (std::isfinite(texel) && texel > 0)
        for (size_t i = 0; i < out.size(); ++i) out[i] = std::min(out[i], texel);
      continue;
    }
    // A spot light's perspective spans its full cone; a cube face 90 degrees.
    const double half_angle =
        light.type == LightType::kSpot
            ? 0.5 * glm::radians(std::clamp(double(light.cone_angle_deg), 1e-3, 179.0))
            : 0.25 * 3.14159265358979323846;
    const glm::dvec3 at(light.position);
    for (size_t i = 0; i < out.size(); ++i) {
      const Bounds& b = bounds[i].world;
      if (!bounds[i].receives || b.empty()) continue;
      const glm::dvec3 nearest = glm::clamp(at, b.lo, b.hi);
      double d = glm::length(nearest - at);
      if (b.contains(at)) {  // a room around the light: its walls are the box's faces
        d = INFINITY;
        for (int k = 0; k < 3; ++k) d = std::min({d, at[k] - b.lo[k], b.hi[k] - at[k]});
      }
      // A box the light touches: taken at a thousandth of its size (the tile's cap holds anyway).
      d = std::max(d, 1e-3 * glm::length(b.hi - b.lo));
      const double texel = 2.0 * d * std::tan(half_angle) / size;
      if (std::isfinite(texel) && texel > 0) out[i] = std::min(out[i], texel);
    }
  }
  for (size_t i = 0; i < out.size(); ++i)
    if (!scene.instances[i].receives_shadows || !std::isfinite(out[i])) out[i] = 0.0;
  return out;
}

AtlasLayout pack_atlas(const std::vector<uint32_t>& sizes) {
  AtlasLayout layout;
  std::vector<uint32_t> order;
  for (uint32_t i = 0; i < sizes.size(); ++i)
    if (sizes[i] > 0) order.push_back(i);
  layout.size.receivers = order.size();
  if (order.empty()) return layout;
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return sizes[a] > sizes[b]; });
  const uint64_t block = sizes[order.front()];
  layout.largest = uint32_t(block);
  layout.cell = sizes[order.back()];
  uint64_t area = 0;
  for (uint32_t i : order) area += uint64_t{sizes[i]} * sizes[i];
  const uint64_t blocks = (area + block * block - 1) / (block * block);
  uint64_t columns = uint64_t(std::ceil(std::sqrt(double(blocks))));
  while (columns * columns < blocks) ++columns;  // sqrt's rounding
  // Largest first: every tile starts where the Z-order curve has filled a multiple of its own
  // area, so it is an aligned square of the curve, apart from every other.
  uint64_t offset = 0;
  layout.tiles.resize(order.size());
  std::vector<AtlasTile> placed(sizes.size());
  for (uint32_t i : order) {
    const uint64_t s = sizes[i], b = offset / (block * block), z = offset % (block * block);
    AtlasTile& t = placed[i];
    t.instance = i;
    t.x = uint32_t(b % columns * block + even_bits(z));
    t.y = uint32_t(b / columns * block + even_bits(z >> 1));
    t.size = uint32_t(s);
    offset += s * s;
    layout.size.width = std::max<uint64_t>(layout.size.width, t.x + s);
    layout.size.height = std::max<uint64_t>(layout.size.height, t.y + s);
  }
  size_t k = 0;
  for (uint32_t i = 0; i < sizes.size(); ++i)
    if (sizes[i] > 0) layout.tiles[k++] = placed[i];
  return layout;
}

std::vector<glm::uvec4> tile_cells(const AtlasLayout& layout) {
  if (layout.cell == 0) return {};
  const uint64_t w = layout.size.width / layout.cell, h = layout.size.height / layout.cell;
  std::vector<glm::uvec4> cells(w * h, glm::uvec4(0));
  for (const AtlasTile& t : layout.tiles)
    for (uint32_t y = t.y / layout.cell; y < (t.y + t.size) / layout.cell; ++y)
      for (uint32_t x = t.x / layout.cell; x < (t.x + t.size) / layout.cell; ++x)
        cells[y * w + x] = glm::uvec4(t.x, t.y, t.size, 1u);
  return cells;
}

namespace {

// Each tile's texel in world units: its instance's UV unit over its texels.
AtlasLayout with_texel_sizes(AtlasLayout layout, const std::vector<double>& span) {
  for (AtlasTile& t : layout.tiles) t.texel_world_size = span[t.instance] / t.size;
  return layout;
}

// The request's tile for every receiving instance (AtlasSettings::tile), 0 for the others.
std::vector<uint32_t> fixed_tile_sizes(const RenderRequest& r) {
  std::vector<uint32_t> sizes(r.scene->instances.size(), 0);
  for (size_t i = 0; i < sizes.size(); ++i)
    if (r.scene->instances[i].receives_shadows) sizes[i] = r.atlas.tile;
  return sizes;
}

}  // namespace

AtlasLayout atlas_layout(const RenderRequest& r) {
  const Scene& scene = *r.scene;
  const AtlasSettings& a = r.atlas;
  const std::vector<double> span = world_per_uv(r);
  if (a.tile != 0) return with_texel_sizes(pack_atlas(fixed_tile_sizes(r)), span);
  std::vector<uint32_t> sizes(scene.instances.size(), 0);
  const std::vector<double> texel = a.texel_world_size > 0
                                        ? std::vector<double>(sizes.size(), a.texel_world_size)
                                        : map_texel_world_size(r);
  const uint32_t lo = min_density_tile(a.gutter);
  for (uint32_t halved = 0;; ++halved) {
    bool all_smallest = true;
    for (size_t i = 0; i < sizes.size(); ++i) {
      if (!scene.instances[i].receives_shadows) continue;
      const double want = texel[i] > 0 ? std::ldexp(span[i] / texel[i], -int(halved)) : 0.0;
      sizes[i] = std::clamp(power_of_two_at_least(want), lo, kMaxAtlasTile);
      all_smallest = all_smallest && sizes[i] == lo;
    }
    // The request's density is kept whatever it costs (validate() refuses it past the limits);
    // the default's keeps to its budget.
    AtlasLayout layout = pack_atlas(sizes);
    if (a.texel_world_size > 0 || all_smallest ||
        layout.size.width * layout.size.height <= kDefaultAtlasTexels) {
      layout.halved = halved;
      return with_texel_sizes(std::move(layout), span);
    }
  }
}

AtlasSize atlas_size(const RenderRequest& request) {
  // A fixed tile needs no walk over the meshes' areas: those only say what its texels span.
  if (request.atlas.tile != 0) return pack_atlas(fixed_tile_sizes(request)).size;
  return atlas_layout(request).size;
}

bool wants_atlas(const RenderRequest& request) {
  return std::any_of(request.products.begin(), request.products.end(), [](Product p) {
    return p == Product::kShadowAtlas || p == Product::kShadowAtlasMips ||
           p == Product::kShadowAtlasSat;
  });
}

bool uses_atlas(const RenderRequest& request) {
  return wants_atlas(request) || is_atlas_filter(request.filter.kind);
}

UvCharts uv_charts(const Mesh& mesh) {
  const size_t triangles = mesh.triangle_count(), vertices = mesh.vertex_count();
  constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  // Each vertex's point: the first vertex with its position and UV bits (split vertices that
  // agree in both are one point), found in an open-addressing table of vertex ids (a mesh
  // loaded from OBJ has a vertex per corner: millions of keys, and a node per key was a third
  // of an atlas request's host time).
  using Key = std::array<uint32_t, 5>;
  const auto key_of = [&](uint32_t v) {
    // + 0.0f: -0 and 0 are one point. No UVs: joined by position alone.
    const bool uv = mesh.uvs.size() >= 2 * (size_t{v} + 1);
    const float corner[5] = {
        mesh.positions[3 * size_t{v}] + 0.0f, mesh.positions[3 * size_t{v} + 1] + 0.0f,
        mesh.positions[3 * size_t{v} + 2] + 0.0f, uv ? mesh.uvs[2 * size_t{v}] + 0.0f : 0.0f,
        uv ? mesh.uvs[2 * size_t{v} + 1] + 0.0f : 0.0f};
    Key key;
    std::memcpy(key.data(), corner, sizeof corner);
    return key;
  };
  // Seeded once per process: a client cannot choose positions whose keys all land on one slot.
  // The points found do not depend on it (each is the first vertex with its key).
  static const uint64_t seed = (uint64_t{std::random_device{}()} << 32) ^ std::random_device{}();
  size_t slots = 16;
  while (slots < 2 * vertices) slots *= 2;  // at most half full
  std::vector<uint32_t> slot(slots, kNone);
  std::vector<uint32_t> point(vertices);
  for (uint32_t v = 0; v < vertices; ++v) {
    const Key key = key_of(v);
    uint64_t h = seed;
    for (uint32_t word : key) {
      h = (h ^ word) * 0xff51afd7ed558ccdull;
      h ^= h >> 33;
    }
    for (size_t i = h & (slots - 1);; i = (i + 1) & (slots - 1)) {
      if (slot[i] == kNone) {
        slot[i] = point[v] = v;
        break;
      }
      if (key_of(slot[i]) == key) {
        point[v] = slot[i];
        break;
      }
    }
  }
  // Triangles joined through the points their corners share (union-find).
  std::vector<uint32_t> parent(triangles);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto root = [&](uint32_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];
    return t;
  };
  std::vector<uint32_t> first_triangle(vertices, kNone);  // per point
  for (uint32_t t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k) {
      uint32_t& first = first_triangle[point[mesh.indices[3 * size_t{t} + k]]];
      if (first == kNone)
        first = t;
      else
        parent[root(t)] = root(first);
    }
  // Charts numbered in order of their first triangle.
  UvCharts out;
  out.of_triangle.resize(triangles);
  std::vector<uint32_t> label(triangles, kNone);  // per root
  for (uint32_t t = 0; t < triangles; ++t) {
    uint32_t& l = label[root(t)];
    if (l == kNone) l = out.count++;
    out.of_triangle[t] = l;
  }
  return out;
}

bool uvs_degenerate(const Mesh& mesh) {
  if (mesh.uvs.empty() || mesh.indices.empty()) return false;  // laid out by the server; none
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
    const float* a = &mesh.uvs[2 * size_t{mesh.indices[i]}];
    const float* b = &mesh.uvs[2 * size_t{mesh.indices[i + 1]}];
    const float* c = &mesh.uvs[2 * size_t{mesh.indices[i + 2]}];
    const double area = (double(b[0]) - a[0]) * (double(c[1]) - a[1]) -
                        (double(b[1]) - a[1]) * (double(c[0]) - a[0]);
    if (area != 0.0) return false;
  }
  return true;
}

}  // namespace shadow
