#include "squeeze/render/plot.h"

#include <plplot/plplot.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"

namespace squeeze::render {
namespace fs = std::filesystem;

namespace {
std::mutex plplot_mutex;  // PLplot keeps global state

bool has_device(const char* name) {
  const char* menu[64];
  const char* devs[64];
  const char** pm = menu;
  const char** pd = devs;
  int n = 64;
  plgDevs(&pm, &pd, &n);
  for (int i = 0; i < n; ++i)
    if (pd[i] && std::strcmp(pd[i], name) == 0) return true;
  return false;
}
}  // namespace

bool plot_drivers_available() {
  std::lock_guard<std::mutex> lock(plplot_mutex);
  return has_device("pngcairo") && has_device("svgcairo");
}

void save_plot(const fs::path& path, const LinePlot& plot) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  const char* device = ext == ".png" ? "pngcairo" : ext == ".svg" ? "svgcairo" : nullptr;
  if (!device) throw InputError(path.string() + ": unknown plot format (.png or .svg)");
  if (plot.x.empty() || plot.series.empty()) throw InputError(path.string() + ": nothing to plot");
  for (const PlotSeries& s : plot.series)
    if (s.y.size() != plot.x.size()) throw std::invalid_argument("save_plot: a series has the wrong length");

  double xmin = *std::min_element(plot.x.begin(), plot.x.end());
  double xmax = *std::max_element(plot.x.begin(), plot.x.end());
  if (!(xmax > xmin)) xmax = xmin + 1;
  double ymin = INFINITY, ymax = -INFINITY;
  for (const PlotSeries& s : plot.series)
    for (double y : s.y)
      if (std::isfinite(y)) {
        ymin = std::min(ymin, y);
        ymax = std::max(ymax, y);
      }
  if (!std::isfinite(ymin)) ymin = ymax = 0;
  const double mid = 0.5 * (ymin + ymax);
  double span = std::max(ymax - ymin, plot.min_y_span) * 1.15;
  ymin = mid - 0.5 * span;
  ymax = mid + 0.5 * span;

  std::lock_guard<std::mutex> lock(plplot_mutex);
  if (!has_device(device))
    throw InputError(path.string() + ": PLplot has no " + device + " driver (install plplot-driver-cairo)");
  write_atomically(path, [&](const fs::path& tmp) {
    PLINT previous = 0, stream = 0;
    plgstrm(&previous);
    plmkstrm(&stream);
    if (stream < 0) throw InputError(path.string() + ": no free PLplot stream");
    plsdev(device);
    plsfnam(tmp.c_str());
    plspage(0, 0, plot.width, plot.height, 0, 0);
    plscolbg(255, 255, 255);
    plscol0(1, 0, 0, 0);        // axes, labels
    plscol0(2, 200, 200, 200);  // grid
    const int n = static_cast<int>(plot.series.size());
    for (int i = 0; i < n && i < 12; ++i) {
      const Eigen::Vector3f c = plot.series[static_cast<size_t>(i)].rgb.cwiseMax(0).cwiseMin(1) * 255.0f;
      plscol0(3 + i, static_cast<PLINT>(c.x()), static_cast<PLINT>(c.y()), static_cast<PLINT>(c.z()));
    }
    plinit();
    plcol0(1);
    plschr(0, 1.1);
    plenv(xmin, xmax, ymin, ymax, 0, 2);  // 2: axes, ticks, labels and a grid at the major ticks
    pllab(plot.x_label.c_str(), plot.y_label.c_str(), plot.title.c_str());
    std::vector<PLINT> opts, colours, styles, text_colours;
    std::vector<PLFLT> widths;
    std::vector<const char*> labels;
    for (int i = 0; i < n; ++i) {
      const PlotSeries& s = plot.series[static_cast<size_t>(i)];
      const PLINT colour = 3 + (i % 12);
      plcol0(colour);
      plwidth(2.5);
      plline(static_cast<PLINT>(plot.x.size()), plot.x.data(), s.y.data());
      opts.push_back(PL_LEGEND_LINE);
      colours.push_back(colour);
      styles.push_back(1);
      widths.push_back(2.5);
      text_colours.push_back(1);
      labels.push_back(s.label.c_str());
    }
    plwidth(1);
    PLFLT lw = 0, lh = 0;
    pllegend(&lw, &lh, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX, PL_POSITION_TOP | PL_POSITION_RIGHT | PL_POSITION_INSIDE,
             0.02, 0.02, 0.08, 0, 1, 1, 0, 0, n, opts.data(), 1.0, 0.9, 2.0, 0.0, text_colours.data(),
             labels.data(), nullptr, nullptr, nullptr, nullptr, colours.data(), styles.data(), widths.data(), nullptr,
             nullptr, nullptr, nullptr);
    plend1();
    plsstrm(previous);
    std::error_code ec;
    if (!fs::exists(tmp, ec) || fs::file_size(tmp, ec) == 0)
      throw InputError(path.string() + ": PLplot wrote nothing");
  });
}

}  // namespace squeeze::render
