// SPDX-License-Identifier: MIT
// Discovery beyond its library, on readings of the independent generator (independent_readings.hpp):
// the noise floor and the verdict, where the structure lives, the learned term, false alarms on clean
// readings. The full campaign is bench/discovery (bench_discovery_campaign).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ballbar/analysis/compensate.hpp"
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
        o.library_ok = std::any_of(r.steps.begin(), r.steps.end(), [&](const ba::DiscoveryStep& s) {
            return !s.withdrawn && s.effect->id == sc.library_effect;
        });
    o.extra = r.learned.size() > 1 || std::any_of(r.steps.begin(), r.steps.end(), [&](const ba::DiscoveryStep& s) {
                  return !s.withdrawn && s.effect->id != sc.library_effect;
              });
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
    int ok = 0, total = 0, extra = 0;
    for (const char* type : {"TTTRR", "RRTTT", "RTTTR"})
        for (const std::string& kind : indep::kinds())
            for (bool lib : {false, true}) {
                const std::uint64_t seed = 100 + static_cast<std::uint64_t>(total);
                const indep::Scenario sc = indep::make_scenario(type, kind, lib, seed);
                const Outcome o = run(sc, seed);
                ++total;
                const bool good = o.family_ok && o.library_ok && o.rms_ok;
                ok += good;
                extra += o.extra;
                EXPECT_TRUE(good) << type << " " << kind << (lib ? " + " + sc.library_effect : "") << ": found '"
                                  << o.found << "' library " << o.library_ok << " rms " << o.rms_ok;
            }
    std::printf(
        "found in the right variable, library effect named, final RMS <= 1.5x floor: %d of %d (%d with "
        "something else named too)\n",
        ok, total, extra);
    EXPECT_LE(extra, 2);
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

TEST(DiscoveryBeyond, EmpiricalTermNamesRoundTrip) {
    std::mt19937_64 rng(1);
    const ba::ReadingSet set =
        indep::generate(indep::make_scenario("TTTRR", "clean", false, 1).m, rng).to_reading_set();
    for (const auto& fam : ba::empirical_families(set))
        for (const auto& t : fam.terms) {
            const auto back = ba::parse_empirical_term(t.name());
            ASSERT_TRUE(back) << t.name();
            EXPECT_EQ(back->name(), t.name());
        }
    EXPECT_TRUE(ba::parse_empirical_term("C_angular_h1_cos"));
    EXPECT_TRUE(ba::parse_empirical_term("X_positioning_p2"));
    EXPECT_TRUE(ba::parse_empirical_term("X0C_drift"));
    EXPECT_FALSE(ba::parse_empirical_term("C_angular_h1_tan"));
    EXPECT_FALSE(ba::parse_empirical_term("EXX_drift"));
    EXPECT_FALSE(ba::parse_empirical_term("nonsense"));
}

/// RMS over poses of the tool-ball error on the table (µm, table frame) on the generator's machine,
/// commanding `comp`'s exact correction (or the nominal pose without `comp`).
double compensated_error_um(const indep::Machine& truth, const ba::MachineGeometry& g, const ba::Compensator* comp) {
    double sum = 0;
    int count = 0;
    for (double a : {0.0, 20.0, -25.0})
        for (int c = 0; c < 36; ++c) {
            const indep::V3 socket(100, 15, 40);
            const double cdeg = 10.0 * c + 5;
            const indep::V3 s_nom = indep::nominal_table_ball(truth, a, cdeg, socket);
            const indep::V3 cmd = indep::command_for(truth, a, cdeg, s_nom + indep::V3(0, 0, 100));
            ba::Pose u;
            u.X_mm = cmd.x();
            u.Y_mm = cmd.y();
            u.Z_mm = cmd.z();
            u.A_rad = a * indep::kDeg;
            u.C_rad = cdeg * indep::kDeg;
            const ba::Pose v = comp ? comp->exact(u).commanded : u;
            indep::Row r;
            r.X = v.X_mm;
            r.Y = v.Y_mm;
            r.Z = v.Z_mm;
            r.r1_deg = v.A_rad / indep::kDeg;
            r.r2_deg = v.C_rad / indep::kDeg;
            r.socket = socket;
            // Where the tool ball is on the table, against where the nominal machine puts it.
            const indep::V3 nominal_on_table =
                indep::rz(-cdeg * indep::kDeg) *
                (indep::rx(-a * indep::kDeg) * (cmd + truth.tool - truth.a_pivot) - truth.c_offset);
            sum += (indep::actual_tool_in_table(truth, r) - nominal_on_table).squaredNorm();
            ++count;
        }
    (void)g;
    return std::sqrt(sum / count) * 1e3;
}

TEST(DiscoveryBeyond, CompensationWithTheLearnedAngularTableRemovesTheEffect) {
    indep::Scenario sc = indep::make_scenario("TTTRR", "angular", false, 11);
    sc.m.angular_amp_rad = 80e-6;
    sc.m.err["A_zero"] = sc.m.err["C_zero"] = 0;  // what no ball-bar reading can see (docs/discovery.md)
    std::mt19937_64 rng(11);
    const ba::ReadingSet set = indep::generate(sc.m, rng).to_reading_set();
    const ba::DiscoveryResult r = ba::discover(set);
    ASSERT_FALSE(r.learned.empty());
    ASSERT_EQ(r.learned.front().family, "C_angular");
    indep::Machine truth = sc.m;
    truth.socket_offsets.clear();
    const ba::Compensator without(set.machine, r.final_fit.model);
    const ba::Compensator with(set.machine, r.final_fit.model, r.learned_terms);
    const double none = compensated_error_um(truth, set.machine, nullptr);
    const double lib = compensated_error_um(truth, set.machine, &without);
    const double learned = compensated_error_um(truth, set.machine, &with);
    std::printf("tool-ball error RMS: uncompensated %.3f um, model without the learned term %.3f um, with it %.3f um\n",
                none, lib, learned);
    EXPECT_GT(lib, 3.0);
    EXPECT_LT(learned, 0.2 * lib);
    EXPECT_LT(learned, 1.0);
}

}  // namespace
