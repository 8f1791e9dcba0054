#include "engine/passes/summed_area.hpp"

#include <stdexcept>

namespace shadow {
namespace {
constexpr uint32_t kStrip = 1024;    // SAT_STRIP in summed_area.cl
constexpr uint32_t kBand = 64;       // SAT_BAND
constexpr uint32_t kBlockRows = 64;  // SAT_BLOCK_ROWS there
}  // namespace

bool SummedAreaPass::gpu_shape() const {
  return runtime_.device_info().profile().shape == cl::KernelShape::kGpu;
}

std::string SummedAreaPass::gpu_options() const {
  return "-DGROUP=" + std::to_string(runtime_.device_info().profile().group_size);
}

void SummedAreaPass::warm_up() {
  if (gpu_shape()) {
    for (const char* k : {"sat_gpu_row_sums", "sat_gpu_max", "sat_gpu_rows", "sat_gpu_column_sums",
                          "sat_gpu_column_offsets", "sat_gpu_column_scan", "sat_gpu_box"})
      kernels_.kernel("summed_area.cl", k, gpu_options());
    kernels_.kernel("summed_area.cl", "sat_scale");
    return;
  }
  for (const char* k : {"sat_row_sums", "sat_strip_offsets", "sat_scale", "sat_scan", "sat_box"})
    kernels_.kernel("summed_area.cl", k);
}

const SummedAreaTable& SummedAreaPass::run(const DeviceTexture& src, const std::string& pass,
                                           Timeline& timeline) {
  if (src.channels == 0 || src.channels > kMaxChannels)
    throw std::invalid_argument("summed-area table: 1.." + std::to_string(kMaxChannels) +
                                " channels");
  SummedAreaTable& table = tables_[pass];
  if (gpu_shape()) {
    run_gpu(src, table, pass, timeline);
    return table;
  }
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

  cl_kernel sums = kernels_.kernel("summed_area.cl", "sat_row_sums");
  cl::set_args(sums, *src.buffer, src.width, src.height, src.channels, strips, offsets_, item_max_);
  timeline.add(pass + ".row_sums", runtime_.launch(sums, items));
  cl_kernel offsets = kernels_.kernel("summed_area.cl", "sat_strip_offsets");
  cl::set_args(offsets, offsets_, src.height, src.channels, strips);
  timeline.add(pass + ".offsets", runtime_.launch(offsets, (src.height + 63) / 64));
  cl_kernel scale = kernels_.kernel("summed_area.cl", "sat_scale");
  cl::set_args(scale, item_max_, items, src.width, src.height, scale_);
  timeline.add(pass + ".scale", runtime_.launch(scale, 1));
  cl_kernel scan = kernels_.kernel("summed_area.cl", "sat_scan");
  cl::set_args(scan, *src.buffer, src.width, src.height, src.channels, strips, offsets_, scale_,
               table.sums);
  timeline.add(pass + ".scan", runtime_.launch(scan, strips));
  return table;
}

void SummedAreaPass::run_gpu(const DeviceTexture& src, SummedAreaTable& table,
                             const std::string& pass, Timeline& timeline) {
  const size_t group = runtime_.device_info().profile().group_size;
  const std::string options = gpu_options();
  const uint32_t strips = (src.width + kStrip - 1) / kStrip;
  const size_t strip_rows = size_t{src.height} * strips;
  const auto groups = uint32_t((strip_rows + group - 1) / group);  // sat_gpu_row_sums'
  // The CPU shape sums more than 8 channels one at a time: a work-item each then.
  const bool per_channel =
      !(src.channels == 1 || src.channels == 2 || src.channels == 4 || src.channels == 8);
  const auto columns = uint32_t(size_t{src.width} * src.channels);
  const uint32_t blocks = (src.height + kBlockRows - 1) / kBlockRows;
  table.width = src.width;
  table.height = src.height;
  table.channels = src.channels;
  runtime_.ensure(table.sums, src.floats() * sizeof(double));
  runtime_.ensure(offsets_, strip_rows * src.channels * sizeof(double));
  runtime_.ensure(item_max_, size_t{groups} * sizeof(double));
  runtime_.ensure(max_, sizeof(double));
  runtime_.ensure(block_sums_, size_t{blocks} * columns * sizeof(double));
  runtime_.ensure(scale_, 2 * sizeof(double));

  cl_kernel sums = kernels_.kernel("summed_area.cl", "sat_gpu_row_sums", options);
  cl::set_args(sums, *src.buffer, src.width, src.height, src.channels, strips, offsets_, item_max_);
  timeline.add(pass + ".row_sums", runtime_.launch(sums, strip_rows, group));
  cl_kernel max = kernels_.kernel("summed_area.cl", "sat_gpu_max", options);
  cl::set_args(max, item_max_, groups, max_);
  timeline.add(pass + ".max", runtime_.launch(max, group, group));
  // The CPU shape's own quantum computation, so both shapes make the same table.
  cl_kernel scale = kernels_.kernel("summed_area.cl", "sat_scale");
  cl::set_args(scale, max_, uint32_t{1}, src.width, src.height, scale_);
  timeline.add(pass + ".scale", runtime_.launch(scale, 1));
  cl_kernel rows = kernels_.kernel("summed_area.cl", "sat_gpu_rows", options);
  cl::set_args(rows, *src.buffer, src.width, src.height, src.channels, strips, offsets_, scale_,
               table.sums);
  timeline.add(pass + ".rows",
               runtime_.launch(rows, strip_rows * (per_channel ? src.channels : 1), group));
  if (src.height > 1) {
    const size_t block_items = size_t{blocks} * columns;
    cl_kernel block = kernels_.kernel("summed_area.cl", "sat_gpu_column_sums", options);
    cl::set_args(block, table.sums, columns, src.height, block_sums_);
    timeline.add(pass + ".column_sums", runtime_.launch(block, block_items, group));
    cl_kernel above = kernels_.kernel("summed_area.cl", "sat_gpu_column_offsets", options);
    cl::set_args(above, block_sums_, columns, blocks);
    timeline.add(pass + ".column_offsets", runtime_.launch(above, columns, group));
    cl_kernel scan = kernels_.kernel("summed_area.cl", "sat_gpu_column_scan", options);
    cl::set_args(scan, table.sums, columns, src.height, block_sums_);
    timeline.add(pass + ".column_scan", runtime_.launch(scan, block_items, group));
  }
}

void SummedAreaPass::box_filter(const SummedAreaTable& sat, uint32_t rx, uint32_t ry,
                                cl::Buffer& out, const std::string& pass, Timeline& timeline) {
  const size_t texels = size_t{sat.width} * sat.height;
  runtime_.ensure(out, texels * sat.channels * sizeof(float));
  if (gpu_shape()) {
    cl_kernel k = kernels_.kernel("summed_area.cl", "sat_gpu_box", gpu_options());
    cl::set_args(k, sat.sums, sat.width, sat.height, sat.channels, rx, ry, out);
    const size_t group = runtime_.device_info().profile().group_size;
    timeline.add(pass, runtime_.launch(k, texels, group));
    return;
  }
  cl_kernel k = kernels_.kernel("summed_area.cl", "sat_box");
  cl::set_args(k, sat.sums, sat.width, sat.height, sat.channels, rx, ry, out);
  timeline.add(pass, runtime_.launch(k, size_t{sat.height} * ((sat.width + 63) / 64)));
}

}  // namespace shadow
