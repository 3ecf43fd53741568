// SPDX-License-Identifier: MIT
// Identification as a use case (`ballbar identify`, and any front end): the readings of sessions and
// readings files, the error model fitted to them, the model stored as the next version of its name with
// the sessions, and an `identification` result on each session (docs/identification.md).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/identify.hpp"
#include "ballbar/analysis/reading.hpp"
#include "ballbar/storage/model_codec.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/session_key.hpp"

namespace ballbar::workflow {

/// The readings `identify` and `discover` take, one set per input, in the order given.
struct ReadingInputs {
    std::vector<analysis::ReadingSet> sets;
    std::vector<std::int64_t> sessions;  ///< the inputs that were sessions
    std::vector<std::string> names;      ///< "session 3" or the file's path, per set
    /// The coarsest resolution of the instruments that measured the sessions (their sample segments):
    /// no residual below it is structure. Empty when no input says it (readings files).
    std::optional<double> resolution_mm;
};

/// Opens the database a use case reads sessions from or writes to, when it first needs it.
using StoreOpener = std::function<storage::Store&()>;

/// Readings files by path; anything else is a session (an id or a uuid prefix) of the database
/// `sessions` opens, called at the first session only. Error (bad input) for a path that is neither a
/// file nor a session key, a file that is not a readings file (naming its line), a key that matches no
/// session, a session without readings.
ReadingInputs read_inputs(std::span<const std::string> inputs, const StoreOpener& sessions);

/// The model the fit made of `readings`, as it is stored (ballbar-model/1), with the span of their poses.
storage::ErrorModel fitted_model(const analysis::ReadingSet& readings, const analysis::FitSummary& fit);

struct IdentifyOptions {
    std::vector<analysis::Param> free_params;  ///< empty: the rotary axes' location errors of the type
    std::string model_name;                    ///< empty: the machine's name, else its type
    bool store_model = true;                   ///< store a converged fit's model (and a result per session)
};

struct IdentifyResult {
    analysis::FitSummary fit;
    storage::ErrorModel model;
    std::optional<storage::ModelRecord> stored;  ///< the model as stored: id, name, version
    /// The `identification` result as printed (`identify --json`) and stored with each session.
    std::string payload_json;
};

/// Fits the error model to the inputs' readings merged. Error (bad input) when the sets cannot be merged
/// (other machines); Error (failed) when the readings cannot support the fit (too few for the unknowns).
/// A fit that did not converge is returned, not stored.
IdentifyResult identify(ReadingInputs inputs, const IdentifyOptions& options, const StoreOpener& for_writing);

}  // namespace ballbar::workflow
