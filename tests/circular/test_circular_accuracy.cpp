// SPDX-License-Identifier: MIT
// Accuracy of the circular analysis on random traces of the independent generator: every plane, full
// circles and 180° partial arcs, radius 50–150 mm, feed 500–2000 mm/min, noise 0.1–0.25 µm, random
// subsets of the effects. bench/circular runs the same with 1000 cases and prints the table.
#include <gtest/gtest.h>

#include <random>

#include "../sanitizers.hpp"
#include "accuracy.hpp"

namespace {

using namespace ballbar::testgen;

using ballbar::test::kSanitized;

TEST(CircularAccuracy, RandomTracesFromTheIndependentGenerator) {
    std::mt19937_64 rng(20261201);
    // The accuracy statistics on the optimised build; under the sanitizers (10× slower: 92 s for 60) the
    // first 12 of the same cases, which run every path of the analysis.
    constexpr int kCases = kSanitized ? 12 : 60;
    int failures = 0;
    for (int i = 0; i < kCases; ++i) {
        const GenCase c = random_case(rng);
        const GenTrace g = generate(c.spec, c.fx, rng);
        circ::CircularResult r;
        try {
            r = circ::analyze_circular(to_test(c.spec), to_samples(g));
        } catch (const std::exception& e) {
            ADD_FAILURE() << "case " << i << ": " << e.what();
            ++failures;
            continue;
        }
        for (const Check& k : judge(c, g, r)) {
            if (k.pass) continue;
            ++failures;
            ADD_FAILURE() << "case " << i << " (" << plane_text(c.spec.plane) << ", R " << c.spec.radius_mm << ", F "
                          << c.spec.feed_mm_min << ", arc " << c.spec.runs[0].data_arc_deg << "): " << k.name
                          << (k.injected ? " injected " : " absent ") << k.truth << ", found " << k.estimate
                          << " (error " << k.error << " > " << k.tolerance << ")";
        }
    }
    EXPECT_EQ(failures, 0);
}

}  // namespace
