#include "shadowctl/report.hpp"

#include <algorithm>
#include <cstdio>

#include "output/cube_writer.hpp"
#include "wire/names.hpp"
#include "wire/units.hpp"

namespace shadow::ctl {
namespace {

std::string printf_string(const char* format, auto... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, format, args...);
  return buffer;
}

// "light: ..." with the PSM parameters, the PSM cube's texel sizes and the cube faces, if the
// fit reported them.
std::string format_light_fit(const LightFitReport& fit, const std::string& label) {
  std::string out;
  if (!fit.light_case.empty()) out += label + ": " + fit.light_case + "\n";
  if (fit.virtual_far > 0) {
    out += printf_string(
        "  psm: virtual camera near %.6g far %.6g, slide-back %.6g; light depth %.6g .. %.6g\n",
        fit.virtual_near, fit.virtual_far, fit.slide_back, fit.light_near, fit.light_far);
  }
  // As 1/N of the unit cube's edge: N = the texels a fully used face would put across it.
  if (fit.cube_texel_min > 0 && fit.cube_texel_max > 0) {
    out += printf_string("  psm cube: texels 1/%.0f .. 1/%.0f of the unit cube's edge\n",
                         1 / fit.cube_texel_min, 1 / fit.cube_texel_max);
  }
  if (fit.lispsm_n > 0) out += printf_string("  lispsm: warp n %.6g\n", fit.lispsm_n);
  // AUTO's candidates: the prediction each was scored by and, where tried, the trial's measure.
  for (const AutoCandidateReport& c : fit.auto_candidates) {
    std::string line = printf_string("  auto: %-8s %u x %u^2: predicted %.4f per boundary pixel",
                                     std::string(names::kTechniques.name(c.technique)).c_str(),
                                     c.maps, c.map_size, c.predicted_error);
    if (c.trial_map_size > 0)
      line += printf_string(", trial at %u^2 %.5f", c.trial_map_size, c.trial_edge);
    if (fit.auto_technique == c.technique) line += " (picked)";
    out += line + "\n";
  }
  if (!fit.cube_faces.empty()) {
    const auto rendered = std::count_if(fit.cube_faces.begin(), fit.cube_faces.end(),
                                        [](const CubeFaceReport& f) { return f.rendered; });
    out +=
        printf_string("  cube: %d of %zu faces rendered\n", int(rendered), fit.cube_faces.size());
    for (const CubeFaceReport& f : fit.cube_faces) {
      out += printf_string("    %-3s %-9s %s\n", f.name.c_str(),
                           f.rendered ? "rendered" : "skipped", f.reason.c_str());
    }
  }
  return out;
}

}  // namespace

std::string human_bytes(uintmax_t bytes) {
  if (bytes >= (uintmax_t{1} << 20)) return printf_string("%.1f MiB", bytes / 1048576.0);
  if (bytes >= 1024) return printf_string("%.1f KiB", bytes / 1024.0);
  return std::to_string(bytes) + " B";
}

std::string format_virtual_pages(const VirtualPageCounts& v) {
  constexpr uint64_t kMiB = uint64_t{1} << 20;
  const std::string pool = v.pool_bytes % kMiB == 0
                               ? std::to_string(v.pool_bytes / kMiB)
                               : printf_string("%.1f", double(v.pool_bytes) / double(kMiB));
  return "virtual pages: requested " + std::to_string(v.requested) + ", resident " +
         std::to_string(v.resident) + ", rendered " + std::to_string(v.rendered) + ", coarsened " +
         std::to_string(v.coarsened_pixels) + " pixels, pool " + pool + " MiB";
}

std::string format_report(const RenderResult& result, const std::vector<output::WrittenFile>& files,
                          const Timeline& timeline) {
  std::string out = "wrote:\n";
  for (const auto& f : files) {
    const Texture& t = *f.texture;
    const bool exr = f.path.extension() == ".exr";
    const char* type = t.format == PixelFormat::kFloat16   ? "float16"
                       : t.format == PixelFormat::kFloat64 ? "float64 (hi+lo float32)"
                                                           : "float32";
    std::string shape = exr ? printf_string("%ux%u, %u channel%s %s", t.width, t.height, t.channels,
                                            t.channels == 1 ? "" : "s", type)
                            : printf_string("%ux%u preview", t.width, t.height * t.faces);
    if (exr && output::is_cube(t)) shape += printf_string(", %u faces", t.faces);
    out += printf_string("  %-40s %-32s %10s\n", f.path.string().c_str(), shape.c_str(),
                         human_bytes(f.bytes).c_str());
  }
  for (const Texture& t : result.textures) {
    if (output::is_cube(t) && t.faces == 0)
      out += "  (" + t.name + ": no cube face rendered, no file written)\n";
  }

  if (result.quality)
    out += printf_string("quality goal: %s %u, predicted %.3f%% misclassified in %.0f ms%s\n  %s\n",
                         std::string(names::kTechniques.name(result.quality->technique)).c_str(),
                         result.quality->size, 100 * result.quality->predicted_error,
                         result.quality->predicted_device_ms,
                         result.quality->goal_met ? "" : " (goal not met: the closest)",
                         result.quality->reason.c_str());
  for (size_t i = 0; i < result.light_fits.size(); ++i)
    out += format_light_fit(result.light_fits[i], result.light_fits.size() > 1
                                                      ? "light " + std::to_string(i)
                                                      : std::string("light"));
  if (result.virtual_pages) out += format_virtual_pages(*result.virtual_pages) + "\n";
  out += "passes:";
  for (const auto& p : result.passes) out += " " + p;
  out += "\ntimings (device):\n";
  size_t width = 5;
  for (const auto& t : result.timings) width = std::max(width, t.pass.size());
  double total = 0;
  for (const auto& t : result.timings) {
    out +=
        printf_string("  %-*s %10.3f ms\n", static_cast<int>(width), t.pass.c_str(), t.device_ms);
    total += t.device_ms;
  }
  out += printf_string("  %-*s %10.3f ms\n", static_cast<int>(width), "total", total);
  out += "client wall clock (ms after the request was sent):\n";
  out += printf_string("  header (server queue, render, readback) %10.1f\n", timeline.header);
  out += printf_string("  last chunk                              %10.1f\n", timeline.last_chunk);
  if (timeline.exr_rows > 0)
    out += printf_string("  EXR rows written as they came           %10.1f\n", timeline.exr_rows);
  out +=
      printf_string("  all files written                       %10.1f  (%.1fx the device time)\n",
                    timeline.done, total > 0 ? timeline.done / total : 0.0);
  return out;
}

}  // namespace shadow::ctl

namespace shadow::ctl {

std::string format_price(const v1::Price& p) {
  std::string out = "estimate: " + ms_text(p.device_ms()) + " of device time";
  if (p.frames() > 0)
    out += " for " + std::to_string(p.frames()) + " frames (" +
           ms_text(p.device_ms() / p.frames()) + " a frame on average)";
  if (p.quality_goal()) out += " for the quality goal's probe; the pick adds its candidate's";
  if (!p.largest_term().empty()) out += ", mostly " + p.largest_term();
  out += "\n";
  out += "memory: " + human_bytes(p.device_bytes()) + " of device buffers, " +
         human_bytes(p.reply_bytes()) + (p.frames() > 0 ? " the largest frame's reply" : " reply") +
         "\n";
  const auto limit = [](double ms) { return ms > 0 ? ms_text(ms) : std::string("none"); };
  out += "limits: " + limit(p.max_request_cost_ms()) + " a request (--max-request-cost), " +
         limit(p.max_sequence_cost_ms()) + " a sequence (--max-sequence-cost), " +
         human_bytes(p.memory_budget()) + " of memory (--memory-budget)\n";
  out += p.admitted() ? "admitted: yes\n" : "admitted: no, over " + p.refused_field() + "\n";
  return out;
}

namespace {

std::string percentiles(const char* what, const v1::Percentiles& p) {
  if (p.samples() == 0) return std::string(what) + ": none yet\n";
  return printf_string("%s: p50 %.1f ms, p90 %.1f, p99 %.1f, max %.1f (%llu renders)\n", what,
                       p.p50_ms(), p.p90_ms(), p.p99_ms(), p.max_ms(),
                       (unsigned long long)p.samples());
}

// The first kStatisticsRows of `rows` by `key`, largest first, and how many were left out.
template <class Row, class Key>
std::vector<Row> largest(const google::protobuf::RepeatedPtrField<Row>& rows, Key key,
                         size_t* left_out) {
  std::vector<Row> sorted(rows.begin(), rows.end());
  std::stable_sort(sorted.begin(), sorted.end(),
                   [&](const Row& a, const Row& b) { return key(a) > key(b); });
  *left_out = sorted.size() > kStatisticsRows ? sorted.size() - kStatisticsRows : 0;
  if (*left_out) sorted.resize(kStatisticsRows);
  return sorted;
}

uint64_t requests(const v1::TenantStatistics& t) {
  uint64_t n = 0;
  for (const v1::StatusCount& c : t.requests()) n += c.count();
  return n;
}

}  // namespace

std::string format_statistics(const v1::Statistics& s) {
  std::string out;
  if (!s.device_name().empty())
    out += "device: " + s.device_name() + " (" + s.device_type() + ", " + s.device_platform() +
           ", driver " + s.device_driver() + "), " + s.kernel_profile() + " kernel profile\n";
  out += printf_string("load: %u of %u workspaces busy, %u requests waiting, memory %s of %s\n",
                       s.workspaces_busy(), s.workspaces(), s.requests_waiting(),
                       human_bytes(s.device_memory_bytes()).c_str(),
                       human_bytes(s.device_memory_budget()).c_str());
  const v1::TenantStatistics& t = s.total();
  std::string codes;
  for (const v1::StatusCount& c : t.requests())
    codes += (codes.empty() ? "" : ", ") + c.code() + " " + std::to_string(c.count());
  out += "requests: " + (codes.empty() ? std::string("none yet") : codes);
  if (s.undecodable_requests() > 0)
    out += ", " + std::to_string(s.undecodable_requests()) + " undecodable";
  out += "\n";
  out += percentiles("queue time", t.queue_time());
  out += percentiles("run time", t.run_time());
  const v1::SceneCacheStatistics& cache = t.scene_cache();
  out += printf_string("scene cache: %llu scenes, %s; %llu hits, %llu misses, %llu evictions\n",
                       (unsigned long long)cache.scenes(), human_bytes(cache.bytes()).c_str(),
                       (unsigned long long)cache.hits(), (unsigned long long)cache.misses(),
                       (unsigned long long)cache.evictions());
  out += printf_string("device time: %.1f ms\n", t.device_ms());
  size_t left = 0;
  const auto passes = largest(
      t.passes(), [](const v1::PassStatistics& p) { return p.device_ms(); }, &left);
  if (!passes.empty()) {
    out += "passes, by device time:\n";
    for (const v1::PassStatistics& p : passes)
      out += printf_string("  %-32s %8llu runs %12.1f ms %5.1f%%\n", p.pass().c_str(),
                           (unsigned long long)p.runs(), p.device_ms(),
                           t.device_ms() > 0 ? 100 * p.device_ms() / t.device_ms() : 0.0);
    if (left) out += printf_string("  ... %zu more (--json)\n", left);
  }
  const auto tenants = largest(
      s.tenants(), [](const v1::TenantStatistics& x) { return x.device_ms(); }, &left);
  if (!tenants.empty()) {
    out += "tenants, by device time:\n";
    for (const v1::TenantStatistics& x : tenants)
      out += printf_string("  %-24s %8llu requests %12.1f ms %5.1f%% of the device\n",
                           x.tenant().empty() ? "(no token)" : x.tenant().c_str(),
                           (unsigned long long)requests(x), x.device_ms(), 100 * x.device_share());
    if (left) out += printf_string("  ... %zu more (--json)\n", left);
  }
  return out;
}

}  // namespace shadow::ctl
