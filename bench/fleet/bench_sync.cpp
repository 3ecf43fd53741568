// SPDX-License-Identifier: MIT
// bench_fleet_sync: how fast `ballbar sync` sends raw samples, against psql's \copy of the same rows into
// the same table of the same server (PostgreSQL's own bulk path: the target is ≥ 0.8× its rate), and how
// long a sync takes that has nothing to send (100 sessions: the target is ≤ 1 s). A throwaway server
// (scripts/pg_throwaway.sh) over its Unix socket; each run alternates the two, tables emptied between.
//
//   bench_fleet_sync [--samples 2000000] [--runs 5] [--sessions 100]
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ballbar/fleet/sync.hpp"
#include "ballbar/storage/store.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using namespace ballbar;

std::string run(const std::string& cmd) {
    std::string out;
    FILE* p = ::popen(cmd.c_str(), "r");
    char buf[4096];
    std::size_t n;
    while (p && (n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    if (!p || ::pclose(p) != 0) throw std::runtime_error("failed: " + cmd + "\n" + out);
    return out;
}

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : (v[v.size() / 2 - 1] + v[v.size() / 2]) / 2;
}

/// A session with `samples` raw samples (a bar signal's shape: slow drift and a ripple) and `points`
/// points, `results` results of ~4 KB.
std::int64_t add_session(storage::Store& store, std::int64_t samples, int points, int results) {
    storage::NewSession ns;
    ns.source = storage::SessionSource::emulator;
    ns.procedure = "bench";
    const auto id = store.create_session(ns);
    store.start_session(id);
    if (samples > 0) {
        auto st = store.db().prepare(
            "WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i + 1 < ?) "
            "INSERT INTO samples(session_id, seq, device_time_us, displacement_nm, flags, bar_temp_mC) "
            "SELECT ?, i, 1000 + i * 1000, (i * 7919) % 200001 - 100000, 0, 20000 + i % 97 FROM n");
        st.bind(1, samples).bind(2, id).run();
    }
    for (int p = 0; p < points; ++p) {
        storage::PointRecord r;
        r.reading.measured_mm = 100.0 + p * 1e-4;
        r.reading.location = 0;
        r.reading.point = p;
        r.nominal_mm = 100.0;
        store.add_point(id, r);
    }
    const std::string payload = "{\"figures\": [" + std::string(4000, '1') + "]}";
    for (int r = 0; r < results; ++r) store.add_result(id, "bench", payload);
    store.finish_session(id);
    return id;
}

}  // namespace

int main(int argc, char** argv) {
    std::int64_t samples = 2000000;
    int runs = 5, sessions = 100;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i];
        if (a == "--samples")
            samples = std::atoll(argv[i + 1]);
        else if (a == "--runs")
            runs = std::atoi(argv[i + 1]);
        else if (a == "--sessions")
            sessions = std::atoi(argv[i + 1]);
    }
    std::istringstream where(run(std::string("bash ") + BALLBAR_PG_THROWAWAY + " start"));
    std::string dir;
    int port = 0;
    where >> dir >> port;
    const std::string conn = "host=" + dir + " port=" + std::to_string(port) + " user=postgres dbname=postgres";
    const std::string psql = "psql -X -q -v ON_ERROR_STOP=1 -At '" + conn + "'";
    const std::string work = dir + "-bench";
    std::filesystem::create_directories(work);
    int status = 0;
    try {
        // 1. Raw samples: one session of `samples` samples.
        {
            storage::Store station(work + "/samples.db");
            add_session(station, samples, 20, 3);
            fleet::pg::Connection c(conn);
            fleet::SyncOptions records_only;
            fleet::sync(station, c, records_only);  // the schema and the session row
            const std::string uuid = station.sessions().at(0).uuid;
            // The same rows psql copies: COPY's text format, as the sync sends them.
            run("sqlite3 -separator '\t' '" + work + "/samples.db' \"SELECT '" + uuid +
                "', seq, device_time_us, displacement_nm, flags, bar_temp_mC FROM samples ORDER BY seq\" > '" + work +
                "/samples.tsv'");
            std::vector<double> t_psql, t_sync;
            const std::string reset =
                psql + " -c 'TRUNCATE ballbar.samples; UPDATE ballbar.sessions SET samples_next_seq = 0; CHECKPOINT'";
            fleet::SyncOptions with_samples;
            with_samples.samples = true;
            for (int r = 0; r < runs; ++r) {
                run(reset);
                auto t0 = Clock::now();
                run(psql +
                    " -c \"\\copy ballbar.samples (session_uuid, seq, device_time_us, displacement_nm, flags, "
                    "bar_temp_mc) FROM '" +
                    work + "/samples.tsv'\"");
                t_psql.push_back(seconds_since(t0));
                run(reset);
                t0 = Clock::now();
                fleet::pg::Connection s(conn);
                const auto rep = fleet::sync(station, s, with_samples);
                t_sync.push_back(seconds_since(t0));
                if (rep.samples != samples) throw std::runtime_error("the sync sent " + std::to_string(rep.samples));
            }
            const double mp = median(t_psql), ms = median(t_sync);
            std::printf("raw samples: %lld, %d runs side by side (medians)\n", static_cast<long long>(samples), runs);
            std::printf("  psql \\copy      %7.3f s  %8.0f samples/s\n", mp, static_cast<double>(samples) / mp);
            std::printf("  ballbar sync    %7.3f s  %8.0f samples/s  (chunks of 200000, one transaction each)\n", ms,
                        static_cast<double>(samples) / ms);
            std::printf("  ratio sync/psql %7.2f  (target >= 0.80)\n", mp / ms);
        }
        // 2. A no-op re-sync of `sessions` sessions with their points and results.
        {
            storage::Store station(work + "/many.db");
            for (int s = 0; s < sessions; ++s) add_session(station, 2000, 24, 4);
            {
                fleet::pg::Connection c(conn);
                fleet::SyncOptions o;
                o.samples = true;
                fleet::sync(station, c, o);
            }
            std::vector<double> t;
            for (int r = 0; r < runs; ++r) {
                const auto t0 = Clock::now();
                storage::StoreOptions so;
                so.recover = false;
                storage::Store again(work + "/many.db", so);
                fleet::pg::Connection c(conn);
                fleet::SyncOptions o;
                o.samples = true;
                const auto rep = fleet::sync(again, c, o);
                t.push_back(seconds_since(t0));
                if (rep.rows() != 0) throw std::runtime_error("a no-op sync wrote rows");
            }
            std::printf(
                "no-op re-sync of %d sessions (open, connect, compare): median %.3f s, max %.3f s "
                "(target <= 1 s)\n",
                sessions, median(t), *std::max_element(t.begin(), t.end()));
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_fleet_sync: %s\n", e.what());
        status = 1;
    }
    std::filesystem::remove_all(work);
    run(std::string("bash ") + BALLBAR_PG_THROWAWAY + " stop '" + dir + "'");
    return status;
}
