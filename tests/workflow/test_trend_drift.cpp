// SPDX-License-Identifier: MIT
// `ballbar trend`'s drift (workflow::assess_drift, docs/fleet.md): the weighted line through a figure's
// values and its flags, against fits worked out by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "ballbar/workflow/trend.hpp"

namespace {

using ballbar::report::TrendSeries;
using ballbar::report::TrendValue;

TrendSeries series_of(std::initializer_list<std::pair<double, double>> t_y, std::optional<double> sd) {
    TrendSeries s;
    s.key = "G_XY_um";
    s.label = "G, XY plane";
    s.unit = "µm";
    int i = 0;
    for (const auto& [t, y] : t_y) {
        TrendValue v;
        v.session = std::to_string(++i);
        v.t_days = t;
        v.value = y;
        v.value_std = sd;
        s.values.push_back(v);
    }
    return s;
}

TEST(TrendDrift, AStraightLineWithUncertaintiesIsFittedAsWorkedOutByHand) {
    // y = 10 + 2 µm a year, σ = 0.1 µm, at 0, 100, 200, 300 days: Σw(t − 150)² = 100 · 50000 d²/µm².
    const double k = 2 / 365.25;
    auto s = series_of({{0, 10}, {100, 10 + 100 * k}, {200, 10 + 200 * k}, {300, 10 + 300 * k}}, 0.1);
    ballbar::workflow::assess_drift(s, "2026-01-01T00:00:00Z");
    ASSERT_TRUE(s.slope_per_year);
    EXPECT_NEAR(*s.slope_per_year, 2.0, 1e-9);
    EXPECT_NEAR(*s.slope_per_year_std, 365.25 / std::sqrt(5e6), 1e-9) << "χ²/dof = 0: no Birge scaling";
    EXPECT_NEAR(*s.intercept, 10.0, 1e-9);
    EXPECT_EQ(s.flag, "drifting");

    s.tolerance = 12;  // the line reaches 12 µm at 365.25 days: 65 days after the last session
    ballbar::workflow::assess_drift(s, "2026-01-01T00:00:00Z");
    EXPECT_EQ(s.flag, "drifting toward tolerance");
    EXPECT_NE(s.detail.find("about 2027-01"), std::string::npos) << s.detail;

    s.tolerance = 20;  // reached only after four years: a drift, not yet a threat
    ballbar::workflow::assess_drift(s, "2026-01-01T00:00:00Z");
    EXPECT_EQ(s.flag, "drifting");

    s.tolerance = 11;  // the last value, 11.64 µm, is beyond it
    ballbar::workflow::assess_drift(s, "2026-01-01T00:00:00Z");
    EXPECT_EQ(s.flag, "over tolerance");
    EXPECT_NE(s.detail.find("session 4"), std::string::npos) << s.detail;
}

TEST(TrendDrift, ScatterBeyondTheUncertaintiesWidensTheSlopesByTheBirgeRatio) {
    // y = 1, 2, 4 µm at 0, 1, 2 days with σ = 0.01 µm: slope 1.5 µm/d; residuals 1/6, −1/3, 1/6 µm, so
    // χ² = (1/6)/σ² and χ²/dof = 1666.7; σ_k = sqrt(1/(w·2)) · sqrt(χ²/dof) = sqrt(1/12) µm/d.
    auto s = series_of({{0, 1}, {1, 2}, {2, 4}}, 0.01);
    ballbar::workflow::assess_drift(s, "2026-01-01T00:00:00Z");
    ASSERT_TRUE(s.slope_per_year);
    EXPECT_NEAR(*s.slope_per_year, 1.5 * 365.25, 1e-9);
    EXPECT_NEAR(*s.slope_per_year_std, std::sqrt(1.0 / 12) * 365.25, 1e-9);
    EXPECT_EQ(s.flag, "drifting") << "1.5 against 0.29: more than 3σ";

    // Without uncertainties: ordinary least squares, σ from the scatter: s² = (1/6)/1, σ_k = sqrt(s²/2).
    auto u = series_of({{0, 1}, {1, 2}, {2, 4}}, std::nullopt);
    ballbar::workflow::assess_drift(u, "2026-01-01T00:00:00Z");
    EXPECT_NEAR(*u.slope_per_year_std, std::sqrt(1.0 / 12) * 365.25, 1e-9);
}

TEST(TrendDrift, TooFewValuesOrADayOnlyGiveNoSlopeAndNoiseIsNoDrift) {
    auto two = series_of({{0, 1}, {30, 5}}, 0.1);
    ballbar::workflow::assess_drift(two, "2026-01-01T00:00:00Z");
    EXPECT_FALSE(two.slope_per_year);
    EXPECT_EQ(two.flag, "");
    auto same_day = series_of({{0, 1}, {0.2, 2}, {0.4, 3}}, 0.1);
    ballbar::workflow::assess_drift(same_day, "2026-01-01T00:00:00Z");
    EXPECT_FALSE(same_day.slope_per_year);
    // Values within their uncertainties of a flat line: no drift.
    auto flat = series_of({{0, 5.0}, {60, 5.1}, {120, 4.95}, {180, 5.05}}, 0.1);
    ballbar::workflow::assess_drift(flat, "2026-01-01T00:00:00Z");
    ASSERT_TRUE(flat.slope_per_year);
    EXPECT_EQ(flat.flag, "") << *flat.slope_per_year << " ± " << *flat.slope_per_year_std;
}

}  // namespace
