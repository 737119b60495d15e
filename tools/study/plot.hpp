#pragma once
// Minimal 2-D plots drawn with OpenCV (axes, ticks, labels, legend) for docs/img/*.png: scatter
// series and line series on linear axes. Values beyond the chosen range are clipped to the frame.
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace naneye::tools::study {

struct Series {
  std::string label;
  cv::Scalar color;  // BGR
  std::vector<double> x, y;
  bool line = false;  // joined by a polyline (in the given order) instead of dots
  int size = 2;       // dot radius or line thickness, px
};

struct Figure {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  // Axis ranges; empty: from the data (x: min..max; y: 0..the 99th percentile, so that a few outliers do
  // not flatten everything else).
  std::optional<double> x_min, x_max, y_min, y_max;
};

inline constexpr int kPlotWidth = 960, kPlotHeight = 600;

cv::Mat draw_figure(const Figure& f, cv::Size size = {kPlotWidth, kPlotHeight});
// Draws and writes a PNG; throws std::runtime_error when it cannot be written.
void save_figure(const Figure& f, const std::filesystem::path& file);

// Binned mean of y over x: bins of `width` from x_min, empty bins skipped (for line series over clouds).
Series binned_mean(const Series& cloud, double width, std::string label, cv::Scalar color);

}  // namespace naneye::tools::study
