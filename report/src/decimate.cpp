// SPDX-License-Identifier: MIT
#include "ballbar/report/decimate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace ballbar::report {

MinMaxDecimator::MinMaxDecimator(double x_min, double x_max, std::size_t columns)
    : x_min_(x_min), width_(x_max - x_min), columns_(columns) {
    if (columns == 0) throw std::invalid_argument("decimation needs at least one column");
    if (!(x_max >= x_min) || !std::isfinite(x_min) || !std::isfinite(x_max))
        throw std::invalid_argument("decimation range is empty or not finite");
}

std::size_t MinMaxDecimator::column_of(double x) const {
    if (!(width_ > 0)) return 0;
    const double f = (x - x_min_) / width_ * static_cast<double>(columns_);
    if (!(f > 0)) return 0;
    if (f >= static_cast<double>(columns_)) return columns_ - 1;  // beyond the range (and no overflowing cast)
    return static_cast<std::size_t>(f);
}

void MinMaxDecimator::add(double x, double y) {
    const std::size_t c = column_of(x);
    if (open_ && c != col_) flush();
    if (!open_) {
        open_ = true;
        col_ = c;
        n_ = 0;
        fx_ = lx_ = minx_ = maxx_ = x;
        fy_ = ly_ = miny_ = maxy_ = y;
        fi_ = li_ = mini_ = maxi_ = seen_;
    } else {
        lx_ = x;
        ly_ = y;
        li_ = seen_;
        if (y < miny_) miny_ = y, minx_ = x, mini_ = seen_;
        if (y > maxy_) maxy_ = y, maxx_ = x, maxi_ = seen_;
    }
    ++n_;
    ++seen_;
}

void MinMaxDecimator::flush() {
    if (!open_) return;
    // First, min, max, last in the order they arrived; drop repeats of the same sample.
    std::array<std::pair<std::size_t, std::pair<double, double>>, 4> pts{
        {{fi_, {fx_, fy_}}, {mini_, {minx_, miny_}}, {maxi_, {maxx_, maxy_}}, {li_, {lx_, ly_}}}};
    std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::size_t last = static_cast<std::size_t>(-1);
    for (const auto& [i, p] : pts) {
        if (i == last) continue;
        last = i;
        out_.x.push_back(p.first);
        out_.y.push_back(p.second);
    }
    open_ = false;
}

XYSeries MinMaxDecimator::take() {
    flush();
    return std::move(out_);
}

XYSeries decimate_minmax(std::span<const double> x, std::span<const double> y, double x_min, double x_max,
                         std::size_t columns) {
    if (x.size() != y.size())
        throw std::invalid_argument("decimation: " + std::to_string(x.size()) + " x values but " +
                                    std::to_string(y.size()) + " y values");
    if (x.size() <= 4 * columns) return {{x.begin(), x.end()}, {y.begin(), y.end()}};
    MinMaxDecimator d(x_min, x_max, columns);
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (i > 0 && x[i] < x[i - 1])
            throw std::invalid_argument("decimation: x decreases at index " + std::to_string(i));
        d.add(x[i], y[i]);
    }
    return d.take();
}

}  // namespace ballbar::report
