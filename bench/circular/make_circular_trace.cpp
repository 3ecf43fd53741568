// SPDX-License-Identifier: MIT
// Writes one ballbar-trace/1 file from the independent generator, for the whole-process timing of
// `ballbar circle analyze` and for trying the CLI by hand.
//   make_circular_trace OUT.csv [--samples N] [--seed S] [--plane XY|YZ|ZX] [--partial]
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include "trace_generator.hpp"

using namespace ballbar::testgen;

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: make_circular_trace OUT [--samples N] [--seed S] [--plane P] [--partial]\n");
        return 2;
    }
    long samples = 100000;
    unsigned long long seed = 7;
    int plane = 0;
    bool partial = false;
    for (int i = 2; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--samples") && i + 1 < argc)
            samples = std::atol(argv[++i]);
        else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc)
            seed = std::strtoull(argv[++i], nullptr, 10);
        else if (!std::strcmp(argv[i], "--plane") && i + 1 < argc) {
            const std::string p = argv[++i];
            plane = p == "YZ" ? 1 : p == "ZX" ? 2 : 0;
        } else if (!std::strcmp(argv[i], "--partial"))
            partial = true;
    }
    std::mt19937_64 rng(seed);
    GenCase c = random_case(rng, 0.5);
    c.spec.plane = plane;
    c.spec.radius_mm = 100.0;
    c.spec.feed_mm_min = 1000.0;
    c.spec.centre_mm = {0.0, 0.0, 0.0};
    c.spec.runs = partial ? std::vector<GenRun>{{true, -20, 20, 180}, {false, 200, 20, 180}}
                          : std::vector<GenRun>{{true, 0, 45, 360}, {false, 90, 45, 360}};
    // The sample rate that makes the whole recording `samples` long.
    const double arc_s = [&] {
        double s = 0;
        for (const auto& r : c.spec.runs)
            s += (2 * r.overshoot_deg + r.data_arc_deg) * M_PI / 180.0 * c.spec.radius_mm / (c.spec.feed_mm_min / 60.0);
        return s;
    }();
    c.spec.sample_hz = static_cast<double>(samples) / (arc_s + 2.0);
    const GenTrace g = generate(c.spec, c.fx, rng);
    // A new file only: never write over what this program did not create ("x": exclusive creation).
    std::FILE* out = std::fopen(argv[1], "wbx");
    if (!out) {
        std::fprintf(stderr, "make_circular_trace: cannot create %s (it exists, or: %s); nothing written\n", argv[1],
                     std::strerror(errno));
        return 1;
    }
    const std::string text = to_file(c.spec, g);
    const bool ok = std::fwrite(text.data(), 1, text.size(), out) == text.size();
    if (std::fclose(out) != 0 || !ok) {
        std::fprintf(stderr, "make_circular_trace: writing %s failed\n", argv[1]);
        return 1;
    }
    std::fprintf(stderr, "%zu samples at %.1f Hz\n", g.time_s.size(), c.spec.sample_hz);
    return 0;
}
