// SPDX-License-Identifier: MIT
#include <cairo-pdf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ballbar/report/report.hpp"
#include "ballbar/report/trend.hpp"
#include "document.hpp"
#include "plot.hpp"

namespace ballbar::report {
namespace {

std::string trend_number(double v, int decimals = 2) {
    char b[48];
    std::snprintf(b, sizeof b, "%.*f", decimals, v);
    std::string s = b;
    if (s == "-0" || s.rfind("-0.", 0) == 0) {
        bool zero = true;
        for (char c : s.substr(1))
            if (c != '0' && c != '.') zero = false;
        if (zero) s = s.substr(1);
    }
    if (!s.empty() && s[0] == '-') s = "\u2212" + s.substr(1);
    return s;
}

/// The uncertainty to two significant digits, the value to the same decimals.
std::string trend_with_std(double v, const std::optional<double>& sd) {
    if (!sd || *sd <= 0) return trend_number(v);
    const int decimals = std::clamp(1 - static_cast<int>(std::floor(std::log10(*sd))), 0, 6);
    return trend_number(v, decimals) + " \u00b1 " + trend_number(*sd, decimals);
}

int trend_layout(cairo_surface_t* surface, const TrendDocument& t, int total_pages) {
    Document doc(surface, "Trend of machine " + t.machine, total_pages, "ballbar machine trend");
    doc.title("Machine " + t.machine + ": trend", std::to_string(t.sessions) + " completed sessions, " +
                                                      t.first_at.substr(0, 10) + " to " + t.last_at.substr(0, 10));
    doc.key_values({{"machine", t.machine},
                    {"from", t.source},
                    {"sessions since", t.since.empty() ? "the first" : t.since},
                    {"made", t.generated_at + ", ballbar " + t.software_version}});
    doc.gap(6);
    int flagged = 0;
    for (const auto& s : t.series) flagged += s.flag.empty() ? 0 : 1;
    if (flagged == 0)
        doc.verdict_line("No figure drifts or exceeds its tolerance", kPass);
    else
        doc.verdict_line(std::to_string(flagged) + " figure(s) drift or exceed their tolerance", kFail);
    doc.paragraph(
        "Each figure is fitted by a straight line in time, weighted by the values' standard uncertainties "
        "(k = 1), its slope's uncertainty scaled by the Birge ratio when the values scatter more than their "
        "uncertainties say. A slope more than three of its standard uncertainties from zero is a drift; "
        "with a tolerance, a drift whose line reaches it within half a year of the last session is flagged "
        "'drifting toward tolerance'; a last value beyond it, 'over tolerance'. Uncertainties are those the "
        "analyses reported; figures without one are fitted by their scatter alone.");
    doc.gap(4);
    std::vector<std::vector<std::string>> rows;
    for (const auto& s : t.series) {
        const auto& last = s.values.back();
        rows.push_back({s.label, s.unit, std::to_string(s.values.size()), trend_with_std(last.value, last.value_std),
                        s.tolerance ? trend_number(*s.tolerance) : "-",
                        s.slope_per_year ? trend_with_std(*s.slope_per_year, s.slope_per_year_std) : "-",
                        s.flag.empty() ? "" : s.flag});
    }
    doc.table({{"figure", 2.6},
               {"unit", 0.8},
               {"n", 0.5, HAlign::Right},
               {"latest", 1.6, HAlign::Right},
               {"tolerance", 1.0, HAlign::Right},
               {"slope a year", 1.6, HAlign::Right},
               {"flag", 2.0}},
              rows);
    for (const auto& s : t.series) {
        doc.heading(s.label + (s.flag.empty() ? "" : ": " + s.flag), 230);
        if (!s.detail.empty()) doc.paragraph(s.detail, 7.5, s.flag.empty() ? kBlack : kFail);
        Plot plot(s.label + " (" + s.unit + ")");
        plot.x_axis("days since " + t.first_at.substr(0, 10), "d").y_axis(s.label, s.unit);
        std::vector<double> x, y, e, xd, yd, ed;
        for (const auto& v : s.values) {
            auto& X = v.demo ? xd : x;
            (v.demo ? yd : y).push_back(v.value);
            (v.demo ? ed : e).push_back(v.value_std.value_or(0));
            X.push_back(v.t_days);
        }
        double x0 = s.values.front().t_days, x1 = s.values.back().t_days;
        const double margin = std::max(0.5, 0.05 * (x1 - x0));  // the first and last points off the frame
        x0 -= margin, x1 += margin;
        if (!x.empty()) plot.scatter_errors("sessions (± 1 standard uncertainty)", x, y, e, palette(0), 2.2);
        if (!xd.empty()) plot.scatter_errors("emulator sessions", xd, yd, ed, palette(1), 2.2);
        if (s.tolerance) {
            plot.line("tolerance", {x0, x1}, {*s.tolerance, *s.tolerance}, kFail, 1.0);
            if (s.key.find("G_") != 0 && s.key.find("dV_") != 0)  // signed figures: both sides
                plot.line("", {x0, x1}, {-*s.tolerance, -*s.tolerance}, kFail, 1.0);
        }
        if (s.slope_per_year && s.intercept) {
            const double k = *s.slope_per_year / 365.25;
            plot.line("fitted line", {x0, x1}, {*s.intercept + k * x0, *s.intercept + k * x1},
                      s.flag.empty() ? kGrey : kFail, 0.8);
        }
        plot.x_range(x0, x1);
        plot.draw(doc.cr(), doc.reserve(190));
        doc.gap(6);
    }
    return doc.finish();
}

}  // namespace

std::string render_trend_pdf_bytes(const TrendDocument& t, int* pages) {
    if (t.series.empty()) throw ReportError("no figure to plot: the machine has no completed session with results");
    return two_pass_pdf([&](cairo_surface_t* surface, int total) { return trend_layout(surface, t, total); },
                        "Trend of machine " + t.machine, "ballbar " + t.software_version, pages);
}

}  // namespace ballbar::report
