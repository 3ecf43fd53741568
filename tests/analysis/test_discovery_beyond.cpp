// SPDX-License-Identifier: MIT
// Discovery beyond its library, on readings of the independent generator (independent_readings.hpp):
// the noise floor and the verdict, where the structure lives, the learned term, false alarms on clean
// readings. The full campaign is bench/discovery (bench_discovery_campaign).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ballbar/analysis/discovery.hpp"
#include "independent_readings.hpp"

namespace ba = ballbar::analysis;

namespace {

struct Outcome {
    bool family_ok = false, library_ok = true, rms_ok = false, extra = false;
    std::string found;
};

Outcome run(const indep::Scenario& sc, std::uint64_t seed, ba::DiscoveryResult* keep = nullptr) {
    std::mt19937_64 rng(seed * 7919 + 17);
    const ba::ReadingSet set = indep::generate(sc.m, rng).to_reading_set();
    ba::DiscoveryResult r = ba::discover(set);
    Outcome o;
    for (const auto& l : r.learned) o.found += (o.found.empty() ? "" : ",") + l.family;
    o.family_ok = !r.learned.empty() && r.learned.front().family == sc.family;
    if (!sc.library_effect.empty())
        o.library_ok = std::any_of(r.steps.begin(), r.steps.end(),
                                   [&](const ba::DiscoveryStep& s) { return s.effect->id == sc.library_effect; });
    o.extra = r.learned.size() > 1 || r.steps.size() > (sc.library_effect.empty() ? 0u : 1u);
    o.rms_ok = r.noise_floor.known() && r.rms_final_mm <= 1.5 * r.noise_floor.sigma_mm;
    if (keep) *keep = std::move(r);
    return o;
}

TEST(DiscoveryBeyond, ChiSquareTail) {
    EXPECT_NEAR(ba::chi_square_sf(3.841459, 1), 0.05, 1e-6);
    EXPECT_NEAR(ba::chi_square_sf(18.307038, 10), 0.05, 1e-6);
    EXPECT_NEAR(ba::chi_square_sf(124.342, 100), 0.05, 1e-4);
    EXPECT_NEAR(ba::chi_square_sf(2.0, 2), std::exp(-1.0), 1e-12);
    EXPECT_EQ(ba::chi_square_sf(0, 5), 1.0);
    EXPECT_NEAR(ba::f_critical(0.05, 1, 10), 4.9646, 1e-3);
    EXPECT_NEAR(ba::f_critical(0.05, 3, 20), 3.0984, 1e-3);
}

TEST(DiscoveryBeyond, IssueExampleIsStructureOnTheCAxisNotNoise) {
    indep::Scenario sc = indep::make_scenario("TTTRR", "angular", false, 5);
    sc.m.angular_amp_rad = 80e-6;
    sc.m.angular_phase_rad = 40 * indep::kDeg;
    ba::DiscoveryResult r;
    const Outcome o = run(sc, 5, &r);
    std::printf("floor %.3f um (%s); after library %.3f um: %s (chi2 %.1f, dof %.0f, p %.3g)\n",
                r.noise_floor.sigma_mm * 1e3, r.noise_floor.source.c_str(), r.verdict_library.rms_mm * 1e3,
                r.verdict_library.text.c_str(), r.verdict_library.chi2, r.verdict_library.dof,
                r.verdict_library.p_value);
    for (const auto& l : r.learned) std::printf("learned %s: %s\n", l.family.c_str(), l.description.c_str());
    std::printf("final %.3f um: %s\n", r.rms_final_mm * 1e3, r.verdict.text.c_str());
    EXPECT_EQ(r.noise_floor.source, "within-point spread");
    EXPECT_NEAR(r.noise_floor.sigma_mm, 0.0003, 0.00003);
    EXPECT_TRUE(r.verdict_library.structure);
    ASSERT_TRUE(o.family_ok) << o.found;
    EXPECT_NE(r.learned.front().description.find("once per revolution"), std::string::npos);
    double a = 0, b = 0;
    for (const auto& t : r.learned_terms)
        if (t.term.kind == ba::EmpiricalKind::rotary_angular && t.term.order == 1) (t.term.sine ? b : a) = t.value;
    EXPECT_NEAR(std::hypot(a, b), 80e-6, 8e-6);
    EXPECT_NEAR(std::atan2(b, a) / indep::kDeg, 40, 5);
    EXPECT_TRUE(o.rms_ok);
    EXPECT_FALSE(r.verdict.structure);
}

TEST(DiscoveryBeyond, EachKindFoundInItsVariableOnEveryType) {
    int ok = 0, total = 0;
    for (const char* type : {"TTTRR", "RRTTT", "RTTTR"})
        for (const std::string& kind : indep::kinds())
            for (bool lib : {false, true}) {
                const std::uint64_t seed = 100 + static_cast<std::uint64_t>(total);
                const indep::Scenario sc = indep::make_scenario(type, kind, lib, seed);
                const Outcome o = run(sc, seed);
                ++total;
                const bool good = o.family_ok && o.library_ok && o.rms_ok;
                ok += good;
                EXPECT_TRUE(good) << type << " " << kind << (lib ? " + " + sc.library_effect : "") << ": found '"
                                  << o.found << "' library " << o.library_ok << " rms " << o.rms_ok;
            }
    std::printf("found in the right variable, library effect named, final RMS <= 1.5x floor: %d of %d\n", ok, total);
}

TEST(DiscoveryBeyond, CleanReadingsRaiseFewFalseAlarms) {
    int alarms = 0, total = 0;
    for (const char* type : {"TTTRR", "RRTTT", "RTTTR"})
        for (std::uint64_t seed = 0; seed < 30; ++seed) {
            const indep::Scenario sc = indep::make_scenario(type, "clean", false, 5000 + seed);
            ba::DiscoveryResult r;
            run(sc, 5000 + seed, &r);
            ++total;
            if (!r.steps.empty() || !r.learned.empty() || r.verdict.structure) ++alarms;
        }
    std::printf("clean readings: %d false alarms of %d\n", alarms, total);
    EXPECT_LE(alarms, 1);
}

}  // namespace
