// SPDX-License-Identifier: MIT
// The report's pages: set-up, results tables, figures, procedure, model, discovery, compensation.
#include <cairo-pdf.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "ballbar/analysis/types.hpp"
#include "ballbar/fileio/output.hpp"
#include "ballbar/report/report.hpp"
#include "circular.hpp"
#include "document.hpp"
#include "figures.hpp"
#include "format.hpp"

namespace ballbar::report {

namespace {

std::string vec_mm(const Vec3& v) {
    return "[" + fixed(v.x(), 3) + ", " + fixed(v.y(), 3) + ", " + fixed(v.z(), 3) + "] mm";
}

void setup_section(Document& doc, const Report& r) {
    const Header& h = r.header;
    const auto& m = h.machine;
    std::vector<std::pair<std::string, std::string>> kv{
        {"Machine", or_dash(m.name)},
        {"Type", std::string(analysis::to_string(m.type))},
        {"Tool ball", vec_mm(m.tool_ball_mm)},
    };
    if (m.type != analysis::MachineType::RRTTT) kv.emplace_back("A-axis pivot", vec_mm(m.a_pivot_mm));
    if (m.type == analysis::MachineType::TTTRR) kv.emplace_back("C-frame offset", vec_mm(m.c_offset_mm));
    kv.emplace_back("Operator", or_dash(h.operator_name));
    kv.emplace_back("Started", local_time(h.started_at));
    kv.emplace_back("Finished", local_time(h.finished_at));
    kv.emplace_back("Status", or_dash(h.status));
    kv.emplace_back("Instrument", or_dash(h.instrument_model));
    kv.emplace_back("Serial", or_dash(h.instrument_serial));
    kv.emplace_back("Firmware", or_dash(h.instrument_firmware));
    kv.emplace_back("Calibrated", or_dash(h.instrument_calibration_date));
    kv.emplace_back("Bar length", h.calibrated_length_mm ? fixed(*h.calibrated_length_mm, 4) + " mm" : "–");
    kv.emplace_back("Bar temperature", range_C(h.bar_temp_C));
    kv.emplace_back("Machine temp.", range_C(h.machine_temp_C));
    kv.emplace_back("Air temperature", range_C(h.air_temp_C));
    kv.emplace_back("Software", "ballbar " + or_dash(h.software_version));
    doc.heading("Set-up", 60);
    doc.key_values(kv, 2);
    if (!h.notes.empty()) doc.paragraph("Notes: " + h.notes);
}

/// Which locations an orientation error came from, in the CLI's words: "test 2" when both are that
/// test's steps (labelled "test 2 step 1, …"), else the locations' numbers ("L3 → L4").
std::string orientation_source(const Report& r, const OrientationError& o) {
    if (o.from_location < 0) return "–";
    const auto test_of = [&r](int location) -> std::string {
        for (const auto& l : r.locations)
            if (l.location == location && l.label.starts_with("test ")) return l.label.substr(0, l.label.find(" step"));
        return {};
    };
    const std::string a = test_of(o.from_location), b = test_of(o.to_location);
    if (!a.empty() && a == b) return a;
    return "L" + std::to_string(o.from_location) + " → L" + std::to_string(o.to_location);
}

/// At the top of an SSM report: PASS/FAIL against the tolerances (the machine file's or given), the
/// figures beyond them, and where the tolerances came from; without tolerances, how to give them.
void verdict_section(Document& doc, const Report& r) {
    const SsmVerdict v = ssm_verdict(r);
    if (!v.judged) {
        if (r.locations.empty()) return;
        doc.paragraph(
            "No tolerance, so no verdict: give them in the machine file (\"tolerances\": {\"location_um\": …, "
            "\"angle_arcsec\": …}) or with `ballbar report SESSION --location-tolerance UM --angle-tolerance ARCSEC`.",
            7, kGrey);
        return;
    }
    // Each kind's tolerance as judged: one value, or the range of the tests' own.
    std::optional<double> loc_lo, loc_hi, ang_lo, ang_hi;
    auto widen = [](std::optional<double>& lo, std::optional<double>& hi, std::optional<double> tol) {
        if (!tol) return;
        lo = std::min(lo.value_or(*tol), *tol), hi = std::max(hi.value_or(*tol), *tol);
    };
    for (const auto& l : r.locations) widen(loc_lo, loc_hi, r.location_tolerance_at(l.location));
    for (const auto& o : r.orientation)
        if (o.exact_rad) widen(ang_lo, ang_hi, r.angle_tolerance_for(o));
    const bool by_test = (loc_lo && *loc_lo != *loc_hi) || (ang_lo && *ang_lo != *ang_hi);
    auto span = [](double lo, double hi, const char* unit) {
        return lo == hi ? given(lo) + unit : given(lo) + "–" + given(hi) + unit;
    };
    std::string limits = by_test ? "by test: " : "";
    if (loc_lo) limits += "|ΔV| ≤ " + span(*loc_lo, *loc_hi, " µm");
    if (ang_lo)
        limits += std::string(loc_lo ? ", " : "") + (by_test ? "angles ≤ " : "|Δα|, |Δβ|, |Δγ| ≤ ") +
                  span(*ang_lo, *ang_hi, "″");
    if (v.pass)
        doc.verdict_line("PASS: all " + std::to_string(v.checked) + " figures within tolerance (" + limits + ")",
                         kPass);
    else
        doc.verdict_line("FAIL: " + std::to_string(v.failures.size()) + " of " + std::to_string(v.checked) +
                             " figures beyond tolerance (" + limits + ")",
                         kFail);
    for (const std::string& f : v.failures) doc.paragraph("• " + f, 7.5, kFail);
    std::string source;  // "Tolerances: given." or "Tolerance on |ΔV|: given; on the angles: the machine file, ..."
    if (loc_lo && ang_lo && r.location_tolerance_source == r.angle_tolerance_source)
        source = "Tolerances: " + r.location_tolerance_source;
    else if (loc_lo)
        source = "Tolerance on |ΔV|: " + r.location_tolerance_source +
                 (ang_lo ? "; on the angles: " + r.angle_tolerance_source : std::string());
    else
        source = "Tolerance on the angles: " + r.angle_tolerance_source;
    doc.paragraph(source +
                      ". Each value is judged as measured; its standard uncertainty is shown beside it in the tables "
                      "below, not subtracted.",
                  7, kGrey);
}

void results_section(Document& doc, const Report& r) {
    doc.heading("Total position errors per location", 60);
    if (r.locations.empty()) {
        doc.paragraph("No location was solved in this session.");
    } else {
        doc.paragraph("ΔV in the machine frame, µm, ± standard uncertainty (k = 1), from the single socket method.", 7,
                      kGrey);
        std::vector<std::vector<std::string>> rows;
        for (const auto& l : r.locations)
            rows.push_back({std::to_string(l.location), l.label, plus_minus(l.error_um.x(), l.uncertainty_um.x(), 2),
                            plus_minus(l.error_um.y(), l.uncertainty_um.y(), 2),
                            plus_minus(l.error_um.z(), l.uncertainty_um.z(), 2), fixed(l.error_um.norm(), 2),
                            std::to_string(l.points), fixed(l.residual_rms_um, 2)});
        doc.table({{"Loc.", 0.5},
                   {"where", 2.2},
                   {"Δx (µm)", 1.5, HAlign::Right},
                   {"Δy (µm)", 1.5, HAlign::Right},
                   {"Δz (µm)", 1.5, HAlign::Right},
                   {"|ΔV| (µm)", 0.9, HAlign::Right},
                   {"points", 0.65, HAlign::Right},
                   {"rms (µm)", 0.95, HAlign::Right}},
                  rows);
    }

    doc.heading("Orientation errors", 50);
    if (r.orientation.empty()) {
        doc.paragraph("No orientation error was computed in this session.");
        return;
    }
    doc.paragraph(
        "First-order: the seed's linearised equations (corrected); exact: nonlinear inversion. "
        "u: standard uncertainty of the exact value.",
        7, kGrey);
    std::vector<std::vector<std::string>> rows;
    for (const auto& o : r.orientation) {
        const std::string from = orientation_source(r, o);
        rows.push_back(
            {o.symbol, o.axis, o.commanded_rad ? fixed(analysis::rad_to_deg(*o.commanded_rad), 3) + "°" : "–",
             degrees(o.first_order_rad), arcseconds(o.first_order_rad), degrees(o.exact_rad), arcseconds(o.exact_rad),
             arcseconds(o.uncertainty_rad,  // more decimals for a small u, as plus_minus does
                        o.uncertainty_rad
                            ? uncertainty_decimals(analysis::rad_to_arcsec(*o.uncertainty_rad), kArcsecDecimals)
                            : kArcsecDecimals),
             from});
    }
    doc.table({{"error", 0.6},
               {"axis", 0.45},
               {"at", 0.8, HAlign::Right},
               {"first-order (°)", 1.15, HAlign::Right},
               {"(arcsec)", 0.85, HAlign::Right},
               {"exact (°)", 1.15, HAlign::Right},
               {"(arcsec)", 0.85, HAlign::Right},
               {"u (arcsec)", 0.8, HAlign::Right},
               {"from", 0.9}},
              rows);
}

void procedure_section(Document& doc, const Report& r) {
    doc.heading("Procedure as followed", 50);
    if (r.procedure.empty()) {
        doc.paragraph("No procedure steps were recorded.");
        return;
    }
    int repeats = 0, pauses = 0;
    for (const auto& e : r.procedure) {
        repeats += e.kind == "repeat";
        pauses += e.kind == "pause";
    }
    doc.paragraph(fmt::format("{} events; {} repeated, {} paused.", r.procedure.size(), repeats, pauses), 7, kGrey);
    // Summarised: a run of three or more events of one kind and step (the points of a program, say) is
    // one row saying how many, with its first and last detail; the rest one row each.
    std::vector<std::vector<std::string>> rows;
    for (std::size_t i = 0; i < r.procedure.size();) {
        const auto& e = r.procedure[i];
        std::size_t j = i + 1;
        while (j < r.procedure.size() && r.procedure[j].kind == e.kind && r.procedure[j].step == e.step) ++j;
        if (j - i >= 3)
            rows.push_back(
                {clock_time(e.time_s), local_time(e.timestamp), e.kind, e.step,
                 fmt::format("{} events, from \"{}\" to \"{}\"", j - i, e.detail, r.procedure[j - 1].detail)});
        else
            for (std::size_t k = i; k < j; ++k) {
                const auto& x = r.procedure[k];
                rows.push_back({clock_time(x.time_s), local_time(x.timestamp), x.kind, x.step, x.detail});
            }
        i = j;
    }
    doc.table({{"time", 0.6, HAlign::Right}, {"timestamp", 1.6}, {"event", 0.7}, {"step", 1.4}, {"detail", 3.0}}, rows);
}

void model_section(Document& doc, const IdentifiedModel& m) {
    doc.heading("Identified model" + (m.name.empty() ? std::string() : ": " + m.name), 60);
    std::string summary;
    if (m.converged) summary += *m.converged ? "converged" : "did NOT converge";
    if (m.iterations) summary += fmt::format(" after {} iterations", *m.iterations);
    if (m.residual_rms_before_um || m.residual_rms_after_um)
        summary += "; residual rms " + fixed(m.residual_rms_before_um, kUmDecimals) + " → " +
                   fixed(m.residual_rms_after_um, kUmDecimals) + " µm";
    if (m.condition) summary += "; condition " + fixed(*m.condition, 1);
    if (!summary.empty()) doc.paragraph(summary, 7.5);
    std::vector<std::vector<std::string>> rows;
    for (const auto& p : m.parameters)
        rows.push_back({p.name, fixed(p.value, 3), fixed(p.uncertainty, 3), p.unit, fixed(p.observability, 2), p.note});
    doc.table({{"parameter", 1.0},
               {"value", 1.0, HAlign::Right},
               {"± u", 0.9, HAlign::Right},
               {"unit", 0.7},
               {"observability", 0.9, HAlign::Right},
               {"note", 2.2}},
              rows);
}

void discovery_section(Document& doc, const Report& r) {
    doc.heading("Discovery steps", 200);
    for (const std::string& note : r.discovery_notes) doc.paragraph(note);
    std::vector<std::vector<std::string>> rows;
    for (std::size_t i = 0; i < r.discovery.size(); ++i) {
        const auto& s = r.discovery[i];
        rows.push_back({std::to_string(i + 1), s.effect,
                        s.variable + (s.variable_unit.empty() ? "" : " (" + s.variable_unit + ")"),
                        fixed(s.rms_before_um, kUmDecimals), fixed(s.rms_after_um, kUmDecimals),
                        s.accepted ? (*s.accepted ? "yes" : "no") : "–", s.note});
    }
    doc.table({{"#", 0.3},
               {"effect", 1.4},
               {"explaining variable", 1.4},
               {"rms before (µm)", 1.15, HAlign::Right},
               {"rms after (µm)", 1.15, HAlign::Right},
               {"kept", 0.5},
               {"note", 1.6}},
              rows);
    figure_discovery(doc, r.discovery);
}

void compensation_section(Document& doc, const Report& r) {
    doc.heading("Compensation", 180);
    if (!r.compensation_metric.empty()) doc.paragraph("Bars: " + r.compensation_metric + ".", 7, kGrey);
    std::vector<std::vector<std::string>> rows;
    for (const auto& c : r.compensation) {
        const double gain = c.after != 0 ? c.before / c.after : std::nan("");
        rows.push_back(
            {c.axis, fixed(c.before, 2), fixed(c.after, 2), c.unit, std::isfinite(gain) ? fixed(gain, 1) + "×" : "–"});
    }
    doc.table({{"axis", 0.6},
               {"before", 1.0, HAlign::Right},
               {"after", 1.0, HAlign::Right},
               {"unit", 0.7},
               {"improvement", 1.0, HAlign::Right}},
              rows);
    figure_compensation(doc, r);
}

int layout(cairo_surface_t* surface, const Report& r, int total_pages) {
    const Header& h = r.header;
    Document doc(surface,
                 (h.machine.name.empty() ? std::string("machine") : h.machine.name) + " · session " +
                     std::to_string(h.session_id) + (h.session_name.empty() ? "" : " (" + h.session_name + ")"),
                 total_pages);
    const bool circular = r.circular || !r.circular_note.empty();
    doc.title(circular ? "Ball-bar circular test report (ISO 230-4)" : "Ball-bar session report",
              (h.session_name.empty() ? "Session " + std::to_string(h.session_id) : h.session_name) + " · " +
                  (circular ? (r.circular ? "plane " + r.circular->plane : std::string("circular test"))
                   : h.machine.name.empty()
                       ? std::string(analysis::to_string(h.machine.type))
                       : h.machine.name + " (" + std::string(analysis::to_string(h.machine.type)) + ")") +
                  (h.started_at.empty() ? "" : " · " + local_time(h.started_at)));
    if (circular) {  // a circular test: its own conditions and figures instead of the SSM's
        circular_sections(doc, r);
        doc.heading("Bar reading", 200);
        figure_trace(doc, r);
        procedure_section(doc, r);
        return doc.finish();
    }
    verdict_section(doc, r);
    setup_section(doc, r);
    results_section(doc, r);
    doc.heading("Figures", 200);
    figure_trace(doc, r);
    figure_vectors(doc, r);
    figure_orientation(doc, r);
    procedure_section(doc, r);
    if (r.model) model_section(doc, *r.model);
    if (!r.discovery.empty()) discovery_section(doc, r);
    if (!r.compensation.empty()) compensation_section(doc, r);
    return doc.finish();
}

}  // namespace

std::string render_pdf_bytes(const Report& report, int* pages_out) {
    return two_pass_pdf([&](cairo_surface_t* surface, int total) { return layout(surface, report, total); },
                        "Ball-bar session report, session " + std::to_string(report.header.session_id),
                        "ballbar " + report.header.software_version, pages_out);
}

int render_pdf(const Report& report, const std::string& path) {
    int pages = 0;
    const std::string pdf = render_pdf_bytes(report, &pages);
    try {
        fileio::write_file(path, "--out", pdf);
    } catch (const fileio::FileError& e) {
        throw ReportError(e.what());
    }
    return pages;
}

}  // namespace ballbar::report
