#include "shadowctl/request.hpp"

#include <fstream>
#include <sstream>

#include <google/protobuf/util/json_util.h>

#include "scenes/demo_scene.hpp"
#include "scenes/scene_loader.hpp"
#include "service/convert.hpp"
#include "shadowctl/args.hpp"

namespace shadow::ctl {

v1::RenderRequest read_request_json(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw FlagError("--request", file.string() + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  v1::RenderRequest request;
  const auto status = google::protobuf::util::JsonStringToMessage(text.str(), &request);
  if (!status.ok())
    throw FlagError("--request", file.string() + ": not a RenderRequest in canonical JSON: " +
                                     std::string(status.message()));
  return request;
}

void apply_scene(const std::string& scene, v1::RenderRequest& request) {
  if (scene == kDemoScene) {
    const scenes::DemoSetup demo = scenes::demo_scene();
    *request.mutable_scene() = convert::to_proto(demo.scene);
    if (!request.has_camera()) *request.mutable_camera() = convert::to_proto(demo.camera);
    if (!request.has_light()) *request.mutable_light() = convert::to_proto(demo.light);
    if (!request.has_shadow_map())
      *request.mutable_shadow_map() = convert::to_proto(demo.shadow_map);
    return;
  }
  try {
    *request.mutable_scene() = convert::to_proto(scenes::load_scene(scene));
  } catch (const std::runtime_error& e) {
    throw FlagError("--scene", e.what());
  }
}

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

  v1::Light& light = *request.mutable_light();
  if (f.light) {
    const float size = light.size();  // --light picks the kind; the size is a separate flag
    light = convert::to_proto(parse_light(*f.light, "--light"));
    light.set_size(size);
  }
  if (f.light_size) light.set_size(parse_float(*f.light_size, "--light-size"));

  v1::ShadowMapSettings& map = *request.mutable_shadow_map();
  if (f.map_size) map.set_size(parse_uint(*f.map_size, "--map-size"));
  if (f.technique) {
    parse_technique(*f.technique, "--technique");  // uniform is the only one so far
    map.set_technique(v1::TECHNIQUE_UNIFORM);
  }
  if (f.bias_constant) map.set_bias_constant(parse_float(*f.bias_constant, "--bias-constant"));
  if (f.bias_slope) map.set_bias_slope(parse_float(*f.bias_slope, "--bias-slope"));

  if (f.products) {
    request.clear_products();
    for (Product p : parse_products(*f.products, "--products"))
      request.add_products(convert::to_proto(p));
  }
}

void complete(v1::RenderRequest& request) {
  if (request.scene().instances_size() == 0)
    throw FlagError("--scene", "required (a file or builtin:demo), unless --request has a scene");
  const v1::Camera& cam = request.camera();
  if (!cam.has_eye()) throw FlagError("--eye", "required: no camera eye in --request");
  if (!cam.has_target()) throw FlagError("--target", "required: no camera target in --request");
  if (cam.width() == 0 && cam.height() == 0) {
    request.mutable_camera()->set_width(kDefaultWidth);
    request.mutable_camera()->set_height(kDefaultHeight);
  }
  if (request.light().kind_case() == v1::Light::KIND_NOT_SET)
    throw FlagError("--light", "required: no light in --request");
  if (request.products_size() == 0)
    for (auto p : {v1::PRODUCT_SHADOW_MAP, v1::PRODUCT_VISIBILITY, v1::PRODUCT_POSITION})
      request.add_products(p);
}

v1::RenderRequest build_request(const RequestFlags& flags) {
  v1::RenderRequest request;
  if (flags.request) request = read_request_json(*flags.request);
  if (flags.scene) apply_scene(*flags.scene, request);
  apply_flags(flags, request);
  complete(request);
  return request;
}

}  // namespace shadow::ctl
