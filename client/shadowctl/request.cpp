#include "shadowctl/request.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include <google/protobuf/util/json_util.h>

#include "engine/plan/validate.hpp"
#include "scenes/demo_scene.hpp"
#include "scenes/scene_loader.hpp"
#include "shadowctl/args.hpp"
#include "shadowctl/server_errors.hpp"
#include "wire/convert.hpp"
#include "wire/errors.hpp"
#include "wire/names.hpp"

namespace shadow::ctl {

void read_json(const std::filesystem::path& file, const std::string& flag,
               google::protobuf::Message& message, const std::string& what) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw FlagError(flag, file.string() + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  const auto status = google::protobuf::util::JsonStringToMessage(text.str(), &message);
  if (!status.ok())
    throw FlagError(flag, file.string() + ": not " + what +
                              " in canonical JSON: " + std::string(status.message()));
}

v1::RenderRequest read_request_json(const std::filesystem::path& file) {
  v1::RenderRequest request;
  read_json(file, "--request", request, "a RenderRequest");
  return request;
}

void apply_scene(const std::string& scene, v1::RenderRequest& request) {
  if (scene == kDemoScene) {
    const scenes::DemoSetup demo = scenes::demo_scene();
    *request.mutable_scene() = convert::to_proto(demo.scene);
    if (!request.has_camera()) *request.mutable_camera() = convert::to_proto(demo.camera);
    if (request.lights_size() == 0) *request.add_lights() = convert::to_proto(demo.light);
    if (!request.has_shadow_map()) {
      *request.mutable_shadow_map() = convert::to_proto(demo.shadow_map);
      // The demo suggests biases, not a technique, a size or a fit: the server picks the
      // light's default (e.g. cube for --light point:...), the technique's size (16384 for
      // virtual, else 2048) and the fit the products need (the scene's for an atlas).
      request.mutable_shadow_map()->clear_technique();
      request.mutable_shadow_map()->clear_size();
      request.mutable_shadow_map()->clear_fit();
    }
    return;
  }
  try {
    *request.mutable_scene() = convert::to_proto(scenes::load_scene(scene));
  } catch (const std::runtime_error& e) {
    throw FlagError("--scene", e.what());
  }
}

namespace {

// A settings flag must match the filter kind (from --filter, or from --request).
void require_kind(const v1::RenderRequest& r, FilterKind kind, const char* flag) {
  if (r.filter().kind_case() != names::kFilterKinds.to_proto(kind))
    throw FlagError(flag, "only with --filter " + std::string(names::kFilterKinds.name(kind)));
}

// CSM settings go to whichever of csm / pcss_csm the filter is.
void apply_csm_flags(const RequestFlags& f, v1::RenderRequest& request) {
  const std::pair<bool, const char*> given[] = {
      {f.csm_terms.has_value(), "--csm-terms"},
      {f.csm_storage.has_value(), "--csm-storage"},
      {f.csm_lookup.has_value(), "--csm-lookup"},
      {f.csm_window.has_value(), "--csm-window"},
      {f.csm_damping.has_value(), "--csm-damping"},
      {f.csm_depth_offset.has_value(), "--csm-depth-offset"},
      {f.csm_scale.has_value(), "--csm-scale"}};
  v1::Filter& filter = *request.mutable_filter();
  const bool pcss = filter.kind_case() == v1::Filter::kPcssCsm;
  for (const auto& [set, flag] : given) {
    if (!set) continue;
    if (std::string_view(flag) == "--csm-window")
      require_kind(request, FilterKind::kCsm, flag);
    else if (!pcss && filter.kind_case() != v1::Filter::kCsm)
      throw FlagError(flag, "only with --filter csm or pcss_csm");
  }
  if (std::none_of(std::begin(given), std::end(given), [](const auto& g) { return g.first; }))
    return;
  v1::CsmSettings& c = pcss ? *filter.mutable_pcss_csm() : *filter.mutable_csm();
  if (f.csm_terms) c.set_terms(parse_uint(*f.csm_terms, "--csm-terms"));
  if (f.csm_storage)
    c.set_storage(names::kCsmStorages.to_proto(parse_csm_storage(*f.csm_storage, "--csm-storage")));
  if (f.csm_lookup)
    c.set_lookup(names::kCsmLookups.to_proto(parse_csm_lookup(*f.csm_lookup, "--csm-lookup")));
  if (f.csm_window) c.set_window(parse_float(*f.csm_window, "--csm-window"));
  if (f.csm_damping) c.set_damping(parse_float(*f.csm_damping, "--csm-damping"));
  if (f.csm_depth_offset)
    c.set_depth_offset(parse_float(*f.csm_depth_offset, "--csm-depth-offset"));
  if (f.csm_scale) c.set_scale(parse_float(*f.csm_scale, "--csm-scale"));
}

void apply_filter_flags(const RequestFlags& f, v1::RenderRequest& request) {
  v1::Filter& filter = *request.mutable_filter();
  if (f.filter) convert::set_kind(filter, parse_filter(*f.filter, "--filter"));
  if (f.pcf_taps || f.pcf_radius || f.pcf_rotate) {
    for (const auto& [given, flag] : {std::pair{f.pcf_taps.has_value(), "--pcf-taps"},
                                      {f.pcf_radius.has_value(), "--pcf-radius"},
                                      {f.pcf_rotate.has_value(), "--pcf-rotate"}})
      if (given) require_kind(request, FilterKind::kPoisson, flag);
    v1::PoissonSettings& p = *filter.mutable_poisson();
    if (f.pcf_taps) p.set_taps(parse_uint(*f.pcf_taps, "--pcf-taps"));
    if (f.pcf_radius) p.set_radius(parse_float(*f.pcf_radius, "--pcf-radius"));
    if (f.pcf_rotate) p.set_rotate(parse_bool(*f.pcf_rotate, "--pcf-rotate"));
  }
  if (f.pcss_blocker_samples || f.pcss_filter_samples || f.pcss_rotate) {
    for (const auto& [given, flag] :
         {std::pair{f.pcss_blocker_samples.has_value(), "--pcss-blocker-samples"},
          {f.pcss_filter_samples.has_value(), "--pcss-filter-samples"},
          {f.pcss_rotate.has_value(), "--pcss-rotate"}})
      if (given) require_kind(request, FilterKind::kPcss, flag);
    v1::PcssSettings& p = *filter.mutable_pcss();
    if (f.pcss_blocker_samples)
      p.set_blocker_samples(parse_uint(*f.pcss_blocker_samples, "--pcss-blocker-samples"));
    if (f.pcss_filter_samples)
      p.set_filter_samples(parse_uint(*f.pcss_filter_samples, "--pcss-filter-samples"));
    if (f.pcss_rotate) p.set_rotate(parse_bool(*f.pcss_rotate, "--pcss-rotate"));
  }
  if (f.blur_radius || f.blur_passes) {
    for (const auto& [given, flag] : {std::pair{f.blur_radius.has_value(), "--blur-radius"},
                                      {f.blur_passes.has_value(), "--blur-passes"}})
      if (given) require_kind(request, FilterKind::kBlur, flag);
    v1::BlurSettings& b = *filter.mutable_blur();
    if (f.blur_radius) b.set_radius(parse_uint(*f.blur_radius, "--blur-radius"));
    if (f.blur_passes) b.set_passes(parse_uint(*f.blur_passes, "--blur-passes"));
  }
  apply_csm_flags(f, request);
  // Only blur reads receiver classes; any other filter would ignore them.
  if (!f.receiver_classes.empty()) require_kind(request, FilterKind::kBlur, "--receiver-class");
  for (const std::string& text : f.receiver_classes) {
    const ReceiverClass rc = parse_receiver_class(text, "--receiver-class");
    const int n = request.scene().instances_size();
    if (rc.instance >= uint32_t(n))
      throw FlagError("--receiver-class", "instance " + std::to_string(rc.instance) +
                                              " is not in the scene (it has " + std::to_string(n) +
                                              " instances)");
    request.mutable_scene()
        ->mutable_instances(int(rc.instance))
        ->set_receiver_class(rc.receiver_class);
  }
  if (!f.filter && filter.kind_case() == v1::Filter::KIND_NOT_SET) request.clear_filter();
}

}  // namespace

void apply_flags(const RequestFlags& f, v1::RenderRequest& request) {
  v1::Camera& cam = *request.mutable_camera();
  if (f.eye) *cam.mutable_eye() = convert::to_proto(parse_vec3(*f.eye, "--eye"));
  if (f.target) *cam.mutable_target() = convert::to_proto(parse_vec3(*f.target, "--target"));
  if (f.up) *cam.mutable_up() = convert::to_proto(parse_vec3(*f.up, "--up"));
  if (f.fov) cam.set_fov_deg(parse_float(*f.fov, "--fov"));
  if (f.size) {
    const ImageSize size = parse_size(*f.size, "--size");
    cam.set_width(size.width);
    cam.set_height(size.height);
  }
  if (f.near) cam.set_near(parse_float(*f.near, "--near"));
  if (f.far) cam.set_far(parse_float(*f.far, "--far"));

  if (!f.lights.empty()) {
    // --light picks the kind; the size is a separate flag, so light i keeps the size it had.
    std::vector<float> sizes;
    for (const v1::Light& l : request.lights()) sizes.push_back(l.size());
    request.clear_lights();
    for (size_t i = 0; i < f.lights.size(); ++i) {
      v1::Light& light = *request.add_lights();
      light = convert::to_proto(parse_light(f.lights[i], "--light"));
      light.set_size(i < sizes.size() ? sizes[i] : 0.0f);
    }
  }
  if (f.light_size) {
    const float size = parse_float(*f.light_size, "--light-size");
    for (v1::Light& light : *request.mutable_lights()) light.set_size(size);
  }

  v1::ShadowMapSettings& map = *request.mutable_shadow_map();
  if (f.max_error && f.max_device_ms)
    throw FlagError("--max-device-ms", "give one goal: --max-error or --max-device-ms");
  if ((f.max_error || f.max_device_ms) && (f.map_size || f.technique))
    throw FlagError(f.map_size ? "--map-size" : "--technique",
                    "the quality goal (--max-error, --max-device-ms) picks it");
  if (f.max_error) {
    // A percentage on the command line, a share on the wire.
    request.mutable_quality()->set_max_error(parse_float(*f.max_error, "--max-error") / 100.0f);
    map.clear_size();
  }
  if (f.max_device_ms) {
    request.mutable_quality()->set_max_device_ms(parse_float(*f.max_device_ms, "--max-device-ms"));
    map.clear_size();
  }
  if (f.map_size) map.set_size(parse_uint(*f.map_size, "--map-size"));
  if (f.technique)
    map.set_technique(convert::to_proto(parse_technique(*f.technique, "--technique")));
  const bool psm =
      map.technique() == v1::TECHNIQUE_PSM || map.technique() == v1::TECHNIQUE_PSM_CUBE;
  if ((f.psm_casters || f.psm_near) && !psm)
    throw FlagError(f.psm_casters ? "--psm-casters" : "--psm-near",
                    "only with --technique psm or psm_cube");
  if (f.psm_casters) {
    map.set_psm_casters(
        names::kPsmCasters.to_proto(parse_psm_casters(*f.psm_casters, "--psm-casters")));
  }
  if (f.psm_near)
    map.set_psm_near(names::kPsmNear.to_proto(parse_psm_near(*f.psm_near, "--psm-near")));
  if (f.psm_virtual_slide) {
    if (map.psm_near() != v1::PSM_NEAR_VIRTUAL_SLIDE_BACK)
      throw FlagError("--psm-virtual-slide", "only with --psm-near virtual-slide-back");
    map.set_psm_virtual_slide(parse_float(*f.psm_virtual_slide, "--psm-virtual-slide"));
  }
  if (f.fit) map.set_fit(names::kMapFits.to_proto(parse_map_fit(*f.fit, "--fit")));
  if (f.lispsm_n) {
    if (map.technique() != v1::TECHNIQUE_LISPSM)
      throw FlagError("--lispsm-n", "only with --technique lispsm");
    map.set_lispsm_n(parse_float(*f.lispsm_n, "--lispsm-n"));
  }
  for (const auto& [given, flag] : {std::pair{f.virtual_lod_bias.has_value(), "--virtual-lod-bias"},
                                    {f.virtual_pool_pages.has_value(), "--virtual-pool-pages"},
                                    {f.virtual_refuse_coarsening, "--virtual-refuse-coarsening"}})
    if (given && map.technique() != v1::TECHNIQUE_VIRTUAL)
      throw FlagError(flag, "only with --technique virtual");
  if (f.virtual_lod_bias)
    map.set_virtual_lod_bias(parse_float(*f.virtual_lod_bias, "--virtual-lod-bias"));
  if (f.virtual_pool_pages)
    map.set_virtual_pool_pages(parse_uint(*f.virtual_pool_pages, "--virtual-pool-pages"));
  if (f.virtual_refuse_coarsening) map.set_virtual_refuse_coarsening(true);
  if (f.bias_world_constant)
    map.set_bias_world_constant(parse_float(*f.bias_world_constant, "--bias-world-constant"));
  if (f.bias_world_texel)
    map.set_bias_world_texel(parse_float(*f.bias_world_texel, "--bias-world-texel"));
  if (f.bias_constant) map.set_bias_constant(parse_float(*f.bias_constant, "--bias-constant"));
  if (f.bias_slope) map.set_bias_slope(parse_float(*f.bias_slope, "--bias-slope"));

  apply_filter_flags(f, request);
  if (f.atlas_tile)
    request.mutable_atlas()->set_tile_size(parse_uint(*f.atlas_tile, "--atlas-tile"));
  if (f.atlas_density)
    request.mutable_atlas()->set_texel_world_size(parse_float(*f.atlas_density, "--atlas-density"));
  if (f.atlas_gutter)
    request.mutable_atlas()->set_gutter(parse_uint(*f.atlas_gutter, "--atlas-gutter"));
  if (f.atlas_generate_uvs) request.mutable_atlas()->set_generate_uvs(true);
  if (f.pixel_format) {
    const PixelFormat format = parse_pixel_format(*f.pixel_format, "--pixel-format");
    if (format == PixelFormat::kFloat64)
      throw FlagError("--pixel-format", "float64 is for summed-area tables only");
    request.set_pixel_format(names::kPixelFormats.to_proto(format));
  }
  if (f.chunk_compression) {
    request.set_chunk_compression(names::kChunkCompressions.to_proto(
        parse_chunk_compression(*f.chunk_compression, "--chunk-compression")));
  }

  if (f.products) {
    request.clear_products();
    for (Product p : parse_products(*f.products, "--products"))
      request.add_products(convert::to_proto(p));
  }
}

void complete(v1::RenderRequest& request, const RequestFlags& flags) {
  // What a missing flag would supply; where --request was given, it lacks that too.
  const auto required = [&](const char* flag, const std::string& what) {
    return FlagError(flag,
                     "required: " + what +
                         (flags.request ? " (and --request " + *flags.request + " has none)" : ""));
  };
  if (request.scene_id().empty() && request.scene().instances_size() == 0)
    throw required("--scene",
                   "an OBJ, .gltf or .glb file, or builtin:demo (or --scene-id of an uploaded "
                   "scene)");
  const v1::Camera& cam = request.camera();
  if (!cam.has_eye())
    throw required("--eye", "the camera's position X,Y,Z (builtin:demo brings its own camera)");
  if (!cam.has_target())
    throw required("--target",
                   "the camera's look-at point X,Y,Z (builtin:demo brings its own camera)");
  if (cam.width() == 0 && cam.height() == 0) {
    request.mutable_camera()->set_width(kDefaultWidth);
    request.mutable_camera()->set_height(kDefaultHeight);
  }
  if (request.lights_size() == 0)
    throw required("--light", "a light, e.g. directional:0,-1,0 (builtin:demo brings a sun)");
  if (request.products_size() == 0) {
    // A virtual map has no dense map to return (the server refuses PRODUCT_SHADOW_MAP with it).
    if (request.shadow_map().technique() != v1::TECHNIQUE_VIRTUAL)
      request.add_products(v1::PRODUCT_SHADOW_MAP);
    for (auto p : {v1::PRODUCT_VISIBILITY, v1::PRODUCT_POSITION}) request.add_products(p);
  }
}

void refuse_idle_flags(const RequestFlags& flags, const v1::RenderRequest& request) {
  const v1::Filter::KindCase kind = request.filter().kind_case();
  const std::string filter_name =
      names::kFilterKinds.from_proto(kind)
          ? std::string(names::kFilterKinds.name(*names::kFilterKinds.from_proto(kind)))
          : "hard";
  // Blur reads its planes only on instances with a class; without one every receiver gets the
  // hard test and the output is the hard filter's, bit for bit.
  // (A scene the server holds is its to check.)
  if (kind == v1::Filter::kBlur && request.scene_id().empty() &&
      std::none_of(request.scene().instances().begin(), request.scene().instances().end(),
                   [](const v1::Instance& i) { return i.has_receiver_class(); }))
    throw FlagError(flags.filter ? "--filter" : "--receiver-class",
                    "blur softens the shadow only on instances given a receiver class, and none "
                    "has one: add --receiver-class INSTANCE:CLASS (class 0..3, e.g. 0:0 for the "
                    "ground); without one the output is the hard test's");
  // The light's size is the penumbra's: only the filters with one read it.
  const bool penumbra = kind == v1::Filter::kPcss || kind == v1::Filter::kPcssCsm ||
                        kind == v1::Filter::kAtlasSat || kind == v1::Filter::kAtlasMip;
  if (flags.light_size && !penumbra)
    throw FlagError("--light-size",
                    "only with --filter pcss, pcss_csm, atlas_sat or atlas_mip (the penumbra's "
                    "light size; --filter " +
                        filter_name + " does not read it)");
  if (penumbra)
    for (int i = 0; i < request.lights_size(); ++i)
      if (request.lights(i).size() == 0.0f)
        throw FlagError("--light-size",
                        "required by --filter " + filter_name + ": light " + std::to_string(i) +
                            " has no size (degrees across for a directional light, the radius "
                            "for spot and point lights)");
  // The atlas settings shape only an atlas.
  const bool atlas = kind == v1::Filter::kAtlasSat || kind == v1::Filter::kAtlasMip ||
                     std::any_of(request.products().begin(), request.products().end(), [](int p) {
                       return p == v1::PRODUCT_SHADOW_ATLAS || p == v1::PRODUCT_SHADOW_ATLAS_MIPS ||
                              p == v1::PRODUCT_SHADOW_ATLAS_SAT || p == v1::PRODUCT_ATLAS_UVS;
                     });
  for (const auto& [given, flag] : {std::pair{flags.atlas_tile.has_value(), "--atlas-tile"},
                                    {flags.atlas_density.has_value(), "--atlas-density"},
                                    {flags.atlas_gutter.has_value(), "--atlas-gutter"},
                                    {flags.atlas_generate_uvs, "--atlas-generate-uvs"}})
    if (given && !atlas)
      throw FlagError(flag,
                      "only with an atlas: --products shadow_atlas, shadow_atlas_mips, "
                      "shadow_atlas_sat or atlas_uvs, or --filter atlas_sat or atlas_mip");
  if (flags.atlas_tile && flags.atlas_density)
    throw FlagError("--atlas-density",
                    "not with --atlas-tile: one tile for every instance, or tiles sized from the "
                    "world, not both");
}

v1::RenderRequest build_request(const RequestFlags& flags) {
  v1::RenderRequest request;
  if (flags.request) request = read_request_json(*flags.request);
  const bool own_lights = request.lights_size() > 0;
  if (flags.scene && flags.scene_id)
    throw FlagError("--scene-id", "not with --scene: the scene is the one the server holds");
  if (flags.scene) apply_scene(*flags.scene, request);
  if (flags.scene_id) {
    if (flags.scene_id->empty()) throw FlagError("--scene-id", "is empty");
    request.clear_scene();
    request.set_scene_id(*flags.scene_id);
  }
  // --light replaces builtin:demo's sun whole, its size too. The demo's 0.53 is the sun's angular
  // diameter in degrees: kept for a --light spot it would become a radius of 0.53 world units,
  // and for another sun a size nobody chose. So the soft filters need --light-size wherever
  // --light gives the light, as on a file scene. (Lights from --request keep their size: the
  // user wrote it, and --light-size is how to change it.)
  if (!own_lights && !flags.lights.empty()) request.clear_lights();
  apply_flags(flags, request);
  complete(request, flags);
  refuse_idle_flags(flags, request);
  return request;
}

void check_like_the_server(const v1::RenderRequest& request) {
  if (!request.scene_id().empty()) return;  // its scene is on the server
  try {
    // Its limits on bytes are its own: none here.
    validate(convert::from_proto(request), Limits{UINT64_MAX, UINT64_MAX});
  } catch (const FieldError& e) {
    const std::string flag = flag_for_field(e.field()), named = flag.empty() ? "--request" : flag;
    // The rules speak proto, as the server's errors do: the same note names their flags.
    throw FlagError(
        named, e.what() + flag_note(grpc::StatusCode::INVALID_ARGUMENT, named + ": " + e.what()));
  }
}

}  // namespace shadow::ctl
