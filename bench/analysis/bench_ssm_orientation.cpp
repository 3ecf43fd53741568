// SPDX-License-Identifier: MIT
// ns/op of the hot numerical services: one exact 3-point SSM solve, and each exact orientation
// inversion (with its first-order formulas, which the same call evaluates). Target: ≤ 1 µs each.
//   bench_analysis --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/layout.hpp"
#include "ballbar/analysis/orientation.hpp"
#include "ballbar/analysis/ssm.hpp"

namespace ba = ballbar::analysis;
using ba::Vec3;

// Every heap allocation of the process (operator new and Eigen's aligned_malloc both end in malloc) is
// counted by interposing glibc's malloc, so each benchmark reports allocations per call: the hot
// paths must show 0.
namespace {
std::size_t g_allocations = 0;
}  // namespace

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* malloc(std::size_t size) {
    ++g_allocations;
    return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
    ++g_allocations;
    return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
    ++g_allocations;
    return __libc_realloc(p, size);
}
}

namespace {

/// Runs `call` in the benchmark loop and reports allocations per call.
template <typename F>
void measure(benchmark::State& state, F&& call) {
    const std::size_t before = g_allocations;
    for (auto _ : state) call();
    state.counters["allocs_per_op"] =
        benchmark::Counter(static_cast<double>(g_allocations - before) /
                           static_cast<double>(std::max<benchmark::IterationCount>(state.iterations(), 1)));
}

void BM_SsmExact3Point(benchmark::State& state) {
    const Vec3 socket{10, -20, 30};
    const auto lay = ba::make_layout(ba::LayoutKind::CubeCorner, socket, 100.0, Vec3::UnitZ());
    const std::array<Vec3, 3> pts{lay.points_mm[0], lay.points_mm[1], lay.points_mm[2]};
    const Vec3 e{0.3, -0.25, 0.3};  // |e| ≈ 0.49 mm: the iteration count of a large error
    std::array<double, 3> dl{};
    for (std::size_t i = 0; i < 3; ++i) dl[i] = (pts[i] + e - socket).norm() - (pts[i] - socket).norm();
    measure(state, [&] {
        const auto r = ba::solve_ssm(socket, pts, dl);
        benchmark::DoNotOptimize(r.exact_mm);
    });
}
BENCHMARK(BM_SsmExact3Point);

void BM_SsmExact6Point(benchmark::State& state) {
    const Vec3 socket{10, -20, 30};
    const auto lay = ba::make_layout(ba::LayoutKind::SixPoint, socket, 100.0, Vec3::UnitZ());
    const Vec3 e{0.3, -0.25, 0.3};
    std::array<double, 6> dl{};
    for (std::size_t i = 0; i < 6; ++i)
        dl[i] = (lay.points_mm[i] + e - socket).norm() - (lay.points_mm[i] - socket).norm() + (i % 2 ? 1e-4 : -1e-4);
    measure(state, [&] {
        const auto r = ba::solve_ssm(socket, lay.points_mm, dl);
        benchmark::DoNotOptimize(r.exact_mm);
    });
}
BENCHMARK(BM_SsmExact6Point);

/// Positive control of the allocation counter: above 16 points the rows live on the heap.
void BM_SsmExact20PointHeap(benchmark::State& state) {
    const Vec3 socket{0, 0, 0};
    std::vector<Vec3> pts;
    for (int k = 0; k < 20; ++k) {
        const double az = 2.0 * ba::kPi * k / 20.0, th = k % 2 ? 0.6 : 1.2;
        pts.push_back(100.0 * Vec3(std::sin(th) * std::cos(az), std::sin(th) * std::sin(az), std::cos(th)));
    }
    const Vec3 e{0.1, 0.2, -0.1};
    std::vector<double> dl;
    for (const auto& p : pts) dl.push_back((p + e).norm() - p.norm());
    measure(state, [&] {
        const auto r = ba::solve_ssm(socket, pts, dl);
        benchmark::DoNotOptimize(r.exact_mm);
    });
}
BENCHMARK(BM_SsmExact20PointHeap);

void BM_OrientationRrttt(benchmark::State& state) {
    // Table 1, case 3.
    ba::MachineGeometry g;
    g.type = ba::MachineType::RRTTT;
    g.tool_ball_mm = {0, 0, -250};
    const ba::Pose pose{-50, -15, 500, ba::deg_to_rad(45), ba::deg_to_rad(60), 0};
    ba::ErrorParams err;
    err[ba::Param::A_zero] = ba::deg_to_rad(0.12);
    err[ba::Param::B_zero] = ba::deg_to_rad(0.1);
    const Vec3 dv2 = ba::actual_tool_ball(g, err, pose, ba::ReadingConditions{}) - ba::nominal_tool_ball(g, pose);
    const ba::RrtttInput in{pose.linear_mm(), -250, pose.A_rad, pose.B_rad, Vec3::Zero(), dv2};
    measure(state, [&] {
        const auto s = ba::solve_orientation(in);
        benchmark::DoNotOptimize(s.exact);
    });
}
BENCHMARK(BM_OrientationRrttt);

void BM_OrientationTttrr(benchmark::State& state) {
    ba::MachineGeometry g;
    g.type = ba::MachineType::TTTRR;
    g.c_offset_mm = {0, 0, -100};
    const Vec3 socket{-49.275, -14.312, -77.777};
    ba::Pose pose;
    pose.A_rad = ba::deg_to_rad(10);
    pose.C_rad = ba::deg_to_rad(30);
    ba::ErrorParams err;
    err[ba::Param::A_zero] = 0.002;
    err[ba::Param::C_zero] = -0.003;
    const Vec3 dv2 = ba::actual_table_ball<double>(g, err, pose, socket) - ba::nominal_table_ball(g, pose, socket);
    const ba::TtttrrInput in{Vec3::Zero(), -100, socket, pose.A_rad, pose.C_rad, Vec3::Zero(), dv2};
    measure(state, [&] {
        const auto s = ba::solve_orientation(in);
        benchmark::DoNotOptimize(s.exact);
    });
}
BENCHMARK(BM_OrientationTttrr);

void BM_OrientationRtttrSpindle(benchmark::State& state) {
    const ba::RtttrSpindleInput in{{10, 20, 400}, -200, 0.6, Vec3::Zero(), {-0.2, 0, 0.15}};
    measure(state, [&] {
        const auto s = ba::solve_orientation(in);
        benchmark::DoNotOptimize(s.exact);
    });
}
BENCHMARK(BM_OrientationRtttrSpindle);

void BM_OrientationRtttrTable(benchmark::State& state) {
    const ba::RtttrTableInput in{Vec3::Zero(), {20, 60, 80}, 0.4, Vec3::Zero(), {0, -0.15, 0.1}};
    measure(state, [&] {
        const auto s = ba::solve_orientation(in);
        benchmark::DoNotOptimize(s.exact);
    });
}
BENCHMARK(BM_OrientationRtttrTable);

}  // namespace

BENCHMARK_MAIN();
