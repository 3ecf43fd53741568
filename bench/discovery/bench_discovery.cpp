// SPDX-License-Identifier: MIT
// The discovery workflow end to end (base fit, residual analysis, candidate scores, refits) on
// synthetic TTTRR sessions of 252 to 100,800 readings with one hidden effect (scale_X), and the
// parts alone: the base fit and the residual analysis. Target: 100,000 readings in under 1 s.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <random>
#include <string_view>

#include "ballbar/analysis/discovery.hpp"
#include "ballbar/analysis/simulate_readings.hpp"
#include "ballbar/storage/readings_file.hpp"

namespace ba = ballbar::analysis;

namespace {

ba::ReadingSet session(int repeat) {
    std::mt19937_64 rng(42);
    const ba::SimulationPlan plan = ba::default_plan(ba::MachineType::TTTRR);
    ba::SimulatedMachine m = ba::random_base_machine(plan, rng);
    m.errors[ba::Param::EXX] = 60e-6;
    return ba::simulate_readings(plan, m, rng, repeat);
}

void BM_Discover(benchmark::State& state) {
    const ba::ReadingSet set = session(static_cast<int>(state.range(0)));
    std::size_t steps = 0;
    for (auto _ : state) {
        const ba::DiscoveryResult r = ba::discover(set);
        steps = r.steps.size();
        benchmark::DoNotOptimize(r.rms_final_mm);
    }
    state.counters["readings"] = static_cast<double>(set.readings.size());
    state.counters["steps"] = static_cast<double>(steps);
}
BENCHMARK(BM_Discover)->Arg(1)->Arg(40)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BaseFit(benchmark::State& state) {
    const ba::ReadingSet set = session(static_cast<int>(state.range(0)));
    ba::FitOptions fo;
    fo.free_params = ba::rotary_params_for(set.machine.type);
    for (auto _ : state) benchmark::DoNotOptimize(ba::fit_error_model(set, fo).residual_rms_mm);
    state.counters["readings"] = static_cast<double>(set.readings.size());
}
BENCHMARK(BM_BaseFit)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ResidualAnalysis(benchmark::State& state) {
    const ba::ReadingSet set = session(static_cast<int>(state.range(0)));
    const Eigen::MatrixXd vars = ba::explaining_variables(set);
    const Eigen::VectorXd r = Eigen::VectorXd::Random(vars.rows());
    for (auto _ : state) benchmark::DoNotOptimize(ba::analyse_residuals(r, vars).rms_mm);
    state.counters["readings"] = static_cast<double>(set.readings.size());
}
BENCHMARK(BM_ResidualAnalysis)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

// `bench_discovery --write-readings FILE [REPEAT]` writes the benchmark's session as a
// ballbar-readings/1 file instead (for run_discover_100k.sh, the whole-process measurement).
int main(int argc, char** argv) {
    if (argc >= 3 && std::string_view(argv[1]) == "--write-readings") {
        const int repeat = argc >= 4 ? std::atoi(argv[3]) : 400;
        ballbar::storage::write_readings_file(argv[2], session(repeat));
        return 0;
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
