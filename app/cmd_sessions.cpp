// SPDX-License-Identifier: MIT
// `ballbar sessions [--json]` lists the stored sessions; `ballbar sessions show SESSION [--json]` shows
// one (SESSION: id or uuid prefix) with its audit trail, points summary and results.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ballbar/storage/imports.hpp"
#include "ballbar/storage/session_clock.hpp"
#include "ballbar/storage/session_export.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/trend.hpp"
#include "command.hpp"
#include "figures.hpp"
#include "files.hpp"
#include "resume_line.hpp"

namespace ballbar::app {
namespace {

struct SessionsOptions {
    bool json = false;
    // The list's filters.
    std::string filter_machine;    ///< --machine: the machine as the list names it ("TTTRR mill-1")
    std::string filter_procedure;  ///< --procedure ssm|circular
    std::string filter_state;      ///< --state completed|interrupted|failed|…
    std::string since;             ///< --since YYYY-MM-DD (the session's start, UTC)
    std::string session;
    bool show_json = false;
    std::string machine;  ///< sessions trend MACHINE
    bool trend_json = false;
};

storage::Store open_reader(const Globals& globals) {
    storage::StoreOptions so;
    so.recover = false;                                    // listing must not touch a running acquisition's session
    return storage::Store(existing_db_path(globals), so);  // a reader never creates one
}

using workflow::machine_label;  // "TTTRR mill-1": the list's, the trend's and the web page's

/// Columns a text takes on a terminal: its UTF-8 code points ("µ" and "Δ" are one each).
std::size_t text_width(const std::string& text) {
    return static_cast<std::size_t>(
        std::count_if(text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

/// The sessions the list's filters keep.
bool kept(const SessionsOptions& o, const storage::SessionInfo& s) {
    if (!o.filter_machine.empty() && machine_label(s) != o.filter_machine) return false;
    if (!o.filter_procedure.empty() &&
        (o.filter_procedure == "circular") != (s.procedure == "circular"))  // ssm: every other procedure
        return false;
    if (!o.filter_state.empty() && storage::to_string(s.state) != o.filter_state) return false;
    if (!o.since.empty() && s.started_at < o.since) return false;  // ISO 8601: the text orders as the time
    return true;
}

void print_sessions_table(storage::Store& store, const std::vector<storage::SessionInfo>& sessions, std::ostream& out) {
    char line[512];
    std::snprintf(line, sizeof line, "%5s  %-8s  %-11s  %-24s  %-20s  %-18s  %6s  ", "id", "uuid", "state", "machine",
                  "started", "result", "points");
    out << line << "operator\n";
    for (const auto& s : sessions) {
        std::string result;
        try {
            result = workflow::headline(workflow::session_figures(store, s));
        } catch (const std::exception&) {
            result = "(unreadable)";  // a damaged result: its `sessions show` says why
        }
        // The start to the second (the stored text keeps its milliseconds and zone).
        const std::string started = s.started_at.substr(0, 19);
        std::snprintf(line, sizeof line, "%5lld  %-8s  %-11s  %-24s  %-20s  ", static_cast<long long>(s.id),
                      s.uuid.substr(0, 8).c_str(), std::string(storage::to_string(s.state)).c_str(),
                      machine_label(s).c_str(), started.c_str());
        out << line << result << std::string(text_width(result) < 18 ? 18 - text_width(result) : 0, ' ');
        std::snprintf(line, sizeof line, "  %6lld  ", static_cast<long long>(s.point_count));
        out << line << s.operator_name << '\n';
    }
}

int list_sessions(const SessionsOptions& o, const Globals& globals, std::ostream& out) {
    const std::string path = resolve_db_path(globals);
    if (!std::filesystem::exists(path)) {  // listing does not create a database
        out << (o.json ? "[]" : "no sessions (no database at " + path + ")") << '\n';
        return kExitOk;
    }
    if (!o.since.empty() && (o.since.size() != 10 || o.since[4] != '-' || o.since[7] != '-'))
        throw Error(ErrorCategory::bad_input, "--since " + o.since + ": give a date as YYYY-MM-DD");
    auto store = open_reader(globals);
    note_database_damage(store.damage());
    std::vector<storage::SessionInfo> sessions;
    for (auto& s : store.sessions())
        if (kept(o, s)) sessions.push_back(std::move(s));
    const bool filtered = !(o.filter_machine + o.filter_procedure + o.filter_state + o.since).empty();
    if (o.json && !filtered) {
        out << storage::sessions_json(store) << '\n';  // what GET /api/sessions answers
        return kExitOk;
    }
    if (o.json) {
        // The same objects as without filters, the kept ones only.
        auto all = nlohmann::json::parse(storage::sessions_json(store));
        nlohmann::json shown = nlohmann::json::array();
        for (auto& j : all)
            if (std::any_of(sessions.begin(), sessions.end(),
                            [&j](const storage::SessionInfo& s) { return j.value("id", std::int64_t{-1}) == s.id; }))
                shown.push_back(std::move(j));
        out << shown.dump(2) << '\n';
        return kExitOk;
    }
    if (sessions.empty()) {
        out << "no sessions" << (filtered ? " match the filters" : "") << " in " << store.path() << '\n';
        return kExitOk;
    }
    // The emulator's demo sessions apart from the machines' own.
    std::vector<storage::SessionInfo> real, demo;
    for (auto& s : sessions) (s.source == storage::SessionSource::emulator ? demo : real).push_back(std::move(s));
    if (!real.empty()) print_sessions_table(store, real, out);
    if (!demo.empty()) {
        if (!real.empty()) out << '\n';
        out << "Demo sessions (the emulator):\n";
        print_sessions_table(store, demo, out);
    }
    return kExitOk;
}

/// Each sample segment with the instrument's resolution and measured reading rate over its samples
/// (schema v4); nothing for a session whose segments carry none.
void print_segments(storage::Store& store, std::int64_t id, std::ostream& out) {
    const auto segments = store.sample_segments(id);
    const bool any = std::any_of(segments.begin(), segments.end(),
                                 [](const storage::SampleSegment& g) { return g.resolution_mm || g.reading_rate_hz; });
    if (!any) return;
    const std::uint64_t end = store.next_seq(id);
    for (std::size_t k = 0; k < segments.size(); ++k) {
        const auto& g = segments[k];
        const std::uint64_t next = k + 1 < segments.size() ? segments[k + 1].first_seq : end;
        out << "    samples " << g.first_seq << "-" << (next > g.first_seq ? next - 1 : g.first_seq) << ": ";
        char line[120];
        if (g.resolution_mm && g.reading_rate_hz) {
            std::snprintf(line, sizeof line, "resolution %.4g µm, %.1f readings/s measured", *g.resolution_mm * 1e3,
                          *g.reading_rate_hz);
            out << line << '\n';
        } else {
            out << "resolution and reading rate not recorded\n";
        }
    }
}

/// The stream's gaps (schema v6): how many, how long in all, and the first few.
void print_gaps(storage::Store& store, std::int64_t id, std::ostream& out) {
    const auto gaps = store.sample_gaps(id);
    if (gaps.empty()) {
        out << "  gaps        none recorded\n";
        return;
    }
    double total_s = 0;
    for (const auto& g : gaps) total_s += g.duration_s.value_or(0);
    char line[160];
    std::snprintf(line, sizeof line, "  gaps        %zu in the stream, %.3f s in all (samples the host lost)\n",
                  gaps.size(), total_s);
    out << line;
    constexpr std::size_t kShown = 10;
    for (std::size_t i = 0; i < gaps.size() && i < kShown; ++i) {
        const auto& g = gaps[i];
        if (g.duration_s)
            std::snprintf(line, sizeof line, "    before sample %llu: %.3f s, %s\n",
                          static_cast<unsigned long long>(g.before_seq), *g.duration_s, g.cause.c_str());
        else
            std::snprintf(line, sizeof line, "    before sample %llu: %s (the instrument's clock restarted)\n",
                          static_cast<unsigned long long>(g.before_seq), g.cause.c_str());
        out << line;
    }
    if (gaps.size() > kShown) out << "    … " << gaps.size() - kShown << " more: sessions show " << id << " --json\n";
}

int show_session(const SessionsOptions& o, const Globals& globals, std::ostream& out) {
    auto store = open_reader(globals);
    note_database_damage(store.damage());
    const auto id = store.find_session(o.session);
    if (o.show_json) {
        out << storage::session_json(store, id, true) << '\n';
        return kExitOk;
    }
    const auto s = store.session(id);
    out << "session " << s.id << "  " << s.uuid << '\n' << "  state       " << storage::to_string(s.state);
    if (s.state != storage::SessionState::completed && !s.reason.empty())
        out << "  (" << state_reason(storage::to_string(s.state), s.reason) << ")";
    out << '\n';
    if (s.resumable())
        out << "  resume      " << resume_command(s.procedure, s.id, globals.db_path, "", "")
            << (s.procedure == "circular" ? "  (runs the program again for the runs it lacks)"
                                          : "  (continues after its " + std::to_string(s.point_count) + " points)")
            << '\n';
    out << "  source      " << storage::to_string(s.source) << '\n'
        << "  procedure   " << s.procedure << '\n'
        << "  operator    " << s.operator_name << '\n'
        << "  machine     " << machine_label(s) << '\n'
        << "  started     " << s.started_at << '\n'
        << "  ended       " << s.ended_at.value_or("-") << '\n';
    if (s.instrument) {
        const auto& in = *s.instrument;
        out << "  instrument  " << (in.model.empty() ? "-" : in.model) << ", serial "
            << (in.serial.empty() ? "-" : in.serial) << ", firmware " << (in.firmware.empty() ? "-" : in.firmware)
            << ", calibrated length ";
        if (in.calibrated_length_mm) {
            char len[32];
            std::snprintf(len, sizeof len, "%.4f mm", *in.calibrated_length_mm);
            out << len;
        } else {
            out << "-";
        }
        out << ", calibrated on " << (in.calibration_date.empty() ? "-" : in.calibration_date) << '\n';
    } else {
        out << "  instrument  - (not recorded)\n";
    }
    if (!s.notes.empty()) out << "  notes       " << s.notes << '\n';
    if (const auto imp = storage::import_of(store, id))
        out << "  imported    from " << imp->file_name << " (" << imp->bytes << " bytes, SHA-256 "
            << imp->content_sha256 << ") at " << imp->imported_at << '\n';
    out << "  samples     " << s.sample_count;
    if (s.sample_count > 0) {
        const storage::SessionClock clock(store, id);
        char span[160];
        std::snprintf(span, sizeof span, ", %.1f s of samples from %.1f s to %.1f s of session time, %zu segment%s",
                      clock.sampled_s(), clock.first_s(), clock.last_s(), clock.segments(),
                      clock.segments() == 1 ? "" : "s (device clock runs: reconnects, resumes)");
        out << span;
    }
    out << '\n';
    print_segments(store, id, out);
    print_gaps(store, id, out);
    out << "  points      " << s.point_count << '\n';
    for (const auto& p : store.points(id)) {
        const auto& rd = p.reading;
        char line[200];
        std::string where;
        if (rd.step > 0 && rd.location >= 0 && rd.point >= 0) {  // as measure numbers them: from 1
            where = "test " + std::to_string((rd.location - (rd.step - 1)) / 2 + 1) + " step " +
                    std::to_string(rd.step) + " point " + std::to_string(rd.point + 1);
        } else {
            where = "location " + std::to_string(rd.location) + " point " + std::to_string(rd.point);
        }
        std::snprintf(line, sizeof line, "    %-26s %10.5f mm (nominal %.5f mm)", where.c_str(), rd.measured_mm,
                      p.nominal_mm);
        out << line;
        if (rd.std_mm) {
            std::snprintf(line, sizeof line, ", std %.2f µm", *rd.std_mm * 1e3);
            out << line;
        }
        out << ", n " << rd.n << '\n';
    }
    out << "  transitions\n";
    for (const auto& t : store.transitions(id)) {
        out << "    " << t.at << "  " << (t.from ? std::string(storage::to_string(*t.from)) : std::string("-"))
            << " -> " << storage::to_string(t.to) << "  (" << t.event << ")\n";
    }
    if (const auto steps = store.procedure_steps(id); !steps.empty()) {
        out << "  procedure steps  " << steps.size() << ", the last " << steps.back().from << " -> " << steps.back().to
            << " (" << steps.back().event << ") at " << steps.back().at << "; all of them: sessions show " << id
            << " --json\n";
    }
    const auto results = store.results(id);
    if (!results.empty()) out << "  results\n";
    for (const auto& r : results) {
        out << "    #" << r.id << "  " << r.kind << "  " << r.created_at;
        if (r.model_id) out << "  model " << *r.model_id;
        if (!r.producer.empty()) out << "  by " << r.producer;
        out << '\n';
        for (const auto& line : result_lines(r.kind, r.payload_json, s.machine.type)) out << "        " << line << '\n';
    }
    return kExitOk;
}

/// `sessions trend MACHINE`: the machine's headline figures across its completed sessions.
int show_trend(const SessionsOptions& o, const Globals& globals, std::ostream& out) {
    auto store = open_reader(globals);
    note_database_damage(store.damage());
    const auto points = workflow::machine_trend(store, o.machine);
    if (o.trend_json) {
        out << workflow::trend_json(o.machine, points) << '\n';
        return kExitOk;
    }
    if (points.empty()) {
        out << "no completed session of machine \"" << o.machine << "\" holds a result (the machines are the "
            << "list's column: ballbar sessions)\n";
        return kExitOk;
    }
    out << "machine " << o.machine << ": " << points.size() << " sessions, oldest first\n";
    for (const auto& p : points) {
        out << "  " << p.started_at.substr(0, 19) << "  session " << p.session << "  " << p.procedure
            << (p.demo ? " (demo)" : "") << '\n';
        for (const auto& [name, value] : p.figures) {
            char line[96];
            std::snprintf(line, sizeof line, "      %-22s %10.3f\n", name.c_str(), value);
            out << line;
        }
    }
    return kExitOk;
}

int run_sessions(const SessionsOptions& o, const Globals& globals, bool show, bool trend = false) {
    // Stored text (operator, notes, machine names, file names, reasons) is anyone's: the screen gets it
    // with its control characters made visible, never a terminal escape sequence (issue 24).
    std::ostringstream text;
    int code = kExitOk;
    try {
        code = trend  ? show_trend(o, globals, text)
               : show ? show_session(o, globals, text)
                      : list_sessions(o, globals, text);
    } catch (const storage::StorageError& e) {
        throw as_error(e);
    }
    const bool as_json = trend ? o.trend_json : show ? o.show_json : o.json;
    std::cout << (as_json ? text.str() : printable(text.str(), true));
    return code;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(sessions) {
    auto opts = std::make_shared<ballbar::app::SessionsOptions>();
    auto* sub = root.add_subcommand("sessions", "List stored sessions, or show one");
    sub->add_flag("--json", opts->json, "as JSON");
    sub->add_option("--machine", opts->filter_machine, "only this machine, as the list names it (\"TTTRR mill-1\")");
    sub->add_option("--procedure", opts->filter_procedure, "only ssm or circular sessions")
        ->check(CLI::IsMember({"ssm", "circular"}));
    sub->add_option("--state", opts->filter_state, "only sessions in this state")
        ->check(CLI::IsMember({"created", "running", "completed", "interrupted", "failed", "aborted"}));
    sub->add_option("--since", opts->since, "only sessions started on or after this date (YYYY-MM-DD)");
    auto* show = sub->add_subcommand("show", "Show one session: metadata, audit trail, results");
    show->add_option("SESSION", opts->session, "session id or uuid prefix")->required();
    show->add_flag("--json", opts->show_json, "the whole session as JSON (as `export --format json`)");
    auto* trend = sub->add_subcommand("trend", "A machine's headline figures across its completed sessions");
    trend->add_option("MACHINE", opts->machine, "the machine as the list names it, e.g. \"TTTRR mill-1\"")->required();
    trend->add_flag("--json", opts->trend_json, "as JSON (what the web page's trend shows)");
    sub->callback([opts, show, trend, &globals] {
        const bool is_show = show->parsed(), is_trend = trend->parsed();
        globals.action = [opts, is_show, is_trend, &globals] {
            return ballbar::app::run_sessions(*opts, globals, is_show, is_trend);
        };
    });
}
