#include "engine/passes/summed_area.hpp"

#include <stdexcept>

namespace shadow {
namespace {
constexpr uint32_t kStrip = 1024;  // SAT_STRIP in sat.cl
constexpr uint32_t kBand = 64;     // SAT_BAND
}  // namespace

void SummedAreaPass::warm_up() {
  for (const char* k : {"sat_row_sums", "sat_strip_offsets", "sat_scale", "sat_scan", "sat_box"})
    kernels_.kernel("sat.cl", k);
}

const SummedAreaTable& SummedAreaPass::run(const DeviceTexture& src, const std::string& pass,
                                           Timeline& timeline) {
  if (src.channels == 0 || src.channels > kMaxChannels)
    throw std::invalid_argument("summed-area table: 1.." + std::to_string(kMaxChannels) +
                                " channels");
  SummedAreaTable& table = tables_[pass];
  const uint32_t strips = (src.width + kStrip - 1) / kStrip;
  const uint32_t bands = (src.height + kBand - 1) / kBand;
  const uint32_t items = bands;  // sat_row_sums: one work-item per band of rows
  table.width = src.width;
  table.height = src.height;
  table.channels = src.channels;
  runtime_.ensure(table.sums, src.floats() * sizeof(double));
  runtime_.ensure(offsets_, size_t{src.height} * strips * src.channels * sizeof(double));
  runtime_.ensure(item_max_, size_t{items} * sizeof(double));
  runtime_.ensure(scale_, 2 * sizeof(double));

  cl_kernel sums = kernels_.kernel("sat.cl", "sat_row_sums");
  cl::set_args(sums, *src.buffer, src.width, src.height, src.channels, strips, offsets_, item_max_);
  timeline.add(pass + ".row_sums", runtime_.launch(sums, items));
  cl_kernel offsets = kernels_.kernel("sat.cl", "sat_strip_offsets");
  cl::set_args(offsets, offsets_, src.height, src.channels, strips);
  timeline.add(pass + ".offsets", runtime_.launch(offsets, (src.height + 63) / 64));
  cl_kernel scale = kernels_.kernel("sat.cl", "sat_scale");
  cl::set_args(scale, item_max_, items, src.width, src.height, scale_);
  timeline.add(pass + ".scale", runtime_.launch(scale, 1));
  cl_kernel scan = kernels_.kernel("sat.cl", "sat_scan");
  cl::set_args(scan, *src.buffer, src.width, src.height, src.channels, strips, offsets_, scale_,
               table.sums);
  timeline.add(pass + ".scan", runtime_.launch(scan, strips));
  return table;
}

void SummedAreaPass::box_filter(const SummedAreaTable& sat, uint32_t rx, uint32_t ry,
                                cl::Buffer& out, const std::string& pass, Timeline& timeline) {
  const size_t texels = size_t{sat.width} * sat.height;
  runtime_.ensure(out, texels * sat.channels * sizeof(float));
  cl_kernel k = kernels_.kernel("sat.cl", "sat_box");
  cl::set_args(k, sat.sums, sat.width, sat.height, sat.channels, rx, ry, out);
  timeline.add(pass, runtime_.launch(k, size_t{sat.height} * ((sat.width + 63) / 64)));
}

}  // namespace shadow
