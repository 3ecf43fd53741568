// SPDX-License-Identifier: MIT
// `ballbar report` for a session of 1 million samples (≈ 17 min at 1 kHz): the database read with the
// min/max reduction (build_report), the PDF (render_pdf), and both together — the acceptance figure
// (under 2 s). The session is stored once, in a temporary database, before the timings.
//
//   bench_report --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "ballbar/report/build.hpp"
#include "poppler.hpp"
#include "store_fixture.hpp"

namespace {

using namespace ballbar;

constexpr std::uint64_t kSamples = 1'000'000;

struct Fixture {
    report::testing::TempDir dir;
    std::unique_ptr<storage::Store> store;
    std::int64_t session = 0;

    Fixture() {
        storage::StoreOptions o;
        o.sync_full = false;
        store = std::make_unique<storage::Store>((dir.path / "bench.db").string(), o);
        session = report::testing::store_synthetic_session(*store, analysis::MachineType::TTTRR, kSamples, 1, 4, 6).id;
    }
};

Fixture& fixture() {
    static Fixture f;
    return f;
}

void BM_BuildReport(benchmark::State& state) {
    auto& f = fixture();
    for (auto _ : state) {
        report::Report r = report::build_report(*f.store, f.session);
        benchmark::DoNotOptimize(r.trace.time_s.data());
    }
    state.counters["samples"] = static_cast<double>(kSamples);
}

void BM_RenderPdf(benchmark::State& state) {
    auto& f = fixture();
    const report::Report r = report::build_report(*f.store, f.session);
    const auto pdf = (f.dir.path / "render.pdf").string();
    for (auto _ : state) benchmark::DoNotOptimize(report::render_pdf(r, pdf));
}

void BM_ReportFromDatabaseToPdf(benchmark::State& state) {
    auto& f = fixture();
    const auto pdf = (f.dir.path / "report.pdf").string();
    for (auto _ : state) {
        const report::Report r = report::build_report(*f.store, f.session);
        benchmark::DoNotOptimize(report::render_pdf(r, pdf));
    }
    state.counters["samples"] = static_cast<double>(kSamples);
}

BENCHMARK(BM_BuildReport)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_RenderPdf)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_ReportFromDatabaseToPdf)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
