// SPDX-License-Identifier: MIT
// Renders reports of the three machine types and reads them back with poppler: A4 pages, page count,
// and the key figures (the same numbers the JSON holds) in the extracted text.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "ballbar/report/report.hpp"
#include "poppler.hpp"
#include "synthetic.hpp"
#include "text_format.hpp"

namespace ballbar::report {
namespace {

using testing::fixed_text;
using testing::plus_minus_text;

using testing::pdf_page_size;
using testing::pdf_pages;
using testing::pdf_text;
using testing::TempDir;

class RenderByType : public ::testing::TestWithParam<analysis::MachineType> {};

TEST_P(RenderByType, PdfHoldsTheKeyFiguresOfTheJson) {
    const auto type = GetParam();
    const Report r = testing::synthetic_report(type, 50000, 11);
    TempDir dir;
    const auto pdf = dir.path / "report.pdf";
    const int pages = render_pdf(r, pdf.string());
    EXPECT_GE(pages, 2);
    EXPECT_EQ(pdf_pages(pdf), pages);
    EXPECT_NE(pdf_page_size(pdf).find("A4"), std::string::npos) << pdf_page_size(pdf);

    const std::string text = pdf_text(pdf);
    const nlohmann::json j = to_json(r);
    auto expect_in_text = [&](const std::string& s) { EXPECT_NE(text.find(s), std::string::npos) << "missing: " << s; };

    expect_in_text(j["header"]["machine"]["name"].get<std::string>());
    expect_in_text(j["header"]["machine"]["type"].get<std::string>());
    expect_in_text(j["header"]["instrument"]["serial"].get<std::string>());
    expect_in_text(j["header"]["instrument"]["calibration_date"].get<std::string>());
    expect_in_text(j["header"]["operator"].get<std::string>());
    expect_in_text("page 1 of " + std::to_string(pages));
    ASSERT_EQ(j["locations"].size(), r.locations.size());
    for (const auto& l : j["locations"]) {
        for (int k = 0; k < 3; ++k) {
            expect_in_text(plus_minus_text(l["dV_um"][k].get<double>(), l["dV_um_std"][k].get<double>()));
        }
        expect_in_text(fixed_text(l["magnitude_um"].get<double>(), 2));
    }
    ASSERT_EQ(j["orientation"].size(), r.orientation.size());
    for (const auto& o : j["orientation"]) {
        expect_in_text(fixed_text(o["exact_deg"].get<double>(), 5) + "°");
        expect_in_text(fixed_text(o["exact_arcsec"].get<double>(), 1) + "″");
        expect_in_text(fixed_text(o["first_order_deg"].get<double>(), 5) + "°");
        expect_in_text(fixed_text(o["first_order_arcsec"].get<double>(), 1) + "″");
    }
    for (const auto& p : j["model"]["parameters"]) {
        expect_in_text(p["name"].get<std::string>());
        expect_in_text(fixed_text(p["value"].get<double>(), 3));
    }
    for (const auto& s : j["discovery"]) expect_in_text(s["effect"].get<std::string>());
    for (const auto& e : j["procedure"]) expect_in_text(e["step"].get<std::string>());
    // Axis titles carry their units.
    expect_in_text("session time (s)");
    expect_in_text("bar displacement (µm)");
    expect_in_text("orientation error (arcsec)");
}

TEST(Render, CompensationBarsCarryTheirValuesAndTheVerdictOpensTheReport) {
    Report r = testing::synthetic_report(analysis::MachineType::TTTRR, 5000, 3);
    TempDir dir;
    auto count = [](const std::string& text, const std::string& s) {
        std::size_t n = 0;
        for (auto at = text.find(s); at != std::string::npos; at = text.find(s, at + 1)) ++n;
        return n;
    };
    // No tolerance: no verdict, and the report says how to give one.
    render_pdf(r, (dir.path / "none.pdf").string());
    const std::string none = pdf_text(dir.path / "none.pdf");
    EXPECT_EQ(none.find("PASS:"), std::string::npos);
    EXPECT_EQ(none.find("FAIL:"), std::string::npos);
    EXPECT_NE(none.find("No tolerance, so no verdict"), std::string::npos);
    // Each bar's value written on it: an "after" value is in the text twice, the table's and its bar's.
    ASSERT_FALSE(r.compensation.empty());
    for (const auto& c : r.compensation)
        EXPECT_GE(count(none, fixed_text(c.after, c.unit == "arcsec" ? 1 : 2)), 2u) << c.axis << " " << c.after;

    // A location tolerance between the smallest and the largest |ΔV|: FAIL, with each figure beyond it.
    double lo = 1e9, hi = 0;
    for (const auto& l : r.locations) lo = std::min(lo, l.error_um.norm()), hi = std::max(hi, l.error_um.norm());
    ASSERT_LT(lo, hi);
    set_ssm_tolerances(r, (lo + hi) / 2, std::nullopt);
    const SsmVerdict v = ssm_verdict(r);
    ASSERT_TRUE(v.judged);
    ASSERT_FALSE(v.failures.empty());
    render_pdf(r, (dir.path / "fail.pdf").string());
    const std::string fail = pdf_text(dir.path / "fail.pdf");
    const auto verdict_at =
        fail.find("FAIL: " + std::to_string(v.failures.size()) + " of " + std::to_string(v.checked));
    ASSERT_NE(verdict_at, std::string::npos) << fail.substr(0, 800);
    EXPECT_LT(verdict_at, fail.find("Set-up")) << "the verdict opens the report";
    EXPECT_NE(fail.find("Tolerance on |ΔV|: given."), std::string::npos);
    // Above every |ΔV|: PASS.
    set_ssm_tolerances(r, hi + 1, std::nullopt);
    render_pdf(r, (dir.path / "pass.pdf").string());
    EXPECT_NE(pdf_text(dir.path / "pass.pdf").find("PASS: all " + std::to_string(r.locations.size()) + " figures"),
              std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, RenderByType,
                         ::testing::Values(analysis::MachineType::RRTTT, analysis::MachineType::TTTRR,
                                           analysis::MachineType::RTTTR),
                         [](const auto& p) { return std::string(analysis::to_string(p.param)); });

TEST(Render, EmptySessionStillGivesAReadablePage) {
    Report r;
    r.header.session_id = 3;
    r.header.machine.type = analysis::MachineType::RRTTT;
    TempDir dir;
    const auto pdf = dir.path / "empty.pdf";
    const int pages = render_pdf(r, pdf.string());
    EXPECT_EQ(pages, pdf_pages(pdf));
    const std::string text = pdf_text(pdf);
    EXPECT_NE(text.find("No location was solved"), std::string::npos);
    EXPECT_NE(text.find("No procedure steps were recorded"), std::string::npos);
}

TEST(Render, LongTablesBreakAcrossPagesWithTheirHeader) {
    Report r = testing::synthetic_report(analysis::MachineType::TTTRR, 1000, 2);
    const int before = [&] {
        TempDir dir;
        return render_pdf(r, (dir.path / "a.pdf").string());
    }();
    for (int i = 0; i < 200; ++i)
        r.procedure.push_back({1000.0 + i, "", "step", "extra step " + std::to_string(i), "detail"});
    TempDir dir;
    const auto pdf = dir.path / "long.pdf";
    const int pages = render_pdf(r, pdf.string());
    EXPECT_GE(pages, before + 2);
    const std::string text = pdf_text(pdf);
    EXPECT_NE(text.find("extra step 0"), std::string::npos);
    EXPECT_NE(text.find("extra step 199"), std::string::npos);
    // The table header ("timestamp") repeats on each page the table continues on.
    std::size_t headers = 0;
    for (auto pos = text.find("timestamp"); pos != std::string::npos; pos = text.find("timestamp", pos + 1)) ++headers;
    EXPECT_GE(headers, 3u);
}

TEST(Render, UnwritablePathIsAClearError) {
    const Report r = testing::synthetic_report(analysis::MachineType::RTTTR, 1000, 1);
    try {
        render_pdf(r, "/nonexistent-dir/report.pdf");
        FAIL() << "no error";
    } catch (const ReportError& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/report.pdf"), std::string::npos) << e.what();
    }
}

TEST(Render, DegenerateSeriesDoNotHangOrCrash) {
    Report r = testing::synthetic_report(analysis::MachineType::TTTRR, 1000, 4);
    // A trace whose range is tiny against its magnitude, and non-finite values in it.
    r.trace.time_s = {1e9, 1e9 + 1e-6, 1e9 + 2e-6};
    r.trace.displacement_um = {5.0, std::nan(""), 5.0 + 1e-12};
    r.locations.resize(1);
    r.locations[0].error_um = Vec3::Zero();  // nothing to draw to scale
    TempDir dir;
    const auto pdf = dir.path / "degenerate.pdf";
    const int pages = render_pdf(r, pdf.string());
    EXPECT_EQ(testing::pdf_pages(pdf), pages);
}

TEST(Json, HoldsTheContentWithUnitsAndNullForMissing) {
    Report r = testing::synthetic_report(analysis::MachineType::RRTTT, 20000, 5);
    r.orientation[0].first_order_rad.reset();  // singular first-order model
    const nlohmann::json j = to_json(r);
    EXPECT_EQ(j["schema"], "ballbar-report/2");
    EXPECT_TRUE(j["orientation"][0]["first_order_rad"].is_null());
    EXPECT_NEAR(j["orientation"][0]["exact_arcsec"].get<double>(), analysis::rad_to_arcsec(*r.orientation[0].exact_rad),
                1e-9);
    EXPECT_EQ(j["bar_trace"]["samples"].get<std::uint64_t>(), 20000u);
    EXPECT_EQ(j["bar_trace"]["time_s"].size(), r.trace.time_s.size());
    EXPECT_LE(r.trace.time_s.size(), 4u * 2000u);
    EXPECT_EQ(j["bar_trace"]["max_um"].get<double>(), *r.trace.max_um);
    EXPECT_EQ(j["header"]["machine"].count("c_offset_mm"), 0u);  // an RRTTT has no C frame
    EXPECT_EQ(j["locations"][1]["dV_um"][2].get<double>(), r.locations[1].error_um.z());
    EXPECT_EQ(j["compensation"]["axes"].size(), r.compensation.size());
    EXPECT_TRUE(j["header"]["temperatures_C"]["air"].is_null());
}

}  // namespace
}  // namespace ballbar::report
