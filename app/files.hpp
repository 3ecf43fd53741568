// SPDX-License-Identifier: MIT
// The CLI's side of fileio: reading inputs with their stated caps and writing outputs safely
// (docs/cli.md, "Files"). fileio::FileError reaching main() is exit 2 when the input or output path is
// refused, 1 when the system failed.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "ballbar/device/emulator.hpp"
#include "ballbar/fileio/input.hpp"
#include "ballbar/fileio/output.hpp"
#include "command.hpp"

namespace ballbar::app {

/// An error message as the operator sees it: any run of non-blank characters longer than 120 bytes (a
/// malformed token echoed from a file) is cut to 40 with "…", and the whole to 2000 bytes.
std::string readable_message(std::string_view message);

/// `text` with its control characters made visible for a terminal: C0 (ESC, BEL, CR, tab…), DEL and the
/// C1 controls (U+0080–U+009F) as \xNN or \u00NN, so stored text shown by a command can never move
/// the cursor, retitle the window or hide what it says. `keep_newlines`: line feeds stay.
std::string printable(std::string_view text, bool keep_newlines = false);

/// A whole NC program (at most fileio::kMaxTextBytes, lines of at most fileio::kMaxLineBytes).
std::string read_program_file(const std::string& path, const char* what);

/// --faults: the emulator's "faults" object (docs/emulator.md), inline JSON or a file holding it. Error
/// (bad input) naming what is wrong.
device::FaultConfig parse_faults_option(const std::string& spec);

/// The database and its side files (-wal, -shm, -journal): never an output.
std::vector<fileio::Protected> database_files(const Globals& globals);

/// Writes `text` to `path` through fileio::OutputFile ("-": standard output), refusing the paths in
/// `inputs`.
void write_output(const std::string& path, std::string_view option, std::string_view text,
                  const std::vector<fileio::Protected>& inputs);

}  // namespace ballbar::app
