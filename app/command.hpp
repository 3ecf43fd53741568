// SPDX-License-Identifier: MIT
// The `ballbar` CLI: each subcommand lives in its own cmd_*.cpp and registers itself here.
// app/ is the composition root: the only place that prints to the operator or chooses exit codes.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/session_key.hpp"

namespace ballbar::app {

/// Exit codes of the `ballbar` command (the table in docs/cli.md).
enum ExitCode : int {
    kExitOk = 0,
    kExitFailure = 1,      ///< the operation failed (device lost, database error, measurement refused)
    kExitUsage = 2,        ///< bad command line or malformed input (JSON request, readings file)
    kExitInterrupted = 3,  ///< stopped by the operator (Ctrl-C); what was measured is stored
};

/// Errors are the workflow layer's (a message and a category); the CLI reports each as
/// "ballbar: error: <message>" and exits with the code of its category.
using workflow::Error;
using workflow::ErrorCategory;

/// The exit code of an error of `category`: the one place the CLI decides it (the table in docs/cli.md).
constexpr int exit_code(ErrorCategory category) {
    switch (category) {
        case ErrorCategory::bad_input:
        case ErrorCategory::not_found:
            return kExitUsage;
        case ErrorCategory::interrupted:
            return kExitInterrupted;
        case ErrorCategory::device:
        case ErrorCategory::failed:
        case ErrorCategory::internal:
            return kExitFailure;
    }
    return kExitFailure;
}

/// A library's error as the workflow layer's, its category sorted once (workflow::category_of).
inline Error as_error(const std::exception& e) {
    return Error(workflow::category_of(e), e.what());
}

/// Options every subcommand shares.
struct Globals {
    std::string db_path;  ///< --db PATH; empty: $XDG_DATA_HOME/ballbar/ballbar.db
    bool color = false;   ///< stdout is a terminal and NO_COLOR is unset
    /// Set by the parsed subcommand's callback; main() runs it after parsing and returns its code.
    std::function<int()> action;
};

/// Adds one subcommand to `root` and, in its callback, sets `globals.action`.
using CommandSetup = void (*)(CLI::App& root, Globals& globals);

struct CommandRegistrar {
    CommandRegistrar(std::string_view name, CommandSetup setup);
};

/// Defines and registers a subcommand's set-up function:
///   BALLBAR_COMMAND(solve) { auto* sub = root.add_subcommand("solve", "..."); ... }
#define BALLBAR_COMMAND(ident)                                                                               \
    static void ballbar_setup_##ident(CLI::App& root, ::ballbar::app::Globals& globals);                     \
    static const ::ballbar::app::CommandRegistrar ballbar_registrar_##ident(#ident, &ballbar_setup_##ident); \
    static void ballbar_setup_##ident([[maybe_unused]] CLI::App& root,                                       \
                                      [[maybe_unused]] ::ballbar::app::Globals& globals)

/// A numeric option's range, checked before the value is used: the text must be a finite number within
/// [lo, hi] (`lo_open`: above lo). CLI::Range lets "nan" through (every comparison with NaN is false)
/// and "inf" through a range up to the largest double; every numeric option uses this instead, so an
/// option can never carry a value its command was not written for (issue 24: `--chord-tolerance 1000`
/// wrote arcs as lines through their centre). The error reads "--OPTION: VALUE is outside [lo, hi] UNIT".
CLI::Validator in_range(double lo, double hi, std::string unit = {}, bool lo_open = false);

/// Ends every subcommand's --help with its examples and the exit codes (app/help_footers.cpp).
void add_help_footers(CLI::App& root);

/// The database path to use: --db, else $XDG_DATA_HOME/ballbar/ballbar.db, else
/// ~/.local/share/ballbar/ballbar.db. Creates the parent directory of the default.
std::string resolve_db_path(const Globals& globals);

/// The database path for a command that only reads sessions from it: like resolve_db_path, but a
/// database that does not exist is the user's mistake (a mistyped --db), never created.
/// Throws Error (bad input) naming the path.
std::string existing_db_path(const Globals& globals);

/// A reader found its database damaged (storage::Store::damage(), not empty): says so on stderr at once,
/// and the command exits kExitFailure however it ends otherwise — what it read and showed may be
/// incomplete. Nothing is said for an empty `damage`.
void note_database_damage(const std::string& damage);

using workflow::looks_like_session_key;  ///< an id or a uuid prefix (workflow/session_key.hpp)

/// The whole of a JSON input file, at most fileio::kMaxJsonBytes (app/files.cpp). Throws
/// Error naming `what`: bad input when it cannot be read or is refused, failed for an I/O error ("machine file") when
/// it cannot be read or is refused.
std::string read_file(const std::string& path, const char* what);

}  // namespace ballbar::app
