// SPDX-License-Identifier: MIT
// The circular test's pages: conditions, the ISO 230-4 figures against the tolerance, the polar plot of
// the runs (deviation magnified, with its scale and the tolerance band), the ranked diagnostics and the
// effects this data cannot separate.
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "circular.hpp"
#include "format.hpp"
#include "plot.hpp"

namespace ballbar::report {

namespace {

/// The diagnosed model's dash, on the plot and in its legend.
constexpr double kModelDash[] = {3.0, 2.0};

std::string um(double v) {
    return fixed(v, kUmDecimals) + " µm";
}

/// "ccw from 0°: 360° of data between 45° overshoots".
std::string arc_text(const CircularRun& r) {
    return r.direction + " from " + fixed(r.start_deg, 0) + "°: " + fixed(r.data_arc_deg, 0) + "° data, " +
           fixed(r.overshoot_deg, 0) + "° overshoots";
}

std::string axis_letters(const std::string& plane, int i) {
    return plane.size() == 2 ? std::string(1, plane[static_cast<std::size_t>(i)]) : (i == 0 ? "p" : "q");
}

void conditions(Document& doc, const Report& r) {
    const CircularTest& c = *r.circular;
    const Header& h = r.header;
    std::vector<std::pair<std::string, std::string>> kv{
        {"Plane", c.plane + " (0° = +" + axis_letters(c.plane, 0) + ", 90° = +" + axis_letters(c.plane, 1) + ")"},
        {"Radius", fixed(c.radius_mm, 3) + " mm"},
        {"Feed", fixed(c.feed_mm_min, 0) + " mm/min"},
        {"Feed-in", fixed(c.feed_in_mm, 3) + " mm"},
        {"Centre", "[" + fixed(c.centre_mm.x(), 3) + ", " + fixed(c.centre_mm.y(), 3) + ", " +
                       fixed(c.centre_mm.z(), 3) + "] mm"},
    };
    for (std::size_t k = 0; k < c.runs.size(); ++k)
        kv.emplace_back("Run " + std::to_string(k + 1), arc_text(c.runs[k]));
    kv.emplace_back("Sample rate", c.sample_rate_hz ? fixed(*c.sample_rate_hz, 1) + " Hz" : "–");
    kv.emplace_back("Samples used", c.samples_used ? fixed(*c.samples_used, 0) : "–");
    kv.emplace_back("Bar temperature", range_C(c.bar_temp_C));
    kv.emplace_back("Air temperature", range_C(c.air_temp_C));
    kv.emplace_back("Instrument", or_dash(h.instrument_model) +
                                      (h.instrument_serial.empty() ? "" : ", serial " + h.instrument_serial));
    kv.emplace_back("Calibrated", or_dash(h.instrument_calibration_date) +
                                      (h.calibrated_length_mm ? ", " + fixed(*h.calibrated_length_mm, 4) + " mm" : ""));
    kv.emplace_back("Date", local_time(h.started_at));
    kv.emplace_back("Operator", or_dash(h.operator_name));
    kv.emplace_back("Status", or_dash(h.status));
    kv.emplace_back("Software", "ballbar " + or_dash(h.software_version));
    doc.heading("Circular test (ISO 230-4): conditions", 120);
    doc.key_values(kv, 2);
    if (c.instrument.size() > 2 && h.instrument_model.empty()) doc.paragraph("Instrument: " + c.instrument, 7, kGrey);
    if (!h.notes.empty()) doc.paragraph("Notes: " + h.notes);
}

void figures(Document& doc, const CircularTest& c) {
    doc.heading("Circular deviation", 120);
    const auto tol = c.tolerance_um;
    auto judged = [&](double v) -> std::string {
        if (!tol) return "–";
        return v <= *tol ? "PASS" : "FAIL";
    };
    std::vector<std::vector<std::string>> rows;
    for (std::size_t k = 0; k < c.runs.size(); ++k) {
        const auto& run = c.runs[k];
        rows.push_back({"G, run " + std::to_string(k + 1) + " (" + run.direction + ")", fixed(run.circularity_um, 2),
                        tol ? "≤ " + fixed(*tol, 2) : "–", judged(run.circularity_um),
                        "F max " + fixed(run.radial_max_um, 2) + ", min " + fixed(run.radial_min_um, 2) + " µm"});
    }
    if (c.bidirectional_um)
        rows.push_back({"G(b), bidirectional", fixed(*c.bidirectional_um, 2), tol ? "≤ " + fixed(*tol, 2) : "–",
                        judged(*c.bidirectional_um), "one least-squares centre for both runs"});
    if (c.hysteresis_um)
        rows.push_back(
            {"H, circular hysteresis", fixed(*c.hysteresis_um, 2), "", "", "ccw path vs cw path, 1° sectors"});
    rows.push_back({"F max (radial deviation)", fixed(c.radial_max_um, 2), "", "", "measured − programmed radius"});
    rows.push_back({"F min (radial deviation)", fixed(c.radial_min_um, 2), "", "", "over every data arc"});
    rows.push_back(
        {"residual RMS after the diagnosis", fixed(c.residual_rms_um, 3), "", "", "what no diagnostic explains"});
    if (c.mean_radius_um)
        rows.push_back({"mean radius − programmed radius",
                        plus_minus(*c.mean_radius_um, c.mean_radius_uncertainty_um, 2), "", "",
                        "absolute only with a calibrated bar"});
    doc.table({{"figure", 2.2},
               {"value (µm)", 1.1, HAlign::Right},
               {"tolerance (µm)", 1.1, HAlign::Right},
               {"result", 0.7, HAlign::Center},
               {"", 2.6}},
              rows);
    if (tol) {
        const bool pass = c.pass();
        doc.verdict_line(std::string(pass ? "PASS" : "FAIL") + ": circular deviation G of " +
                             (c.runs.size() > 1 ? "every run" : "the run") + (pass ? " within " : " beyond ") +
                             fixed(*tol, 2) + " µm",
                         pass ? kPass : kFail);
        doc.paragraph("Tolerance " + fixed(*tol, 2) + " µm (" + c.tolerance_source +
                          "); the verdict is on G, as `circle analyze --tolerance` judges; G(b) is shown against "
                          "the same value.",
                      7, kGrey);
    } else {
        doc.paragraph(
            "No tolerance: give one with `ballbar report SESSION --tolerance UM` (or store one with "
            "`circle analyze --tolerance UM --store`) for a pass/fail verdict.",
            7, kGrey);
    }
}

void polar_plot(Document& doc, const CircularTest& c) {
    const double height = 330;
    const Rect area = doc.reserve(height);
    cairo_t* cr = doc.cr();
    const double side = std::min(area.h, area.w * 0.66);
    const double cx = area.x + side / 2, cy = area.y + side / 2;
    const double rmax = side / 2 - 24;
    const double d = c.plot_deviation_um > 0 ? c.plot_deviation_um : 1.0;
    const double rho0 = 0.6 * rmax, gain = 0.38 * rmax / d;  // points per µm
    auto rho = [&](double dev) { return std::max(rho0 + gain * dev, 0.0); };
    auto at = [&](double deg, double rad_pt) {
        const double a = deg * std::numbers::pi / 180.0;
        return std::pair<double, double>{cx + rad_pt * std::cos(a), cy - rad_pt * std::sin(a)};
    };
    cairo_save(cr);
    // The tolerance band: T wide, centred on the least-squares circle.
    if (c.tolerance_um) {
        set_color(cr, kPass, 0.18);
        cairo_new_path(cr);
        cairo_arc(cr, cx, cy, rho(0.5 * *c.tolerance_um), 0, 2 * std::numbers::pi);
        cairo_new_sub_path(cr);
        cairo_arc_negative(cr, cx, cy, rho(-0.5 * *c.tolerance_um), 2 * std::numbers::pi, 0);
        cairo_fill(cr);
    }
    // Rings every d/2 from −d to +d; the least-squares circle (0) solid.
    for (int i = -2; i <= 2; ++i) {
        const double dev = 0.5 * d * i;
        set_color(cr, i == 0 ? kGrey : kLightGrey);
        cairo_set_line_width(cr, i == 0 ? 0.8 : 0.5);
        if (i != 0) {
            const double dash[] = {2.0, 2.0};
            cairo_set_dash(cr, dash, 2, 0);
        }
        cairo_new_path(cr);
        cairo_arc(cr, cx, cy, rho(dev), 0, 2 * std::numbers::pi);
        cairo_stroke(cr);
        cairo_set_dash(cr, nullptr, 0, 0);
    }
    // Spokes every 30°, labelled; the plane's axes named at 0° and 90°.
    set_font(cr, 6.5);
    for (int a = 0; a < 360; a += 30) {
        const auto [x0, y0] = at(a, rho(-d));
        const auto [x1, y1] = at(a, rho(d) + 3);
        set_color(cr, kLightGrey);
        cairo_set_line_width(cr, 0.4);
        cairo_move_to(cr, x0, y0);
        cairo_line_to(cr, x1, y1);
        cairo_stroke(cr);
        const auto [tx, ty] = at(a, rho(d) + 9);
        std::string label = std::to_string(a) + "°";
        if (a == 0) label += " +" + axis_letters(c.plane, 0);
        if (a == 90) label += " +" + axis_letters(c.plane, 1);
        const HAlign h = std::abs(std::cos(a * std::numbers::pi / 180)) < 0.2 ? HAlign::Center
                         : std::cos(a * std::numbers::pi / 180) > 0           ? HAlign::Left
                                                                              : HAlign::Right;
        set_color(cr, kGrey);
        draw_text(cr, tx, ty, label, h, VAlign::Middle);
    }
    // The runs, each with its diagnosed model's curve dashed over it, a darker shade of the run's colour.
    auto model_colour = [](std::size_t k) {
        const Rgb p = palette(k == 0 ? 0 : 1);
        return Rgb{0.55 * p.r, 0.55 * p.g, 0.55 * p.b};
    };
    for (std::size_t k = 0; k < c.runs.size(); ++k) {
        const auto& run = c.runs[k];
        if (run.angle_deg.size() < 2) continue;
        // One polyline through (angle, deviation) pairs, stroked.
        auto stroke_curve = [&](const std::vector<double>& angles, const std::vector<double>& deviations) {
            cairo_new_path(cr);
            for (std::size_t i = 0; i < angles.size(); ++i) {
                const auto [x, y] = at(angles[i], rho(deviations[i]));
                if (i == 0)
                    cairo_move_to(cr, x, y);
                else
                    cairo_line_to(cr, x, y);
            }
            cairo_stroke(cr);
        };
        set_color(cr, palette(k == 0 ? 0 : 1));
        cairo_set_line_width(cr, 0.7);
        stroke_curve(run.angle_deg, run.deviation_um);
        if (run.model_angle_deg.size() >= 2 && run.model_angle_deg.size() == run.model_deviation_um.size()) {
            set_color(cr, model_colour(k));
            cairo_set_line_width(cr, 0.9);
            cairo_set_dash(cr, kModelDash, 2, 0);
            stroke_curve(run.model_angle_deg, run.model_deviation_um);
            cairo_set_dash(cr, nullptr, 0, 0);
            set_color(cr, palette(k == 0 ? 0 : 1));
        }
        // Where the run's data starts (a dot) and which way it goes (an arrowhead an eighth of the way on,
        // along the path), so the two directions and a reversal's place can be read off the plot.
        const auto [sx, sy] = at(run.angle_deg.front(), rho(run.deviation_um.front()));
        cairo_new_path(cr);
        cairo_arc(cr, sx, sy, 2.6, 0, 2 * std::numbers::pi);
        cairo_fill(cr);
        // The arrow follows the chord to a point some 15° on: within an angle column the reduced points
        // go first/min/max/last, so neighbours can be a radial step apart.
        const std::size_t n = run.angle_deg.size();
        const std::size_t i = std::min(n - 2, n / 8), j = std::min(n - 1, i + std::max<std::size_t>(1, n / 24));
        const auto [ax, ay] = at(run.angle_deg[i], rho(run.deviation_um[i]));
        const auto [bx, by] = at(run.angle_deg[j], rho(run.deviation_um[j]));
        const double len = std::hypot(bx - ax, by - ay);
        if (len > 0) {
            const double ux = (bx - ax) / len, uy = (by - ay) / len;
            cairo_new_path(cr);
            cairo_move_to(cr, ax + 10 * ux, ay + 10 * uy);
            cairo_line_to(cr, ax - 4.5 * uy, ay + 4.5 * ux);
            cairo_line_to(cr, ax + 4.5 * uy, ay - 4.5 * ux);
            cairo_close_path(cr);
            cairo_fill(cr);
        }
    }
    // Ring labels along the 75° spoke.
    set_font(cr, 6);
    for (int i = -2; i <= 2; ++i) {
        const double dev = 0.5 * d * i;
        const auto [x, y] = at(75, rho(dev));
        const std::string label = (dev > 0 ? "+" : "") + tick_label(dev, d < 2 ? 2 : d < 20 ? 1 : 0) + " µm";
        set_color(cr, Rgb{1, 1, 1}, 0.85);
        const double w = text_width(cr, label);
        cairo_rectangle(cr, x + 1, y - 4, w + 2, 8);
        cairo_fill(cr);
        set_color(cr, kGrey);
        draw_text(cr, x + 2, y, label, HAlign::Left, VAlign::Middle);
    }
    cairo_restore(cr);

    // Legend and scale, to the right of the plot.
    const double lx = area.x + side + 18, lw = area.right() - lx;
    double y = area.y + 6;
    set_font(cr, 8.5, true);
    set_color(cr, kBlack);
    draw_text(cr, lx, y, "Polar plot of the runs", HAlign::Left, VAlign::Top);
    y += 16;
    set_font(cr, 7);
    for (std::size_t k = 0; k < c.runs.size(); ++k) {
        const auto& run = c.runs[k];
        set_color(cr, palette(k == 0 ? 0 : 1));
        cairo_set_line_width(cr, 1.5);
        cairo_move_to(cr, lx, y + 4);
        cairo_line_to(cr, lx + 16, y + 4);
        cairo_stroke(cr);
        set_color(cr, kBlack);
        draw_text(cr, lx + 20, y + 4,
                  "run " + std::to_string(k + 1) + " " + run.direction + ": G " + um(run.circularity_um), HAlign::Left,
                  VAlign::Middle);
        y += 12;
    }
    bool model = false;
    for (std::size_t k = 0; k < c.runs.size(); ++k) {
        const auto& run = c.runs[k];
        if (run.model_angle_deg.size() < 2 || run.model_angle_deg.size() != run.model_deviation_um.size()) continue;
        model = true;
        set_color(cr, model_colour(k));
        cairo_set_line_width(cr, 1.2);
        cairo_set_dash(cr, kModelDash, 2, 0);
        cairo_move_to(cr, lx, y + 4);
        cairo_line_to(cr, lx + 16, y + 4);
        cairo_stroke(cr);
        cairo_set_dash(cr, nullptr, 0, 0);
        set_color(cr, kBlack);
        draw_text(cr, lx + 20, y + 4, "run " + std::to_string(k + 1) + ": the diagnosed model", HAlign::Left,
                  VAlign::Middle);
        y += 12;
    }
    set_color(cr, kGrey);
    draw_text(cr, lx, y + 4, "dot: where the data starts; arrowhead: the direction", HAlign::Left, VAlign::Middle);
    y += 12;
    if (c.tolerance_um) {
        set_color(cr, kPass, 0.3);
        cairo_rectangle(cr, lx, y, 16, 8);
        cairo_fill(cr);
        set_color(cr, kBlack);
        draw_text(cr, lx + 20, y + 4, "tolerance band " + um(*c.tolerance_um) + " wide", HAlign::Left, VAlign::Middle);
        y += 12;
    }
    y += 6;
    const double magnification = gain / (rho0 / (c.radius_mm * 1000.0));  // deviation vs the drawn radius
    const std::vector<std::string> notes{
        "Radial scale: " +
            tick_label(0.5 * d, d < 2    ? 2
                                : d < 20 ? 1
                                         : 0) +
            " µm between rings (dashed), " +
            tick_label(d, d < 2    ? 2
                          : d < 20 ? 1
                                   : 0) +
            " µm at the outer ring.",
        "Deviation magnified " + fixed(magnification, 0) + " × against the " + fixed(c.radius_mm, 0) +
            " mm radius (drawn as the solid grey circle).",
        "Reference: one least-squares circle for all runs (its centre and radius removed, as for G(b)); outwards "
        "is positive.",
        "Angles: the axes' position (the commanded angle less the feed-ins' servo lag), 0° = +" +
            axis_letters(c.plane, 0) + ", counter-clockwise towards +" + axis_letters(c.plane, 1) + ".",
        "Each run: its data arc only, reduced to first/min/max/last per angle column (720 per run).",
    };
    std::vector<std::string> all_notes = notes;
    if (!model && !c.runs.empty())
        all_notes.push_back(
            "No model curve: this result was stored before ballbar drew one (`ballbar circle analyze SESSION "
            "--store` stores the analysis again, with it).");
    if (model)
        all_notes.push_back(
            "Model (dashed): every diagnosed effect of the path together (all but the vibration, which widens "
            "the run's line), about its own least-squares circle; where the run's line leaves it, no diagnostic "
            "explains.");
    set_color(cr, kGrey);
    set_font(cr, 6.8);
    for (const auto& n : all_notes) {
        for (const auto& line : wrap_text(cr, n, lw)) {
            draw_text(cr, lx, y, line, HAlign::Left, VAlign::Top);
            y += 9;
        }
        y += 3;
    }
    set_color(cr, kBlack);
}

void diagnostics(Document& doc, const CircularTest& c) {
    doc.heading("Diagnostics, ranked by share of the circular deviation", 80);
    doc.paragraph(
        "Each effect's value ± standard uncertainty (k = 1) and its share: the peak-to-valley of its radial "
        "signature over the data as a percentage of the sum over all diagnostics. Signs and meanings: "
        "ballbar-trace/1 (docs/formats/trace.md).",
        7, kGrey);
    std::vector<std::vector<std::string>> rows;
    for (const auto& d : c.diagnostics)
        rows.push_back({d.rank > 0 ? std::to_string(d.rank) : "", d.name, d.key,
                        plus_minus(d.value, d.uncertainty, d.unit == "mm" || d.unit == "ms" ? 3 : 2), d.unit,
                        d.share_percent ? fixed(*d.share_percent, 1) + " %" : ""});
    if (rows.empty())
        doc.paragraph("No diagnostic was reported.");
    else
        doc.table({{"#", 0.3},
                   {"diagnostic", 1.5},
                   {"key", 1.9},
                   {"value ± u", 1.5, HAlign::Right},
                   {"unit", 0.6},
                   {"share", 0.7, HAlign::Right}},
                  rows);
    std::vector<std::string> actions;
    for (const auto& d : c.diagnostics)
        if (!d.action.empty()) actions.push_back(std::to_string(d.rank) + ". " + d.action + ".");
    if (!actions.empty()) {
        doc.heading("What to do, largest first", 30);
        for (const auto& a : actions) doc.paragraph(a, 8);
    }
    if (!c.not_detected.empty()) {
        std::string list;
        for (const auto& k : c.not_detected) list += (list.empty() ? "" : ", ") + k;
        doc.paragraph("Searched, not detected: " + list + ".", 7.5);
    }
    if (!c.unseparable.empty()) {
        doc.heading("Effects this data cannot separate", 40);
        std::vector<std::vector<std::string>> urows;
        for (const auto& g : c.unseparable) {
            std::string keys;
            for (const auto& k : g.keys) keys += (keys.empty() ? "" : " + ") + k;
            std::string combined = "–";
            if (!g.combined_key.empty() && g.combined_value)
                combined = g.combined_key + " = " + plus_minus(*g.combined_value, g.combined_uncertainty, 3);
            urows.push_back({keys, g.reason, combined});
        }
        doc.table({{"effects", 2.2}, {"why", 2.6}, {"together, as", 2.0}}, urows);
    }
    doc.paragraph("Residual RMS after the centre and every diagnosis: " + fixed(c.residual_rms_um, 3) + " µm.", 7.5);
}

}  // namespace

void circular_sections(Document& doc, const Report& r) {
    if (!r.circular) {
        doc.heading("Circular test (ISO 230-4)", 40);
        doc.paragraph(r.circular_note.empty() ? "No circular result." : "No figures: " + r.circular_note + ".");
        return;
    }
    const CircularTest& c = *r.circular;
    conditions(doc, r);
    doc.paragraph("Figures: " + c.source + ".", 7, kGrey);
    figures(doc, c);
    polar_plot(doc, c);
    diagnostics(doc, c);
}

}  // namespace ballbar::report
