// SPDX-License-Identifier: MIT
// Reduction of long series for plotting: per column of the plot, the first, smallest, largest and last
// point, in their original order ("M4"). A line through the kept points looks like the line through all
// of them at that resolution, and every column's extremes are kept exactly.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace ballbar::report {

struct XYSeries {
    std::vector<double> x, y;
};

/// Keeps at most four points per column of `columns` equal-width columns spanning [x_min, x_max]
/// (points outside go to the first/last column). `x` must be non-decreasing and as long as `y`; series
/// of at most 4·columns points are returned unchanged. Throws std::invalid_argument otherwise.
XYSeries decimate_minmax(std::span<const double> x, std::span<const double> y, double x_min, double x_max,
                         std::size_t columns);

/// Streaming form: feed points one by one (x non-decreasing), then take the result. Used to reduce a
/// million samples read from the database without holding them all.
class MinMaxDecimator {
  public:
    MinMaxDecimator(double x_min, double x_max, std::size_t columns);
    void add(double x, double y);
    /// The kept points so far (closes the current column).
    XYSeries take();
    std::size_t seen() const { return seen_; }

  private:
    void flush();
    std::size_t column_of(double x) const;

    double x_min_, width_;
    std::size_t columns_;
    std::size_t seen_ = 0;
    bool open_ = false;
    std::size_t col_ = 0;
    std::size_t n_ = 0;  // points in the open column
    double fx_ = 0, fy_ = 0, lx_ = 0, ly_ = 0, minx_ = 0, miny_ = 0, maxx_ = 0, maxy_ = 0;
    std::size_t fi_ = 0, li_ = 0, mini_ = 0, maxi_ = 0;
    XYSeries out_;
};

}  // namespace ballbar::report
