#include "engine/passes/blur.hpp"

#include "engine/passes/light_args.hpp"

#include <cmath>

namespace shadow {

std::vector<float> BlurPass::weights(uint32_t radius) {
  const double sigma = 0.5 * radius;
  std::vector<double> w(2 * radius + 1);
  double sum = 0;
  for (int k = -int(radius); k <= int(radius); ++k)
    sum += w[k + radius] = std::exp(-double(k) * k / (2 * sigma * sigma));
  std::vector<float> f;
  for (double x : w) f.push_back(float(x / sum));
  return f;
}

const cl::Buffer& BlurPass::classify(const RasterOutput& raster, uint32_t draw_count, uint32_t size,
                                     uint32_t planes, Timeline& timeline) {
  const uint32_t texels = size * size;
  runtime_.ensure(planes_, size_t{texels} * planes * sizeof(float));
  cl_kernel k = kernel("blur_classes");
  cl::set_args(k, raster.ids, raster.draws, draw_count, texels, planes, planes_);
  const PixelShape sh = shape();
  timeline.add("shadow_map.classes", runtime_.launch(k, sh.work_items(texels), sh.group));
  return planes_;
}

void BlurPass::blur(const cl::Buffer& data, uint32_t width, uint32_t height, uint32_t planes,
                    uint32_t radius, uint32_t passes, Timeline& timeline) {
  if (radius != radius_) {
    weight_data_ = weights(radius);
    runtime_.ensure(weights_, weight_data_.size() * sizeof(float));
    timeline.add("shadow_map.blur", runtime_.write(weights_, weight_data_.data(),
                                                   weight_data_.size() * sizeof(float)));
    radius_ = radius;
  }
  runtime_.ensure(scratch_, size_t{width} * height * planes * sizeof(float));
  const PixelShape sh = shape();
  const uint32_t strips = uint32_t(sh.work_items(width)), rows = planes * height;
  const int r = int(radius);
  cl_kernel h = kernel("blur_rows");
  cl_kernel v = kernel("blur_columns");
  for (uint32_t i = 0; i < passes; ++i) {
    cl::set_args(h, data, scratch_, width, rows, strips, weights_, r);
    timeline.add("shadow_map.blur", runtime_.launch(h, size_t{rows} * strips, sh.group));
    cl::set_args(v, scratch_, data, width, height, planes, strips, weights_, r);
    timeline.add("shadow_map.blur", runtime_.launch(v, size_t{rows} * strips, sh.group));
  }
}

void BlurPass::apply(const GBuffer& gb, uint32_t pixels, const cl::Buffer& blurred,
                     const ViewSetup& light_view, const Light& light, uint32_t map_size,
                     const cl::Buffer& visibility, Timeline& timeline) {
  cl_kernel k = kernel("blur_visibility");
  cl::set_args(k, gb.position, gb.normal, pixels, shadow_lookup(light_view, light, map_size),
               blurred, visibility);
  const PixelShape sh = shape();
  timeline.add("visibility.blur", runtime_.launch(k, sh.work_items(pixels), sh.group));
}

}  // namespace shadow
