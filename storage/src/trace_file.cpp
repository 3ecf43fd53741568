// SPDX-License-Identifier: MIT
// ballbar-trace/1: parse (whole or refused with line and problem), write, store as a session, load.
#include "ballbar/storage/trace_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ballbar/analysis/decimal_text.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/sample.hpp"
#include "ballbar/fileio/input.hpp"
#include "ballbar/fileio/json_fields.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/sqlite.hpp"
#include "shortest.hpp"

namespace ballbar::storage {
namespace {

namespace circ = analysis::circular;
using ojson = nlohmann::ordered_json;

constexpr std::string_view kTraceMagic = "# ballbar-trace/1";

std::string_view trim_blanks(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

std::optional<double> parse_cell(std::string_view s) {
    s = trim_blanks(s);
    if (s.empty()) return std::nullopt;
    if (s.front() == '+') s.remove_prefix(1);
    double v = 0;
    // Most cells are short plain decimals: read them fast, bit for bit what from_chars gives.
    if (std::size_t pos = 0; analysis::read_short_decimal(s, pos, v) && pos == s.size()) return v;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
    return v;
}

using detail::shortest;

double need_number(const ojson& j, const char* key) {
    if (!j.contains(key)) throw std::runtime_error(std::string("needs \"") + key + "\"");
    if (!j[key].is_number()) throw std::runtime_error(std::string("\"") + key + "\" must be a number");
    return j[key].get<double>();
}

/// A key of a test header object that the format does not have is refused: a misspelt key would
/// otherwise describe a test that was not run. `where`: "" or "runs[0]: ".
void only_keys(const ojson& j, const std::string& where, std::initializer_list<std::string_view> allowed) {
    const auto refuse = [&where](const std::string&, const std::string& problem) {
        throw std::runtime_error(where + problem);
    };
    fileio::JsonFields<ojson, decltype(refuse)>(j, "", refuse).only_known(allowed);
}

/// A number column's range (docs/formats/trace.md, "Ranges").
std::string column_problem(std::string_view column, double v) {
    namespace lim = analysis::limits;
    std::string why;
    if (column == "time_s")
        why = lim::check_in(v, -lim::kTime_s, lim::kTime_s, "s");
    else if (column == "measured_mm")
        why = lim::check_above(v, 0, lim::kLength_mm, "mm");
    else
        why = lim::check_in(v, lim::kTempMin_C, lim::kTempMax_C, "C");
    return why.empty() ? why : std::string(column) + " " + why;
}

circ::TestSpec test_from_json(const ojson& j) {
    if (!j.is_object()) throw std::runtime_error("must be a JSON object");
    only_keys(j, "", {"kind", "plane", "radius_mm", "centre_mm", "feed_mm_min", "feed_in_mm", "runs"});
    if (!j.contains("kind") || j["kind"] != "circular")
        throw std::runtime_error("\"kind\" must be \"circular\" (the only kind of this version)");
    circ::TestSpec t;
    if (!j.contains("plane") || !j["plane"].is_string()) throw std::runtime_error("needs \"plane\": XY, YZ or ZX");
    const auto plane = circ::parse_plane(j["plane"].get<std::string>());
    if (!plane) throw std::runtime_error("\"plane\" " + j["plane"].dump() + " is not XY, YZ or ZX");
    t.plane = *plane;
    t.radius_mm = need_number(j, "radius_mm");
    t.feed_mm_min = need_number(j, "feed_mm_min");
    t.feed_in_mm = need_number(j, "feed_in_mm");
    if (!j.contains("centre_mm")) throw std::runtime_error("needs \"centre_mm\"");
    const ojson& c = j["centre_mm"];
    if (!c.is_array() || c.size() != 3) throw std::runtime_error("\"centre_mm\" must be an array of 3 numbers");
    for (std::size_t i = 0; i < 3; ++i) {
        if (!c[i].is_number()) throw std::runtime_error("\"centre_mm\" must be an array of 3 numbers");
        t.centre_mm[i] = c[i].get<double>();
    }
    if (!j.contains("runs") || !j["runs"].is_array() || j["runs"].empty())
        throw std::runtime_error("needs \"runs\", a non-empty array");
    for (std::size_t i = 0; i < j["runs"].size(); ++i) {
        const ojson& r = j["runs"][i];
        const std::string where = "runs[" + std::to_string(i) + "]: ";
        if (!r.is_object()) throw std::runtime_error(where + "must be an object");
        only_keys(r, where, {"direction", "start_deg", "overshoot_deg", "data_arc_deg"});
        circ::RunSpec run;
        if (!r.contains("direction") || !r["direction"].is_string())
            throw std::runtime_error(where + "needs \"direction\": ccw or cw");
        const auto dir = circ::parse_direction(r["direction"].get<std::string>());
        if (!dir) throw std::runtime_error(where + "\"direction\" " + r["direction"].dump() + " is not ccw or cw");
        run.direction = *dir;
        try {
            run.start_deg = need_number(r, "start_deg");
            run.overshoot_deg = need_number(r, "overshoot_deg");
            run.data_arc_deg = need_number(r, "data_arc_deg");
        } catch (const std::runtime_error& e) {
            throw std::runtime_error(where + e.what());
        }
        t.runs.push_back(run);
    }
    if (const std::string bad = t.validate(); !bad.empty()) throw std::runtime_error(bad);
    return t;
}

/// The lines of `text` one at a time (views into it, without their line ends; the empty line after a
/// final line end is not one), numbered from 1. No vector of them: a trace has 10⁵ lines or more.
class LineCursor {
  public:
    explicit LineCursor(std::string_view text) : text_(text) {}
    bool next(std::string_view& line) {
        if (pos_ >= text_.size()) return false;
        const auto end = text_.find('\n', pos_);
        line = text_.substr(pos_, end == std::string_view::npos ? std::string_view::npos : end - pos_);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos_ = end == std::string_view::npos ? text_.size() : end + 1;
        ++number_;
        return true;
    }
    int number() const { return number_; }  ///< of the line next() gave last
    std::size_t lines_left() const {        ///< at most; to reserve
        std::size_t count = 1;              // memchr, not std::count: a 2 MB file's newlines in a few µs
        for (auto at = pos_; (at = text_.find('\n', at)) != std::string_view::npos; ++at) ++count;
        return count;
    }

  private:
    std::string_view text_;
    std::size_t pos_ = 0;
    int number_ = 0;
};

bool is_key(std::string_view k) {
    if (k.empty()) return false;
    for (char c : k)
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
    return true;
}

}  // namespace

bool looks_like_trace(std::string_view text) {
    return text.rfind("# ballbar-trace/", 0) == 0;
}

std::string test_json(const circ::TestSpec& t) {
    ojson j = {{"kind", "circular"},           {"plane", circ::plane_name(t.plane)},
               {"radius_mm", t.radius_mm},     {"centre_mm", {t.centre_mm[0], t.centre_mm[1], t.centre_mm[2]}},
               {"feed_mm_min", t.feed_mm_min}, {"feed_in_mm", t.feed_in_mm}};
    ojson runs = ojson::array();
    for (const auto& r : t.runs)
        runs.push_back({{"direction", circ::direction_name(r.direction)},
                        {"start_deg", r.start_deg},
                        {"overshoot_deg", r.overshoot_deg},
                        {"data_arc_deg", r.data_arc_deg}});
    j["runs"] = runs;
    return j.dump();
}

TraceFile parse_trace(std::string_view text) {
    LineCursor lines(text);
    std::string_view line;
    if (!lines.next(line)) throw TraceFileError(1, "empty file");
    if (line != kTraceMagic) {
        if (line.rfind("# ballbar-trace/", 0) == 0)
            throw TraceFileError(
                1, "unsupported format version \"" + std::string(line.substr(2)) + "\" (this is ballbar-trace/1)");
        throw TraceFileError(1, "not a ballbar-trace/1 file (the first line must be \"# ballbar-trace/1\")");
    }
    TraceFile out;
    bool have_test = false;
    std::vector<std::string> seen;
    bool have_column_row = false;
    while (lines.next(line)) {
        const int no = lines.number();
        if (line.empty()) continue;
        if (line[0] != '#') {
            have_column_row = true;
            break;
        }
        const std::string_view body = trim_blanks(line.substr(1));
        const auto colon = body.find(':');
        if (colon == std::string_view::npos || !is_key(body.substr(0, colon))) continue;  // a comment
        const std::string key(body.substr(0, colon));
        const std::string value(trim_blanks(body.substr(colon + 1)));
        static const char* known[] = {"test", "instrument", "machine", "operator", "started_at", "notes"};
        const bool is_known = std::find_if(std::begin(known), std::end(known),
                                           [&](const char* k) { return key == k; }) != std::end(known);
        ojson j;
        try {
            j = ojson::parse(value);
        } catch (const ojson::exception&) {
            if (!is_known) continue;  // "# remark: text" is a comment
            throw TraceFileError(no, "the value of \"" + key + "\" is not one line of JSON");
        }
        if (std::find(seen.begin(), seen.end(), key) != seen.end())
            throw TraceFileError(no, "duplicate header \"" + key + "\"");
        seen.push_back(key);
        if (key == "test") {
            try {
                out.test = test_from_json(j);
            } catch (const std::runtime_error& e) {
                throw TraceFileError(no, std::string("test: ") + e.what());
            }
            have_test = true;
        } else if (key == "instrument") {
            try {
                (void)instrument_from_json(value);
            } catch (const std::exception& e) {
                throw TraceFileError(no, std::string("instrument: ") + e.what());
            }
            out.instrument_json = j.dump();
        } else if (key == "machine") {
            out.machine_json = j.dump();
        } else if (key == "operator" || key == "started_at" || key == "notes") {
            if (!j.is_string()) throw TraceFileError(no, "\"" + key + "\" must be a JSON string");
            (key == "operator" ? out.operator_name
             : key == "notes"  ? out.notes
                               : out.started_at) = j.get<std::string>();
        } else {
            out.extra.emplace_back(key, j.dump());
        }
    }
    if (!have_column_row) throw TraceFileError(lines.number(), "no column row and no data");
    const int header_no = lines.number();
    if (!have_test) throw TraceFileError(header_no, "no \"# test: {…}\" header before the column row");
    // Column row.
    std::vector<std::string> cols;
    {
        std::stringstream ss{std::string(line)};
        std::string c;
        while (std::getline(ss, c, ',')) cols.emplace_back(trim_blanks(c));
        if (!line.empty() && line.back() == ',') cols.emplace_back();
    }
    int c_time = -1, c_len = -1, c_bar = -1, c_air = -1;
    std::vector<std::string> unknown;
    for (std::size_t k = 0; k < cols.size(); ++k) {
        for (std::size_t m = 0; m < k; ++m)
            if (cols[m] == cols[k]) throw TraceFileError(header_no, "column \"" + cols[k] + "\" appears twice");
        const int idx = static_cast<int>(k);
        if (cols[k] == "time_s")
            c_time = idx;
        else if (cols[k] == "measured_mm")
            c_len = idx;
        else if (cols[k] == "bar_temp_C")
            c_bar = idx;
        else if (cols[k] == "air_temp_C")
            c_air = idx;
        else
            unknown.push_back(cols[k]);
    }
    if (c_time < 0) throw TraceFileError(header_no, "missing column \"time_s\"");
    if (c_len < 0) throw TraceFileError(header_no, "missing column \"measured_mm\"");
    if (!unknown.empty()) {
        std::string list;
        for (const auto& u : unknown) list += (list.empty() ? "\"" : ", \"") + u + "\"";
        out.warnings.push_back("unknown column(s) " + list + " ignored");
    }
    std::vector<std::string_view> fields;
    out.samples.reserve(lines.lines_left());
    while (lines.next(line)) {
        const int no = lines.number();
        if (trim_blanks(line).empty()) continue;
        if (line[0] == '#') throw TraceFileError(no, "a header line after the column row");
        fields.clear();
        std::string_view rest = line;
        while (true) {
            const auto comma = rest.find(',');
            fields.push_back(rest.substr(0, comma));
            if (comma == std::string_view::npos) break;
            rest.remove_prefix(comma + 1);
        }
        if (fields.size() != cols.size())
            throw TraceFileError(
                no, std::to_string(fields.size()) + " fields where the column row has " + std::to_string(cols.size()));
        const auto t = parse_cell(fields[static_cast<std::size_t>(c_time)]);
        if (!t)
            throw TraceFileError(
                no, "time_s \"" + std::string(fields[static_cast<std::size_t>(c_time)]) + "\" is not a number");
        const auto m = parse_cell(fields[static_cast<std::size_t>(c_len)]);
        if (!m)
            throw TraceFileError(
                no, "measured_mm \"" + std::string(fields[static_cast<std::size_t>(c_len)]) + "\" is not a number");
        if (*m <= 0.0) throw TraceFileError(no, "measured_mm must be > 0");
        // In range (NaN and ±inf fail these comparisons too), or column_problem says why not.
        namespace lim = analysis::limits;
        if (!(*t >= -lim::kTime_s && *t <= lim::kTime_s && *m > 0.0 && *m <= lim::kLength_mm))
            for (const auto& [name, v] : {std::pair{"time_s", *t}, std::pair{"measured_mm", *m}})
                if (const std::string why = column_problem(name, v); !why.empty()) throw TraceFileError(no, why);
        if (!out.samples.empty() && !(*t > out.samples.back().time_s))
            throw TraceFileError(no, "time_s " + shortest(*t) + " is not after the previous row's (" +
                                         shortest(out.samples.back().time_s) + "): it must strictly increase");
        out.samples.push_back({*t, *m});
        auto temp = [&](int c, std::vector<std::optional<double>>& into, const char* name) {
            if (c < 0) return;
            const std::string_view f = trim_blanks(fields[static_cast<std::size_t>(c)]);
            if (f.empty()) return into.push_back(std::nullopt);
            const auto v = parse_cell(f);
            if (!v) throw TraceFileError(no, std::string(name) + " \"" + std::string(f) + "\" is not a number");
            if (const std::string why = column_problem(name, *v); !why.empty()) throw TraceFileError(no, why);
            into.push_back(v);
        };
        temp(c_bar, out.bar_temp_C, "bar_temp_C");
        temp(c_air, out.air_temp_C, "air_temp_C");
    }
    if (out.samples.empty()) throw TraceFileError(header_no, "no data rows after the column row");
    return out;
}

TraceFile read_trace_file(const std::filesystem::path& path) {
    std::string text;
    try {  // at most 256 MiB, lines of at most 1 MiB; a directory, a FIFO or a device is refused
        text = fileio::read_text(path.string(), "trace file");
    } catch (const fileio::FileError& e) {
        throw TraceFileError(0, e.what());
    }
    return parse_trace(text);
}

std::string format_trace(const TraceFile& t) {
    std::string out(kTraceMagic);
    out += "\n# test: " + test_json(t.test) + "\n";
    if (!t.instrument_json.empty()) out += "# instrument: " + t.instrument_json + "\n";
    if (!t.machine_json.empty()) out += "# machine: " + t.machine_json + "\n";
    if (!t.operator_name.empty()) out += "# operator: " + ojson(t.operator_name).dump() + "\n";
    if (!t.started_at.empty()) out += "# started_at: " + ojson(t.started_at).dump() + "\n";
    if (!t.notes.empty()) out += "# notes: " + ojson(t.notes).dump() + "\n";
    for (const auto& [k, v] : t.extra) out += "# " + k + ": " + v + "\n";
    const bool bar = !t.bar_temp_C.empty(), air = !t.air_temp_C.empty();
    out += "time_s,measured_mm";
    if (bar) out += ",bar_temp_C";
    if (air) out += ",air_temp_C";
    out += '\n';
    out.reserve(out.size() + t.samples.size() * 32);
    for (std::size_t i = 0; i < t.samples.size(); ++i) {
        out += shortest(t.samples[i].time_s);
        out += ',';
        out += shortest(t.samples[i].measured_mm);
        if (bar) out += "," + (i < t.bar_temp_C.size() && t.bar_temp_C[i] ? shortest(*t.bar_temp_C[i]) : "");
        if (air) out += "," + (i < t.air_temp_C.size() && t.air_temp_C[i] ? shortest(*t.air_temp_C[i]) : "");
        out += '\n';
    }
    return out;
}

std::int64_t import_trace(Store& store, const TraceFile& trace, const std::string& file_name, SessionSource source) {
    NewSession ns;
    ns.machine.name = "circular test";
    if (!trace.instrument_json.empty()) ns.instrument = instrument_from_json(trace.instrument_json);
    ns.source = source;
    ns.operator_name = trace.operator_name;
    ns.procedure = "circular";
    ns.notes = trace.notes;
    ns.started_at = trace.started_at;
    // Samples hold nanometres from a reference length (an int32): half-way down the feed-in.
    const double reference_mm = trace.test.radius_mm + 0.5 * trace.test.feed_in_mm;
    ojson meta = {{"format", "ballbar-trace/1"},
                  {"file", file_name},
                  {"test", ojson::parse(test_json(trace.test))},
                  {"reference_length_mm", reference_mm},
                  {"has_bar_temp", !trace.bar_temp_C.empty()}};
    if (!trace.machine_json.empty()) meta["machine"] = ojson::parse(trace.machine_json);
    if (!trace.instrument_json.empty()) meta["instrument"] = ojson::parse(trace.instrument_json);
    ojson extra = ojson::object();
    for (const auto& [k, v] : trace.extra) extra[k] = ojson::parse(v);
    meta["extra"] = extra;
    if (!trace.air_temp_C.empty()) {
        ojson air = ojson::array();
        for (const auto& a : trace.air_temp_C) air.push_back(a ? ojson(*a) : ojson(nullptr));
        meta["air_temp_C"] = air;
    }
    ns.metadata_json = meta.dump();

    Transaction tx(store.db());
    const std::int64_t id = store.create_session(ns);
    store.start_session(id);
    Statement ins(store.db(),
                  "INSERT INTO samples(session_id, seq, device_time_us, displacement_nm, flags, bar_temp_mC) "
                  "VALUES (?,?,?,?,?,?)");
    for (std::size_t i = 0; i < trace.samples.size(); ++i) {
        const double nm = std::round((trace.samples[i].measured_mm - reference_mm) * 1e6);
        if (std::abs(nm) > 2.0e9)
            throw StorageError(StorageError::Kind::invalid,
                               "sample " + std::to_string(i + 1) + " is more than 2 mm from the reference length");
        const double us = std::round(trace.samples[i].time_s * 1e6);
        double temp_C = 20.0;  // stored for a sample without one, and flagged so: never read back as a temperature
        std::int64_t flags = 0;
        if (i < trace.bar_temp_C.size() && trace.bar_temp_C[i].has_value())
            temp_C = *trace.bar_temp_C[i];
        else if (!trace.bar_temp_C.empty())
            flags = analysis::kSampleTempInvalid;
        ins.bind(1, id)
            .bind(2, static_cast<std::int64_t>(i))
            .bind(3, static_cast<std::int64_t>(us))
            .bind(4, static_cast<std::int64_t>(nm))
            .bind(5, flags)
            .bind(6, static_cast<std::int64_t>(std::llround(temp_C * 1000.0)));
        ins.run();
    }
    store.transition(id, SessionState::completed, "import: " + file_name);
    tx.commit();
    return id;
}

TraceFile load_trace(Store& store, std::int64_t session_id) {
    const SessionInfo info = store.session(session_id);
    if (info.procedure != "circular")
        throw std::runtime_error("session " + std::to_string(session_id) + " is not a circular test (procedure \"" +
                                 info.procedure + "\")");
    const ojson meta = ojson::parse(info.metadata_json.empty() ? "{}" : info.metadata_json);
    if (!meta.contains("test"))
        throw std::runtime_error("session " + std::to_string(session_id) + " has no test header");
    TraceFile t;
    t.test = test_from_json(meta["test"]);
    double reference_mm = meta.value("reference_length_mm", t.test.radius_mm);
    const bool bar = meta.value("has_bar_temp", false);
    // A measured session (`circle measure`) holds every sample of every run of the program; its trace is
    // the good run's window (the last "circular.attempt" result marked good), in the instrument's length.
    std::optional<std::pair<std::int64_t, std::int64_t>> window;
    for (const auto& r : store.results(session_id)) {
        if (r.kind != "circular.attempt") continue;
        const ojson a = ojson::parse(r.payload_json, nullptr, false);
        if (a.is_discarded() || !a.value("good", false)) continue;
        window = std::make_pair(a.value("first_seq", std::int64_t{0}), a.value("last_seq", std::int64_t{-1}));
        reference_mm = a.value("reference_length_mm", reference_mm);
    }
    if (meta.contains("instrument")) t.instrument_json = meta["instrument"].dump();
    if (meta.contains("machine")) t.machine_json = meta["machine"].dump();
    if (meta.contains("extra"))
        for (const auto& [k, v] : meta["extra"].items()) t.extra.emplace_back(k, v.dump());
    t.operator_name = info.operator_name;
    t.notes = info.notes;
    t.started_at = info.started_at;
    Statement st(
        store.db(),
        "SELECT device_time_us, displacement_nm, bar_temp_mC, flags FROM samples WHERE session_id = ? AND seq >= ? "
        "AND seq <= ? ORDER BY seq");
    st.bind(1, session_id);
    st.bind(2, window ? window->first : std::int64_t{0});
    st.bind(3, window ? window->second : std::numeric_limits<std::int64_t>::max());
    // Stored in whole µs and nm: each value is rebuilt as the double nearest its decimal (an integer
    // divided by 10⁶ is rounded once), so an export writes back the text that was imported (100.7889,
    // not 100.78890000000001) and a re-import is recognised as the same file.
    const double reference_nm = reference_mm * 1e6;
    const bool whole_nm = std::abs(reference_nm - std::round(reference_nm)) < 1e-3;
    while (st.step()) {
        const auto nm = static_cast<double>(st.column_int(1));
        t.samples.push_back({static_cast<double>(st.column_int(0)) / 1e6,
                             whole_nm ? (std::round(reference_nm) + nm) / 1e6 : reference_mm + nm * 1e-6});
        // A sample without a bar temperature (a gauge's, or a failed sensor's) has none in the trace.
        if (bar)
            t.bar_temp_C.push_back((st.column_int(3) & analysis::kSampleTempInvalid)
                                       ? std::nullopt
                                       : std::optional<double>(static_cast<double>(st.column_int(2)) / 1000.0));
    }
    if (meta.contains("air_temp_C"))
        for (const auto& a : meta["air_temp_C"])
            t.air_temp_C.push_back(a.is_null() ? std::nullopt : std::optional<double>(a.get<double>()));
    return t;
}

circ::TestSpec parse_test_json(std::string_view text) {
    const ojson j = ojson::parse(text, nullptr, false);
    if (j.is_discarded()) throw std::runtime_error("not valid JSON");
    circ::TestSpec t = test_from_json(j);
    if (const std::string bad = t.validate(); !bad.empty()) throw std::runtime_error(bad);
    return t;
}

}  // namespace ballbar::storage
