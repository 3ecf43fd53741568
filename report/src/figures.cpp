// SPDX-License-Identifier: MIT
// The report's figures, each drawn into space reserved on the page.
#include "figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ballbar/analysis/types.hpp"
#include "format.hpp"
#include "plot.hpp"

namespace ballbar::report {

namespace {

/// 1, 2 or 5 × 10^k nearest below v (v > 0).
double nice_below(double v) {
    const double mag = std::pow(10.0, std::floor(std::log10(v)));
    const double f = v / mag;
    return (f >= 5 ? 5 : f >= 2 ? 2 : 1) * mag;
}

}  // namespace

void figure_trace(Document& doc, const Report& r) {
    const BarTrace& t = r.trace;
    const double span = t.time_s.empty() ? 0 : t.time_s.back() - t.time_s.front();
    const bool minutes = span > 600;
    const double k = minutes ? 1.0 / 60 : 1.0;
    std::vector<double> x(t.time_s.size());
    std::transform(t.time_s.begin(), t.time_s.end(), x.begin(), [k](double s) { return s * k; });

    Plot p("Bar reading over time");
    p.x_axis("session time", minutes ? "min" : "s").y_axis("bar displacement", "µm");
    std::vector<std::pair<double, double>> spans;
    for (const auto& c : r.captures) spans.emplace_back(c.start_s * k, c.end_s * k);
    if (!spans.empty()) p.bands("capture windows (" + std::to_string(spans.size()) + ")", spans, palette(1));
    std::string gaps = "no gap";
    if (t.gaps > 0) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "%zu gap%s in the stream, %.3f s", t.gaps, t.gaps == 1 ? "" : "s", t.gap_s);
        gaps = buf;
    }
    p.line("bar reading (" + std::to_string(t.samples) + " samples, " + gaps + ", min/max per column)", std::move(x),
           t.displacement_um, palette(0), 0.5);
    if (t.time_s.empty()) p.note("no samples stored");
    p.draw(doc.cr(), doc.reserve(190));
}

void figure_vectors(Document& doc, const Report& r) {
    if (r.locations.empty()) return;
    // One scale for all three projections: the largest error is drawn at ~18 % of the layout's extent.
    double extent = 0, largest = 0;
    Vec3 lo = r.locations.front().position_mm, hi = lo;
    for (const auto& l : r.locations) {
        lo = lo.cwiseMin(l.position_mm);
        hi = hi.cwiseMax(l.position_mm);
        largest = std::max(largest, l.error_um.norm());
    }
    extent = std::max(10.0, (hi - lo).maxCoeff());
    const double ref_um = largest > 0 ? nice_below(largest) : 1.0;
    const double mm_per_um = largest > 0 ? 0.18 * extent / largest : 1.0;
    const std::string note = "arrows: " + fixed(ref_um, ref_um < 1 ? 1 : 0) + " µm drawn as " +
                             fixed(ref_um * mm_per_um, ref_um * mm_per_um < 10 ? 1 : 0) + " mm";

    const Rect area = doc.reserve(215);
    doc.paragraph(
        "Total position error ΔV of each location, projected on the machine planes; axes to scale (mm), " + note + ".",
        7, kGrey);
    const int axes[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    const char* names = "XYZ";
    const double w = area.w / 3;
    for (int v = 0; v < 3; ++v) {
        const int a = axes[v][0], b = axes[v][1];
        Plot p(std::string("ΔV projected on ") + names[a] + names[b]);
        p.x_axis(std::string(1, names[a]), "mm").y_axis(std::string(1, names[b]), "mm").equal_aspect();
        for (std::size_t i = 0; i < r.locations.size(); ++i) {
            const auto& l = r.locations[i];
            const std::string name = "L" + std::to_string(l.location);
            p.arrows(name, {{l.position_mm[a], l.position_mm[b], l.error_um[a] * mm_per_um, l.error_um[b] * mm_per_um}},
                     palette(static_cast<int>(i)));
        }
        p.draw(doc.cr(), {area.x + v * w + (v > 0 ? 4 : 0), area.y, w - 4, area.h});
    }
}

void figure_orientation(Document& doc, const Report& r) {
    if (r.orientation.empty()) return;
    Plot p("Orientation errors of the rotary axes");
    std::vector<std::string> cats;
    std::vector<double> first, exact, u;
    const double nan = std::nan("");
    for (const auto& o : r.orientation) {
        cats.push_back(o.symbol + " (" + o.axis +
                       (o.commanded_rad ? " at " + fixed(analysis::rad_to_deg(*o.commanded_rad), 1) + "°" : "") + ")");
        first.push_back(o.first_order_rad ? analysis::rad_to_arcsec(*o.first_order_rad) : nan);
        exact.push_back(o.exact_rad ? analysis::rad_to_arcsec(*o.exact_rad) : nan);
        u.push_back(o.uncertainty_rad ? analysis::rad_to_arcsec(*o.uncertainty_rad) : 0.0);
    }
    p.y_axis("orientation error", "arcsec").bar_categories(cats);
    p.bars("first-order model", first, palette(4));
    p.bars("exact inversion (± u)", exact, palette(0), u);
    p.draw(doc.cr(), doc.reserve(160));
}

void figure_discovery(Document& doc, const std::vector<DiscoveryStep>& steps) {
    for (std::size_t i = 0; i < steps.size(); i += 2) {
        const Rect area = doc.reserve(165);
        for (std::size_t j = i; j < std::min(i + 2, steps.size()); ++j) {
            const auto& s = steps[j];
            Plot p("Step " + std::to_string(j + 1) + ": " + s.effect);
            p.x_axis(s.variable, s.variable_unit)
                .y_axis(s.y_label.empty() ? "residual" : s.y_label, s.y_unit.empty() ? "µm" : s.y_unit)
                .include_zero_y();
            if (s.binned) {  // binned means: of this step's residuals, or the workflow's first and last
                p.line(s.own_step ? "before the step (bin means)" : "before discovery (bin means)", s.x, s.before_um,
                       kGrey, 0.8);
                p.scatter("", s.x, s.before_um, kGrey, 1.8, true);
                p.line(s.own_step ? "after the step (bin means)" : "after discovery (bin means)", s.x, s.after_um,
                       palette(0), 0.8);
                p.scatter("", s.x, s.after_um, palette(0), 1.6);
            } else {
                p.scatter("before (rms " + fixed(s.rms_before_um, kUmDecimals) + " µm)", s.x, s.before_um, kGrey, 1.5,
                          true);
                p.scatter("after (rms " + fixed(s.rms_after_um, kUmDecimals) + " µm)", s.x, s.after_um, palette(0),
                          1.3);
            }
            if (s.x.empty()) p.note("no residuals stored for this step");
            const double w = area.w / 2;
            p.draw(doc.cr(), {area.x + static_cast<double>(j - i) * w + (j > i ? 6 : 0), area.y, w - 6, area.h});
        }
    }
}

void figure_compensation(Document& doc, const Report& r) {
    // One chart per unit (linear axes in µm, rotary axes in arcsec), side by side.
    std::vector<std::string> units;
    for (const auto& c : r.compensation)
        if (std::find(units.begin(), units.end(), c.unit) == units.end()) units.push_back(c.unit);
    if (units.empty()) return;
    const Rect area = doc.reserve(160);
    const double w = area.w / static_cast<double>(units.size());
    for (std::size_t k = 0; k < units.size(); ++k) {
        Plot p(units.size() > 1 ? "Compensation, " + units[k] : "Compensation");
        std::vector<std::string> cats;
        std::vector<double> before, after;
        for (const auto& c : r.compensation) {
            if (c.unit != units[k]) continue;
            cats.push_back(c.axis);
            before.push_back(c.before);
            after.push_back(c.after);
        }
        // Values on the bars: a compensation's "after" is often a tenth of its "before", a sliver beside it.
        p.y_axis("error", units[k]).bar_values(units[k] == "arcsec" ? 1 : 2).bar_categories(cats);
        p.bars("before", before, kGrey);
        p.bars("after", after, palette(2));
        p.draw(doc.cr(), {area.x + static_cast<double>(k) * w + (k > 0 ? 6 : 0), area.y, w - 6, area.h});
    }
}

}  // namespace ballbar::report
