// SPDX-License-Identifier: MIT
// `ballbar import FILE`: a `ballbar-readings/1` or `ballbar-trace/1` file into a new session
// (workflow/import_export.hpp), in one transaction. An invalid file is refused whole (exit 2) with its
// line number and the problem. Content imported before is refused (exit 2) naming the session it
// duplicates, unless --allow-duplicate.
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "ballbar/workflow/import_export.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

struct ImportArgs {
    std::string file;
    bool json = false;
    bool allow_duplicate = false;
};

int run_import(const ImportArgs& a, const Globals& globals) {
    workflow::ImportOptions o;
    o.allow_duplicate = a.allow_duplicate;
    const workflow::ImportResult r = workflow::import_file(a.file, resolve_db_path(globals), o);
    for (const auto& w : r.warnings) std::cerr << "ballbar: warning: " << a.file << ": " << w << '\n';
    if (a.json) {
        nlohmann::json j{{"session", r.session}, {"uuid", r.uuid}};  // keys sorted, as before
        if (r.trace) {
            j["samples"] = r.samples;
            j["format"] = "ballbar-trace/1";
        } else {
            j["readings"] = r.readings;
        }
        j["warnings"] = r.file_warnings;
        if (!r.trace) j["nominal_mismatches"] = r.nominal_mismatches;
        j["sha256"] = r.sha256;
        j["duplicate_of"] = r.duplicate_of;
        std::cout << j.dump(2) << '\n';
    } else if (r.trace) {
        std::cout << "imported " << r.samples << " samples of a circular test from " << a.file << " into session "
                  << r.session << " (" << r.uuid << ")\n";
    } else {
        std::cout << "imported " << r.readings << " readings from " << a.file << " into session " << r.session << " ("
                  << r.uuid << ")\n";
    }
    return kExitOk;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(import) {
    auto args = std::make_shared<ballbar::app::ImportArgs>();
    auto* sub = root.add_subcommand("import", "Import a ballbar-readings/1 or ballbar-trace/1 file into a new session");
    sub->add_option("FILE", args->file, "readings or trace file (docs/formats/readings.md, docs/formats/trace.md)")
        ->required();
    sub->add_flag("--json", args->json, "print the new session as JSON");
    sub->add_flag("--allow-duplicate", args->allow_duplicate,
                  "import content that was imported before (refused by default, naming the session)");
    sub->callback(
        [args, &globals] { globals.action = [args, &globals] { return ballbar::app::run_import(*args, globals); }; });
}
