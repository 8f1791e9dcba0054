// shadowctl render: sends a scene to a shadow-server and writes the returned textures.
// shadowctl sequence: uploads a scene once and renders a list of frames over it.
// shadowctl upload: uploads a scene and prints its id, for render and sequence --scene-id.
// shadowctl stats: prints a summary of the server's statistics (--json: all of them).
#include <chrono>
#include <cstdio>
#include <iostream>

#include <google/protobuf/util/json_util.h>
#include <CLI/CLI.hpp>

#include "output/output_options.hpp"
#include "shadow_client.hpp"
#include "shadowctl/args.hpp"
#include "shadowctl/progress_display.hpp"
#include "shadowctl/render_to_files.hpp"
#include "shadowctl/report.hpp"
#include "shadowctl/request.hpp"
#include "shadowctl/sequence_to_files.hpp"
#include "shadowctl/server_errors.hpp"
#include "wire/names.hpp"
#include "wire/status_names.hpp"

namespace {

using shadow::ctl::RequestFlags;
namespace names = shadow::names;

// Options are taken as strings and parsed by shadowctl/args so errors name the flag. `fallback`
// is what an absent flag means, shown by --help in brackets (display only: the flag stays
// unset, so the server's default applies and --request's value is kept).
void add_string(CLI::App& app, const std::string& name, std::optional<std::string>& into,
                const std::string& help, const std::string& fallback = "") {
  CLI::Option* option = app.add_option_function<std::string>(
      name, [&into](const std::string& value) { into = value; }, help);
  if (!fallback.empty()) option->default_str(fallback);
}

// Inside a catch block: the message for a failed call (the server's status, with the flags
// behind the fields it names, or what failed here, e.g. a file) and exit code 1.
int call_failed(const std::string& server) {
  try {
    throw;
  } catch (const shadow::client::RpcError& e) {
    std::cerr << "shadowctl: server " << server << " said " << shadow::status_code_name(e.code())
              << ": " << e.what() << shadow::ctl::flag_note(e.code(), e.what()) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "shadowctl: " << e.what() << "\n";
  }
  return 1;
}

// shadowctl sequence: one line per frame as it is written, then the cost of the frames after
// the first (the first pays for everything the others may keep).
int run_sequence(const std::string& server, const shadow::client::Credentials& credentials,
                 shadow::v1::RenderRequest base, const std::vector<shadow::v1::Frame>& frames,
                 const std::string& out_dir, const shadow::output::OutputOptions& output,
                 bool quiet) {
  try {
    shadow::client::ShadowClient client(server, credentials);
    shadow::ctl::ProgressDisplay display(stderr);
    if (!quiet) {
      base.set_progress(true);
      client.on_progress([&](const shadow::v1::Progress& p) { display.show(p); });
    }
    double device = 0, wall = 0;
    size_t later = 0;
    const std::string id = shadow::ctl::sequence_to_files(
        client, std::move(base), frames, out_dir, output, [&](const shadow::ctl::FrameWritten& f) {
          display.done();
          std::cout << shadow::ctl::format_frame(f) << "\n" << std::flush;
          if (f.frame == 0) return;
          device += f.device_ms, wall += f.wall_ms;
          ++later;
        });
    std::cout << "scene " << id << ": " << frames.size() << " frames in " << out_dir
              << "/frame_*\n";
    if (later > 0)
      std::printf("after the first frame: %.2f ms device, %.2f ms wall per frame (mean of %zu)\n",
                  device / later, wall / later, later);
    return 0;
  } catch (...) {
    return call_failed(server);
  }
}

// --estimate: the server's price (Estimate) of the request or sequence, without rendering it.
// Exit 0 when it would be admitted, 1 when it would be refused (the refusal printed as a failed
// call's), so a scheduler can branch on it.
int print_estimate(const std::string& server, const shadow::client::Credentials& credentials,
                   const shadow::v1::EstimateRequest& request) {
  try {
    shadow::client::ShadowClient client(server, credentials);
    const shadow::v1::Price p = client.estimate(request);
    std::cout << shadow::ctl::format_price(p);
    if (p.admitted()) return 0;
    std::cerr << "shadowctl: the server would refuse it: " << p.refusal()
              << shadow::ctl::flag_note(grpc::StatusCode::RESOURCE_EXHAUSTED, p.refusal()) << "\n";
    return 1;
  } catch (...) {
    return call_failed(server);
  }
}

int run(int argc, char** argv) {
  CLI::App app{"shadowctl: render shadow textures with a shadow-server"};
  app.require_subcommand(1);
  CLI::App& render = *app.add_subcommand("render", "Render a scene and write EXR + PNG products");

  CLI::App& sequence = *app.add_subcommand(
      "sequence", "Upload a scene once, render frames over it, write DIR/frame_NNNN/ per frame");
  CLI::App& upload = *app.add_subcommand(
      "upload", "Upload a scene (UploadScene) and print its id, for render/sequence --scene-id");
  CLI::App& stats = *app.add_subcommand(
      "stats", "Print a summary of the server's statistics (GetStatistics); --json: all of it");
  bool stats_json = false;
  stats.add_flag("--json", stats_json,
                 "the whole document in protobuf's JSON mapping instead of the summary");

  std::string server = "127.0.0.1:50051";
  std::string out_dir;
  RequestFlags f;
  shadow::client::Credentials credentials;
  for (CLI::App* command : {&render, &sequence, &upload, &stats}) {
    command
        ->add_option("--server", server,
                     "HOST:PORT; several replicas as IP:PORT,IP:PORT or one DNS name as "
                     "dns:///NAME:PORT (round_robin, UNAVAILABLE retried on another)")
        ->capture_default_str();
    command
        ->add_option("--tls-server-name", credentials.tls_server_name,
                     "name the server's certificate must carry")
        ->default_str("the first host of --server");
    command->add_option("--tls-ca", credentials.tls_ca,
                        "PEM CA certificates that sign the server's: connect with TLS (without "
                        "any --tls-* or --token: plaintext)");
    command->add_option("--tls-cert", credentials.tls_cert, "PEM client certificate (mTLS)");
    command->add_option("--tls-key", credentials.tls_key, "PEM key of --tls-cert");
    command->add_option("--token", credentials.token,
                        "bearer token (the server's --auth-tokens); implies TLS");
  }
  std::optional<std::string> exr_compression, preview, frames_file, upload_scene;
  add_string(upload, "--scene", upload_scene, "OBJ, .gltf or .glb file, or builtin:demo");
  // The same request and output flags for both: a sequence's flags make its base request. The
  // default in brackets is what an absent flag leaves to the server (or, for the output flags,
  // to shadowctl); builtin:demo brings its own camera and sun (--scene's help says which).
  for (CLI::App* each : {&render, &sequence}) {
    CLI::App& command = *each;
    command.add_option("--out", out_dir, "output directory (created if needed); required");
    add_string(command, "--scene", f.scene,
               "OBJ, .gltf or .glb file, or builtin:demo (ground, boxes and spheres with its own "
               "camera, eye 13,9,15 target 0,1,0 fov 50 near 0.5 far 200, and sun, 0.53 "
               "degrees across, each only where no flag gives one); required unless --request "
               "has a scene");
    add_string(command, "--scene-id", f.scene_id,
               "a scene the server holds (shadowctl upload prints its id) instead of --scene");
    add_string(command, "--request", f.request,
               "RenderRequest in protobuf JSON for every other field; flags override it");
    add_string(command, "--eye", f.eye,
               "camera position X,Y,Z; required (but for builtin:demo or --request)");
    add_string(command, "--target", f.target,
               "camera look-at point X,Y,Z; required (but for builtin:demo or --request)");
    add_string(command, "--up", f.up, "camera up X,Y,Z", "0,1,0");
    add_string(command, "--fov", f.fov, "vertical field of view in degrees", "60");
    add_string(command, "--size", f.size, "camera image WxH, each 1..16384", "1280x720");
    add_string(command, "--near", f.near, "near clip distance", "0.1");
    add_string(command, "--far", f.far, "far clip distance", "1000");
    command.add_option("--light", f.lights,
                       "directional:DX,DY,DZ | spot:PX,PY,PZ:DX,DY,DZ:CONE_DEG | point:PX,PY,PZ; "
                       "repeat for several lights (each gets its own maps, files *_light<i>); "
                       "required (but for builtin:demo or --request); replaces builtin:demo's "
                       "sun, size included");
    add_string(command, "--light-size", f.light_size,
               "angular diameter in degrees (directional) or radius (spot, point), every light; "
               "for the filters with a penumbra (pcss, pcss_csm, atlas_sat, atlas_mip), which "
               "need it",
               "0: hard; builtin:demo's sun 0.53");
    add_string(command, "--map-size", f.map_size,
               "shadow map (cube: each face's; virtual: each level's) edge in texels, "
               "256..8192; virtual: a power of two, 2048..32768",
               "2048; virtual: 16384");
    add_string(command, "--max-error", f.max_error,
               "a quality goal instead of --technique and --map-size: the fastest technique and "
               "size predicted to misclassify at most this % of the receivers' pixels");
    add_string(command, "--max-device-ms", f.max_device_ms,
               "a quality goal: the most accurate technique and size predicted to take at most "
               "this many ms of device time");
    add_string(command, "--technique", f.technique, names::kTechniques.listing(" | ", " | "),
               "per light: cube for a point light, else uniform");
    add_string(
        command, "--psm-casters", f.psm_casters,
        "psm, psm_cube: casters behind the camera by " + names::kPsmCasters.listing(" | ", " | "),
        "inverse-projection");
    add_string(command, "--psm-near", f.psm_near,
               "psm, psm_cube: the virtual near/far at the visible receivers, at the camera's "
               "or slid back: " +
                   names::kPsmNear.listing(" | ", " | "),
               "receivers");
    add_string(command, "--psm-virtual-slide", f.psm_virtual_slide,
               "virtual-slide-back: slide in world units", "the pushed near distance");
    add_string(command, "--fit", f.fit,
               "uniform maps: view (the receivers in view) | scene (all of them: the map stays "
               "while the camera moves)",
               "view");
    add_string(command, "--lispsm-n", f.lispsm_n,
               "lispsm: the warp's near distance n in world units", "Wimmer's n_opt");
    add_string(command, "--virtual-lod-bias", f.virtual_lod_bias,
               "virtual: the level a pixel reads is the one whose texel is its footprint times "
               "2^bias (negative: finer, more pages), -4..4",
               "-0.5");
    add_string(command, "--virtual-pool-pages", f.virtual_pool_pages,
               "virtual: the pool's 128^2 float32 pages (64 KiB each), shared by the lights, "
               "1..16384",
               "1024");
    command.add_flag(
        "--virtual-refuse-coarsening", f.virtual_refuse_coarsening,
        "virtual: refuse the request where the marked pages exceed the pool; "
        "default off: the farthest pixels read a coarser level, counted in the report");
    add_string(command, "--bias-world-constant", f.bias_world_constant,
               "caster offset away from the light, world units", "0");
    add_string(command, "--bias-world-texel", f.bias_world_texel,
               "caster offset away from the light, in world-space map texels", "0");
    add_string(command, "--bias-constant", f.bias_constant, "depth bias in NDC units", "2e-5");
    add_string(command, "--bias-slope", f.bias_slope,
               "slope-scaled depth bias, times the receiver's NDC depth change per texel", "0.75");
    add_string(command, "--products", f.products,
               "comma-separated: " + names::kProducts.listing(",", ","),
               "shadowmap,visibility,position; virtual: visibility,position");
    add_string(command, "--filter", f.filter,
               "visibility filter: " + names::kFilterKinds.listing(" | ", " | "), "hard");
    add_string(command, "--pcf-taps", f.pcf_taps, "poisson: taps, 1..64", "16");
    add_string(command, "--pcf-radius", f.pcf_radius, "poisson: radius in texels", "2");
    add_string(command, "--pcf-rotate", f.pcf_rotate, "poisson: on | off per-pixel rotation", "on");
    add_string(command, "--pcss-blocker-samples", f.pcss_blocker_samples,
               "pcss: blocker-search taps, 1..64", "16");
    add_string(command, "--pcss-filter-samples", f.pcss_filter_samples,
               "pcss: filter taps, 1..64; the light size is --light-size", "32");
    add_string(command, "--pcss-rotate", f.pcss_rotate, "pcss: on | off per-pixel rotation", "on");
    add_string(command, "--blur-radius", f.blur_radius, "blur: Gaussian radius in texels, 1..32",
               "4");
    add_string(command, "--blur-passes", f.blur_passes, "blur: separable passes, 1..16", "2");
    add_string(command, "--csm-terms", f.csm_terms, "csm, pcss_csm: Fourier terms M, 1..16", "8");
    add_string(command, "--csm-storage", f.csm_storage,
               "csm, pcss_csm: basis storage " + names::kCsmStorages.listing(" | ", " | "),
               "float32");
    add_string(command, "--csm-lookup", f.csm_lookup,
               "csm, pcss_csm: how the basis is read over a window: " +
                   names::kCsmLookups.listing(" | ", " | ") +
                   " (mips: trilinear; sat: a box, float32 storage only)",
               "mips");
    add_string(command, "--csm-window", f.csm_window, "csm: filter window in texels, >= 1", "4");
    add_string(command, "--csm-damping", f.csm_damping,
               "csm, pcss_csm: ringing damping exp(-a (k/M)^2), >= 0", "2");
    add_string(command, "--csm-depth-offset", f.csm_depth_offset,
               "csm, pcss_csm: receiver depth offset in units of 1/M of the linear depth, 0..16",
               "0.25");
    add_string(command, "--csm-scale", f.csm_scale,
               "csm, pcss_csm: scale-and-clamp about 1/2, >= 1", "4");
    command.add_option("--receiver-class", f.receiver_classes,
                       "blur: INSTANCE:CLASS (class 0..3), repeatable; those instances get the "
                       "blurred shadow, the rest the hard test, so blur needs at least one");
    add_string(command, "--atlas-tile", f.atlas_tile,
               "shadow_atlas: texels across every receiving instance's tile, 16..4096, one size "
               "for all (not with --atlas-density)",
               "sized per instance from --atlas-density");
    add_string(command, "--atlas-density", f.atlas_density,
               "shadow_atlas: world units per atlas texel, > 0; each instance's tile is the "
               "power of two (16..4096) that meets it on its surface",
               "the shadow map's texel footprint on each receiver, within 4096^2 texels");
    add_string(command, "--atlas-gutter", f.atlas_gutter,
               "shadow_atlas: texels filled around every chart, 0..16", "2");
    command.add_flag("--atlas-generate-uvs", f.atlas_generate_uvs,
                     "shadow_atlas: lay out every receiving mesh on the server, its own UVs "
                     "unused (for overlapping, mirrored or tiled UVs); default off: each mesh's "
                     "own UVs where it has them");
    add_string(command, "--pixel-format", f.pixel_format,
               "float products as float32 | float16 (half the bytes, rounded to nearest even; "
               "written as half EXR; SATs stay float64)",
               "float32");
    add_string(command, "--chunk-compression", f.chunk_compression,
               "reply chunks: none | zstd (lossless; pays on slow links and sparse maps)", "none");
    add_string(command, "--exr-compression", exr_compression,
               "auto | none | rle | zips | zip | piz, all lossless; auto: zip for visibility "
               "and atlases, none for depths and the rest (their bits do not compress cheaply)",
               std::string(shadow::output::kDefaultExrCompression));
    add_string(command, "--preview", preview,
               "png | full | none: 8-bit PNG previews, at most 1024 pixels across (png) or one "
               "per texel (full)",
               "png");
  }
  bool estimate = false, quiet = false;
  for (CLI::App* each : {&render, &sequence})
    each->add_flag("--quiet", quiet,
                   "no progress on stderr (by default: a bar on a terminal, else a line with the "
                   "percentage done at least once a second, for work of over half a second)");
  for (CLI::App* each : {&render, &sequence})
    each->add_flag("--estimate", estimate,
                   "print the server's price of the work (estimated device time, memory, reply "
                   "bytes and the limits they meet) without rendering; exit 0 if it would be "
                   "admitted, 1 if refused; --out is not needed");
  add_string(sequence, "--frames", frames_file,
             "JSON {\"frames\": [...]}: each frame's camera, lights (empty: the flags') and "
             "instance transforms, in protobuf's JSON mapping of shadow.v1.Frame");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help prints and exits 0; every other refusal is a usage error, 2 (not CLI11's own 105,
    // 106, 109, ...).
    if (e.get_exit_code() == int(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << "shadowctl: " << e.what() << " (--help lists the flags)\n";
    return 2;
  }
  CLI::App& command = sequence.parsed() ? sequence : upload.parsed() ? upload : render;
  const auto usage_error = [&](const shadow::ctl::FlagError& e) {
    std::cerr << "shadowctl: " << e.what() << "\n";
    // The flag's help says its range and default.
    if (const CLI::Option* o = command.get_option_no_throw(e.flag()))
      std::cerr << "  " << e.flag() << ": " << o->get_description() << "\n";
    return 2;
  };

  if (stats.parsed()) {
    try {
      shadow::client::ShadowClient client(server, credentials);
      const shadow::v1::Statistics statistics = client.statistics();
      if (!stats_json) {
        std::cout << shadow::ctl::format_statistics(statistics);
        return 0;
      }
      std::string json;
      google::protobuf::util::JsonPrintOptions options;
      options.add_whitespace = true;
      options.preserve_proto_field_names = true;
      (void)google::protobuf::util::MessageToJsonString(statistics, &json, options);
      std::cout << json;
      return 0;
    } catch (...) {
      return call_failed(server);
    }
  }
  if (upload.parsed()) {
    shadow::v1::RenderRequest scene;
    try {
      if (!upload_scene) throw shadow::ctl::FlagError("--scene", "is required");
      shadow::ctl::apply_scene(*upload_scene, scene);
    } catch (const shadow::ctl::FlagError& e) {
      return usage_error(e);
    }
    try {
      shadow::client::ShadowClient client(server, credentials);
      std::cout << client.upload_scene(scene.scene()) << "\n";  // the id alone, for scripts
      return 0;
    } catch (...) {
      return call_failed(server);
    }
  }
  if (out_dir.empty() && !estimate) {
    std::cerr << "shadowctl: --out is required\n";
    return 2;
  }

  shadow::v1::RenderRequest request;
  try {
    request = shadow::ctl::build_request(f);
    shadow::ctl::check_like_the_server(request);
  } catch (const shadow::ctl::FlagError& e) {
    return usage_error(e);
  } catch (const std::exception& e) {  // e.g. std::bad_alloc while loading the scene
    std::cerr << "shadowctl: " << e.what() << "\n";
    return 2;
  }

  shadow::output::OutputOptions output;
  try {
    if (exr_compression)
      output.exr_compression =
          shadow::ctl::parse_exr_compression(*exr_compression, "--exr-compression");
    if (preview) output.preview = shadow::ctl::parse_preview(*preview, "--preview");
  } catch (const shadow::ctl::FlagError& e) {
    return usage_error(e);
  }

  if (sequence.parsed()) {
    std::vector<shadow::v1::Frame> frames;
    try {
      if (!frames_file) throw shadow::ctl::FlagError("--frames", "is required");
      frames = shadow::ctl::read_frames_json(*frames_file);
    } catch (const shadow::ctl::FlagError& e) {
      return usage_error(e);
    }
    if (estimate) {
      shadow::v1::EstimateRequest priced;
      *priced.mutable_sequence()->mutable_base() = request;
      for (const shadow::v1::Frame& frame : frames)
        *priced.mutable_sequence()->add_frames() = frame;
      return print_estimate(server, credentials, priced);
    }
    return run_sequence(server, credentials, std::move(request), frames, out_dir, output, quiet);
  }
  if (estimate) {
    shadow::v1::EstimateRequest priced;
    *priced.mutable_render() = request;
    return print_estimate(server, credentials, priced);
  }

  try {
    shadow::client::ShadowClient client(server, credentials);
    shadow::ctl::ProgressDisplay display(stderr);
    if (!quiet) {
      request.set_progress(true);
      client.on_progress([&](const shadow::v1::Progress& p) { display.show(p); });
    }
    const shadow::ctl::RenderedFiles r =
        shadow::ctl::render_to_files(client, request, out_dir, output);
    display.done();
    std::cout << shadow::ctl::format_report(r.result, r.files, r.timeline);
    if (client.stream_restarts() > 0)
      std::cerr << "shadowctl: the reply broke off (UNAVAILABLE) and was asked for again "
                << client.stream_restarts() << " time(s)\n";
  } catch (...) {
    return call_failed(server);
  }
  return 0;
}

}  // namespace

// No exception leaves main: whatever run() lets through (a failed allocation, a library's own
// exception) is a message on stderr and exit code 2, like every error found before the render.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "shadowctl: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "shadowctl: unexpected error\n";
  }
  return 2;
}
