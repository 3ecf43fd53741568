// SPDX-License-Identifier: MIT
// How the CLI reports a storage error: a session key that matches nothing (or more than one) is the
// operator's input, exit 2; anything else is a failure, exit 1.
#pragma once

#include "ballbar/storage/sqlite.hpp"
#include "command.hpp"

namespace ballbar::app {

inline CliError cli_error(const storage::StorageError& e) {
    return CliError(e.kind() == storage::StorageError::Kind::not_found ? kExitUsage : kExitFailure, e.what());
}

}  // namespace ballbar::app
