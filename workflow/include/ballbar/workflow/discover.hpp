// SPDX-License-Identifier: MIT
// The discovery workflow as a use case (`ballbar discover`, and any front end): the readings of sessions
// and readings files merged, the effects the model misses named and added one at a time, the extended
// model stored (one version per step) and a `discovery` result with each input session
// (docs/discovery.md).
#pragma once

#include <optional>
#include <string>

#include "ballbar/analysis/discovery.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/identify.hpp"

namespace ballbar::workflow {

struct DiscoverOptions {
    std::optional<double> noise_um;  ///< the noise of one reading; empty: from the readings
    std::string model;               ///< the model to start from (parameters or effect ids); empty: the base
    std::string save_model;          ///< the stored model's name; empty: "<machine>-discovered"
};

struct DiscoverResult {
    analysis::DiscoveryResult result;
    analysis::ReadingSet readings;               ///< the inputs merged
    std::vector<std::string> input_names;        ///< "session 3" or the file's path, per input
    std::optional<storage::ModelRecord> stored;  ///< the extended model's last version, when stored
};

/// Runs the workflow on the inputs merged. With sessions among the inputs (and `for_writing`), stores the
/// extended model and the result with each session. Error (bad input) for inputs that cannot be merged,
/// a malformed --noise-um or --model; Error (failed) when the readings cannot support the workflow.
DiscoverResult discover(ReadingInputs inputs, const DiscoverOptions& options, const StoreOpener& for_writing);

/// The result in docs/cli.md's JSON vocabulary (docs/discovery.md): what `discover --json` prints; the
/// stored result adds `details` and `model`.
std::string discovery_json(const analysis::DiscoveryResult& result);

}  // namespace ballbar::workflow
