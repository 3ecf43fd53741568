// SPDX-License-Identifier: MIT
// Input files with stated limits: every file ballbar reads is opened here. Only regular files are read
// (a directory is "is a directory", a FIFO or device is refused before anything blocks), whole-file
// reads check the size against a cap before reading a byte, and line-oriented reads stream with a
// maximum line length — so /dev/zero, a FIFO nobody writes, a 10 GB file or a directory get a clear
// error at once and in bounded memory.
//
//   auto text = fileio::read_whole(path, "machine file", fileio::kMaxJsonBytes);
//   fileio::LineReader lines(fileio::InputFile::open(path, "readings file"));
//   while (auto line = lines.next()) { ... }
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace ballbar::fileio {

/// Whole-file JSON inputs (machine, plan, model, offsets, emulator configuration, solve requests).
inline constexpr std::size_t kMaxJsonBytes = std::size_t{16} << 20;  // 16 MiB
/// Line-oriented files that are held in memory whole (NC programs, traces, readings for analysis).
inline constexpr std::size_t kMaxTextBytes = std::size_t{256} << 20;  // 256 MiB
/// Longest line of any line-oriented input (readings, traces, NC programs).
inline constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;  // 1 MiB

/// Why a file could not be used. `refused`: the input is wrong (missing, a directory, too large, a
/// line too long: the CLI's exit 2); `failed`: the system failed while reading or writing (exit 1).
class FileError : public std::runtime_error {
  public:
    enum class Kind { refused, failed };
    FileError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
    Kind kind() const { return kind_; }

  private:
    Kind kind_;
};

/// `text` cut to `max_chars` bytes (at a UTF-8 boundary) with "…" appended when longer: for echoing
/// what a user's file holds in an error message.
std::string cut(std::string_view text, std::size_t max_chars = 40);

/// An open, regular input file (move-only; closes on destruction).
class InputFile {
  public:
    /// Opens `path` for reading without blocking (O_NONBLOCK until checked, O_NOCTTY, O_CLOEXEC).
    /// Throws FileError(refused) naming `what` and the path: no such file, permission denied, is a
    /// directory, not a regular file (FIFO, socket, device).
    static InputFile open(const std::string& path, std::string_view what);
    /// Standard input (not closed): whatever it is, read with the caller's caps.
    static InputFile standard_input(std::string_view what);

    InputFile(InputFile&& other) noexcept;
    InputFile& operator=(InputFile&& other) noexcept;
    InputFile(const InputFile&) = delete;
    InputFile& operator=(const InputFile&) = delete;
    ~InputFile();

    /// Up to `n` bytes; 0 at the end. Throws FileError(failed) on a read error.
    std::size_t read(char* buf, std::size_t n);
    /// The size at opening (0 for standard input that is not a regular file).
    std::uint64_t size() const { return size_; }
    const std::string& path() const { return path_; }
    const std::string& what() const { return what_; }

  private:
    InputFile(int fd, bool owned, std::string path, std::string what, std::uint64_t size)
        : fd_(fd), owned_(owned), path_(std::move(path)), what_(std::move(what)), size_(size) {}
    int fd_ = -1;
    bool owned_ = false;
    std::string path_, what_;
    std::uint64_t size_ = 0;
};

/// The whole of `file`, refusing (FileError refused) a file larger than `max_bytes` — checked against
/// its size before reading and again while reading (a file that grows, standard input).
std::string read_whole(InputFile& file, std::size_t max_bytes);
/// InputFile::open + read_whole.
std::string read_whole(const std::string& path, std::string_view what, std::size_t max_bytes);

/// The deepest nesting of arrays and objects any of the project's JSON formats has is a handful of
/// levels; a parser building a document of 16 MiB of "[" spent 1.27 GB before it failed.
inline constexpr int kMaxJsonDepth = 64;
/// The most values (numbers, strings, arrays, objects, …) a JSON input may hold. A parsed value costs
/// about 52 bytes: 16 MiB of "0," (8 M values) took 418 MB; 2 M values stay within about 110 MB, and
/// the largest input the project's formats need (a plan of 10,000 points) has about 150,000.
inline constexpr std::size_t kMaxJsonValues = 2'000'000;

/// Refuses (FileError refused, naming `what` and the byte) JSON text whose arrays and objects nest
/// deeper than `max_depth`, or that holds more than `max_values` values, by one pass over the bytes
/// (strings skipped) and no allocation: called on every JSON input before it is parsed.
void check_json_nesting(std::string_view text, std::string_view what, int max_depth = kMaxJsonDepth,
                        std::size_t max_values = kMaxJsonValues);

/// read_whole of a JSON input (at most kMaxJsonBytes) with its nesting checked.
std::string read_json(const std::string& path, std::string_view what);

/// read_whole for a line-oriented file held in memory whole (an NC program, a trace): also refuses a
/// line longer than `max_line` bytes.
std::string read_text(const std::string& path, std::string_view what, std::size_t max_bytes = kMaxTextBytes,
                      std::size_t max_line = kMaxLineBytes);

/// The first `n` bytes of a file (fewer when shorter), for sniffing its format.
std::string read_head(const std::string& path, std::string_view what, std::size_t n);

/// Lines of a file, streamed through a fixed buffer: LF or CRLF endings (the CR is dropped), the last
/// line may lack its LF. A line longer than `max_line` bytes is refused (FileError refused, with its
/// line number) without reading the rest of it.
class LineReader {
  public:
    explicit LineReader(InputFile file, std::size_t max_line = kMaxLineBytes);
    /// The next line (valid until the next call), or nothing at the end of the file.
    std::optional<std::string_view> next();
    /// Number of the line next() returned last (1-based).
    std::uint64_t line_number() const { return line_; }
    const InputFile& file() const { return file_; }
    /// Called with every piece the file gives, in order: each byte once (a hash of what was read, taken
    /// as it is read, so that what is hashed is what was parsed).
    void set_tap(std::function<void(std::string_view)> tap) { tap_ = std::move(tap); }

  private:
    bool fill();
    InputFile file_;
    std::function<void(std::string_view)> tap_;
    std::size_t max_line_;
    std::string buf_;
    std::size_t begin_ = 0, end_ = 0;
    bool eof_ = false;
    std::uint64_t line_ = 0;
};

}  // namespace ballbar::fileio
