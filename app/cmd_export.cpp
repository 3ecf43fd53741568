// SPDX-License-Identifier: MIT
// `ballbar export SESSION --format readings|json|csv --out PATH`. readings: the interchange file; json: the
// whole session (metadata, transitions, points, results); csv: PATH is a directory that receives
// points.csv and samples.csv (docs/storage.md), or NAME.csv: NAME-points.csv and NAME-samples.csv. `--out -` writes
// readings or json to stdout.
#include <filesystem>
#include <iostream>

#include "ballbar/storage/session_export.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/import_export.hpp"
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
        if (o.format != "csv") {
            const auto format = o.format == "readings" ? workflow::ExportFormat::readings
                                : o.format == "trace"  ? workflow::ExportFormat::trace
                                                       : workflow::ExportFormat::json;
            write_text(o.out, workflow::export_session(store, id, format));
        } else {
            if (o.out == "-")
                throw Error(ErrorCategory::bad_input,
                            "--format csv writes two files: give --out DIRECTORY or --out NAME.csv");
            const std::filesystem::path out(o.out);
            if (out.extension() == ".csv" || out.extension() == ".CSV") {
                // A file name, not a directory to make: NAME-points.csv and NAME-samples.csv beside it.
                const auto stem = out.parent_path() / out.stem();
                const std::string points = stem.string() + "-points" + out.extension().string(),
                                  samples = stem.string() + "-samples" + out.extension().string();
                for (const auto& f : {points, samples}) fileio::check_output(f, "--out", inputs);
                storage::export_csv_files(store, id, points, samples);
                std::cerr << "ballbar: exported session " << id << " (csv) to " << points << " and " << samples << '\n';
                return kExitOk;
            }
            for (const char* name : {"points.csv", "samples.csv"})
                fileio::check_output((out / name).string(), "--out", inputs);
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
    sub->add_option("--out", opts->out,
                    "output file (readings, json; - for stdout); csv: a directory, or NAME.csv for NAME-points.csv and "
                    "NAME-samples.csv")
        ->required();
    sub->callback(
        [opts, &globals] { globals.action = [opts, &globals] { return ballbar::app::run_export(*opts, globals); }; });
}
