// SPDX-License-Identifier: MIT
// The circular test's stored result (kind "circular", as `circle analyze --json` prints it) becomes
// report content: ranked diagnostics with their names and units, the tolerance, the unseparable
// groups; a malformed payload is refused naming the key; the PDF shows the figures and the verdict.
#include <gtest/gtest.h>

#include "ballbar/report/report.hpp"
#include "ballbar/report/results.hpp"
#include "poppler.hpp"

namespace ballbar::report {
namespace {

using nlohmann::json;

json payload() {
    return json::parse(R"({
      "test": {"kind": "circular", "plane": "ZX", "radius_mm": 150, "centre_mm": [0, 0, 0], "feed_mm_min": 1000,
               "feed_in_mm": 1.5, "runs": [{"direction": "ccw", "start_deg": -20, "overshoot_deg": 20, "data_arc_deg": 180},
                                           {"direction": "cw", "start_deg": 200, "overshoot_deg": 20, "data_arc_deg": 180}]},
      "runs": [{"direction": "ccw", "circularity_um": 7.25, "radial_deviation_um": {"max": 4.5, "min": -3.75},
                "feed_in_end_s": 1.2, "feed_in_lag_ms": 9.5, "data_start_s": 3.3, "data_end_s": 22.1, "samples": 9400},
               {"direction": "cw", "circularity_um": 8.5, "radial_deviation_um": {"max": 5.0, "min": -4.0},
                "feed_in_end_s": 30.2, "feed_in_lag_ms": 9.7, "data_start_s": 32.3, "data_end_s": 51.1, "samples": 9400}],
      "bidirectional_circularity_um": 11.0,
      "radial_deviation_um": {"max": 5.0, "min": -4.0},
      "diagnostics": {"backlash_z_um": 4.2, "cyclic_error_x_um": 0.8, "cyclic_pitch_x_mm": 5.01, "vibration_um": 0.3,
                      "vibration_hz": 24.9, "scale_mismatch_ppm": 12.5},
      "uncertainties": {"backlash_z_um": 0.05, "cyclic_error_x_um": 0.02, "cyclic_pitch_x_mm": 0.004,
                        "vibration_um": 0.01, "vibration_hz": 0.02, "scale_mismatch_ppm": 0.3},
      "shares_percent": {"backlash_z_um": 60, "scale_mismatch_ppm": 25, "cyclic_error_x_um": 10, "vibration_um": 5},
      "ranking": ["backlash_z_um", "scale_mismatch_ppm", "cyclic_error_x_um", "vibration_um"],
      "not_detected": ["cyclic_error_z_um"],
      "unseparable": [{"keys": ["backlash_x_um", "centre"], "reason": "one partial arc",
                       "combined": {"as": "", "value": 0, "std_uncertainty": 0}}],
      "residual_rms_um": 0.215,
      "mean_radius_um": {"value": 1.5, "std_uncertainty": 0.01},
      "conditions": {"plane": "ZX", "radius_mm": 150, "feed_mm_min": 1000, "sample_rate_hz": 500, "samples_used": 18800,
                     "bar_temp_C": {"min": 20.1, "max": 20.3}, "air_temp_C": null, "instrument": null},
      "tolerance": {"circularity_um": 8.0, "pass": false}
    })");
}

TEST(CircularReport, StoredResultBecomesContentRankedWithCompanions) {
    Report r;
    ASSERT_TRUE(add_result(r, "circular", payload()));
    ASSERT_TRUE(r.circular);
    const CircularTest& c = *r.circular;
    EXPECT_EQ(c.plane, "ZX");
    ASSERT_EQ(c.runs.size(), 2u);
    EXPECT_EQ(c.runs[1].direction, "cw");
    EXPECT_DOUBLE_EQ(c.runs[1].start_deg, 200);
    EXPECT_DOUBLE_EQ(c.runs[0].data_arc_deg, 180);
    ASSERT_EQ(c.diagnostics.size(), 6u);
    // Ranked by share; a cyclic error's pitch and a vibration's frequency follow their amplitude, unranked.
    const char* order[] = {"backlash_z_um",     "scale_mismatch_ppm", "cyclic_error_x_um",
                           "cyclic_pitch_x_mm", "vibration_um",       "vibration_hz"};
    for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(c.diagnostics[i].key, order[i]) << i;
    EXPECT_EQ(c.diagnostics[0].rank, 1);
    EXPECT_EQ(c.diagnostics[3].rank, 0);
    EXPECT_EQ(c.diagnostics[4].rank, 4);
    EXPECT_EQ(c.diagnostics[0].name, "backlash Z");
    EXPECT_EQ(c.diagnostics[0].unit, "µm");
    EXPECT_EQ(c.diagnostics[1].unit, "ppm");
    EXPECT_EQ(c.diagnostics[3].unit, "mm");
    EXPECT_EQ(c.diagnostics[5].name, "vibration frequency");
    EXPECT_EQ(c.diagnostics[5].unit, "Hz");
    EXPECT_DOUBLE_EQ(*c.tolerance_um, 8.0);
    EXPECT_FALSE(c.pass());  // the cw run's G is 8.5
    ASSERT_EQ(c.unseparable.size(), 1u);
    EXPECT_EQ(c.unseparable[0].keys.size(), 2u);
    EXPECT_DOUBLE_EQ(*c.bar_temp_C.max, 20.3);
    EXPECT_FALSE(c.air_temp_C.present());
}

TEST(CircularReport, MalformedPayloadIsRefusedNamingTheKey) {
    Report r;
    json p = payload();
    p["runs"][1]["circularity_um"] = "big";
    try {
        add_result(r, "circular", p);
        FAIL() << "accepted";
    } catch (const ReportError& e) {
        EXPECT_NE(std::string(e.what()).find("runs[1].circularity_um"), std::string::npos) << e.what();
    }
    p = payload();
    p.erase("runs");
    EXPECT_THROW(add_result(r, "circular", p), ReportError);
    p = payload();
    p["test"] = 3;
    EXPECT_THROW(add_result(r, "circular", p), ReportError);
}

TEST(CircularReport, PdfShowsTheFiguresTheVerdictAndTheDiagnostics) {
    Report r;
    r.header.session_id = 4;
    r.header.session_name = "circular 1a2b3c4d";
    add_result(r, "circular", payload());
    // A polar plot of a few points per run, as build_report would give.
    for (auto& run : r.circular->runs)
        for (int a = 0; a <= 180; a += 10) run.angle_deg.push_back(a), run.deviation_um.push_back(a % 20 ? 2.0 : -2.0);
    r.circular->plot_deviation_um = 5;
    testing::TempDir dir;
    const auto pdf = dir.path / "c.pdf";
    const int pages = render_pdf(r, pdf.string());
    EXPECT_GE(pages, 1);
    const std::string text = testing::pdf_text(pdf);
    for (const char* s : {"circular test report", "FAIL", "7.25", "8.50", "11.00", "backlash_z_um", "4.20 ± 0.05",
                          "60.0 %", "cyclic_pitch_x_mm", "5.010 ± 0.004", "cyclic_error_z_um", "one partial arc",
                          "0.215", "ZX", "150.000 mm", "1000 mm/min", "500.0 Hz", "20.20 °C", "Polar plot"})
        EXPECT_NE(text.find(s), std::string::npos) << s;
    const json j = to_json(r);
    EXPECT_EQ(j["circular"]["tolerance"]["pass"], false);
    EXPECT_EQ(j["circular"]["runs"][0]["pass"], true);
    EXPECT_EQ(j["circular"]["runs"][1]["pass"], false);
    EXPECT_EQ(j["circular"]["diagnostics"][0]["key"], "backlash_z_um");
    EXPECT_EQ(j["circular"]["runs"][0]["polar"]["angle_deg"].size(), 19u);
}

TEST(CircularReport, SessionsOfOtherProceduresHaveNoCircularPart) {
    const json j = to_json(Report{});
    EXPECT_TRUE(j["circular"].is_null());
}

}  // namespace
}  // namespace ballbar::report
