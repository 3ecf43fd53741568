// SPDX-License-Identifier: MIT
// Output files that cannot hurt: every file ballbar writes goes through OutputFile.
//
//  - "-" is standard output.
//  - A regular file (new or existing) is written to a temporary file created exclusively beside it
//    (O_CREAT|O_EXCL|O_NOFOLLOW, a random name "NAME.XXXXXXXX.part"), flushed to disk and renamed over
//    the target by commit(); the target keeps its permissions. Until commit() the target is untouched
//    and the destructor removes the temporary file (ours: nothing else is ever deleted). A planted
//    NAME.tmp or NAME.part, symlink or not, is never opened.
//  - The output must not be one of the command's inputs or its database: compared by device and
//    inode (through any name, link or hard link), refused before anything is written.
//  - A symbolic link at the output path is refused: ballbar does not write through links it did not
//    make. Paths under /dev and /proc (/dev/stdout, /dev/null, /proc/self/fd/N) and existing FIFOs,
//    terminals and devices are written directly, as the operator asked.
//  - A directory is refused ("is a directory").
#pragma once

#include <memory>
#include <ostream>
#include <streambuf>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/fileio/input.hpp"

namespace ballbar::fileio {

/// A file the command reads, which its outputs must never replace.
struct Protected {
    std::string path;
    std::string role;  ///< "database", "machine file", "program"…: named in the refusal
};

class OutputFile {
  public:
    /// Checks the target and opens the temporary file. `option` names the target in messages
    /// ("--out"). Throws FileError: refused (a directory, a symlink, one of `inputs`), failed (cannot
    /// create the temporary file: no such directory, permission denied).
    OutputFile(std::string path, std::string option, const std::vector<Protected>& inputs = {});
    ~OutputFile();
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;

    /// True when the output is standard output (the caller's messages go to stderr then).
    bool is_stdout() const { return mode_ == Mode::stdout_; }
    const std::string& path() const { return path_; }
    /// Appends bytes. Throws FileError(failed) (disk full…).
    void write(std::string_view bytes);
    /// The first half of commit(): the temporary file flushed to disk and closed, the target still
    /// untouched. For outputs that must all be whole before any is made visible (finish each, then
    /// commit each: the renames cannot fail for want of space). Throws FileError(failed).
    void finish();
    /// Makes the output visible: flush, fsync, rename the temporary file over the target.
    void commit();

  private:
    enum class Mode { stdout_, direct, replace };
    std::string path_, option_, temp_;
    Mode mode_ = Mode::replace;
    int fd_ = -1;
    bool committed_ = false;
};

/// A std::ostream onto an OutputFile (64 KiB buffer), for writers that stream: errors are thrown as
/// FileError from the writing statement. commit() flushes and commits.
class OutputStream : public std::ostream {
  public:
    OutputStream(std::string path, std::string option, const std::vector<Protected>& inputs = {});
    /// OutputFile::finish(), after the buffer.
    void finish();
    void commit();

  private:
    class Buffer : public std::streambuf {
      public:
        explicit Buffer(OutputFile& file);
        void drain();

      protected:
        int_type overflow(int_type c) override;
        int sync() override;

      private:
        OutputFile& file_;
        std::string buf_;
    };
    OutputFile file_;
    Buffer buffer_;
};

/// OutputFile + write + commit.
void write_file(const std::string& path, std::string_view option, std::string_view bytes,
                const std::vector<Protected>& inputs = {});

/// Throws FileError(refused) when `path` is (device and inode) one of `inputs`; nothing when `path`
/// does not exist.
void refuse_if_input(const std::string& path, std::string_view option, const std::vector<Protected>& inputs);

/// The refusals of OutputFile (one of `inputs`, a symlink, a directory) without creating anything: for
/// a command to check its outputs before it does any work.
void check_output(const std::string& path, std::string_view option, const std::vector<Protected>& inputs);

/// Refuses two outputs of one command that name the same file, before either is written (the same
/// inode when the file exists, else the same absolute, normalised path): the second would replace the
/// first. "-" (standard output) is never refused. Throws FileError (refused) naming both options.
void check_distinct_outputs(const std::string& first, std::string_view first_option, const std::string& second,
                            std::string_view second_option);

}  // namespace ballbar::fileio
