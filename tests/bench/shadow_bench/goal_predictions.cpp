#include "goal_predictions.hpp"

#include <memory>

#include "service/server.hpp"
#include "shadow_client.hpp"
#include "wire/convert.hpp"

namespace shadow::bench {

Camera bench_camera(const scenes::View& view, int width) {
  Camera cam = view.camera;
  cam.width = uint32_t(width);
  cam.height = uint32_t(width * 9 / 16);
  return cam;
}

std::map<std::string, std::vector<QualityCandidate>> goal_candidates(
    const Calibration& calibration, const std::vector<scenes::StandardScene>& scenes, int width) {
  service::ServerOptions options;
  options.listen = "127.0.0.1:0";
  options.engine.calibration = std::make_shared<const Calibration>(calibration);
  service::ShadowServer server(options);
  client::ShadowClient client(server.address());
  std::map<std::string, std::vector<QualityCandidate>> out;
  for (const scenes::StandardScene& sc : scenes) {
    const v1::Scene scene = convert::to_proto(*sc.scene);
    for (const scenes::View& view : sc.views) {
      if (view.light.type == LightType::kPoint) continue;
      v1::RenderRequest req;
      *req.mutable_scene() = scene;
      *req.mutable_camera() = convert::to_proto(bench_camera(view, width));
      *req.add_lights() = convert::to_proto(view.light);
      req.add_products(v1::PRODUCT_VISIBILITY);
      req.mutable_quality()->set_max_error(0.01f);  // any bound: every candidate is weighed
      const RenderResult result = client.render(req);
      if (result.quality) out[sc.name + "/" + view.name] = result.quality->candidates;
    }
  }
  return out;
}

}  // namespace shadow::bench
