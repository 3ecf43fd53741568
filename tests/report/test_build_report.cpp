// SPDX-License-Identifier: MIT
// build_report against a real database: what was stored is what the report (PDF and JSON) shows.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "ballbar/analysis/orientation.hpp"
#include "ballbar/report/build.hpp"
#include "poppler.hpp"
#include "store_fixture.hpp"
#include "text_format.hpp"

namespace ballbar::report {
namespace {

using testing::fixed_text;
using testing::plus_minus_text;

using testing::TempDir;

storage::StoreOptions fast() {
    storage::StoreOptions o;
    o.sync_full = false;  // a test does not need each commit to survive a power loss
    return o;
}

class BuildByType : public ::testing::TestWithParam<analysis::MachineType> {};

TEST_P(BuildByType, StoredSessionBecomesTheReport) {
    TempDir dir;
    storage::Store store((dir.path / "b.db").string(), fast());
    const auto stored = testing::store_synthetic_session(store, GetParam(), 30000, 4);
    const Report r = build_report(store, stored.id, {500, "9.9.9"});

    EXPECT_EQ(r.header.machine.type, GetParam());
    EXPECT_EQ(r.header.instrument_serial, "SN-0042");
    EXPECT_EQ(r.header.status, "completed");
    EXPECT_EQ(r.header.software_version, "9.9.9");
    ASSERT_TRUE(r.header.bar_temp_C.present());
    EXPECT_NEAR(*r.header.bar_temp_C.min, 20.2, 1e-3);
    ASSERT_TRUE(r.header.machine_temp_C.present());
    EXPECT_TRUE(r.header.air_temp_C.mean == std::nullopt);

    EXPECT_EQ(r.trace.samples, 30000u);
    EXPECT_LE(r.trace.time_s.size(), 4u * 500u);
    EXPECT_NEAR(r.trace.time_s.back(), 29.999, 1e-9);  // device time from the first sample
    ASSERT_EQ(r.captures.size(), 12u);
    // Capture windows are the stored sample windows: 1 kHz samples, so seq/1000 s.
    EXPECT_NEAR(r.captures[0].start_s, 1.25, 1e-9);
    EXPECT_NEAR(r.captures[0].end_s, 2.25, 1e-9);

    ASSERT_EQ(r.locations.size(), stored.ssm.size());
    for (std::size_t i = 0; i < r.locations.size(); ++i)
        for (int k = 0; k < 3; ++k)
            EXPECT_DOUBLE_EQ(r.locations[i].error_um[k], stored.ssm[i]["dV_mm"][k].get<double>() * 1000);
    EXPECT_FALSE(r.orientation.empty());
    EXPECT_GE(r.procedure.size(), 3u);  // create, start, finish
    EXPECT_EQ(r.procedure.back().kind, "finish");

    // The numbers appear in the PDF as the JSON gives them.
    const auto pdf = dir.path / "r.pdf";
    const int pages = render_pdf(r, pdf.string());
    EXPECT_EQ(testing::pdf_pages(pdf), pages);
    const std::string text = testing::pdf_text(pdf);
    const auto j = to_json(r);
    for (const auto& l : j["locations"])
        for (int k = 0; k < 3; ++k)
            EXPECT_NE(text.find(plus_minus_text(l["dV_um"][k].get<double>(), l["dV_um_std"][k].get<double>())),
                      std::string::npos);
    for (const auto& o : j["orientation"])
        EXPECT_NE(text.find(fixed_text(o["exact_arcsec"].get<double>(), 1) + "″"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, BuildByType,
                         ::testing::Values(analysis::MachineType::RRTTT, analysis::MachineType::TTTRR,
                                           analysis::MachineType::RTTTR),
                         [](const auto& p) { return std::string(analysis::to_string(p.param)); });

TEST(BuildReport, RtttrTestsGiveOnlyTheirOwnAngle) {
    TempDir dir;
    storage::Store store((dir.path / "b.db").string(), fast());
    const auto stored = testing::store_synthetic_session(store, analysis::MachineType::RTTTR, 3000, 2);
    const Report r = build_report(store, stored.id);
    ASSERT_EQ(r.orientation.size(), 2u);
    EXPECT_EQ(r.orientation[0].symbol, "Δβ");  // test 0: spindle set-up
    EXPECT_EQ(r.orientation[1].symbol, "Δα");  // test 1: table set-up
}

/// Issue 25: "which angles a test measures" had six copies, and for an RTTTR test stored with both axes
/// the report showed Δα and Δβ, the gauge demo Δβ and `measure` nothing; the solver determines Δα
/// (it takes every RTTTR test that is not a spindle test as a table test). One rule now: Δα.
TEST(BuildReport, AnRtttrTestStoredWithBothAxesGivesTheAngleTheSolverDetermines) {
    TempDir dir;
    storage::Store store((dir.path / "b.db").string(), fast());
    const auto stored = testing::store_synthetic_session(store, analysis::MachineType::RTTTR, 3000, 2);
    nlohmann::json o = stored.orientation[0];
    o["kind"] = "BothAxes";
    o["test"] = 2;
    store.add_result(stored.id, "orientation", o.dump());
    const Report r = build_report(store, stored.id);
    ASSERT_EQ(r.orientation.size(), 3u);
    EXPECT_EQ(r.orientation[0].symbol, "Δβ");  // the fixture's spindle test
    EXPECT_EQ(r.orientation[1].symbol, "Δα");  // its table test
    EXPECT_EQ(r.orientation[2].symbol, "Δα");  // both axes: what the solver determines
}

/// Issue 25: the stream's gaps were never stored; the report shows how many and how long.
TEST(BuildReport, TheStreamsRecordedGapsAreShown) {
    TempDir dir;
    storage::Store store((dir.path / "b.db").string(), fast());
    const auto stored = testing::store_synthetic_session(store, analysis::MachineType::TTTRR, 3000, 2);
    EXPECT_EQ(build_report(store, stored.id).trace.gaps, 0u);
    store.add_sample_gap(stored.id, storage::SampleGap{100, 0.25, "lost frames"});
    store.add_sample_gap(stored.id, storage::SampleGap{900, std::nullopt, "reconnect"});
    const Report r = build_report(store, stored.id);
    EXPECT_EQ(r.trace.gaps, 2u);
    EXPECT_DOUBLE_EQ(r.trace.gap_s, 0.25);
    EXPECT_EQ(to_json(r)["bar_trace"]["gaps"], 2);
    const auto pdf = dir.path / "g.pdf";
    render_pdf(r, pdf.string());
    EXPECT_NE(testing::pdf_text(pdf).find("2 gaps in the stream, 0.250 s"), std::string::npos);
}

TEST(BuildReport, MalformedResultIsNamed) {
    TempDir dir;
    storage::Store store((dir.path / "b.db").string(), fast());
    const auto stored = testing::store_synthetic_session(store, analysis::MachineType::TTTRR, 3000, 3);
    nlohmann::json bad = stored.ssm[0];
    bad["dV_mm"] = {1, 2};
    const auto id = store.add_result(stored.id, "ssm", bad.dump());
    try {
        build_report(store, stored.id);
        FAIL() << "no error";
    } catch (const ReportError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("result " + std::to_string(id)), std::string::npos) << what;
        EXPECT_NE(what.find("dV_mm"), std::string::npos) << what;
    }
}

TEST(BuildReport, UnknownSessionIsNotFound) {
    TempDir dir;
    storage::Store store((dir.path / "b.db").string(), fast());
    try {
        build_report(store, 42);
        FAIL() << "no error";
    } catch (const storage::StorageError& e) {
        EXPECT_EQ(e.kind(), storage::StorageError::Kind::not_found);
    }
}

}  // namespace
}  // namespace ballbar::report
