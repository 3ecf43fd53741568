// SPDX-License-Identifier: MIT
// Identification speed: ~16 parameters from 10,000 readings (target ≤ 50 ms), and the pieces.
#include <benchmark/benchmark.h>

#include <random>

#include "ballbar/analysis/identify.hpp"
#include "ballbar/analysis/plan_identification.hpp"

namespace {

using namespace ballbar::analysis;

struct Problem {
    ReadingSet readings;
    FitOptions options;
};

// 10,000 readings of an RRTTT machine (all 16 requested parameters observable) at random angle pairs
// around two sockets, with 0.5 µm noise.
Problem make_problem(std::size_t n_readings) {
    MachineGeometry g;
    g.type = MachineType::RRTTT;
    g.tool_ball_mm = Vec3(0, 0, -150);
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> angle(-0.8, 0.8);
    IdentificationPlan plan;
    const Vec3 sockets[2] = {Vec3(0, 0, -250), Vec3(150, 50, -250)};
    for (std::size_t k = 0; plan.readings() < n_readings; ++k) {
        Pose rot;
        rot.A_rad = angle(rng);
        rot.B_rad = angle(rng);
        plan.locations.push_back(ssm_location(g, rot, sockets[k % 2], 100.0, 0.9553166181245093, 4));
    }
    Problem p;
    p.readings = plan_readings(g, plan);
    ErrorParams truth;
    for (Param q : {Param::Y0A, Param::Z0A, Param::X0B, Param::Z0B}) truth[q] = 0.02;
    for (Param q : {Param::B0A, Param::C0A, Param::A0B, Param::C0B, Param::C0Y, Param::B0Z, Param::A0Z})
        truth[q] = 4e-5;
    for (Param q : {Param::EXX, Param::EYY}) truth[q] = 2e-5;
    const std::vector<Vec3> offsets{Vec3(0.03, -0.02, 0.01), Vec3(-0.01, 0.04, -0.02)};
    const Eigen::VectorXd r = reading_residuals(p.readings, truth, offsets);
    std::normal_distribution<double> noise(0, 0.0005);
    for (std::size_t i = 0; i < p.readings.readings.size(); ++i)
        p.readings.readings[i].measured_mm -= r[static_cast<Eigen::Index>(i)] - noise(rng);
    p.options.free_params = {Param::Y0A, Param::Z0A,    Param::B0A,    Param::C0A,       Param::X0B, Param::Z0B,
                             Param::A0B, Param::C0B,    Param::EXX,    Param::EYY,       Param::C0Y, Param::B0Z,
                             Param::A0Z, Param::A_zero, Param::B_zero, Param::bar_length};
    return p;
}

void BM_Identify16Params10kReadings(benchmark::State& state) {
    const Problem p = make_problem(static_cast<std::size_t>(state.range(0)));
    std::size_t fitted = 0;
    double jevals = 0, iters = 0;
    for (auto _ : state) {
        const FitSummary s = fit_error_model(p.readings, p.options);
        fitted = s.fitted.size();
        jevals = s.jacobian_evaluations;
        iters = s.iterations;
        benchmark::DoNotOptimize(s.residual_rms_mm);
    }
    state.counters["unknowns_fitted"] = static_cast<double>(fitted);
    state.counters["jacobians"] = jevals;
    state.counters["iterations"] = iters;
    state.counters["readings"] = static_cast<double>(p.readings.readings.size());
}
BENCHMARK(BM_Identify16Params10kReadings)->Arg(10000)->Unit(benchmark::kMillisecond)->MinTime(1.0);

void BM_ReadingJacobian10k(benchmark::State& state) {
    const Problem p = make_problem(10000);
    for (auto _ : state) {
        const Eigen::MatrixXd j = reading_jacobian(p.readings, ErrorParams{}, p.options.free_params, {}, true);
        benchmark::DoNotOptimize(j.data());
    }
}
BENCHMARK(BM_ReadingJacobian10k)->Unit(benchmark::kMillisecond);

void BM_Residuals10k(benchmark::State& state) {
    const Problem p = make_problem(10000);
    for (auto _ : state) {
        const Eigen::VectorXd r = reading_residuals(p.readings, ErrorParams{});
        benchmark::DoNotOptimize(r.data());
    }
}
BENCHMARK(BM_Residuals10k)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
