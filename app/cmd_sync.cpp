// SPDX-License-Identifier: MIT
// `ballbar sync CONNINFO`: this station's sessions to the plant's PostgreSQL server (docs/fleet.md).
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/sync.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

struct SyncCliOptions {
    std::string conninfo;
    bool samples = false;
    std::int64_t chunk = 200000;
    bool json = false;
};

int run_sync(const SyncCliOptions& o, const Globals& globals) {
    storage::StoreOptions so;
    so.recover = false;  // only read: a session another process is measuring stays its
    storage::Store store(existing_db_path(globals), so);
    note_database_damage(store.damage());
    fleet::SyncOptions options;
    options.samples = o.samples;
    options.chunk_samples = o.chunk;
    std::int64_t done = 0;
    if (!o.json)
        options.progress = [&done](std::string_view) {
            if (++done % 10 == 0) std::fprintf(stderr, "\r%lld transactions committed", static_cast<long long>(done));
        };
    const fleet::SyncReport r = workflow::sync_station(store, o.conninfo, options);
    if (o.json) {
        std::cout << workflow::sync_json(r) << '\n';
    } else {
        if (done >= 10) std::fprintf(stderr, "\n");
        std::cout << "station " << r.station_uuid << " → " << r.server
                  << (r.server_schema_before == 0 ? " (ballbar's schema created)" : "") << '\n'
                  << "  sessions   " << r.sessions_sent << " of " << r.sessions_local << " had something new\n"
                  << "  written    " << r.rows() << " rows: " << r.sessions << " sessions, " << r.results
                  << " results, " << r.models << " models, " << r.machines << " machines, " << r.points << " points, "
                  << r.transitions << " transitions, " << r.segments + r.gaps << " segments and gaps, " << r.samples
                  << " samples" << (o.samples ? "" : " (raw samples not sent: --samples)") << '\n';
        if (r.rows() == 0 && r.conflicts.empty()) std::cout << "  the server was up to date\n";
    }
    if (!r.conflicts.empty()) {
        std::cerr << "ballbar: " << r.conflicts.size()
                  << " id(s) of this station are on the server under another station; those were not sent "
                     "(nothing was merged):\n";
        for (const auto& c : r.conflicts)
            std::cerr << "  " << c.kind << ' ' << c.uuid << ": station " << c.other_station << '\n';
        return kExitFailure;
    }
    return kExitOk;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(sync) {
    auto o = std::make_shared<ballbar::app::SyncCliOptions>();
    auto* sub =
        root.add_subcommand("sync", "Send this station's sessions to the plant's PostgreSQL server (docs/fleet.md)");
    sub->add_option("CONNINFO", o->conninfo,
                    "the server: a libpq connection string or URI, e.g. \"host=db.plant dbname=ballbar user=station7\" "
                    "(the password from PGPASSWORD or ~/.pgpass, never here)")
        ->required();
    sub->add_flag("--samples", o->samples,
                  "also the raw samples (by COPY); results, points and models are always sent");
    sub->add_option("--chunk", o->chunk, "samples a transaction (a killed sync loses at most one)")
        ->check(CLI::Range(std::int64_t{1000}, std::int64_t{10000000}));
    sub->add_flag("--json", o->json, "the report as JSON");
    sub->callback([o, &globals] { globals.action = [o, &globals] { return ballbar::app::run_sync(*o, globals); }; });
}
