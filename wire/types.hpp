// The vocabulary request and result types that the engine computes with and that the server and
// clients convert proto <-> in one place (wire/convert.hpp). Nothing here knows about gRPC or
// protobuf, so the engine links only this. Field names follow the proto so that error paths
// ("scene.meshes[3].indices[17]") read the same on both sides.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace shadow {

struct Mesh {
  std::vector<float> positions;   // xyz per vertex
  std::vector<uint32_t> indices;  // three per triangle
  std::vector<float> normals;     // optional, xyz per vertex
  std::vector<float> uvs;         // optional, uv per vertex

  size_t vertex_count() const { return positions.size() / 3; }
  size_t triangle_count() const { return indices.size() / 3; }
};

struct Instance {
  uint32_t mesh = 0;
  glm::mat4 transform{1.0f};  // object -> world, column-major (GLM)
  bool casts_shadows = true;
  bool receives_shadows = true;
  // Ping-pong blur (Filter::kBlur): receivers of class 0..3 read the blurred class channel
  // instead of the depth test; kNoClass = ordinary depth test.
  static constexpr uint32_t kNoClass = 0xffffffffu;
  uint32_t receiver_class = kNoClass;
};

struct Scene {
  std::vector<Mesh> meshes;
  std::vector<Instance> instances;
};

enum class LightType { kDirectional, kSpot, kPoint };

struct Light {
  LightType type = LightType::kDirectional;
  glm::vec3 position{0.0f};                // spot, point
  glm::vec3 direction{0.0f, -1.0f, 0.0f};  // directional: direction of travel; spot: axis
  float cone_angle_deg = 45.0f;            // spot: full outer cone angle
  float size = 0.0f;  // directional: angular diameter (degrees); spot/point: radius
};

// Right-handed, GLM lookAt/perspective. Pixel (i, j) has its centre at ((i+0.5)/W, (j+0.5)/H),
// row 0 at the top.
struct Camera {
  glm::vec3 eye{0.0f, 0.0f, 5.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fov_deg = 60.0f;
  uint32_t width = 1280;
  uint32_t height = 720;
  float near = 0.1f;
  float far = 1000.0f;
};

// kCube: six 90-degree faces around a point light (only the faces that can hold casters of the
// visible receivers are rendered); the default for point lights.
// kPsmCube: PSM's cube-map approach (Kozlov 14.2.2): cube faces around the light in the camera's
// post-perspective space, on the sides of the unit cube that face away from the light.
// kLispsm: Light Space Perspective Shadow Maps (Wimmer et al. 2004, engine/light/lispsm_fit.hpp),
// directional lights only.
// kAuto: the server picks one of the others from the light, camera and receivers
// (engine/choose/auto_pick.hpp) and reports which and why.
// kDefault: per light, kCube for a point light and kUniform otherwise (a request's lights share
// one ShadowMapSettings, so the default is resolved light by light: engine/plan/light_request.hpp).
enum class Technique { kUniform, kPsm, kCube, kPsmCube, kLispsm, kAuto, kDefault, kVirtual };

// Perspective Shadow Maps (engine/light/psm_fit.hpp). Casters behind the camera are kept either by
// the light's inverse projection (Kozlov 14.1.1, near = -a, far = a) or by sliding the virtual
// camera back until none is behind it (the paper, section 4.2).
enum class PsmCasters { kInverseProjection, kSlideBack };
// kReceivers: the virtual camera's near/far planes hug the visible receivers' bounds (Kozlov
// 14.1.2); kCamera: the request camera's near/far as given; kVirtualSlideBack: as kReceivers,
// then the virtual camera slides back by `virtual_slide` while its near plane grows by as much
// and its field of view narrows, so the near-plane quad stays the same (Kozlov 14.1.2, Fig 14-6).
enum class PsmNear { kReceivers, kCamera, kVirtualSlideBack };

struct PsmSettings {
  PsmCasters casters = PsmCasters::kInverseProjection;
  PsmNear near = PsmNear::kReceivers;
  // kVirtualSlideBack only: the slide in world units; 0 = the default, the pushed near distance
  // itself (near doubles: Kozlov's example, twice the post-perspective z resolution near it).
  double virtual_slide = 0;

  bool operator==(const PsmSettings&) const = default;
};

// LiSPSM's warp: the distance n (world units) from the warp frustum's centre to the visible
// receivers' nearest edge across the light. 0 = Wimmer's n_opt = (z_n + sqrt(z_n z_f)) /
// sin(gamma).
struct LispsmSettings {
  double n = 0;

  bool operator==(const LispsmSettings&) const = default;
};

// What a uniform map (directional or spot light) is fitted to. kView: the receivers the camera
// sees, so texels go where the camera looks and the map changes whenever the camera moves.
// kScene: every receiver in the scene, whatever the camera sees, so a sequence whose light and
// casters stand still reuses the map while the camera moves (coarser texels in a large scene).
enum class MapFit { kView, kScene };

struct ShadowMapSettings {
  uint32_t size = 2048;  // square, 256..8192
  Technique technique = Technique::kDefault;
  // Lit when z_receiver - bias <= z_map, bias = bias_constant + bias_slope * (|dz/du| + |dz/dv|)
  // of the receiver plane per texel. The constant covers float rounding; the slope is half
  // again the planar worst case of nearest-texel lookup (0.5: the texel centre is at most half a
  // texel away on each axis), for curved receivers and warped maps' non-linear depth. Below 0.5
  // the standard views show acne; larger slopes leak light on receivers the light grazes
  // (docs/benchmarks.md, "The slope bias's default").
  float bias_constant = 2e-5f;  // NDC depth units
  float bias_slope = 0.75f;
  PsmSettings psm{};        // read only when technique is kPsm or kPsmCube
  LispsmSettings lispsm{};  // read only when technique is kLispsm
  // World-space caster bias (Kozlov 14.3.1), in the light's transform only: every caster vertex
  // P moves away from the light by bias_world_constant + bias_world_texel * texel(P) (world
  // units), texel(P) = the world size of one map texel at P across the light. 0 = off.
  float bias_world_constant = 0.0f;  // world units, >= 0
  float bias_world_texel = 0.0f;     // map texels, >= 0
  MapFit fit = MapFit::kView;        // uniform maps only
  // TECHNIQUE_VIRTUAL only (issue 53): the level a pixel reads is the one whose texel matches its
  // footprint times 2^virtual_lod_bias; the pages are drawn into a pool of virtual_pool_pages
  // 128^2 float pages shared by the request's lights. Where the marked pages exceed the pool the
  // farthest pixels read a coarser level (counted in the reply), unless refused instead.
  // -0.5: measured on the standard sun views (docs/benchmarks.md, "Virtual shadow maps").
  float virtual_lod_bias = -0.5f;
  uint32_t virtual_pool_pages = 1024;
  bool virtual_refuse_coarsening = false;

  bool operator==(const ShadowMapSettings&) const = default;
};

// How VISIBILITY filters the shadow test. Each kind reads only its own settings.
// kAtlasSat, kAtlasMip: PCSS's blocker search (its settings in Filter::pcss; filter_samples
// unused), then the prefiltered hard shadow atlas over the penumbra.
enum class FilterKind {
  kHard,
  kPcf2x2,
  kPoisson,
  kPcss,
  kBlur,
  kCsm,
  kPcssCsm,
  kAtlasSat,
  kAtlasMip
};

struct PoissonSettings {
  uint32_t taps = 16;   // 1..64
  float radius = 2.0f;  // in shadow-map texels, > 0
  bool rotate = true;   // rotate the pattern per pixel (noise instead of banding)

  bool operator==(const PoissonSettings&) const = default;
};

// Percentage-closer soft shadows; the light's size is Light::size.
struct PcssSettings {
  uint32_t blocker_samples = 16;  // 1..64
  uint32_t filter_samples = 32;   // 1..64
  bool rotate = true;

  bool operator==(const PcssSettings&) const = default;
};

// Ping-pong Gaussian blur of per-texel receiver-class channels (Kozlov 14.4.2).
struct BlurSettings {
  uint32_t radius = 4;  // in shadow-map texels, 1..32; sigma = radius / 2
  uint32_t passes = 2;  // 1..16 separable (horizontal + vertical) passes

  bool operator==(const BlurSettings&) const = default;
};

// Convolution shadow maps (kernels/csm.cl): the map's linear depth in a Fourier basis of M terms,
// prefiltered with mips. kCsm filters the test over a fixed window; kPcssCsm takes the blocker
// average from the basis (no blocker search) and filters over PCSS's penumbra. The ringing
// controls' defaults were measured against the Embree area-light oracle (docs/benchmarks.md).
enum class CsmStorage { kFloat32, kFloat16 };
enum class CsmLookup { kMips, kSat };  // trilinear from mips, or a box from summed-area tables
struct CsmSettings {
  uint32_t terms = 8;  // M, 1..16
  CsmStorage storage = CsmStorage::kFloat32;
  float window = 4.0f;  // kCsm: the filter window in map texels, >= 1
  // Ringing: coefficient k times exp(-damping (k / M)^2), 0..100 (0 = none); the receiver's
  // linear [0, 1] depth moved towards the light by depth_offset / M (the series' transition
  // narrows as 1/M), 0..16; visibility clamp(1/2 + scale (v - 1/2), 0, 1), 1..1000 (1 = none).
  float damping = 2.0f;
  float depth_offset = 0.25f;
  float scale = 4.0f;
  CsmLookup lookup = CsmLookup::kMips;

  bool operator==(const CsmSettings&) const = default;
};

struct Filter {
  FilterKind kind = FilterKind::kHard;
  PoissonSettings poisson;
  PcssSettings pcss;
  BlurSettings blur;
  CsmSettings csm;  // kCsm and kPcssCsm

  bool operator==(const Filter&) const = default;
};

// kTexelDensity: per camera pixel, the size in pixels of one shadow-map texel's footprint.
// *Mips: one texture per level ("shadowmap_mip0" = the source .. the 1x1 level).
// *Sat: the summed-area table as float64 (PixelFormat::kFloat64).
// kCsmBasis: the CSM basis of the map (needs filter kCsm or kPcssCsm, whose settings it takes):
// channels sin1..sinM, cos1..cosM and, for kPcssCsm, zsin1..zsinM, zcos1..zcosM, z.
// kBlockerDepth: per camera pixel, the CSM blocker average in the basis' linear [0, 1] depth.
// kShadowAtlas: the filtered shadow test at every receiving surface point, in UV space
// (AtlasSettings): 1 lit, 0 shadowed, NaN outside the charts and their gutters.
// kShadowAtlasMips: its mip chain (empty texels left out of each mean).
// kShadowAtlasSat: the SAT of two channels, the atlas with empty texels as 0 and the coverage
// (1 where a texel holds a point): a box's mean visibility is the first sum over the second.
// kAtlasUvs (with the atlas; not per light): for each receiving mesh sent without UVs, the
// layout the server generated, as the UV (2 channels) of each triangle corner: 3 texels wide
// (corners), a row per triangle in the mesh's order. Named "atlas_uvs_mesh<m>".
enum class Product {
  kShadowMap,
  kVisibility,
  kPosition,
  kTexelDensity,
  kShadowMapMips,
  kShadowMapSat,
  kVisibilityMips,
  kVisibilitySat,
  kCsmBasis,
  kBlockerDepth,
  kShadowAtlas,
  kShadowAtlasMips,
  kShadowAtlasSat,
  kAtlasUvs,
  kVirtualPages,  // TECHNIQUE_VIRTUAL's pool, page tables, windows and pixels' levels (issue 53)
};

// PRODUCT_SHADOW_ATLAS: each receiving instance's shadow baked in its own UV space (the mesh's
// UVs, in [0, 1], without overlaps), one square tile per instance in one texture.
// Tiles are sized per instance from the world (engine/plan/atlas_layout.hpp): texel_world_size, or
// by default the shadow map's texel footprint on the receiver; or all `tile` texels.
struct AtlasSettings {
  uint32_t tile = 0;  // texels across every instance's tile, 16..4096; 0 = sized per instance
  // World units per atlas texel on every receiver (finite, > 0; not with `tile`); 0 = the map's
  // texel footprint on each receiver, within the default budget (kDefaultAtlasTexels).
  double texel_world_size = 0;
  uint32_t gutter = 2;  // texels filled around every chart (dilated visibility), 0..16
  // Every receiving mesh laid out by the engine (engine/plan/uv_layouts), its own UVs unused.
  bool generate_uvs = false;

  bool operator==(const AtlasSettings&) const = default;
};

// Where an instance's tile lies in a shadow atlas: texel (x + u * size, y + v * size) holds the
// point at UV (u, v) of its mesh, v = 0 in the tile's top row.
struct AtlasTile {
  uint32_t instance = 0;
  uint32_t x = 0, y = 0, size = 0;
  double texel_world_size = 0;  // at most, on the instance's surface (AtlasTile in shadow.proto)
};

// kFloat64 only for summed-area tables (exact sums); its values live in Texture::data64.
// kFloat16: IEEE binary16, rounded to nearest even on the device (RenderRequest::output_format);
// its bits live in Texture::data16.
enum class PixelFormat { kFloat32, kFloat64, kFloat16 };

// A quality goal (RenderRequest::quality; the proto's Quality says what the engine does): the
// engine picks the technique and the map size, ignoring shadow_map.size (the wire refuses a size
// beside a goal).
struct Quality {
  enum class Goal { kNone, kMaxError, kMaxDeviceMs };
  Goal goal = Goal::kNone;
  double value = 0;  // kMaxError: the share in (0, 1]; kMaxDeviceMs: ms > 0
};

// One technique and map size a goal weighed, with its predictions.
struct QualityCandidate {
  Technique technique = Technique::kUniform;
  uint32_t size = 0;
  double predicted_error = 0;      // share of the camera's seen pixels misclassified, at the
                                   // calibration's 70th percentile (its error margin)
  double predicted_device_ms = 0;  // the calibration's typical rates times its margin
  double typical_device_ms = 0;    // at the typical rates alone (max_error ranks by it)
  // Its times count its maps' raster load (or it draws none: the probe's map); else that load was
  // not needed to pick, and its times are a lower bound.
  bool raster_load_priced = false;
};

// What a goal picked.
struct QualityPick {
  Technique technique = Technique::kUniform;
  uint32_t size = 0;
  double predicted_error = 0;      // share of the camera's seen pixels misclassified
  double predicted_device_ms = 0;  // the calibration's typical rates times its margin
  bool goal_met = false;
  std::string reason;  // the pick, the boundary shares and every candidate, as prose
  // Per light: the probe's share of the seen pixels on a shadow edge a map can misplace, which
  // the predicted error scales with (engine/choose/quality_pick.hpp, engine/passes/boundary.hpp).
  std::vector<double> boundary_share;
  // Every candidate the server would admit, the pick among them (engine/choose/quality_pick.hpp).
  std::vector<QualityCandidate> candidates;
};

// How far a render is (RenderRequest.progress on the wire): the pass recorded last, its device
// ms so far and its admitted estimate (0: none, as for a quality goal); a sequence's frames done
// of all.
struct RenderProgress {
  std::string phase;
  double device_ms = 0;
  double estimate_ms = 0;
  uint32_t frames_done = 0;
  uint32_t frames = 0;
};

struct RenderRequest {
  std::shared_ptr<const Scene> scene;
  Camera camera;
  // Each light gets its own maps and light-space products; the camera view is shared. With more
  // than one light, texture names end in "_light<i>" and pass names start with "light<i>."
  // (Texture::light says which). The vocabulary default is one light, straight down.
  std::vector<Light> lights{Light{}};
  ShadowMapSettings shadow_map;
  std::vector<Product> products;
  Filter filter;
  AtlasSettings atlas;  // read only for kShadowAtlas
  // The float products' format on the wire: kFloat32, or kFloat16 (half the bytes, rounded to
  // nearest even on the device). Summed-area tables stay kFloat64.
  PixelFormat output_format = PixelFormat::kFloat32;
  // The scene is one the server holds (an uploaded scene, named by id) and shares between
  // requests: the engine keeps its device copy for the next request that names it.
  bool scene_held = false;
  // Set by the engine: the meshes whose UVs it generated (engine/plan/uv_layouts), for kAtlasUvs.
  std::vector<uint32_t> generated_layouts;
  Quality quality;
};

// A sequence of frames over one scene (Engine::render_sequence). Frame i renders `base` with the
// frame's camera and lights where given and the listed instances moved to their transforms
// (object -> world, replacing the scene's); everything else as in `base`.
struct InstanceTransform {
  uint32_t instance = 0;
  glm::mat4 transform{1.0f};
};
struct Frame {
  std::optional<Camera> camera;
  std::optional<std::vector<Light>> lights;
  std::vector<InstanceTransform> transforms;
};
struct SequenceRequest {
  RenderRequest base;
  std::vector<Frame> frames;
};

// How a reply's texture chunks travel (RenderRequest.chunk_compression): raw, or zstd frames.
enum class ChunkCompression { kNone, kZstd };

// One face of a cube texture: its name ("+x", "-x", "+y", "-y", "+z", "-z") and matrices.
struct TextureFace {
  std::string name;
  glm::mat4 world_to_ndc{1.0f};
  glm::mat4 world_to_camera{1.0f};
};

// A texture and the matrix that places it: world -> NDC where, after division by w, x and y run
// 0..1 across the image from its top-left corner and z is the stored depth (column-vector, GLM).
struct Texture {
  std::string name;  // "shadowmap", "visibility", "position", "shadowmap_mip3", ...
  Product kind = Product::kShadowMap;
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t channels = 1;
  uint32_t faces = 1;  // cube maps: the rendered faces, = cube_faces.size() (0..6)
  PixelFormat format = PixelFormat::kFloat32;
  glm::mat4 world_to_ndc{1.0f};
  glm::mat4 world_to_camera{1.0f};  // the view of whoever looks through this texture
  std::vector<float> data;          // row-major, row 0 at the top, channels interleaved
  std::vector<double> data64;       // the same layout, for PixelFormat::kFloat64
  std::vector<uint16_t> data16;     // the same layout, for PixelFormat::kFloat16 (binary16 bits)
  // Cube maps: one entry per face in `data` order ([faces][height][width][channels]); each face
  // has its own matrices and world_to_ndc / world_to_camera above are unused (identity).
  std::vector<TextureFace> cube_faces;
  // Multi-channel textures (CSM bases): one name per channel; and how the stored depth relates to
  // the map's NDC z ("linear ..."), for textures that hold something else than that z.
  std::vector<std::string> channel_names;
  std::string depth_mapping;
  uint32_t csm_terms = 0;  // kCsmBasis: M, and how the server stored it
  CsmStorage csm_storage = CsmStorage::kFloat32;
  uint32_t light = 0;  // the index in RenderRequest::lights of the light it belongs to (0: none)
  std::vector<AtlasTile> atlas_tiles;  // kShadowAtlas: each receiving instance's tile
  uint32_t mesh = 0;                   // kAtlasUvs: the mesh laid out

  size_t byte_size() const {
    return data.size() * sizeof(float) + data64.size() * sizeof(double) +
           data16.size() * sizeof(uint16_t);
  }
  size_t value_bytes() const {
    return format == PixelFormat::kFloat64 ? 8 : format == PixelFormat::kFloat16 ? 2 : 4;
  }
  // The bytes held in the storage `format` uses (= byte_size() when the others are empty).
  size_t bytes_of_format() const {
    return format == PixelFormat::kFloat64   ? data64.size() * sizeof(double)
           : format == PixelFormat::kFloat16 ? data16.size() * sizeof(uint16_t)
                                             : data.size() * sizeof(float);
  }
  // The bytes of the storage `format` uses.
  const char* bytes() const {
    return format == PixelFormat::kFloat64   ? reinterpret_cast<const char*>(data64.data())
           : format == PixelFormat::kFloat16 ? reinterpret_cast<const char*>(data16.data())
                                             : reinterpret_cast<const char*>(data.data());
  }
  char* bytes() { return const_cast<char*>(static_cast<const Texture&>(*this).bytes()); }
};

struct PassTiming {
  std::string pass;  // e.g. "shadow_map.raster"
  double device_ms;  // from OpenCL profiling events
};

// One cube face as the fit decided it: rendered, or skipped and why.
struct CubeFaceReport {
  std::string name;  // "+x" .. "-z"
  bool rendered = false;
  std::string reason;  // e.g. "3 casters in front of 2 visible receivers", "no visible receiver"
};

// One candidate of TECHNIQUE_AUTO's pick (engine/choose/auto_pick.hpp).
struct AutoCandidateReport {
  Technique technique = Technique::kUniform;
  uint32_t map_size = 0;  // its maps' edge at the request's texels (PSM_CUBE: each face's)
  uint32_t maps = 1;
  double predicted_error = NAN;  // per shadow-boundary pixel; NaN without a calibration
  double mean_footprint = 0;     // px
  uint32_t trial_map_size = 0;   // where the trial drew it, else 0
  double trial_edge = NAN;       // mean |hard - bilinear 2x2| over the seen pixels, else NaN
};

// How the light's map was set up (the reply header reports it).
struct LightFitReport {
  std::string light_case;   // "uniform: directional", "directional from behind: inverted point"
  double virtual_near = 0;  // PSM: the virtual camera's near/far (world units)
  double virtual_far = 0;
  double slide_back = 0;  // PSM slide-back distance (world units), else 0
  double light_near = 0;  // PSM: light-view near/far in post-perspective space (-a, a for the
  double light_far = 0;   // inverse projection)
  std::vector<CubeFaceReport> cube_faces;  // cubes: all six, in +x -x +y -y +z -z order
  // kPsmCube: the smallest and largest texel of the rendered faces in post-perspective space,
  // as a fraction of the unit cube's edge (a face fully used by a size-N map: 1 / N).
  double cube_texel_min = 0;
  double cube_texel_max = 0;
  double lispsm_n = 0;  // kLispsm: the warp's n (world units), 0 = orthographic (no warp)
  // kAuto: the technique the server picked and why (predicted texel footprints); else unset.
  std::optional<Technique> auto_technique;
  std::string auto_reason;
  // kAuto: the edge of each map drawn, the request's size or each PSM_CUBE face's; else 0.
  uint32_t auto_map_size = 0;
  std::vector<AutoCandidateReport> auto_candidates;  // kAuto: in the order considered
  // The light's maps' raster load, summed over them (engine/plan/cost.hpp, RasterLoad).
  uint64_t raster_overlaps = 0;
  uint64_t raster_box_pixels = 0;
};

// A reply's virtual shadow map pages (TECHNIQUE_VIRTUAL, issue 53), summed over its lights:
// requested, the pages the view marked; resident, those in the pool; rendered, those drawn for
// this reply (not kept from an earlier frame); coarsened_pixels, the pixels that read a coarser
// level than their footprint asked for because the pool was full; pool_bytes, the pool's size.
struct VirtualPageCounts {
  uint64_t requested = 0, resident = 0, rendered = 0, coarsened_pixels = 0, pool_bytes = 0;
  bool operator==(const VirtualPageCounts&) const = default;
};

struct RenderResult {
  std::vector<Texture> textures;
  // One per light, in RenderRequest::lights order (empty light_case when no product needed the
  // light's map).
  std::vector<LightFitReport> light_fits;
  std::vector<std::string> passes;  // in the order they ran
  std::vector<PassTiming> timings;
  // Sequences: the frame's index, and the passes whose results were kept from an earlier frame
  // instead of run again (their inputs are bit-identical, so are their results); `rerun`: the
  // reusable passes that ran again because an input changed (the step cache's misses).
  uint32_t frame = 0;
  std::vector<std::string> reused, rerun;
  std::optional<QualityPick> quality;              // with RenderRequest::quality
  std::optional<VirtualPageCounts> virtual_pages;  // with TECHNIQUE_VIRTUAL
  // The server's side, not sent: the wait for a workspace and the render in it (wall time).
  double queue_ms = 0, run_ms = 0;
};

}  // namespace shadow
