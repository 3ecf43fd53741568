// SPDX-License-Identifier: MIT
// Compensation throughput: first-order (target ≥ 10 M poses/s on one core) and exact, for a TTTRR
// machine with seed-like errors, over a path of varied poses.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/lei_hsu.hpp"

namespace {

using namespace ballbar::analysis;

MachineGeometry geometry() {
    MachineGeometry g;
    g.type = MachineType::TTTRR;
    g.c_offset_mm = Vec3(0, 0, -100);
    return g;
}

ErrorParams errors() {
    ErrorParams e;
    e[Param::Y0A] = 0.025;
    e[Param::Z0A] = -0.018;
    e[Param::B0A] = 40e-6;
    e[Param::C0A] = -30e-6;
    e[Param::X0C] = 0.035;
    e[Param::Y0C] = -0.022;
    e[Param::A0C] = 50e-6;
    e[Param::B0C] = -35e-6;
    e[Param::C0Y] = 10e-6;
    e[Param::EXX] = 8e-6;
    return e;
}

std::vector<Pose> path(std::size_t n) {
    std::vector<Pose> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double s = 2.0 * kPi * static_cast<double>(i) / static_cast<double>(n);
        out[i] = {100 * std::cos(s), 100 * std::sin(s), 50 + 20 * std::sin(3 * s), 0.5 + 0.3 * std::sin(2 * s), s, 0};
        out[i].C_rad = s - kPi;
        out[i].B_rad = 0;
    }
    return out;
}

void BM_CompensateFirstOrder(benchmark::State& state) {
    const Compensator comp(geometry(), errors());
    const std::vector<Pose> poses = path(4096);
    std::size_t i = 0;
    for (auto _ : state) {
        const Correction c = comp.first_order(poses[i++ & 4095]);
        benchmark::DoNotOptimize(c.commanded);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_CompensateFirstOrder);

void BM_CompensateExact(benchmark::State& state) {
    const Compensator comp(geometry(), errors());
    const std::vector<Pose> poses = path(4096);
    std::size_t i = 0;
    for (auto _ : state) {
        const Correction c = comp.exact(poses[i++ & 4095]);
        benchmark::DoNotOptimize(c.commanded);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_CompensateExact);

void BM_LeiHsuFirstOrder(benchmark::State& state) {
    const std::vector<Pose> poses = path(4096);
    Vec6 dv;
    dv << 0.01, -0.02, 0.005, 2e-5, -1e-5, 1e-5;
    std::size_t i = 0;
    for (auto _ : state) {
        const Pose& p = poses[i++ & 4095];
        Vec5 u;
        u << p.X_mm, p.Y_mm, p.Z_mm, p.A_rad, p.C_rad;
        const LeiHsuCorrection c = lei_hsu_first_order(u, dv);
        benchmark::DoNotOptimize(c.du);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_LeiHsuFirstOrder);

}  // namespace

BENCHMARK_MAIN();
