// SPDX-License-Identifier: MIT
// The machine registry's use cases (`ballbar machines add|list|show|edit`, docs/fleet.md): a machine
// registered under the shop's asset id with its machine file, its location and the tolerances its
// results are judged against; `measure`, `circle measure` and `demo` take it with `--asset ID`.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

/// What `machines add` and `machines edit` are given (empty: not given; for edit, kept).
struct MachineChange {
    std::optional<std::string> name;
    std::optional<std::string> location;
    std::string machine_file_text;       ///< a ballbar-machine/1 document; empty: none given
    std::string machine_file_name;       ///< where it came from, for messages
    acquisition::Tolerances tolerances;  ///< each given one replaces the machine file's
};

/// The machine file `change` registers (its file, its tolerances). Error (bad input) for a missing or
/// malformed one: `add` checks it before it opens a database.
acquisition::MachineFile machine_file_of(const MachineChange& change);

/// Registers `asset_id`. Needs the machine file; the name defaults to the file's. Throws Error:
/// bad_input for an empty or taken asset id or a malformed machine file.
storage::MachineEntry add_machine(storage::Store& store, const std::string& asset_id, const MachineChange& change);

/// Changes a registered machine (a new machine file, name, location, tolerances). Throws Error:
/// not_found for an unknown asset id; bad_input for a new geometry of a machine with sessions.
storage::MachineEntry edit_machine(storage::Store& store, const std::string& asset_id, const MachineChange& change);

/// A registered machine's machine file, as `measure --asset` uses it: its geometry named as registered.
acquisition::MachineFile registered_machine_file(storage::Store& store, const std::string& asset_id);

/// {"asset_id", "uuid", "name", "type", "location", "registered", "registered_at", "updated_at",
///  "sessions", "tolerances": {"location_um", "angle_arcsec", "circularity_um"}, "machine_file"}
/// (null where missing; an unregistered machine has asset_id null and no machine file).
std::string machine_json(const storage::MachineEntry& machine);
/// The list: an array of machine_json's objects.
std::string machines_json(const std::vector<storage::MachineEntry>& machines);

}  // namespace ballbar::workflow
