// SPDX-License-Identifier: MIT
// Reader and writer of `ballbar-readings/1` files (docs/formats/readings.md): a `#` header with the
// machine (and optional instrument, operator, started_at, notes, other keys), then RFC 4180 CSV with
// columns identified by name. A file is accepted whole or refused with the line and the problem.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ballbar/analysis/reading.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

/// An invalid readings file. what() is "line N: problem" (N = 0 when the file cannot be read at all).
class ReadingsFileError : public std::runtime_error {
  public:
    ReadingsFileError(int line, const std::string& problem)
        : std::runtime_error(line > 0 ? "line " + std::to_string(line) + ": " + problem : problem),
          line_(line),
          problem_(problem) {}
    int line() const { return line_; }
    const std::string& problem() const { return problem_; }

  private:
    int line_;
    std::string problem_;
};

/// The optional header keys of a readings file.
struct ReadingsMetadata {
    std::optional<Instrument> instrument;
    std::string operator_name;
    std::string started_at;  ///< ISO 8601, as written
    std::string notes;
    /// Unknown header keys, in file order: key and its value as one line of JSON.
    std::vector<std::pair<std::string, std::string>> extra;
};

/// A row whose `nominal_mm` disagrees with the length recomputed from the machine geometry.
struct NominalMismatch {
    int line = 0;
    std::size_t row = 0;  ///< index into ReadingSet::readings
    double file_nominal_mm = 0;
    double computed_nominal_mm = 0;
};

struct ReadingsFile {
    analysis::ReadingSet set;
    ReadingsMetadata metadata;
    std::vector<double> nominal_mm;                   ///< recomputed nominal length of each reading
    std::vector<NominalMismatch> nominal_mismatches;  ///< rows differing by more than kNominalTolerance_mm
    std::vector<std::string> warnings;                ///< unknown columns (one warning), ignored machine keys
};

inline constexpr double kNominalTolerance_mm = 0.001;

/// A readings file read one reading at a time, in memory independent of its length (what `import`
/// uses): the header is parsed on construction, then next() yields each reading with its recomputed
/// nominal length. Throws ReadingsFileError (line 0 when the file cannot be opened or read, or a line
/// is longer than fileio::kMaxLineBytes).
class ReadingsStream {
  public:
    /// The next line (LF and CR removed) or nothing at the end; valid until the next call.
    using Fetch = std::function<std::optional<std::string_view>()>;
    explicit ReadingsStream(Fetch fetch);
    /// Streams the file at `path` (a regular file: fileio::InputFile). `tap`, when given, sees every
    /// byte read, once and in order (import hashes the file with it: one read, so the hash is of what
    /// was parsed).
    static ReadingsStream open(const std::filesystem::path& path, std::function<void(std::string_view)> tap = nullptr);
    ReadingsStream(ReadingsStream&&) noexcept;
    ReadingsStream& operator=(ReadingsStream&&) noexcept;
    ~ReadingsStream();

    const analysis::MachineGeometry& machine() const;
    const ReadingsMetadata& metadata() const;
    const std::vector<std::string>& warnings() const;  ///< from the header and the column row
    /// The next reading, or false at the end (a file without readings throws). `mismatch` is set when
    /// the row's nominal_mm differs from `nominal_mm` by more than kNominalTolerance_mm.
    bool next(analysis::Reading& reading, double& nominal_mm, std::optional<NominalMismatch>& mismatch);
    std::size_t count() const;  ///< readings returned so far

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// Parses a whole file held in memory. Throws ReadingsFileError.
ReadingsFile parse_readings(std::string_view text);
/// Reads and parses `path` into memory: at most fileio::kMaxTextBytes (256 MiB; larger files are
/// refused: import streams them). Throws ReadingsFileError (line 0 when the file cannot be opened).
ReadingsFile read_readings_file(const std::filesystem::path& path);

/// The file for `set`, with `metadata` in the header. Numbers are written with the shortest text that
/// reads back to the same double (angles: that reads back to the same radians), so parse → write →
/// parse is lossless. Optional columns appear only when some reading has a value.
std::string format_readings(const analysis::ReadingSet& set, const ReadingsMetadata& metadata = {});
/// Writes format_readings() to `path` (via a temporary file and rename). Throws std::runtime_error.
void write_readings_file(const std::filesystem::path& path, const analysis::ReadingSet& set,
                         const ReadingsMetadata& metadata = {});

}  // namespace ballbar::storage
