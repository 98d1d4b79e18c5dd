// squeeze::render — line plots through PLplot's cairo drivers (pngcairo, svgcairo).
#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace squeeze::render {

/// One curve of a line plot.
struct PlotSeries {
  std::string label;
  std::vector<double> y;  // one value per x
  Eigen::Vector3f rgb{0, 0, 0};  // sRGB in [0, 1]
};

/// A titled line plot with labelled axes (PLplot: axes, ticks, grid and legend by the library).
struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<double> x;
  std::vector<PlotSeries> series;
  int width = 1200, height = 700;  // pixels (PNG) or points (SVG)
  double min_y_span = 1.0;          // the y range spans at least this (flat curves stay readable)
};

/// Whether PLplot's cairo drivers ("pngcairo", "svgcairo") are installed (Debian:
/// plplot-driver-cairo).
bool plot_drivers_available();

/// Writes `plot` as PNG or SVG (chosen by the extension of `path`, .png or .svg) through a
/// temporary file renamed into place. Throws InputError ("PATH: problem") if the cairo driver is
/// missing, the series are empty or of the wrong length, or the file cannot be written.
void save_plot(const std::filesystem::path& path, const LinePlot& plot);

}  // namespace squeeze::render
