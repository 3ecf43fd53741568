// SPDX-License-Identifier: MIT
// A small plotting layer on cairo: one framed plot with a title, a legend row under the title (so it
// never covers data), ticked axes labelled with their units, and line, scatter, band, arrow and grouped
// bar series. Long line series are reduced to min/max per output column before drawing.
#pragma once

#include <cairo.h>

#include <optional>
#include <string>
#include <vector>

#include "draw.hpp"

namespace ballbar::report {

/// "Nice" tick positions (1, 2, 5 × 10^k) covering [lo, hi] with about `target` intervals.
struct Ticks {
    double step = 1;
    std::vector<double> values;
    int decimals = 0;  ///< digits after the point that tell the ticks apart
};
Ticks nice_ticks(double lo, double hi, int target);
/// A tick label: fixed point with `decimals`, "−" for negative numbers, no "-0".
std::string tick_label(double v, int decimals);

struct Arrow {
    double x = 0, y = 0, dx = 0, dy = 0;  ///< from (x, y) to (x + dx, y + dy), data units
};

class Plot {
  public:
    explicit Plot(std::string title) : title_(std::move(title)) {}

    /// Axis titles are drawn "label (unit)".
    Plot& x_axis(std::string label, std::string unit);
    Plot& y_axis(std::string label, std::string unit);
    Plot& x_range(double lo, double hi);
    Plot& y_range(double lo, double hi);
    /// One data unit is the same length on both axes (to-scale projections).
    Plot& equal_aspect();
    /// Always include y = 0 in the range.
    Plot& include_zero_y();
    /// A note drawn in the top-right corner of the legend row (e.g. an arrow scale).
    Plot& note(std::string text);
    /// Each bar's value written above it with `decimals` decimals: a bar too small to read against its
    /// neighbours (an "after" next to its "before") still says what it is.
    Plot& bar_values(int decimals);

    void line(std::string name, std::vector<double> x, std::vector<double> y, Rgb color, double width = 0.7);
    void scatter(std::string name, std::vector<double> x, std::vector<double> y, Rgb color, double radius = 1.4,
                 bool hollow = false);
    /// Points with a vertical error bar each (± errors[i], data units; 0 or NaN: none).
    void scatter_errors(std::string name, std::vector<double> x, std::vector<double> y, std::vector<double> errors,
                        Rgb color, double radius = 1.8);
    /// Vertical shaded bands [x0, x1] (one legend entry for all).
    void bands(std::string name, std::vector<std::pair<double, double>> spans, Rgb color);
    void arrows(std::string name, std::vector<Arrow> arrows, Rgb color);
    /// Grouped bars over categories: each group holds one value per category (and an optional ± error).
    void bar_categories(std::vector<std::string> categories);
    void bars(std::string name, std::vector<double> values, Rgb color, std::vector<double> errors = {});

    void draw(cairo_t* cr, Rect area) const;

  private:
    enum class Kind { Line, Scatter, Bands, Arrows, Bars };
    struct Series {
        Kind kind;
        std::string name;
        Rgb color;
        double size = 1;
        bool hollow = false;
        std::vector<double> x, y, errors;
        std::vector<std::pair<double, double>> spans;
        std::vector<Arrow> arrows;
    };
    struct Bounds {
        double x0, x1, y0, y1;
    };
    Bounds data_bounds() const;
    /// Lays out (and with `paint`, draws) the legend from the top-left of `row`; returns its rows.
    int draw_legend(cairo_t* cr, Rect row, bool paint) const;
    void draw_series(cairo_t* cr, const Series& s, Rect plot, const Bounds& b, int index) const;

    std::string title_, note_;
    std::optional<int> bar_value_decimals_;
    std::string x_label_, x_unit_, y_label_, y_unit_;
    std::optional<std::pair<double, double>> x_range_, y_range_;
    bool equal_ = false, zero_y_ = false;
    std::vector<std::string> categories_;
    std::vector<Series> series_;
};

}  // namespace ballbar::report
