// SPDX-License-Identifier: MIT
#include "plot.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ballbar/report/decimate.hpp"

namespace ballbar::report {

namespace {
constexpr double kTitleSize = 8.5;
constexpr double kLabelSize = 7.0;
constexpr double kTickSize = 6.5;
constexpr double kLegendSize = 6.5;
constexpr double kTickLen = 3.0;

double finite_or(double v, double fallback) {
    return std::isfinite(v) ? v : fallback;
}

void widen(double& lo, double& hi) {
    if (!(hi > lo)) {
        const double pad = lo == 0 ? 1.0 : std::abs(lo) * 0.1;
        lo -= pad;
        hi += pad;
    }
}
}  // namespace

Ticks nice_ticks(double lo, double hi, int target) {
    Ticks t;
    widen(lo, hi);
    const double raw = (hi - lo) / std::max(1, target);
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double f = raw / mag;
    const double nice = f <= 1 ? 1 : f <= 2 ? 2 : f <= 2.5 ? 2.5 : f <= 5 ? 5 : 10;
    t.step = nice * mag;
    t.decimals = std::max(0, static_cast<int>(-std::floor(std::log10(t.step) + 1e-9)));
    if (nice == 2.5 && mag < 1.5) ++t.decimals;  // 2.5, 0.25, …: one digit more than the magnitude
    const double first = std::ceil(lo / t.step - 1e-9);
    // At most a few dozen ticks, even when the range is tiny against its magnitude (k + 1 == k in doubles).
    for (int i = 0; i < 64; ++i) {
        const double v = (first + i) * t.step;
        if (v > hi + t.step * 1e-9) break;
        t.values.push_back(v);
    }
    return t;
}

std::string tick_label(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    std::string s(buf);
    if (s.find_first_not_of("-0.") == std::string::npos) return std::string(s.begin() + (s[0] == '-'), s.end());
    if (s[0] == '-') return "−" + s.substr(1);
    return s;
}

Plot& Plot::x_axis(std::string label, std::string unit) {
    x_label_ = std::move(label);
    x_unit_ = std::move(unit);
    return *this;
}
Plot& Plot::y_axis(std::string label, std::string unit) {
    y_label_ = std::move(label);
    y_unit_ = std::move(unit);
    return *this;
}
Plot& Plot::x_range(double lo, double hi) {
    x_range_ = {lo, hi};
    return *this;
}
Plot& Plot::y_range(double lo, double hi) {
    y_range_ = {lo, hi};
    return *this;
}
Plot& Plot::equal_aspect() {
    equal_ = true;
    return *this;
}
Plot& Plot::include_zero_y() {
    zero_y_ = true;
    return *this;
}
Plot& Plot::note(std::string text) {
    note_ = std::move(text);
    return *this;
}

void Plot::line(std::string name, std::vector<double> x, std::vector<double> y, Rgb color, double width) {
    series_.push_back({Kind::Line, std::move(name), color, width, false, std::move(x), std::move(y), {}, {}, {}});
}
void Plot::scatter(std::string name, std::vector<double> x, std::vector<double> y, Rgb color, double radius,
                   bool hollow) {
    series_.push_back({Kind::Scatter, std::move(name), color, radius, hollow, std::move(x), std::move(y), {}, {}, {}});
}
void Plot::scatter_errors(std::string name, std::vector<double> x, std::vector<double> y, std::vector<double> errors,
                          Rgb color, double radius) {
    series_.push_back(
        {Kind::Scatter, std::move(name), color, radius, false, std::move(x), std::move(y), std::move(errors), {}, {}});
}
void Plot::bands(std::string name, std::vector<std::pair<double, double>> spans, Rgb color) {
    series_.push_back({Kind::Bands, std::move(name), color, 1, false, {}, {}, {}, std::move(spans), {}});
}
void Plot::arrows(std::string name, std::vector<Arrow> arrows, Rgb color) {
    series_.push_back({Kind::Arrows, std::move(name), color, 0.9, false, {}, {}, {}, {}, std::move(arrows)});
}
Plot& Plot::bar_values(int decimals) {
    bar_value_decimals_ = decimals;
    return *this;
}

void Plot::bar_categories(std::vector<std::string> categories) {
    categories_ = std::move(categories);
}
void Plot::bars(std::string name, std::vector<double> values, Rgb color, std::vector<double> errors) {
    series_.push_back({Kind::Bars, std::move(name), color, 1, false, {}, std::move(values), std::move(errors), {}, {}});
}

Plot::Bounds Plot::data_bounds() const {
    constexpr double inf = std::numeric_limits<double>::infinity();
    Bounds b{inf, -inf, inf, -inf};
    auto add_x = [&](double v) {
        if (std::isfinite(v)) b.x0 = std::min(b.x0, v), b.x1 = std::max(b.x1, v);
    };
    auto add_y = [&](double v) {
        if (std::isfinite(v)) b.y0 = std::min(b.y0, v), b.y1 = std::max(b.y1, v);
    };
    for (const auto& s : series_) {
        switch (s.kind) {
            case Kind::Line:
            case Kind::Scatter:
                for (double v : s.x) add_x(v);
                for (std::size_t i = 0; i < s.y.size(); ++i) {
                    const double e = i < s.errors.size() ? std::abs(finite_or(s.errors[i], 0)) : 0;
                    add_y(s.y[i] + e);
                    add_y(s.y[i] - e);
                }
                break;
            case Kind::Bands:
                for (const auto& [a, c] : s.spans) add_x(a), add_x(c);
                break;
            case Kind::Arrows:
                for (const auto& a : s.arrows) add_x(a.x), add_x(a.x + a.dx), add_y(a.y), add_y(a.y + a.dy);
                break;
            case Kind::Bars:
                for (std::size_t i = 0; i < s.y.size(); ++i) {
                    const double e = i < s.errors.size() ? std::abs(finite_or(s.errors[i], 0)) : 0;
                    add_y(s.y[i] + e);
                    add_y(s.y[i] - e);
                }
                break;
        }
    }
    if (!categories_.empty()) b.x0 = -0.5, b.x1 = static_cast<double>(categories_.size()) - 0.5;
    if (zero_y_ || !categories_.empty()) add_y(0);
    if (!std::isfinite(b.x0)) b.x0 = 0, b.x1 = 1;
    if (!std::isfinite(b.y0)) b.y0 = 0, b.y1 = 1;
    if (x_range_) b.x0 = x_range_->first, b.x1 = x_range_->second;
    if (y_range_) b.y0 = y_range_->first, b.y1 = y_range_->second;
    widen(b.x0, b.x1);
    widen(b.y0, b.y1);
    if (bar_value_decimals_) b.y1 += 0.08 * (b.y1 - b.y0);  // room for the values above the tallest bars
    return b;
}

void Plot::draw(cairo_t* cr, Rect area) const {
    cairo_save(cr);
    Bounds b = data_bounds();

    // Title, then the legend row, then the plot frame with room for tick labels and axis titles.
    set_color(cr, kBlack);
    set_font(cr, kTitleSize, true);
    draw_text(cr, area.x, area.y, fit_text(cr, title_, area.w), HAlign::Left, VAlign::Top);
    const double legend_y = area.y + kTitleSize + 4;
    const bool has_legend = std::any_of(series_.begin(), series_.end(), [](const auto& s) { return !s.name.empty(); });
    const double legend_w = area.w - (kLabelSize + 4);
    const int legend_rows = has_legend || !note_.empty() ? draw_legend(cr, {area.x, legend_y, legend_w, 0}, false) : 0;
    // The y axis's top tick label is centred on the frame's top edge: half a label of room below the
    // legend, so the two never overlap.
    const double top = legend_y + (legend_rows > 0 ? legend_rows * (kLegendSize + 4) + kLabelSize / 2.0 + 2 : 2);

    // Pad the data range by 4 % (not for categories or explicit ranges) and find ticks.
    if (categories_.empty() && !x_range_) {
        const double p = (b.x1 - b.x0) * (equal_ ? 0.08 : 0.0);
        b.x0 -= p, b.x1 += p;
    }
    if (!y_range_) {
        const double p = (b.y1 - b.y0) * 0.06;
        b.y0 = (zero_y_ && b.y0 == 0) ? 0 : b.y0 - p;
        b.y1 += p;
    }
    set_font(cr, kTickSize);
    Ticks yt = nice_ticks(b.y0, b.y1, 5);
    double ytw = 0;
    for (double v : yt.values) ytw = std::max(ytw, text_width(cr, tick_label(v, yt.decimals)));
    Rect plot{area.x + kLabelSize + 4 + ytw + kTickLen + 2, top, 0, 0};
    plot.w = area.right() - plot.x - 4;
    plot.h = area.bottom() - top - (kTickSize + kTickLen + 3) - (kLabelSize + 5);

    if (equal_) {  // same scale on both axes: grow the range of the axis that has room to spare
        const double sx = (b.x1 - b.x0) / plot.w, sy = (b.y1 - b.y0) / plot.h;
        if (sx > sy) {
            const double c = (b.y0 + b.y1) / 2, h = sx * plot.h / 2;
            b.y0 = c - h, b.y1 = c + h;
        } else {
            const double c = (b.x0 + b.x1) / 2, h = sy * plot.w / 2;
            b.x0 = c - h, b.x1 = c + h;
        }
        yt = nice_ticks(b.y0, b.y1, 5);
    }
    const Ticks xt = nice_ticks(b.x0, b.x1, std::max(3, static_cast<int>(plot.w / 55)));
    auto px = [&](double x) { return plot.x + (x - b.x0) / (b.x1 - b.x0) * plot.w; };
    auto py = [&](double y) { return plot.bottom() - (y - b.y0) / (b.y1 - b.y0) * plot.h; };

    // Grid and ticks.
    cairo_set_line_width(cr, 0.3);
    set_color(cr, kLightGrey);
    for (double v : yt.values) {
        if (v < b.y0 || v > b.y1) continue;
        cairo_move_to(cr, plot.x, py(v));
        cairo_line_to(cr, plot.right(), py(v));
    }
    if (categories_.empty())
        for (double v : xt.values) {
            if (v < b.x0 || v > b.x1) continue;
            cairo_move_to(cr, px(v), plot.y);
            cairo_line_to(cr, px(v), plot.bottom());
        }
    cairo_stroke(cr);
    set_color(cr, kBlack);
    set_font(cr, kTickSize);
    cairo_set_line_width(cr, 0.5);
    for (double v : yt.values) {
        if (v < b.y0 || v > b.y1) continue;
        cairo_move_to(cr, plot.x - kTickLen, py(v));
        cairo_line_to(cr, plot.x, py(v));
        draw_text(cr, plot.x - kTickLen - 2, py(v), tick_label(v, yt.decimals), HAlign::Right, VAlign::Middle);
    }
    if (categories_.empty()) {
        for (double v : xt.values) {
            if (v < b.x0 || v > b.x1) continue;
            cairo_move_to(cr, px(v), plot.bottom());
            cairo_line_to(cr, px(v), plot.bottom() + kTickLen);
            draw_text(cr, px(v), plot.bottom() + kTickLen + 1, tick_label(v, xt.decimals), HAlign::Center, VAlign::Top);
        }
    } else {
        const double slot = plot.w / static_cast<double>(categories_.size());
        for (std::size_t i = 0; i < categories_.size(); ++i)
            draw_text(cr, px(static_cast<double>(i)), plot.bottom() + kTickLen + 1,
                      fit_text(cr, categories_[i], slot - 2), HAlign::Center, VAlign::Top);
    }
    cairo_stroke(cr);

    // Axis titles.
    set_font(cr, kLabelSize);
    auto title = [](const std::string& l, const std::string& u) { return u.empty() ? l : l + " (" + u + ")"; };
    if (!x_label_.empty() || !x_unit_.empty())
        draw_text(cr, plot.x + plot.w / 2, area.bottom(), fit_text(cr, title(x_label_, x_unit_), plot.w),
                  HAlign::Center, VAlign::Bottom);
    if (!y_label_.empty() || !y_unit_.empty())
        draw_text_vertical(cr, area.x + kLabelSize / 2 + 1, plot.y + plot.h / 2,
                           fit_text(cr, title(y_label_, y_unit_), plot.h));

    // Series, clipped to the frame.
    cairo_save(cr);
    cairo_rectangle(cr, plot.x, plot.y, plot.w, plot.h);
    cairo_clip(cr);
    if (b.y0 < 0 && b.y1 > 0) {
        set_color(cr, kGrey);
        cairo_set_line_width(cr, 0.4);
        cairo_move_to(cr, plot.x, py(0));
        cairo_line_to(cr, plot.right(), py(0));
        cairo_stroke(cr);
    }
    int bar_index = 0;
    for (const auto& s : series_) {
        if (s.kind == Kind::Bands) draw_series(cr, s, plot, b, 0);  // bands under everything else
    }
    for (const auto& s : series_) {
        if (s.kind == Kind::Bands) continue;
        draw_series(cr, s, plot, b, s.kind == Kind::Bars ? bar_index++ : 0);
    }
    cairo_restore(cr);

    set_color(cr, kBlack);
    cairo_set_line_width(cr, 0.6);
    cairo_rectangle(cr, plot.x, plot.y, plot.w, plot.h);
    cairo_stroke(cr);
    if (legend_rows > 0) draw_legend(cr, {area.right() - legend_w, legend_y, legend_w, kLegendSize + 4}, true);
    cairo_restore(cr);
}

void Plot::draw_series(cairo_t* cr, const Series& s, Rect plot, const Bounds& b, int index) const {
    auto px = [&](double x) { return plot.x + (x - b.x0) / (b.x1 - b.x0) * plot.w; };
    auto py = [&](double y) { return plot.bottom() - (y - b.y0) / (b.y1 - b.y0) * plot.h; };
    set_color(cr, s.color);
    switch (s.kind) {
        case Kind::Line: {
            // At most four points per quarter point of width: far finer than any printer, and bounded.
            const auto cols = static_cast<std::size_t>(std::max(1.0, plot.w * 4));
            const XYSeries d = decimate_minmax(s.x, s.y, b.x0, b.x1, cols);
            cairo_set_line_width(cr, s.size);
            cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
            bool pen = false;
            for (std::size_t i = 0; i < d.x.size(); ++i) {
                if (!std::isfinite(d.x[i]) || !std::isfinite(d.y[i])) {
                    pen = false;
                    continue;
                }
                if (pen)
                    cairo_line_to(cr, px(d.x[i]), py(d.y[i]));
                else
                    cairo_move_to(cr, px(d.x[i]), py(d.y[i]));
                pen = true;
            }
            cairo_stroke(cr);
            break;
        }
        case Kind::Scatter:
            cairo_set_line_width(cr, 0.5);
            for (std::size_t i = 0; i < std::min({s.x.size(), s.y.size(), s.errors.size()}); ++i) {
                const double e = std::abs(finite_or(s.errors[i], 0));
                if (e == 0 || !std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
                const double x = px(s.x[i]);  // the error bar: ± e, with caps
                cairo_move_to(cr, x, py(s.y[i] - e));
                cairo_line_to(cr, x, py(s.y[i] + e));
                for (double end : {s.y[i] - e, s.y[i] + e}) {
                    cairo_move_to(cr, x - 1.8, py(end));
                    cairo_line_to(cr, x + 1.8, py(end));
                }
                cairo_stroke(cr);
            }
            for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
                if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
                cairo_new_sub_path(cr);
                cairo_arc(cr, px(s.x[i]), py(s.y[i]), s.size, 0, 2 * 3.141592653589793);
                if (s.hollow)
                    cairo_stroke(cr);
                else
                    cairo_fill(cr);
            }
            break;
        case Kind::Bands:
            set_color(cr, s.color, 0.25);
            for (const auto& [a, c] : s.spans) {
                const double x0 = px(a), x1 = std::max(px(c), x0 + 0.4);  // visible even when short
                cairo_rectangle(cr, x0, plot.y, x1 - x0, plot.h);
            }
            cairo_fill(cr);
            break;
        case Kind::Arrows:
            cairo_set_line_width(cr, s.size);
            for (const auto& a : s.arrows) {
                const double x0 = px(a.x), y0 = py(a.y), x1 = px(a.x + a.dx), y1 = py(a.y + a.dy);
                cairo_new_sub_path(cr);
                cairo_arc(cr, x0, y0, 1.3, 0, 2 * 3.141592653589793);
                cairo_fill(cr);
                const double len = std::hypot(x1 - x0, y1 - y0);
                if (len < 0.5) continue;
                const double ux = (x1 - x0) / len, uy = (y1 - y0) / len, head = std::min(4.0, len * 0.4);
                cairo_move_to(cr, x0, y0);
                cairo_line_to(cr, x1 - ux * head * 0.8, y1 - uy * head * 0.8);
                cairo_stroke(cr);
                cairo_move_to(cr, x1, y1);
                cairo_line_to(cr, x1 - ux * head - uy * head * 0.4, y1 - uy * head + ux * head * 0.4);
                cairo_line_to(cr, x1 - ux * head + uy * head * 0.4, y1 - uy * head - ux * head * 0.4);
                cairo_close_path(cr);
                cairo_fill(cr);
            }
            break;
        case Kind::Bars: {
            const auto groups = static_cast<double>(
                std::count_if(series_.begin(), series_.end(), [](const auto& t) { return t.kind == Kind::Bars; }));
            const double slot = plot.w / static_cast<double>(std::max<std::size_t>(1, categories_.size()));
            const double bw = slot * 0.7 / groups;
            for (std::size_t i = 0; i < s.y.size() && i < categories_.size(); ++i) {
                if (!std::isfinite(s.y[i])) continue;
                const double x0 = px(static_cast<double>(i)) - slot * 0.35 + bw * index;
                set_color(cr, s.color);
                cairo_rectangle(cr, x0, std::min(py(0), py(s.y[i])), bw, std::abs(py(s.y[i]) - py(0)));
                cairo_fill(cr);
                if (bar_value_decimals_) {
                    set_color(cr, kBlack);
                    set_font(cr, 5.5);
                    const bool up = s.y[i] >= 0;
                    draw_text(cr, x0 + bw / 2, py(s.y[i]) + (up ? -1.5 : 1.5),
                              fmt::format("{:.{}f}", s.y[i], *bar_value_decimals_), HAlign::Center,
                              up ? VAlign::Bottom : VAlign::Top);
                }
                if (i < s.errors.size() && std::isfinite(s.errors[i]) && s.errors[i] > 0) {
                    set_color(cr, kBlack);
                    cairo_set_line_width(cr, 0.5);
                    const double xc = x0 + bw / 2, e0 = py(s.y[i] - s.errors[i]), e1 = py(s.y[i] + s.errors[i]);
                    cairo_move_to(cr, xc, e0);
                    cairo_line_to(cr, xc, e1);
                    cairo_move_to(cr, xc - bw * 0.2, e0);
                    cairo_line_to(cr, xc + bw * 0.2, e0);
                    cairo_move_to(cr, xc - bw * 0.2, e1);
                    cairo_line_to(cr, xc + bw * 0.2, e1);
                    cairo_stroke(cr);
                }
            }
            break;
        }
    }
}

int Plot::draw_legend(cairo_t* cr, Rect row, bool paint) const {
    set_font(cr, kLegendSize);
    const double line_h = kLegendSize + 4;
    double x = row.x;
    double cy = row.y + line_h / 2;
    int rows = 1;
    const double note_w = note_.empty() ? 0 : text_width(cr, note_) + 8;
    for (const auto& s : series_) {
        if (s.name.empty()) continue;
        const double w = 14 + text_width(cr, s.name) + 10;
        if (x > row.x && x + w > row.right() - (rows == 1 ? note_w : 0)) {  // wrap rather than overlap
            x = row.x;
            cy += line_h;
            ++rows;
        }
        if (!paint) {
            x += w;
            continue;
        }
        set_color(cr, s.color, s.kind == Kind::Bands ? 0.35 : 1.0);
        switch (s.kind) {
            case Kind::Line:
                cairo_set_line_width(cr, std::max(1.0, s.size));
                cairo_move_to(cr, x, cy);
                cairo_line_to(cr, x + 11, cy);
                cairo_stroke(cr);
                break;
            case Kind::Scatter:
                cairo_set_line_width(cr, 0.5);
                cairo_arc(cr, x + 5.5, cy, std::max(2.2, s.size), 0, 2 * 3.141592653589793);
                if (s.hollow)
                    cairo_stroke(cr);
                else
                    cairo_fill(cr);
                break;
            case Kind::Arrows:
                cairo_set_line_width(cr, 0.9);
                cairo_move_to(cr, x, cy);
                cairo_line_to(cr, x + 8, cy);
                cairo_stroke(cr);
                cairo_move_to(cr, x + 11, cy);
                cairo_line_to(cr, x + 7, cy - 2);
                cairo_line_to(cr, x + 7, cy + 2);
                cairo_close_path(cr);
                cairo_fill(cr);
                break;
            case Kind::Bands:
            case Kind::Bars:
                cairo_rectangle(cr, x, cy - 3, 11, 6);
                cairo_fill(cr);
                break;
        }
        set_color(cr, kBlack);
        draw_text(cr, x + 14, cy, s.name, HAlign::Left, VAlign::Middle);
        x += w;
    }
    if (!note_.empty() && paint) {
        set_color(cr, kGrey);
        draw_text(cr, row.right(), row.y + line_h / 2, note_, HAlign::Right, VAlign::Middle);
    }
    return rows;
}

}  // namespace ballbar::report
