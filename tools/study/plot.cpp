#include "plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace naneye::tools::study {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kInk(30, 30, 30), kGrid(225, 225, 225);

// A "nice" tick step (1, 2 or 5 times a power of ten) giving about `target` intervals over `range`.
double tick_step(double range, int target) {
  const double raw = range / target;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10 * p;
}

std::string tick_text(double v, double step) {
  char buf[32];
  const int decimals = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return buf;
}

void put_text(cv::Mat& img, const std::string& text, cv::Point at, double scale, int thickness = 1,
              bool centred = false) {
  int base = 0;
  const cv::Size sz = cv::getTextSize(text, kFont, scale, thickness, &base);
  if (centred) at.x -= sz.width / 2;
  cv::putText(img, text, at, kFont, scale, kInk, thickness, cv::LINE_AA);
}

struct Range {
  double lo, hi;
};

// x: the data's extent. y: from 0 (or below) to the 99th percentile of the dots, so that a few outliers
// do not flatten the cloud, but high enough for every line (lines are summaries: they stay whole).
Range data_range(const Figure& f, bool x_axis) {
  std::vector<double> v;
  double line_max = -std::numeric_limits<double>::infinity();
  for (const auto& s : f.series) {
    for (const double d : x_axis ? s.x : s.y) {
      if (!std::isfinite(d)) continue;
      if (s.line && !x_axis)
        line_max = std::max(line_max, d);
      else
        v.push_back(d);
    }
  }
  if (!x_axis && std::isfinite(line_max)) v.push_back(line_max);
  if (v.empty()) return {0, 1};
  std::sort(v.begin(), v.end());
  if (x_axis) return {v.front(), v.back()};
  double top = v[static_cast<std::size_t>(0.99 * static_cast<double>(v.size() - 1))];
  if (std::isfinite(line_max)) top = std::max(top, line_max);
  return {std::min(0.0, v.front()), top > 0 ? top * 1.08 : 1.0};
}

}  // namespace

cv::Mat draw_figure(const Figure& f, cv::Size size) {
  cv::Mat img(size, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 90, right = 24, top = 50, bottom = 70;
  const cv::Rect frame(left, top, size.width - left - right, size.height - top - bottom);

  Range xr = data_range(f, true), yr = data_range(f, false);
  if (f.x_min) xr.lo = *f.x_min;
  if (f.x_max) xr.hi = *f.x_max;
  if (f.y_min) yr.lo = *f.y_min;
  if (f.y_max) yr.hi = *f.y_max;
  if (!(xr.hi > xr.lo)) xr.hi = xr.lo + 1;
  if (!(yr.hi > yr.lo)) yr.hi = yr.lo + 1;
  const auto to_px = [&](double x, double y) {
    x = std::clamp(x, xr.lo, xr.hi);
    y = std::clamp(y, yr.lo, yr.hi);
    return cv::Point2d(frame.x + (x - xr.lo) / (xr.hi - xr.lo) * frame.width,
                       frame.y + frame.height - (y - yr.lo) / (yr.hi - yr.lo) * frame.height);
  };

  // Grid and ticks.
  const double xs = tick_step(xr.hi - xr.lo, 8), ys = tick_step(yr.hi - yr.lo, 6);
  for (double x = std::ceil(xr.lo / xs) * xs; x <= xr.hi + xs * 1e-9; x += xs) {
    const cv::Point2d p = to_px(x, yr.lo);
    cv::line(img, {static_cast<int>(p.x), frame.y}, {static_cast<int>(p.x), frame.y + frame.height}, kGrid);
    cv::line(img, p, p + cv::Point2d(0, 6), kInk);
    put_text(img, tick_text(x, xs), {static_cast<int>(p.x), frame.y + frame.height + 24}, 0.5, 1, true);
  }
  for (double y = std::ceil(yr.lo / ys) * ys; y <= yr.hi + ys * 1e-9; y += ys) {
    const cv::Point2d p = to_px(xr.lo, y);
    cv::line(img, {frame.x, static_cast<int>(p.y)}, {frame.x + frame.width, static_cast<int>(p.y)}, kGrid);
    cv::line(img, p, p - cv::Point2d(6, 0), kInk);
    const std::string t = tick_text(y, ys);
    int base = 0;
    const int w = cv::getTextSize(t, kFont, 0.5, 1, &base).width;
    put_text(img, t, {frame.x - 10 - w, static_cast<int>(p.y) + 5}, 0.5);
  }

  // Data, clipped to the frame.
  cv::Mat plot = img(frame);
  const cv::Point2d origin(frame.x, frame.y);
  for (const auto& s : f.series) {
    if (s.line) {
      std::vector<cv::Point> pts;
      for (std::size_t i = 0; i < s.x.size(); ++i) {
        if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) pts.emplace_back(to_px(s.x[i], s.y[i]) - origin);
      }
      if (pts.size() >= 2) cv::polylines(plot, pts, false, s.color, s.size, cv::LINE_AA);
    } else {
      for (std::size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
        cv::circle(plot, to_px(s.x[i], s.y[i]) - origin, s.size, s.color, cv::FILLED, cv::LINE_AA);
      }
    }
  }
  cv::rectangle(img, frame, kInk, 1);

  // Title, axis labels (the y label turned by 90 degrees), legend.
  put_text(img, f.title, {size.width / 2, 32}, 0.7, 2, true);
  put_text(img, f.x_label, {frame.x + frame.width / 2, size.height - 18}, 0.6, 1, true);
  {
    int base = 0;
    const cv::Size ts = cv::getTextSize(f.y_label, kFont, 0.6, 1, &base);
    cv::Mat label(ts.height + base + 6, ts.width + 6, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(label, f.y_label, {3, ts.height + 2}, kFont, 0.6, kInk, 1, cv::LINE_AA);
    cv::rotate(label, label, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int y0 = std::max(0, frame.y + frame.height / 2 - label.rows / 2);
    const int h = std::min(label.rows, size.height - y0);
    label(cv::Rect(0, 0, label.cols, h)).copyTo(img(cv::Rect(8, y0, label.cols, h)));
  }
  int ly = frame.y + 12, lw = 0;
  for (const auto& s : f.series) {
    int base = 0;
    lw = std::max(lw, cv::getTextSize(s.label, kFont, 0.5, 1, &base).width);
  }
  const int lx = frame.x + 12;
  cv::rectangle(img, {lx - 6, ly - 8}, {lx + lw + 44, ly + 20 * static_cast<int>(f.series.size()) - 4},
                cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(img, {lx - 6, ly - 8}, {lx + lw + 44, ly + 20 * static_cast<int>(f.series.size()) - 4},
                kGrid);
  for (const auto& s : f.series) {
    if (s.line)
      cv::line(img, {lx, ly + 4}, {lx + 26, ly + 4}, s.color, std::max(2, s.size), cv::LINE_AA);
    else
      cv::circle(img, {lx + 13, ly + 4}, std::max(3, s.size), s.color, cv::FILLED, cv::LINE_AA);
    put_text(img, s.label, {lx + 36, ly + 9}, 0.5);
    ly += 20;
  }
  return img;
}

void save_figure(const Figure& f, const std::filesystem::path& file) {
  if (!cv::imwrite(file.string(), draw_figure(f))) throw std::runtime_error("cannot write " + file.string());
}

Series binned_mean(const Series& cloud, double width, std::string label, cv::Scalar color) {
  std::map<long, std::pair<double, int>> bins;
  for (std::size_t i = 0; i < cloud.x.size(); ++i) {
    if (!std::isfinite(cloud.x[i]) || !std::isfinite(cloud.y[i])) continue;
    auto& b = bins[static_cast<long>(std::floor(cloud.x[i] / width))];
    b.first += cloud.y[i];
    ++b.second;
  }
  Series s{std::move(label), color, {}, {}, true, 2};
  for (const auto& [k, b] : bins) {
    s.x.push_back((static_cast<double>(k) + 0.5) * width);
    s.y.push_back(b.first / b.second);
  }
  return s;
}

}  // namespace naneye::tools::study
