// SPDX-License-Identifier: MIT
// `ballbar trend MACHINE`: a machine's figures over months with their uncertainties, tolerances and the
// drift in them, from this station or (--from) the plant's server; --json, --out trend.pdf (docs/fleet.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <memory>
#include <optional>
#include <regex>
#include <sstream>
#include <string>

#include "ballbar/report/trend.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/trend.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

struct TrendOptions {
    std::string machine, since, from, out;
    bool json = false;
};

std::string utc_now() {
    const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
    std::tm tm{};
    gmtime_r(&t, &tm);
    char b[32];
    std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return b;
}

/// "66.263 ± 0.005": the uncertainty to two significant digits and the value to the same decimals
/// (two decimals without one).
std::string value_text(double v, const std::optional<double>& sd) {
    char b[64];
    if (sd && *sd > 0) {
        const int decimals = std::clamp(1 - static_cast<int>(std::floor(std::log10(*sd))), 0, 6);
        std::snprintf(b, sizeof b, "%.*f ± %.*f", decimals, v, decimals, *sd);
    } else {
        std::snprintf(b, sizeof b, "%.2f", v);
    }
    return b;
}

/// `text` padded to `columns` terminal columns (µ, Δ, ± count one each).
std::string pad(const std::string& text, std::size_t columns) {
    std::size_t w = 0;
    for (unsigned char c : text) w += (c & 0xC0) != 0x80;
    return text + std::string(w < columns ? columns - w : 1, ' ');
}

int run_trend(const TrendOptions& o, const Globals& globals) {
    const auto inputs = database_files(globals);
    if (!o.out.empty()) fileio::check_output(o.out, "--out", inputs);  // before any work
    if (!o.since.empty() && !std::regex_match(o.since, std::regex(R"(\d{4}-\d{2}-\d{2})")))
        throw workflow::Error(workflow::ErrorCategory::bad_input,
                              "--since: '" + o.since + "' is not a date YYYY-MM-DD");
    std::optional<storage::Store> store;
    if (o.from.empty()) {
        storage::StoreOptions so;
        so.recover = false;  // a reader: a session being measured stays its writer's
        store.emplace(existing_db_path(globals), so);
        note_database_damage(store->damage());
    }
    report::TrendDocument t = workflow::machine_trend_document(store ? &*store : nullptr, o.machine, o.since, o.from);
    t.generated_at = utc_now();
    if (!o.out.empty()) {
        if (t.series.empty())
            throw workflow::Error(workflow::ErrorCategory::not_found,
                                  "no completed session of machine \"" + o.machine + "\" holds a result" +
                                      (o.since.empty() ? "" : " since " + o.since) + ": no trend to draw");
        int pages = 0;
        const std::string pdf = report::render_trend_pdf_bytes(t, &pages);
        write_output(o.out, "--out", pdf, inputs);
        std::cerr << "ballbar: wrote " << o.out << " (" << pages << (pages == 1 ? " page" : " pages") << ")\n";
    }
    if (o.json) {
        std::cout << workflow::trend_document_json(t) << '\n';
        return kExitOk;
    }
    std::ostringstream out;
    if (t.series.empty()) {
        out << "no completed session of machine \"" << o.machine << "\" holds a result"
            << (o.since.empty() ? "" : " since " + o.since) << " (" << t.source << ")\n";
        std::cout << printable(out.str(), true);
        return kExitOk;
    }
    out << "machine " << o.machine << ": " << t.sessions << " completed sessions, " << t.first_at.substr(0, 10)
        << " to " << t.last_at.substr(0, 10) << " (" << t.source << ")\n";
    out << "  " << pad("figure", 27) << pad("n", 4) << pad("latest", 18) << pad("tolerance", 11)
        << pad("slope a year", 18) << "flag\n";
    for (const auto& s : t.series) {
        const auto& last = s.values.back();
        char tol[32] = "-";
        if (s.tolerance) std::snprintf(tol, sizeof tol, "%g", *s.tolerance);
        out << "  " << pad(s.label + " (" + s.unit + ")", 27) << pad(std::to_string(s.values.size()), 4)
            << pad(value_text(last.value, last.value_std), 18) << pad(tol, 11)
            << pad(s.slope_per_year ? value_text(*s.slope_per_year, s.slope_per_year_std) : "-", 18) << s.flag << '\n';
    }
    for (const auto& s : t.series)
        if (!s.flag.empty()) out << "  " << s.label << ": " << s.flag << ": " << s.detail << '\n';
    std::cout << printable(out.str(), true);
    return kExitOk;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(trend) {
    auto o = std::make_shared<ballbar::app::TrendOptions>();
    auto* sub = root.add_subcommand(
        "trend", "A machine's figures over months: uncertainties, tolerances, drift (this station or --from a server)");
    sub->add_option("MACHINE", o->machine,
                    "its asset id (M-0042), or a machine registered nowhere as the list names it")
        ->required();
    sub->add_option("--since", o->since, "only sessions started on or after this date (YYYY-MM-DD)");
    sub->add_option("--from", o->from,
                    "the plant's PostgreSQL server (a libpq connection string; password from PGPASSWORD or ~/.pgpass): "
                    "every station's sessions of the machine");
    sub->add_option("--out", o->out, "also draw the trend as a PDF: a plot a figure, its tolerance line, the drift");
    sub->add_flag("--json", o->json, "as JSON");
    sub->callback([o, &globals] { globals.action = [o, &globals] { return ballbar::app::run_trend(*o, globals); }; });
}
