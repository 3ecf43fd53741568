// SPDX-License-Identifier: MIT
// Ingest benchmark of the sample store (docs/storage.md, "Performance"):
//  1. SampleWriter into a session (schema v1: WITHOUT ROWID samples keyed (session, seq)), large batches;
//  2. the same with the acquisition's 100 ms batches at 1 kHz (100 samples a commit);
//  3. the sqlite3 shell's `.import` of the same samples as CSV into a same-shaped table.
// Each is run R times on a fresh database; medians are reported, with bytes per stored sample.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <vector>

#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"

namespace {

namespace fs = std::filesystem;
using namespace ballbar;
using Clock = std::chrono::steady_clock;

std::vector<analysis::BarSample> make_samples(std::size_t n) {
    std::vector<analysis::BarSample> v(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double t = static_cast<double>(i) * 1e-3;
        v[i].device_time_us = 1000 + i * 1000;
        v[i].displacement_nm = static_cast<std::int32_t>(
            std::lround(5000 * std::sin(t * 3.1) + 40 * std::sin(static_cast<double>(i) * 1.7)));
        v[i].flags = 0;
        v[i].bar_temp_C = static_cast<float>(20.3 + t * 2e-4);
    }
    return v;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

struct Result {
    double seconds;      ///< wall clock
    double cpu_seconds;  ///< this process's CPU time (user + system); children's for the shell
    double bytes_per_sample;
};

double cpu_now(bool children) {
    rusage u{};
    ::getrusage(children ? RUSAGE_CHILDREN : RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

double db_bytes(storage::Database& db) {
    db.exec("PRAGMA wal_checkpoint(TRUNCATE)");
    return static_cast<double>((db.query_int("PRAGMA page_count") - db.query_int("PRAGMA freelist_count")) *
                               db.query_int("PRAGMA page_size"));
}

Result run_writer(const fs::path& dir, std::span<const analysis::BarSample> samples, std::size_t batch,
                  bool sync_full) {
    const fs::path path = dir / "writer.db";
    fs::remove(path);
    fs::remove(path.string() + "-wal");
    fs::remove(path.string() + "-shm");
    storage::StoreOptions o;
    o.sync_full = sync_full;
    storage::Store store(path.string(), o);
    storage::NewSession ns;
    ns.machine.type = analysis::MachineType::TTTRR;
    const auto id = store.create_session(ns);
    store.start_session(id);
    const double empty = db_bytes(store.db());
    const double c0 = cpu_now(false);
    const auto t0 = Clock::now();
    {
        storage::SampleWriter w(store, id, {UINT64_MAX, batch, std::chrono::hours(1)});
        for (const auto& s : samples) w.append(s);
        w.flush();
    }
    const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
    const double cpu = cpu_now(false) - c0;
    store.finish_session(id);
    const double bytes = db_bytes(store.db()) - empty;
    return {secs, cpu, bytes / static_cast<double>(samples.size())};
}

constexpr const char* kSameShape =
    "CREATE TABLE samples (session_id INTEGER NOT NULL, seq INTEGER NOT NULL, device_time_us INTEGER NOT NULL, "
    "displacement_nm INTEGER NOT NULL, flags INTEGER NOT NULL, bar_temp_mC INTEGER NOT NULL, "
    "PRIMARY KEY (session_id, seq)) WITHOUT ROWID;";

Result run_shell_import(const fs::path& dir, const fs::path& csv, std::size_t n) {
    const fs::path path = dir / "shell.db";
    fs::remove(path);
    fs::remove(path.string() + "-wal");
    {
        storage::Database db(path.string());
        db.exec("PRAGMA journal_mode = WAL");
        db.exec(kSameShape);
    }
    const std::string cmd = "sqlite3 -bail '" + path.string() +
                            "' 'PRAGMA synchronous = NORMAL' '.mode csv' '.import \"" + csv.string() + "\" samples'";
    const double c0 = cpu_now(true);
    const auto t0 = Clock::now();
    const int rc = std::system(cmd.c_str());
    const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
    const double cpu = cpu_now(true) - c0;
    if (rc != 0) throw std::runtime_error("sqlite3 .import failed: " + cmd);
    storage::Database db(path.string());
    if (db.query_int("SELECT count(*) FROM samples") != static_cast<std::int64_t>(n)) {
        throw std::runtime_error("sqlite3 .import stored the wrong number of rows");
    }
    db.exec("PRAGMA journal_mode = WAL");
    return {secs, cpu, db_bytes(db) / static_cast<double>(n)};
}

void report(const char* name, const std::vector<Result>& runs, std::size_t n) {
    std::vector<double> rate, cpu_rate, bytes;
    for (const auto& r : runs) {
        rate.push_back(static_cast<double>(n) / r.seconds);
        cpu_rate.push_back(static_cast<double>(n) / std::max(r.cpu_seconds, 1e-9));
        bytes.push_back(r.bytes_per_sample);
    }
    std::printf(
        "%-46s wall: median %9.0f samples/s (min %9.0f, max %9.0f)  per CPU-second: %9.0f  %5.1f bytes/sample\n", name,
        median(rate), *std::min_element(rate.begin(), rate.end()), *std::max_element(rate.begin(), rate.end()),
        median(cpu_rate), median(bytes));
}

}  // namespace

int main(int argc, char** argv) {
    std::size_t n = 2'000'000;
    int runs = 5;
    // Everything this program writes goes into a directory it makes itself (mkdtemp) inside --dir
    // (default: the system's temporary directory), and only that directory is removed at the end:
    // --dir names a place to work in, never something to delete.
    fs::path parent = fs::temp_directory_path();
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i];
        if (a == "--samples") n = std::stoul(argv[i + 1]);
        if (a == "--runs") runs = std::stoi(argv[i + 1]);
        if (a == "--dir") parent = argv[i + 1];
    }
    std::string tmpl = (parent / "ballbar-bench-storage-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) {
        std::perror(("bench_ingest: cannot create a directory in " + parent.string()).c_str());
        return 1;
    }
    const fs::path dir = tmpl;
    const auto samples = make_samples(n);
    const fs::path csv = dir / "samples.csv";
    {
        std::ofstream out(csv);
        for (std::size_t i = 0; i < n; ++i) {
            const auto& s = samples[i];
            out << 1 << ',' << i << ',' << s.device_time_us << ',' << s.displacement_nm << ',' << s.flags << ','
                << std::lround(static_cast<double>(s.bar_temp_C) * 1000.0) << '\n';
        }
    }
    std::printf("%zu samples, %d runs each, in %s\n", n, runs, dir.c_str());
    const std::size_t n_small = std::min<std::size_t>(n, 100'000);
    std::vector<Result> big, big_full, small_batches, shell;
    for (int r = 0; r < runs; ++r) {
        big.push_back(run_writer(dir, samples, 65'536, false));
        big_full.push_back(run_writer(dir, samples, 65'536, true));
        small_batches.push_back(run_writer(dir, std::span(samples).first(n_small), 100, true));
        shell.push_back(run_shell_import(dir, csv, n));
    }
    report("SampleWriter, 65536-sample batches, NORMAL", big, n);
    report("SampleWriter, 65536-sample batches, FULL", big_full, n);
    report("SampleWriter, 100-sample batches, FULL", small_batches, n_small);
    report("sqlite3 shell .import (CSV, same table), NORMAL", shell, n);
    std::vector<double> ratio;
    for (int r = 0; r < runs; ++r) {
        ratio.push_back(shell[static_cast<std::size_t>(r)].seconds / big[static_cast<std::size_t>(r)].seconds);
    }
    std::vector<double> cpu_ratio;
    for (int r = 0; r < runs; ++r) {
        cpu_ratio.push_back(shell[static_cast<std::size_t>(r)].cpu_seconds /
                            big[static_cast<std::size_t>(r)].cpu_seconds);
    }
    std::printf("SampleWriter (NORMAL) / sqlite3 .import throughput ratio: wall median %.2f, CPU median %.2f\n",
                median(ratio), median(cpu_ratio));
    fs::remove_all(dir);
    return 0;
}
