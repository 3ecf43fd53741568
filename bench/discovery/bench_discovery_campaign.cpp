// SPDX-License-Identifier: MIT
// The campaign beyond the library (docs/discovery.md): readings of the independent generator
// (tests/analysis/independent_readings.hpp: its own kinematics and plan) with one effect outside the
// library — a periodic angular error of a rotary axis, backlash of a rotary axis, a non-linear
// positioning error of a linear axis, a location error drifting during the test — alone and next to
// a library effect, on the three machine types; and clean readings for the false-alarm rate.
// Prints the counts. `--seeds N` (default 20) per case, `--clean N` (default 200) per type.
// `--write-readings FILE ROWS` writes ROWS readings of a TTTRR session with a once-per-revolution C
// error of 80 µrad and a scale error of X instead (for run_discover_100k.sh).
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>

#include "ballbar/analysis/discovery.hpp"
#include "independent_readings.hpp"

namespace ba = ballbar::analysis;

int main(int argc, char** argv) {
    int seeds = 20, clean = 200;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        if (a == "--write-readings" && i + 2 < argc) {
            indep::Scenario sc = indep::make_scenario("TTTRR", "angular", true, 4);  // seed % 4 == 0: scale_X
            sc.m.angular_amp_rad = 80e-6;
            sc.m.angular_phase_rad = 40 * indep::kDeg;
            const long rows = std::atol(argv[i + 2]);
            std::mt19937_64 rng(4);
            const int per_plan = static_cast<int>(indep::generate(sc.m, rng).rows.size());
            indep::Readings r = indep::generate(sc.m, rng, static_cast<int>((rows + per_plan - 1) / per_plan), 0.3);
            r.rows.resize(static_cast<std::size_t>(rows));
            // A new file only: never write over what this program did not create ("x": exclusive creation).
            std::FILE* out = std::fopen(argv[i + 1], "wx");
            if (!out) {
                std::fprintf(stderr, "cannot create %s (it exists, or: %s); nothing written\n", argv[i + 1],
                             std::strerror(errno));
                return 1;
            }
            const std::string text = r.text();
            const bool ok = std::fwrite(text.data(), 1, text.size(), out) == text.size();
            return std::fclose(out) == 0 && ok ? 0 : 1;
        }
        if (a == "--seeds" && i + 1 < argc) seeds = std::atoi(argv[++i]);
        if (a == "--clean" && i + 1 < argc) clean = std::atoi(argv[++i]);
    }
    const auto t0 = std::chrono::steady_clock::now();
    std::printf("%-6s %-12s %-16s %6s %8s %8s %8s %8s %8s\n", "type", "effect", "next to", "runs", "variable",
                "library", "rms<=1.5", "all", "extra");
    int total = 0, all_ok = 0, extra_total = 0;
    double worst_ratio = 0;
    for (const char* type : {"TTTRR", "RRTTT", "RTTTR"})
        for (const std::string& kind : indep::kinds())
            for (bool lib : {false, true}) {
                int var = 0, named = 0, rms = 0, ok = 0, more = 0;
                std::string next = lib ? "library effect" : "-";
                for (int s = 0; s < seeds; ++s) {
                    const auto seed = static_cast<std::uint64_t>(10000 + 97 * s + (lib ? 1 : 0));
                    const indep::Scenario sc = indep::make_scenario(type, kind, lib, seed);
                    std::mt19937_64 rng(seed * 31 + 7);
                    const ba::DiscoveryResult r = ba::discover(indep::generate(sc.m, rng).to_reading_set());
                    const bool v = !r.learned.empty() && r.learned.front().family == sc.family;
                    const bool l = sc.library_effect.empty() ||
                                   std::any_of(r.steps.begin(), r.steps.end(), [&](const ba::DiscoveryStep& st) {
                                       return !st.withdrawn && st.effect->id == sc.library_effect;
                                   });
                    const double ratio = r.rms_final_mm / r.noise_floor.sigma_mm;
                    worst_ratio = std::max(worst_ratio, ratio);
                    const bool q = r.noise_floor.known() && ratio <= 1.5;
                    var += v;
                    named += l;
                    rms += q;
                    ok += v && l && q;
                    const bool x = r.learned.size() > 1 ||
                                   std::any_of(r.steps.begin(), r.steps.end(), [&](const ba::DiscoveryStep& st) {
                                       return !st.withdrawn && st.effect->id != sc.library_effect;
                                   });
                    more += x;
                    extra_total += x;
                    if (!(v && l && q)) {
                        std::string found;
                        for (const auto& st : r.learned) found += st.family + " ";
                        for (const auto& st : r.steps) found += std::string(st.effect->id) + " ";
                        std::printf("  miss: %s %s%s seed %llu: found %s ratio %.2f\n", type, kind.c_str(),
                                    lib ? (" + " + sc.library_effect).c_str() : "",
                                    static_cast<unsigned long long>(seed), found.c_str(), ratio);
                    }
                }
                std::printf("%-6s %-12s %-16s %6d %8d %8d %8d %8d %8d\n", type, kind.c_str(), next.c_str(), seeds, var,
                            named, rms, ok, more);
                total += seeds;
                all_ok += ok;
            }
    std::printf("all criteria met: %d of %d runs; worst final RMS / noise floor %.2f; something else named too in %d\n",
                all_ok, total, worst_ratio, extra_total);
    int alarms = 0, clean_total = 0;
    for (const char* type : {"TTTRR", "RRTTT", "RTTTR"}) {
        int a = 0;
        for (int s = 0; s < clean; ++s) {
            const auto seed = static_cast<std::uint64_t>(900000 + s);
            const indep::Scenario sc = indep::make_scenario(type, "clean", false, seed);
            std::mt19937_64 rng(seed * 31 + 7);
            const ba::DiscoveryResult r = ba::discover(indep::generate(sc.m, rng).to_reading_set());
            a += !r.steps.empty() || !r.learned.empty() || r.verdict.structure;
        }
        std::printf("clean %s: %d false alarms of %d\n", type, a, clean);
        alarms += a;
        clean_total += clean;
    }
    std::printf("clean readings: %d false alarms of %d (%.2f %%)\n", alarms, clean_total,
                100.0 * alarms / std::max(clean_total, 1));
    std::printf("campaign took %.1f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}
