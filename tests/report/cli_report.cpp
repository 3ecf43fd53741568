// SPDX-License-Identifier: MIT
// `ballbar report` on real sessions: `ballbar demo` runs the guided procedure against the emulator for
// each machine type and stores it; the report's PDF must carry the numbers its JSON holds.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>

#include "poppler.hpp"
#include "text_format.hpp"

namespace ballbar::report {
namespace {

using testing::fixed_text;
using testing::plus_minus_text;

using testing::quoted;
using testing::run_capture;
using testing::TempDir;

int run(const std::string& command) {
    const int rc = std::system(command.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

class CliReport : public ::testing::TestWithParam<const char*> {};

TEST_P(CliReport, DemoSessionReportHoldsItsNumbers) {
    TempDir dir;
    const std::string exe = BALLBAR_EXE, db = quoted(dir.path / "demo.db");
    ASSERT_EQ(run(exe + " --db " + db + " demo --machine " + GetParam() + " --seed 3 >/dev/null 2>&1"), 0);
    const auto pdf = dir.path / "report.pdf";
    const std::string out = run_capture(exe + " --db " + db + " report 1 --out " + quoted(pdf) + " --json");
    const auto j = nlohmann::json::parse(out);
    EXPECT_EQ(j["schema"], "ballbar-report/2");
    EXPECT_EQ(j["header"]["machine"]["type"], GetParam());
    EXPECT_GT(j["bar_trace"]["samples"].get<double>(), 1000);
    ASSERT_FALSE(j["locations"].empty());
    ASSERT_FALSE(j["orientation"].empty());

    const int pages = testing::pdf_pages(pdf);
    EXPECT_GE(pages, 2);
    const std::string text = testing::pdf_text(pdf);
    EXPECT_NE(text.find("page 1 of " + std::to_string(pages)), std::string::npos);
    for (const auto& l : j["locations"])
        for (int k = 0; k < 3; ++k)
            EXPECT_NE(text.find(plus_minus_text(l["dV_um"][k].get<double>(), l["dV_um_std"][k].get<double>())),
                      std::string::npos)
                << l.dump();
    // The same numbers as `sessions show --json` holds in the stored results (mm and rad there).
    const auto shown = nlohmann::json::parse(run_capture(exe + " --db " + db + " sessions show 1 --json"));
    int ssm = 0, orientation = 0;
    for (const auto& res : shown["results"]) {
        const auto& p = res["payload"];
        if (res["kind"] == "ssm") {
            ++ssm;
            for (int k = 0; k < 3; ++k)
                EXPECT_NE(text.find(plus_minus_text(p["dV_mm"][k].get<double>() * 1000,
                                                    p["e_std_mm"][k].get<double>() * 1000)),
                          std::string::npos)
                    << p.dump();
        } else if (res["kind"] == "orientation" && p["exact"].is_object()) {
            for (const char* key : {"d_alpha_rad", "d_beta_rad", "d_gamma_rad"}) {
                const double rad = p["exact"][key].get<double>();
                if (rad == 0) continue;  // an angle this test does not measure
                ++orientation;
                EXPECT_NE(text.find(fixed_text(rad * 180 / 3.141592653589793, 5) + "°"), std::string::npos)
                    << key << " " << p.dump();
            }
        }
    }
    EXPECT_EQ(static_cast<std::size_t>(ssm), j["locations"].size());
    EXPECT_GT(orientation, 0);
    for (const auto& o : j["orientation"]) {
        if (o["exact_rad"].is_null()) continue;
        EXPECT_NE(text.find(fixed_text(o["exact_deg"].get<double>(), 5) + "°"), std::string::npos) << o.dump();
        EXPECT_NE(text.find(fixed_text(o["exact_arcsec"].get<double>(), 1) + "″"), std::string::npos) << o.dump();
    }
}

INSTANTIATE_TEST_SUITE_P(AllTypes, CliReport, ::testing::Values("RRTTT", "TTTRR", "RTTTR"),
                         [](const auto& p) { return std::string(p.param); });

TEST(CliReportErrors, UnknownSessionAndMissingOutputAreUsageErrors) {
    TempDir dir;
    const std::string exe = BALLBAR_EXE, db = quoted(dir.path / "demo.db");
    ASSERT_EQ(run(exe + " --db " + db + " demo --machine TTTRR --seed 1 >/dev/null 2>&1"), 0);
    EXPECT_EQ(run(exe + " --db " + db + " report 99 --out " + quoted(dir.path / "x.pdf") + " 2>/dev/null"), 2);
    EXPECT_EQ(run(exe + " --db " + db + " report 1 2>/dev/null"), 2);
    EXPECT_EQ(run(exe + " --db " + db + " report 1 --out /nonexistent-dir/x.pdf 2>/dev/null"), 1);
}

}  // namespace
}  // namespace ballbar::report
