// SPDX-License-Identifier: MIT
// `ballbar report SESSION [--out report.pdf] [--json]`: the session report (docs/report.md) as a vector
// PDF on A4 pages and/or, with --json, the same content as JSON on standard output.
#if __has_include("ballbar/report/build.hpp") && defined(BALLBAR_REPORT_HAS_STORAGE)

#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "ballbar/report/build.hpp"
#include "ballbar/report/report.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/version.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

struct ReportOptions {
    std::string session;
    std::string out;
    bool json = false;
    std::optional<double> tolerance_um;  // circular sessions: the G tolerance
    // SSM sessions: instead of the machine file's (stored with the session's plan)
    std::optional<double> location_tolerance_um, angle_tolerance_arcsec;
};

int run_report(const ReportOptions& o, const Globals& globals) {
    if (o.out.empty() && !o.json)
        throw Error(ErrorCategory::bad_input, "nothing to write: give --out FILE.pdf and/or --json");
    const auto inputs = database_files(globals);
    if (!o.out.empty()) {
        try {
            fileio::check_output(o.out, "--out", inputs);  // before any work
        } catch (const fileio::FileError& e) {
            throw as_error(e);
        }
    }
    storage::StoreOptions so;
    so.read_only = true;  // a report never changes the database
    so.recover = false;
    std::unique_ptr<storage::Store> store;
    const std::string db = existing_db_path(globals);  // a reader never creates one
    try {
        store = std::make_unique<storage::Store>(db, so);
    } catch (const storage::StorageError& e) {
        throw Error(ErrorCategory::failed, "cannot open " + db + ": " + e.what());
    }
    note_database_damage(store->damage());
    std::int64_t id = 0;
    try {
        id = store->find_session(o.session);
    } catch (const storage::StorageError& e) {
        throw as_error(e);  // "no session \"99\"" (exit 2), once
    }
    report::BuildOptions bo;
    bo.software_version = kVersion;
    if (o.tolerance_um && !(*o.tolerance_um > 0.0 && std::isfinite(*o.tolerance_um)))
        throw Error(ErrorCategory::bad_input, "--tolerance must be a circular deviation > 0, µm");
    report::Report r;
    try {
        r = report::build_report(*store, id, bo);
    } catch (const report::ReportError& e) {
        throw Error(ErrorCategory::failed, "session " + std::to_string(id) + ": " + e.what());
    }
    if (o.tolerance_um) report::set_circular_tolerance(r, *o.tolerance_um);
    report::set_ssm_tolerances(r, o.location_tolerance_um, o.angle_tolerance_arcsec);
    if (!o.out.empty()) {
        int pages = 0;
        std::string pdf;
        try {
            pdf = report::render_pdf_bytes(r, &pages);
        } catch (const report::ReportError& e) {
            throw Error(ErrorCategory::failed, e.what());
        }
        write_output(o.out, "--out", pdf, inputs);
        std::cerr << "ballbar: wrote " << o.out << " (" << pages << (pages == 1 ? " page" : " pages") << ")\n";
    }
    if (o.json) std::cout << report::to_json(r).dump(2) << std::endl;
    return kExitOk;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(report) {
    using namespace ballbar::app;
    auto opts = std::make_shared<ReportOptions>();
    auto* sub =
        root.add_subcommand("report", "Session report: a vector PDF with plots (A4), and/or its content as JSON");
    sub->add_option("session", opts->session, "Session id or uuid prefix")->required();
    sub->add_option("--out,-o", opts->out, "Write the PDF report to this file");
    sub->add_flag("--json", opts->json, "Print the report's content as JSON (schema ballbar-report/1)");
    sub->add_option("--tolerance", opts->tolerance_um,
                    "circular test: G allowed, µm, for the pass/fail verdict (default: the stored result's)")
        ->check(in_range(0, 10000, "µm", true));
    sub->add_option("--location-tolerance", opts->location_tolerance_um,
                    "SSM: |ΔV| allowed at each location, µm (default: the machine file's tolerances.location_um)")
        ->check(in_range(0, 10000, "µm", true));
    sub->add_option("--angle-tolerance", opts->angle_tolerance_arcsec,
                    "SSM: |Δα|, |Δβ|, |Δγ| allowed, arcsec (default: the machine file's tolerances.angle_arcsec)")
        ->check(in_range(0, 36000, "arcsec", true));
    sub->callback([opts, &globals] { globals.action = [opts, &globals] { return run_report(*opts, globals); }; });
}

#endif
