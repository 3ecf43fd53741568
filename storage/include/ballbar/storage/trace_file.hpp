// SPDX-License-Identifier: MIT
// Reader and writer of `ballbar-trace/1` files (docs/formats/trace.md): a continuous ball-bar test,
// bar length over time, with the test's specification in a `# test:` header. A file is accepted whole
// or refused with the line and the problem (TraceFileError). Storing a trace makes a session of
// procedure "circular": the test header and the other header keys go to the session's metadata, every
// row to the samples table, the analysis to the results table (kind "circular").
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

/// An invalid trace file. what() is "line N: problem" (N = 0 when the file cannot be read at all).
class TraceFileError : public std::runtime_error {
  public:
    TraceFileError(int line, const std::string& problem)
        : std::runtime_error(line > 0 ? "line " + std::to_string(line) + ": " + problem : problem),
          line_(line),
          problem_(problem) {}
    int line() const { return line_; }
    const std::string& problem() const { return problem_; }

  private:
    int line_;
    std::string problem_;
};

struct TraceFile {
    analysis::circular::TestSpec test;
    std::vector<analysis::circular::TraceSample> samples;
    std::vector<std::optional<double>> bar_temp_C, air_temp_C;  ///< per sample, when the column exists
    std::string instrument_json, machine_json;                  ///< header values as written ("" = none)
    std::string operator_name, started_at, notes;
    std::vector<std::pair<std::string, std::string>> extra;  ///< unknown header keys (value as JSON text)
    std::vector<std::string> warnings;                       ///< unknown columns (one warning)
};

/// True when the text starts with the line `# ballbar-trace/1` (any version of the format, in fact:
/// `# ballbar-trace/`), so that `import` can tell it from a readings file.
bool looks_like_trace(std::string_view text);

TraceFile parse_trace(std::string_view text);
TraceFile read_trace_file(const std::filesystem::path& path);
/// The file text; numbers in the shortest text that reads back to the same double.
std::string format_trace(const TraceFile& trace);
/// The `test` header's JSON for `test` (one line).
std::string test_json(const analysis::circular::TestSpec& test);
/// A `test` header from its JSON text (`circle plan --test-out`); throws std::runtime_error naming the
/// problem.
analysis::circular::TestSpec parse_test_json(std::string_view text);

/// A new session (procedure "circular", source `source`) holding the trace; returns its id.
std::int64_t import_trace(Store& store, const TraceFile& trace, const std::string& file_name,
                          SessionSource source = SessionSource::imported);
/// The trace of a circular session. Throws StorageError-free std::runtime_error when the session is
/// not a circular test.
TraceFile load_trace(Store& store, std::int64_t session_id);

}  // namespace ballbar::storage
