// SPDX-License-Identifier: MIT
// `ballbar export SESSION --format readings|json|csv --out PATH`. readings: the interchange file; json: the
// whole session (metadata, transitions, points, results); csv: PATH is a directory that receives
// points.csv and samples.csv (docs/storage.md). `--out -` writes readings or json to stdout.
#include <filesystem>
#include <iostream>

#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/session_export.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

struct ExportOptions {
    std::string session;
    std::string format = "readings";
    std::string out;
};

int run_export(const ExportOptions& o, const Globals& globals) {
    const auto inputs = database_files(globals);
    auto write_text = [&](const std::string& path, const std::string& text) {
        write_output(path, "--out", text, inputs);
    };
    try {
        storage::StoreOptions so;
        so.recover = false;                                   // a reader: leave sessions of a running acquisition alone
        storage::Store store(existing_db_path(globals), so);  // a reader never creates one
        note_database_damage(store.damage());
        const auto id = store.find_session(o.session);
        if (o.format == "readings") {
            const auto info = store.session(id);
            const auto set = storage::load_readings(store, id);
            if (set.readings.empty())
                throw Error(ErrorCategory::failed, "session " + std::to_string(id) + " has no points");
            write_text(o.out, storage::format_readings(set, storage::readings_metadata(info)));
        } else if (o.format == "trace") {
            std::string text;
            try {
                text = storage::format_trace(storage::load_trace(store, id));
            } catch (const storage::StorageError&) {
                throw;
            } catch (const std::runtime_error& e) {
                throw Error(ErrorCategory::failed, e.what());
            }
            write_text(o.out, text);
        } else if (o.format == "json") {
            write_text(o.out, storage::session_json(store, id) + "\n");
        } else {
            if (o.out == "-")
                throw Error(ErrorCategory::bad_input, "--format csv writes two files: give --out DIRECTORY");
            for (const char* name : {"points.csv", "samples.csv"})
                fileio::check_output((std::filesystem::path(o.out) / name).string(), "--out", inputs);
            storage::export_csv(store, id, o.out);
        }
        if (o.out != "-")
            std::cerr << "ballbar: exported session " << id << " (" << o.format << ") to " << o.out << '\n';
        return kExitOk;
    } catch (const storage::StorageError& e) {
        throw as_error(e);
    }
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(export) {
    auto opts = std::make_shared<ballbar::app::ExportOptions>();
    auto* sub = root.add_subcommand("export", "Export a session as a readings file, JSON or CSV");
    sub->add_option("SESSION", opts->session, "session id or uuid prefix")->required();
    sub->add_option("--format", opts->format, "readings | json | csv | trace (a circular test)")
        ->check(CLI::IsMember({"readings", "json", "csv", "trace"}))
        ->capture_default_str();
    sub->add_option("--out", opts->out, "output file (readings, json; - for stdout) or directory (csv)")->required();
    sub->callback(
        [opts, &globals] { globals.action = [opts, &globals] { return ballbar::app::run_export(*opts, globals); }; });
}
