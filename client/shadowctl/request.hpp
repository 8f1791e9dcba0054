// Builds shadowctl's RenderRequest. Precedence, lowest first: the built-in demo's suggested
// camera, light and shadow-map settings (each only where --request gives none; --light replaces
// the demo's sun whole), the --request JSON, the explicit flags.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "shadow/v1/shadow.pb.h"

namespace shadow::ctl {

// Flag values as typed; nullopt = not given.
struct RequestFlags {
  std::optional<std::string> request;   // path to a RenderRequest in canonical JSON
  std::optional<std::string> scene;     // OBJ / glTF / GLB path, or "builtin:demo"
  std::optional<std::string> scene_id;  // a scene the server holds (shadowctl upload)
  std::optional<std::string> eye, target, up, fov, size, near, far;
  std::vector<std::string> lights;  // --light, repeatable: replaces the request's lights
  std::optional<std::string> light_size;
  std::optional<std::string> map_size, technique, bias_constant, bias_slope;
  std::optional<std::string> psm_casters, psm_near;     // only with --technique psm
  std::optional<std::string> psm_virtual_slide;         // only with --psm-near virtual-slide-back
  std::optional<std::string> lispsm_n;                  // only with --technique lispsm
  std::optional<std::string> max_error, max_device_ms;  // a quality goal instead of technique/size
  std::optional<std::string> fit;                       // uniform maps: view | scene
  std::optional<std::string> bias_world_constant, bias_world_texel;
  // Only with --technique virtual.
  std::optional<std::string> virtual_lod_bias, virtual_pool_pages;
  bool virtual_refuse_coarsening = false;
  std::optional<std::string> products;
  // Filter kind, then per-kind settings; a setting of another kind is a FlagError.
  std::optional<std::string> filter, pcf_taps, pcf_radius, pcf_rotate;
  std::optional<std::string> pcss_blocker_samples, pcss_filter_samples, pcss_rotate;
  std::optional<std::string> blur_radius, blur_passes;
  // csm and pcss_csm (window: csm only).
  std::optional<std::string> csm_terms, csm_storage, csm_lookup, csm_window, csm_damping,
      csm_depth_offset, csm_scale;
  std::vector<std::string> receiver_classes;            // "INSTANCE:CLASS" each
  std::optional<std::string> chunk_compression;         // of the reply: none | zstd
  std::optional<std::string> pixel_format;              // of the float products: float32 | float16
  std::optional<std::string> atlas_tile, atlas_gutter;  // PRODUCT_SHADOW_ATLAS's layout
  std::optional<std::string> atlas_density;             // world units per atlas texel
  bool atlas_generate_uvs = false;
};

inline constexpr const char* kDemoScene = "builtin:demo";
inline constexpr uint32_t kDefaultWidth = 1280, kDefaultHeight = 720;

// Parses `message` (`what` it should be, for the error) from the file, in protobuf's canonical
// JSON mapping. Throws FlagError(flag).
void read_json(const std::filesystem::path& file, const std::string& flag,
               google::protobuf::Message& message, const std::string& what);
// Parses a RenderRequest from protobuf's canonical JSON mapping. Throws FlagError("--request").
v1::RenderRequest read_request_json(const std::filesystem::path& file);

// Replaces the request's scene with `scene` (a file or builtin:demo); the demo also fills in a
// camera, light and shadow-map settings where the request has none (its settings leave the
// technique unspecified, for the server to pick by the light). Throws FlagError("--scene").
void apply_scene(const std::string& scene, v1::RenderRequest& request);

// Overrides single fields with the flags that were given. Throws FlagError naming the flag.
void apply_flags(const RequestFlags& flags, v1::RenderRequest& request);

// Fills what nobody gave (shadowmap, visibility and position, or with --technique virtual, which
// has no dense map, visibility and position; 1280x720) and rejects requests that lack a scene, a
// camera eye/target or a light, naming the flag that would supply it (and --request, where it
// was given and lacks it too).
void complete(v1::RenderRequest& request, const RequestFlags& flags);

// Refuses flags that would change nothing in the finished request, naming what they need:
// --filter blur with no receiver class, --light-size without a filter that has a penumbra, the
// atlas settings without an atlas; and a filter with a penumbra where a light has no size.
void refuse_idle_flags(const RequestFlags& flags, const v1::RenderRequest& request);

// All of the above, in order: the request as the flags say, not yet held to the server's rules.
v1::RenderRequest build_request(const RequestFlags& flags);

// The server's own checks of every field (engine/plan/validate.hpp) on a built request, so that
// a value the server would refuse is a usage error before any connection: FlagError naming the
// flag that sets the field (--request for one no flag sets), with the server's message and its
// range. The server's byte limits are its own, and a request by scene_id leaves its checks to the
// server, which holds the scene.
void check_like_the_server(const v1::RenderRequest& request);

}  // namespace shadow::ctl
