// SPDX-License-Identifier: MIT
// The command line that continues an interrupted session, as the operator copies it: the right command
// for the procedure, and the database and program paths that were given (quoted for a POSIX shell).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace ballbar::app {

/// `text` as one word of a POSIX shell: as it is when it needs no quoting, else in single quotes.
std::string shell_word(std::string_view text);

/// `ballbar [--db DB] measure|circle measure --resume ID --device DEVICE [--program PROGRAM]`: `procedure`
/// "circular" continues with `circle measure`, any other with `measure`; an empty `db` (the default
/// database) or `program` is left out; an empty `device` is written URI, for the operator to fill in.
std::string resume_command(std::string_view procedure, std::int64_t id, const std::string& db,
                           const std::string& device, const std::string& program);

/// Why a session is in its state, said once: the stored reason without the state's name in front
/// ("interrupted: interrupted by the operator" of an interrupted session reads "by the operator").
std::string state_reason(std::string_view state, std::string_view reason);

}  // namespace ballbar::app
