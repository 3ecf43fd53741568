// SPDX-License-Identifier: MIT
// `ballbar report` on circular sessions: a trace from the independent generator (tests/circular) is
// imported; the report's PDF and JSON must carry the figures `circle analyze` gives, the verdict against
// the tolerance (given, or stored with the result) and a polar plot whose points are the samples'
// deviations from one least-squares circle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "poppler.hpp"
#include "text_format.hpp"
#include "trace_generator.hpp"

namespace ballbar::report {
namespace {

using testing::fixed_text;
using testing::plus_minus_text;
using testing::run_capture;
using testing::TempDir;

int run_circular(const std::string& command) {
    const int rc = std::system(command.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// An XY test, both directions, with backlash, squareness and a cyclic error of X.
std::string write_trace(const TempDir& dir) {
    std::mt19937_64 rng(21);
    testgen::GenSpec s;
    s.radius_mm = 100.0, s.feed_mm_min = 2000.0, s.sample_hz = 400.0, s.noise_um = 0.2;
    s.runs = {{true, 0, 45, 360}, {false, 90, 45, 360}};
    testgen::GenEffects fx;
    fx.backlash_um = {6.0, 3.0};
    fx.squareness_um_per_m = 25.0;
    fx.cyclic_um = {1.5, 0.0};
    fx.pitch_mm = {5.0, 5.0};
    const auto path = dir.path / "t.csv";
    std::ofstream(path) << testgen::to_file(s, testgen::generate(s, fx, rng));
    return path.string();
}

struct Imported {
    TempDir dir;
    std::string exe = BALLBAR_EXE, db;
    std::string id;
    Imported() {
        db = testing::quoted(dir.path / "c.db");
        const auto imp = nlohmann::json::parse(
            run_capture(exe + " --db " + db + " import " + testing::quoted(write_trace(dir)) + " --json 2>/dev/null"));
        id = std::to_string(imp["session"].get<int>());
    }
    std::string cmd(const std::string& args) const { return exe + " --db " + db + " " + args; }
};

TEST(CliReportCircular, ImportedTraceReportHoldsTheAnalysisAndTheVerdict) {
    Imported s;
    const auto analysis = nlohmann::json::parse(run_capture(s.cmd("circle analyze " + s.id + " --json")));
    const auto pdf = s.dir.path / "r.pdf";
    const auto j = nlohmann::json::parse(
        run_capture(s.cmd("report " + s.id + " --out " + testing::quoted(pdf) + " --json --tolerance 40 2>/dev/null")));
    ASSERT_TRUE(j["circular"].is_object()) << j.dump().substr(0, 400);
    const auto& c = j["circular"];
    EXPECT_EQ(c["conditions"]["plane"], "XY");
    EXPECT_EQ(c["tolerance"]["circularity_um"], 40.0);
    EXPECT_EQ(c["tolerance"]["source"], "given");
    EXPECT_TRUE(c["tolerance"]["pass"].get<bool>());
    ASSERT_EQ(c["runs"].size(), 2u);
    EXPECT_EQ(c["source"].get<std::string>().rfind("stored result", 0), 0u)  // analyze SESSION stores it
        << c["source"];
    const std::string text = testing::pdf_text(pdf);
    EXPECT_NE(text.find("circular test report"), std::string::npos);
    EXPECT_NE(text.find("PASS"), std::string::npos);
    EXPECT_EQ(text.find("FAIL"), std::string::npos);
    for (std::size_t k = 0; k < 2; ++k) {
        const double g = analysis["runs"][k]["circularity_um"].get<double>();
        EXPECT_DOUBLE_EQ(c["runs"][k]["circularity_um"].get<double>(), g);
        EXPECT_NE(text.find(fixed_text(g, 2)), std::string::npos) << g;
        EXPECT_GT(c["runs"][k]["polar"]["angle_deg"].size(), 1000u);
        EXPECT_EQ(c["runs"][k]["polar"]["angle_deg"].size(), c["runs"][k]["polar"]["deviation_um"].size());
    }
    const double gb = analysis["bidirectional_circularity_um"].get<double>();
    EXPECT_NE(text.find(fixed_text(gb, 2)), std::string::npos);
    EXPECT_NE(text.find(fixed_text(analysis["radial_deviation_um"]["max"].get<double>(), 2)), std::string::npos);
    EXPECT_NE(text.find(fixed_text(analysis["radial_deviation_um"]["min"].get<double>(), 2)), std::string::npos);
    EXPECT_NE(text.find(fixed_text(analysis["residual_rms_um"].get<double>(), 3)), std::string::npos);
    // Every diagnostic with its uncertainty, ranked as the analysis ranks them.
    std::string first_ranked;
    for (const auto& d : analysis["diagnostics"]) {
        const std::string key = d["key"];
        EXPECT_NE(text.find(key), std::string::npos) << key;
        if (key.find("_mm") == std::string::npos && key.find("_ms") == std::string::npos) {
            EXPECT_NE(text.find(plus_minus_text(d["value"].get<double>(), d["value_std"].get<double>())),
                      std::string::npos)
                << key;
        }
        if (d["rank"] == 1) first_ranked = key;
    }
    ASSERT_FALSE(first_ranked.empty());
    for (const auto& d : c["diagnostics"]) {
        if (d["key"] == first_ranked) {
            EXPECT_EQ(d["rank"], 1);
        }
    }
    // The polar plot: the samples' deviation from one least-squares circle for both runs, so its spread
    // over both runs is G(b) (min and max survive the per-column reduction).
    double lo = 1e9, hi = -1e9;
    for (const auto& run : c["runs"])
        for (const auto& v : run["polar"]["deviation_um"])
            lo = std::min(lo, v.get<double>()), hi = std::max(hi, v.get<double>());
    EXPECT_NEAR(hi - lo, gb, 0.05);
    EXPECT_GE(c["polar_plot"]["deviation_um_at_outer_ring"].get<double>(), std::max(hi, -lo));
    // Test conditions.
    EXPECT_NE(text.find("100.000 mm"), std::string::npos);
    EXPECT_NE(text.find("2000 mm/min"), std::string::npos);
    EXPECT_NE(text.find("400.0 Hz"), std::string::npos);
}

TEST(CliReportCircular, StoredToleranceAndFailingVerdict) {
    Imported s;
    ASSERT_EQ(run_circular(s.cmd("circle analyze " + s.id + " --tolerance 0.5 >/dev/null 2>&1")), 1);  // stored, fails
    const auto pdf = s.dir.path / "r.pdf";
    const auto j = nlohmann::json::parse(
        run_capture(s.cmd("report " + s.id + " --out " + testing::quoted(pdf) + " --json 2>/dev/null")));
    const auto& c = j["circular"];
    EXPECT_EQ(c["tolerance"]["circularity_um"], 0.5);
    EXPECT_EQ(c["tolerance"]["source"], "stored with the result");
    EXPECT_FALSE(c["tolerance"]["pass"].get<bool>());
    const std::string text = testing::pdf_text(pdf);
    EXPECT_NE(text.find("FAIL"), std::string::npos);
    EXPECT_NE(text.find("0.50"), std::string::npos);
    // The command line's tolerance wins over the stored one.
    const auto given = nlohmann::json::parse(run_capture(s.cmd("report " + s.id + " --json --tolerance 60")));
    EXPECT_TRUE(given["circular"]["tolerance"]["pass"].get<bool>());
    EXPECT_EQ(run_circular(s.cmd("report " + s.id + " --json --tolerance -3 >/dev/null 2>&1")), 2);
}

TEST(CliReportCircular, WithoutAStoredResultTheReportAnalyses) {
    Imported s;
    const auto j = nlohmann::json::parse(run_capture(s.cmd("report " + s.id + " --json 2>/dev/null")));
    const auto& c = j["circular"];
    EXPECT_EQ(c["source"], "analysed for this report (no stored result)");
    EXPECT_TRUE(c["tolerance"].is_null());
    // The database was opened read-only: nothing stored.
    const auto shown = nlohmann::json::parse(run_capture(s.cmd("sessions show " + s.id + " --json")));
    EXPECT_TRUE(shown["results"].empty()) << shown["results"].dump();
    // The same figures as circle analyze of the file gives.
    const auto analysis = nlohmann::json::parse(run_capture(s.cmd("circle analyze " + s.id + " --json")));
    EXPECT_DOUBLE_EQ(c["runs"][0]["circularity_um"].get<double>(), analysis["runs"][0]["circularity_um"].get<double>());
}

}  // namespace
}  // namespace ballbar::report
