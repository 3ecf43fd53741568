// SPDX-License-Identifier: MIT
// A 1 kHz session at accelerated (simulated) speed: the whole guided procedure — dwell detection,
// averaging, SSM, orientation — over 6 minutes and over one hour of machine time, with the peak RSS
// (getrusage) after each. Flat memory: the hour's peak equals the 6 minutes' peak.
//   bench_acquisition --benchmark_repetitions=3
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/session.hpp"
#include "sim_source.hpp"

namespace {

namespace acq = ballbar::acquisition;
using ballbar::analysis::MachineType;

double peak_rss_mb() {
    rusage u{};
    ::getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_maxrss) / 1024.0;  // kB on Linux
}

/// `minutes` of machine time: two tests of the seed TTTRR plan (12 points), the dwells stretched so
/// the session lasts that long. The plan is the same size either way: only time differs.
void BM_Session(benchmark::State& state) {
    const auto minutes = static_cast<double>(state.range(0));
    const acq::MachineFile m = acq::seed_machine(MachineType::TTTRR);
    acq::PlanSpec spec = acq::default_plan(m);
    spec.tests.resize(2);
    spec.dwell_s = minutes * 60.0 / 12.0 - 1.0;
    const acq::Plan plan = acq::make_plan(m, spec);
    std::uint64_t samples = 0;
    for (auto _ : state) {
        ballbar::device::MachineSetup setup;
        setup.geometry = m.geometry;
        setup.errors = acq::demo_errors(MachineType::TTTRR);
        setup.socket_mm = plan.points.front().socket_mm;
        setup.start = plan.points.front().pose;
        acq::testing::SimOptions so;
        so.record_poses = false;  // flat memory: nothing grows with the session
        acq::testing::SimSource source(setup, plan, so);
        acq::testing::RecordingSink sink;
        acq::testing::SimOperator op(&source);
        acq::Session session(plan, source, sink, op);
        const acq::SessionSummary sum = session.run();
        if (sum.final_state != acq::State::Done) state.SkipWithError(sum.reason.c_str());
        samples = sink.samples;
    }
    state.counters["machine_minutes"] = static_cast<double>(samples) / 1000.0 / 60.0;
    state.counters["samples"] = static_cast<double>(samples);
    state.counters["samples_per_s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
    state.counters["peak_rss_MB"] = peak_rss_mb();
}
BENCHMARK(BM_Session)->Arg(6)->Arg(66)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
