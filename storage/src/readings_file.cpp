// SPDX-License-Identifier: MIT
// Parsing `ballbar-readings/1`: header lines, then RFC 4180 records mapped onto columns by name.
#include "ballbar/storage/readings_file.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <new>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "ballbar/analysis/decimal_text.hpp"
#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/fileio/input.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

using nlohmann::json;

constexpr std::string_view kMagic = "# ballbar-readings/1";

/// Lines (LF or CRLF) from a fetch function, with one line of lookahead. A line stays valid until the
/// next call of next() or peek() fetches another.
class LineReader {
  public:
    explicit LineReader(ReadingsStream::Fetch fetch) : fetch_(std::move(fetch)) {}
    bool done() {
        fill();
        return !pending_;
    }
    int line() const { return line_; }  // number of the line next() returns
    std::string_view peek() {
        fill();
        return pending_ ? current_ : std::string_view();
    }
    std::string_view next() {
        fill();
        if (!pending_) return {};
        pending_ = false;
        ++line_;
        return current_;
    }

  private:
    void fill() {
        if (pending_ || eof_) return;
        if (const auto l = fetch_()) {
            current_ = *l;
            pending_ = true;
        } else {
            eof_ = true;
        }
    }
    ReadingsStream::Fetch fetch_;
    std::string_view current_;
    bool pending_ = false, eof_ = false;
    int line_ = 1;
};

/// Lines of text held in memory.
ReadingsStream::Fetch text_lines(std::string_view text) {
    return [text, pos = std::size_t{0}]() mutable -> std::optional<std::string_view> {
        if (pos >= text.size()) return std::nullopt;
        const std::size_t nl = text.find('\n', pos);
        const std::size_t stop = nl == std::string_view::npos ? text.size() : nl;
        std::string_view line = text.substr(pos, stop - pos);
        pos = nl == std::string_view::npos ? text.size() : nl + 1;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        return line;
    };
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

bool is_blank(char c) {
    return c == ' ' || c == '\t';
}

/// Reads one RFC 4180 record starting at the reader's position into `fields`; quoted fields may span
/// lines. The strings of `fields` are reused (a file's records cost no allocation each).
void read_record(LineReader& in, std::vector<std::string>& fields) {
    const int start_line = in.line();
    std::size_t count = 0;
    std::string_view line = in.next();
    std::size_t i = 0;
    while (true) {  // one field per iteration
        if (count == fields.size()) fields.emplace_back();
        std::string& field = fields[count++];
        field.clear();
        while (i < line.size() && is_blank(line[i])) ++i;
        if (i < line.size() && line[i] == '"') {
            ++i;
            while (true) {
                if (i >= line.size()) {
                    if (in.done()) throw ReadingsFileError(start_line, "a quoted field is not closed");
                    field += '\n';
                    line = in.next();
                    i = 0;
                    continue;
                }
                const char c = line[i++];
                if (c != '"') {
                    field += c;
                } else if (i < line.size() && line[i] == '"') {
                    field += '"';
                    ++i;
                } else {
                    break;
                }
            }
            while (i < line.size() && is_blank(line[i])) ++i;
            if (i < line.size() && line[i] != ',') {
                throw ReadingsFileError(in.line() - 1, "unexpected text after a closing quote");
            }
        } else {
            // One pass to the comma, looking for quotes on the way (fields are a few characters: two
            // memchr calls and a trim cost more than the scan).
            std::size_t end = i, last = i;  // last: past the last non-blank character
            for (; end < line.size() && line[end] != ','; ++end) {
                if (line[end] == '"') throw ReadingsFileError(in.line() - 1, "a quote inside an unquoted field");
                if (!is_blank(line[end])) last = end + 1;
            }
            field.assign(line.substr(i, last - i));
            i = end;
        }
        if (i >= line.size()) break;
        ++i;  // past the comma
    }
    fields.resize(count);
}

std::optional<double> parse_number(std::string_view s) {
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    if (s.empty()) return std::nullopt;
    double v = 0;
    const bool negative = s.front() == '-';
    // Most fields are short decimals: the exact fast path (from_chars' value, bit for bit).
    if (std::size_t pos = negative ? 1 : 0; analysis::read_short_decimal(s, pos, v) && pos == s.size())
        return negative ? -v : v;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
    return v;
}

enum class Col {
    X,
    Y,
    Z,
    rot1,
    rot2,
    sx,
    sy,
    sz,
    measured,
    nominal,
    time,
    bar_temp,
    air_temp,
    machine_temp,
    location,
    point,
    step,
    n,
    std_mm,
    count
};

/// The physical range of a number column (docs/formats/readings.md, "Ranges"); integer columns are
/// checked where they are read.
struct ColumnRange {
    double lo, hi;
    const char* unit;
    bool above_lo = false;  ///< lo itself is outside (a length must be > 0)
};

ColumnRange range_of(Col c) {
    namespace lim = analysis::limits;
    switch (c) {
        case Col::X:
        case Col::Y:
        case Col::Z:
        case Col::sx:
        case Col::sy:
        case Col::sz:
            return {-lim::kPosition_mm, lim::kPosition_mm, "mm"};
        case Col::rot1:
        case Col::rot2:
            return {-lim::kRotary_deg, lim::kRotary_deg, "deg"};
        case Col::measured:
        case Col::nominal:
            return {0, lim::kLength_mm, "mm", true};
        case Col::time:
            return {-lim::kTime_s, lim::kTime_s, "s"};
        case Col::bar_temp:
        case Col::air_temp:
        case Col::machine_temp:
            return {lim::kTempMin_C, lim::kTempMax_C, "C"};
        case Col::std_mm:
            return {0, lim::kSmallLength_mm, "mm"};
        default:
            return {-2e9, 2e9, ""};  // integers: their own ranges
    }
}

struct ColumnSpec {
    Col col;
    std::string name;
    bool required;
};

std::vector<ColumnSpec> columns_for(analysis::MachineType type) {
    const auto rot = analysis::rotary_axes(type);
    return {{Col::X, "X_mm", true},
            {Col::Y, "Y_mm", true},
            {Col::Z, "Z_mm", true},
            {Col::rot1, std::string(1, rot.first) + "_deg", true},
            {Col::rot2, std::string(1, rot.second) + "_deg", true},
            {Col::sx, "socket_x_mm", true},
            {Col::sy, "socket_y_mm", true},
            {Col::sz, "socket_z_mm", true},
            {Col::measured, "measured_mm", true},
            {Col::nominal, "nominal_mm", false},
            {Col::time, "time_s", false},
            {Col::bar_temp, "bar_temp_C", false},
            {Col::air_temp, "air_temp_C", false},
            {Col::machine_temp, "machine_temp_C", false},
            {Col::location, "location", false},
            {Col::point, "point", false},
            {Col::step, "step", false},
            {Col::n, "n", false},
            {Col::std_mm, "std_mm", false}};
}

void set_rotary(analysis::Pose& pose, char axis, double deg) {
    const double rad = analysis::deg_to_rad(deg);
    if (axis == 'A') pose.A_rad = rad;
    if (axis == 'B') pose.B_rad = rad;
    if (axis == 'C') pose.C_rad = rad;
}

struct Header {
    std::optional<analysis::MachineGeometry> machine;
    ReadingsMetadata meta;
    std::vector<std::string> warnings;
};

std::string json_string(const json& v, std::string_view key, int line) {
    if (!v.is_string()) throw ReadingsFileError(line, std::string(key) + " must be a JSON string");
    return v.get<std::string>();
}

bool looks_iso8601(std::string_view s) {
    auto digits = [&](std::size_t from, std::size_t n) {
        if (s.size() < from + n) return false;
        for (std::size_t i = from; i < from + n; ++i) {
            if (s[i] < '0' || s[i] > '9') return false;
        }
        return true;
    };
    return digits(0, 4) && s.size() >= 10 && s[4] == '-' && digits(5, 2) && s[7] == '-' && digits(8, 2) &&
           (s.size() == 10 || s[10] == 'T' || s[10] == ' ');
}

/// Handles one `# key: value` line; returns false when the line is a comment.
bool header_line(std::string_view line, int lineno, Header& h, std::map<std::string, int>& seen) {
    std::string_view body = line.substr(1);
    if (!body.empty() && body.front() == ' ') body.remove_prefix(1);
    const std::size_t colon = body.find(':');
    if (colon == std::string_view::npos || colon == 0) return false;
    const std::string key(body.substr(0, colon));
    for (const char c : key) {
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
    }
    const std::string_view value = trim(body.substr(colon + 1));
    const bool known =
        key == "machine" || key == "instrument" || key == "operator" || key == "started_at" || key == "notes";
    json v;
    try {
        v = json::parse(value);
    } catch (const json::exception& e) {  // parse_error, and out_of_range for a number past double
        if (!known) return false;         // a comment that happens to contain a colon
        throw ReadingsFileError(lineno, "the value of \"" + key + "\" is not one line of JSON: " + e.what());
    }
    if (const auto it = seen.find(key); it != seen.end()) {
        throw ReadingsFileError(
            lineno, "header \"" + key + "\" given twice (first on line " + std::to_string(it->second) + ")");
    }
    seen[key] = lineno;
    try {
        if (key == "machine") {
            h.machine = machine_from_json(value, &h.warnings);
        } else if (key == "instrument") {
            h.meta.instrument = instrument_from_json(value);
        } else if (key == "operator") {
            h.meta.operator_name = json_string(v, key, lineno);
        } else if (key == "notes") {
            h.meta.notes = json_string(v, key, lineno);
        } else if (key == "started_at") {
            h.meta.started_at = json_string(v, key, lineno);
            if (!looks_iso8601(h.meta.started_at)) {
                throw ReadingsFileError(lineno, "started_at \"" + h.meta.started_at + "\" is not an ISO 8601 time");
            }
        } else {
            h.meta.extra.emplace_back(key, v.dump());
        }
    } catch (const FormatError& e) {
        throw ReadingsFileError(lineno, e.what());
    }
    return true;
}

}  // namespace

struct ReadingsStream::Impl {
    explicit Impl(Fetch fetch) : in(std::move(fetch)) {}
    std::optional<fileio::LineReader> file;  // when reading a file: the source of `in`
    LineReader in;
    ReadingsMetadata metadata;
    analysis::MachineGeometry machine;
    std::vector<std::string> warnings;
    std::vector<std::string> names;  // the column row
    std::vector<ColumnSpec> specs;
    std::vector<int> index;
    std::vector<std::string> fields;
    std::size_t count = 0;
    bool first = true;
    void header();
    bool next(analysis::Reading& r, double& nominal_mm, std::optional<NominalMismatch>& mismatch);
};

void ReadingsStream::Impl::header() {
    if (in.done()) throw ReadingsFileError(1, "empty file; expected \"# ballbar-readings/1\"");
    std::string_view first_line = in.next();
    if (first_line.substr(0, 3) == "\xEF\xBB\xBF") first_line.remove_prefix(3);  // UTF-8 byte-order mark
    if (first_line != kMagic) {
        if (first_line.rfind("# ballbar-readings/", 0) == 0) {
            throw ReadingsFileError(1, "unsupported format version \"" + fileio::cut(first_line.substr(2)) +
                                           "\"; this ballbar reads ballbar-readings/1");
        }
        throw ReadingsFileError(1, "not a readings file: line 1 must be \"# ballbar-readings/1\"");
    }

    Header h;
    std::map<std::string, int> seen;
    int columns_line = 0;
    while (!in.done()) {
        const int lineno = in.line();
        const std::string_view line = in.peek();
        if (trim(line).empty()) {
            in.next();
            continue;
        }
        if (line.front() == '#') {
            in.next();
            header_line(line, lineno, h, seen);
            continue;
        }
        columns_line = lineno;
        read_record(in, names);
        break;
    }
    if (!h.machine) {
        throw ReadingsFileError(columns_line ? columns_line : in.line(),
                                "no \"# machine: {...}\" header line before the column row");
    }
    if (columns_line == 0) throw ReadingsFileError(in.line(), "no column header row and no readings");

    machine = *h.machine;
    metadata = std::move(h.meta);
    warnings = std::move(h.warnings);

    // Map columns by name.
    specs = columns_for(machine.type);
    index.assign(static_cast<std::size_t>(Col::count), -1);
    std::vector<std::string> unknown;
    for (std::size_t i = 0; i < names.size(); ++i) {
        const std::string& name = names[i];
        if (name.empty()) throw ReadingsFileError(columns_line, "column " + std::to_string(i + 1) + " has no name");
        bool matched = false;
        for (const auto& spec : specs) {
            if (spec.name != name) continue;
            auto& slot = index[static_cast<std::size_t>(spec.col)];
            if (slot >= 0) throw ReadingsFileError(columns_line, "column \"" + name + "\" appears twice");
            slot = static_cast<int>(i);
            matched = true;
        }
        if (!matched) {
            for (const auto& u : unknown) {
                if (u == name)
                    throw ReadingsFileError(columns_line, "column \"" + fileio::cut(name) + "\" appears twice");
            }
            unknown.push_back(name);
        }
    }
    for (const auto& spec : specs) {
        if (spec.required && index[static_cast<std::size_t>(spec.col)] < 0) {
            throw ReadingsFileError(columns_line, "required column \"" + spec.name + "\" is missing (a " +
                                                      std::string(analysis::to_string(machine.type)) +
                                                      " file needs X_mm, Y_mm, Z_mm, " + specs[3].name + ", " +
                                                      specs[4].name +
                                                      ", socket_x_mm, socket_y_mm, socket_z_mm, measured_mm)");
        }
    }
    if (!unknown.empty()) {
        std::string list;
        for (std::size_t i = 0; i < unknown.size() && i < 20; ++i)
            list += (list.empty() ? "\"" : ", \"") + fileio::cut(unknown[i]) + "\"";
        if (unknown.size() > 20) list += ", …";
        warnings.push_back("line " + std::to_string(columns_line) + ": unknown column" +
                           (unknown.size() > 1 ? "s " : " ") + list + " ignored");
    }
}

bool ReadingsStream::Impl::next(analysis::Reading& r, double& nominal_mm, std::optional<NominalMismatch>& mismatch) {
    const auto rot = analysis::rotary_axes(machine.type);
    mismatch.reset();
    while (!in.done()) {
        const int lineno = in.line();
        const std::string_view line = in.peek();
        if (trim(line).empty()) {
            in.next();
            continue;
        }
        if (line.front() == '#') {
            in.next();
            std::map<std::string, int> none;
            Header dummy;
            if (header_line(line, lineno, dummy, none)) {
                throw ReadingsFileError(lineno, "header line after the column row (headers come first)");
            }
            continue;
        }
        read_record(in, fields);
        if (fields.size() != names.size()) {
            throw ReadingsFileError(lineno, std::to_string(fields.size()) + " fields, but the column row has " +
                                                std::to_string(names.size()));
        }
        auto field = [&](Col c) -> std::optional<std::string_view> {
            const int i = index[static_cast<std::size_t>(c)];
            if (i < 0 || fields[static_cast<std::size_t>(i)].empty()) return std::nullopt;
            return std::string_view(fields[static_cast<std::size_t>(i)]);
        };
        auto name_of = [&](Col c) { return names[static_cast<std::size_t>(index[static_cast<std::size_t>(c)])]; };
        auto number = [&](Col c) -> std::optional<double> {
            const auto f = field(c);
            if (!f) {
                if (specs[static_cast<std::size_t>(c)].required) {
                    throw ReadingsFileError(lineno, "column \"" + name_of(c) + "\" is empty");
                }
                return std::nullopt;
            }
            const auto v = parse_number(*f);
            if (!v) {
                throw ReadingsFileError(
                    lineno, "column \"" + name_of(c) + "\": \"" + fileio::cut(*f) + "\" is not a finite number");
            }
            const ColumnRange range = range_of(c);
            const std::string why = range.above_lo ? analysis::limits::check_above(*v, range.lo, range.hi, range.unit)
                                                   : analysis::limits::check_in(*v, range.lo, range.hi, range.unit);
            if (!why.empty()) throw ReadingsFileError(lineno, "column \"" + name_of(c) + "\" " + why);
            return v;
        };
        auto integer = [&](Col c, int min, int max) -> std::optional<int> {
            const auto v = number(c);
            if (!v) return std::nullopt;
            if (*v != std::floor(*v) || *v < min || *v > max) {
                throw ReadingsFileError(lineno, "column \"" + name_of(c) + "\": " + fileio::cut(*field(c)) +
                                                    " is not an integer in [" + std::to_string(min) + ", " +
                                                    std::to_string(max) + "]");
            }
            return static_cast<int>(*v);
        };

        r = analysis::Reading{};
        r.pose.X_mm = *number(Col::X);
        r.pose.Y_mm = *number(Col::Y);
        r.pose.Z_mm = *number(Col::Z);
        set_rotary(r.pose, rot.first, *number(Col::rot1));
        set_rotary(r.pose, rot.second, *number(Col::rot2));
        r.socket_mm = {*number(Col::sx), *number(Col::sy), *number(Col::sz)};
        r.measured_mm = *number(Col::measured);
        r.time_s = number(Col::time).value_or(0.0);
        r.bar_temp_C = number(Col::bar_temp);
        r.air_temp_C = number(Col::air_temp);
        r.machine_temp_C = number(Col::machine_temp);
        r.location = integer(Col::location, 0, 1'000'000).value_or(-1);
        r.point = integer(Col::point, 0, 1'000'000'000).value_or(-1);
        r.step = integer(Col::step, 1, 2).value_or(0);
        r.n = integer(Col::n, 1, 2'000'000'000).value_or(0);
        r.std_mm = number(Col::std_mm);

        nominal_mm = analysis::nominal_length(machine, r.pose, r.socket_mm);
        // Each coordinate may be in range and the bar they span still not: a reading whose nominal length
        // is no ball-bar's would also be refused when the file is written back.
        if (const std::string why = analysis::limits::check_above(nominal_mm, 0, analysis::limits::kLength_mm, "mm");
            !why.empty()) {
            throw ReadingsFileError(lineno, "the nominal bar length (from the pose and socket) " + why);
        }
        if (const auto given = number(Col::nominal); given && std::abs(*given - nominal_mm) > kNominalTolerance_mm) {
            mismatch = NominalMismatch{lineno, count, *given, nominal_mm};
        }
        ++count;
        return true;
    }
    if (count == 0) throw ReadingsFileError(in.line(), "the file has no readings");
    return false;
}

ReadingsStream::ReadingsStream(Fetch fetch) : impl_(std::make_unique<Impl>(std::move(fetch))) {
    try {
        impl_->header();
    } catch (const fileio::FileError& e) {  // a line too long, a read error
        throw ReadingsFileError(0, e.what());
    }
}

ReadingsStream ReadingsStream::open(const std::filesystem::path& path, std::function<void(std::string_view)> tap) {
    try {
        fileio::LineReader lines(fileio::InputFile::open(path.string(), "readings file"));
        lines.set_tap(std::move(tap));
        auto owned = std::make_shared<fileio::LineReader>(std::move(lines));
        return ReadingsStream([owned] { return owned->next(); });
    } catch (const fileio::FileError& e) {
        throw ReadingsFileError(0, e.what());
    }
}

ReadingsStream::ReadingsStream(ReadingsStream&&) noexcept = default;
ReadingsStream& ReadingsStream::operator=(ReadingsStream&&) noexcept = default;
ReadingsStream::~ReadingsStream() = default;

const analysis::MachineGeometry& ReadingsStream::machine() const {
    return impl_->machine;
}
const ReadingsMetadata& ReadingsStream::metadata() const {
    return impl_->metadata;
}
const std::vector<std::string>& ReadingsStream::warnings() const {
    return impl_->warnings;
}
std::size_t ReadingsStream::count() const {
    return impl_->count;
}

bool ReadingsStream::next(analysis::Reading& reading, double& nominal_mm, std::optional<NominalMismatch>& mismatch) {
    try {
        return impl_->next(reading, nominal_mm, mismatch);
    } catch (const fileio::FileError& e) {  // a line too long, a read error
        throw ReadingsFileError(0, e.what());
    }
}

namespace {

/// The lines of the file at `path` that can be records (not a comment, at least one comma): an upper
/// bound of its readings, counted in one pass of 1 MiB reads. A file of empty lines or of anything
/// else counts none, so that nothing is reserved for it.
std::size_t count_records(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> buf(std::size_t{1} << 20);
    std::size_t records = 0;
    bool line_start = true, comment = false, comma = false;
    while (in) {
        in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
        const auto got = static_cast<std::size_t>(in.gcount());
        for (std::size_t i = 0; i < got; ++i) {
            const char c = buf[i];
            if (c == '\n') {
                if (comma && !comment) ++records;
                line_start = true;
                comment = comma = false;
                continue;
            }
            if (line_start) comment = c == '#';
            line_start = false;
            comma = comma || c == ',';
        }
    }
    if (comma && !comment) ++records;
    return records;
}

/// `expected`: an upper bound of the readings (0: not known). Reserved at once, the readings are held
/// once: grown by doubling, the vector would hold up to twice their size, and three times while it
/// moves (the peak of `identify` on a 250 MiB file, 1.0 GB, was that). Where the room cannot be had at
/// once, the vector grows as it reads.
ReadingsFile collect(ReadingsStream& stream, std::size_t expected = 0) {
    ReadingsFile out;
    try {
        out.set.readings.reserve(expected);
        out.nominal_mm.reserve(expected);
    } catch (const std::bad_alloc&) {
        std::vector<analysis::Reading>().swap(out.set.readings);
        std::vector<double>().swap(out.nominal_mm);
    }
    out.set.machine = stream.machine();
    out.metadata = stream.metadata();
    out.warnings = stream.warnings();
    analysis::Reading r;
    double nominal = 0;
    std::optional<NominalMismatch> mismatch;
    while (stream.next(r, nominal, mismatch)) {
        if (mismatch) out.nominal_mismatches.push_back(*mismatch);
        out.nominal_mm.push_back(nominal);
        out.set.readings.push_back(r);
    }
    return out;
}

}  // namespace

ReadingsFile parse_readings(std::string_view text) {
    ReadingsStream stream(text_lines(text));
    return collect(stream);
}

ReadingsFile read_readings_file(const std::filesystem::path& path) {
    try {
        const fileio::InputFile f = fileio::InputFile::open(path.string(), "readings file");
        if (f.size() > fileio::kMaxTextBytes) {
            throw ReadingsFileError(0, "the readings file " + path.string() + " is too large to analyse (" +
                                           std::to_string(f.size() >> 20) + " MiB; at most " +
                                           std::to_string(fileio::kMaxTextBytes >> 20) +
                                           " MiB are read; `ballbar import` streams files of any length)");
        }
    } catch (const fileio::FileError& e) {
        throw ReadingsFileError(0, e.what());
    }
    ReadingsStream stream = ReadingsStream::open(path);
    return collect(stream, count_records(path));
}

}  // namespace ballbar::storage
