#include "plot.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

namespace shadow::bench {

std::vector<bool> pareto_front(const std::vector<double>& time, const std::vector<double>& error) {
  std::vector<bool> front(time.size(), true);
  for (size_t i = 0; i < time.size(); ++i) {
    for (size_t j = 0; j < time.size(); ++j) {
      const bool no_worse = time[j] <= time[i] && error[j] <= error[i];
      const bool better = time[j] < time[i] || error[j] < error[i];
      if (j != i && no_worse && better) {
        front[i] = false;
        break;
      }
    }
  }
  return front;
}

void write_plot(const std::vector<PlotPoint>& points, const std::filesystem::path& file) {
  namespace IBA = OIIO::ImageBufAlgo;
  const int W = 900, H = 600, margin = 50;
  OIIO::ImageBuf img(OIIO::ImageSpec(W, H, 3, OIIO::TypeDesc::UINT8));
  const float white[3] = {1, 1, 1}, grid[3] = {0.88f, 0.88f, 0.88f}, axis[3] = {0, 0, 0};
  const float grey[3] = {0.45f, 0.45f, 0.55f}, red[3] = {0.85f, 0.1f, 0.1f};
  IBA::fill(img, white);
  if (points.empty()) {
    img.write(file.string());
    return;
  }
  double tmin = 1e300, tmax = 0, emax = 0;
  for (const auto& p : points) {
    tmin = std::min(tmin, p.time_ms);
    tmax = std::max(tmax, p.time_ms);
    emax = std::max(emax, p.error);
  }
  const double lx0 = std::floor(std::log10(std::max(tmin, 1e-3))),
               lx1 = std::ceil(std::log10(std::max(tmax, 1e-3)) + 1e-9);
  const double ey1 = emax > 0 ? emax * 1.1 : 1.0;
  auto px = [&](double t) {
    const double u = (std::log10(std::max(t, 1e-3)) - lx0) / std::max(lx1 - lx0, 1e-9);
    return margin + static_cast<int>(u * (W - 2 * margin));
  };
  auto py = [&](double e) { return H - margin - static_cast<int>(e / ey1 * (H - 2 * margin)); };
  for (double d = lx0; d <= lx1; d += 1) {  // decades, with 2x and 5x ticks
    for (double m : {1.0, 2.0, 5.0}) {
      const double t = m * std::pow(10.0, d);
      if (std::log10(t) > lx1) break;
      IBA::render_line(img, px(t), margin, px(t), H - margin, m == 1.0 ? axis : grid);
    }
  }
  for (int k = 0; k <= 10; ++k)
    IBA::render_line(img, margin, py(ey1 * k / 10), W - margin, py(ey1 * k / 10), grid);
  IBA::render_box(img, margin, margin, W - margin, H - margin, axis);
  std::vector<PlotPoint> front;
  for (const auto& p : points) {
    const int x = px(p.time_ms), y = py(p.error);
    if (p.pareto) {
      front.push_back(p);
    } else {
      IBA::render_box(img, x - 3, y - 3, x + 3, y + 3, grey, true);
    }
  }
  std::sort(front.begin(), front.end(),
            [](const PlotPoint& a, const PlotPoint& b) { return a.time_ms < b.time_ms; });
  for (size_t k = 0; k + 1 < front.size(); ++k)
    IBA::render_line(img, px(front[k].time_ms), py(front[k].error), px(front[k + 1].time_ms),
                     py(front[k + 1].error), red);
  for (const auto& p : front)
    IBA::render_box(img, px(p.time_ms) - 5, py(p.error) - 5, px(p.time_ms) + 5, py(p.error) + 5,
                    red, true);
  if (!img.write(file.string())) throw std::runtime_error(file.string() + ": " + img.geterror());
}

}  // namespace shadow::bench
