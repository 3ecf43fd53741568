// SPDX-License-Identifier: MIT
// The circular analysis's accuracy campaign: N random traces of the independent generator
// (tests/circular/trace_generator.*), judged by the acceptance rule of tests/circular/accuracy.hpp;
// prints, per diagnostic, the count injected and absent, the largest error relative to its
// tolerance and the pass rate.   bench_circular_accuracy [--cases N] [--seed S] [--only I] [--verbose]
// [--write FILE]: with --only, also writes that case as a ballbar-trace/1 file (a new file only), to
// look at it with `ballbar circle analyze FILE`.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <random>

#include "accuracy.hpp"

using namespace ballbar::testgen;

int main(int argc, char** argv) {
    int cases = 1000, only = -1;
    unsigned long long seed = 1;
    bool verbose = false;
    const char* write_to = nullptr;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--cases") && i + 1 < argc)
            cases = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc)
            seed = std::strtoull(argv[++i], nullptr, 10);
        else if (!std::strcmp(argv[i], "--only") && i + 1 < argc)
            only = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--verbose"))
            verbose = true;
        else if (!std::strcmp(argv[i], "--write") && i + 1 < argc)
            write_to = argv[++i];
        else {
            std::fprintf(
                stderr,
                "usage: bench_circular_accuracy [--cases N] [--seed S] [--only I] [--verbose] [--write FILE]\n");
            return 2;
        }
    }
    struct Row {
        int injected = 0, absent = 0, pass_injected = 0, pass_absent = 0;
        double worst_injected = 0.0, worst_absent = 0.0;  // error / tolerance
        double max_error_injected = 0.0, max_error_absent = 0.0;
    };
    std::map<std::string, Row> table;
    std::mt19937_64 rng(seed);
    int failed_cases = 0, thrown = 0;
    double analysis_s = 0.0;
    for (int i = 0; i < cases; ++i) {
        const GenCase c = random_case(rng);
        const GenTrace g = generate(c.spec, c.fx, rng);
        if (only >= 0 && i != only) continue;
        if (write_to != nullptr && only >= 0) {
            std::FILE* out = std::fopen(write_to, "wbx");  // never over a file this did not create
            const std::string text = to_file(c.spec, g);
            if (out == nullptr || std::fwrite(text.data(), 1, text.size(), out) != text.size() ||
                std::fclose(out) != 0) {
                std::fprintf(stderr, "bench_circular_accuracy: cannot write %s (it exists, or the disk refused)\n",
                             write_to);
                return 1;
            }
        }
        circ::CircularResult r;
        const auto t0 = std::chrono::steady_clock::now();
        try {
            r = circ::analyze_circular(to_test(c.spec), to_samples(g));
        } catch (const std::exception& e) {
            std::printf("case %d: %s\n", i, e.what());
            ++thrown, ++failed_cases;
            continue;
        }
        analysis_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        bool ok = true;
        for (const Check& k : judge(c, g, r)) {
            Row& row = table[k.name];
            const double rel = k.error / k.tolerance;
            if (k.injected) {
                ++row.injected, row.pass_injected += k.pass;
                row.worst_injected = std::max(row.worst_injected, rel);
                row.max_error_injected = std::max(row.max_error_injected, k.error);
            } else {
                ++row.absent, row.pass_absent += k.pass;
                row.worst_absent = std::max(row.worst_absent, rel);
                row.max_error_absent = std::max(row.max_error_absent, k.error);
            }
            if (!k.pass) {
                ok = false;
                std::printf("case %d (%s R %.1f F %.0f arc %.0f fs %.0f): %s %s %.4g found %.4g (error %.3g > %.3g)\n",
                            i, plane_text(c.spec.plane), c.spec.radius_mm, c.spec.feed_mm_min,
                            c.spec.runs[0].data_arc_deg, c.spec.sample_hz, k.name.c_str(),
                            k.injected ? "injected" : "absent", k.truth, k.estimate, k.error, k.tolerance);
            } else if (verbose) {
                std::printf("case %d: %s %.4g found %.4g\n", i, k.name.c_str(), k.truth, k.estimate);
            }
        }
        failed_cases += !ok;
    }
    std::printf("\n%d cases (seed %llu), %d with a failed check, %d refused; analysis %.1f ms per case (mean)\n\n",
                only >= 0 ? 1 : cases, seed, failed_cases, thrown,
                1e3 * analysis_s / std::max(1, only >= 0 ? 1 : cases));
    std::printf(
        "| diagnostic | injected | pass | max error / tolerance | absent | pass | max reported / tolerance |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    for (const auto& [name, row] : table) {
        std::printf("| %s | %d | %.1f %% | %.2f | %d | %.1f %% | %.2f |\n", name.c_str(), row.injected,
                    row.injected ? 100.0 * row.pass_injected / row.injected : 100.0, row.worst_injected, row.absent,
                    row.absent ? 100.0 * row.pass_absent / row.absent : 100.0, row.worst_absent);
    }
    return failed_cases == 0 ? 0 : 1;
}
