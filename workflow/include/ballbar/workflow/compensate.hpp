// SPDX-License-Identifier: MIT
// Compensation of an NC program as a use case (`ballbar compensate`, and any front end): the model
// found by file, id or name, the program's dialect and the controller's tool-centre-point codes, the
// work-offset table, and the rewritten program passed to a sink (docs/compensation.md).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/nc_compensate.hpp"
#include "ballbar/storage/model_codec.hpp"

namespace ballbar::workflow {

/// An error model and where it came from ("model.json", "model 3", "model DL-5X v2").
struct ModelChoice {
    storage::ErrorModel model;
    std::string source;
};

/// MODEL: a `ballbar-model/1` file when something is at that path; else a model id (digits) or a model
/// name (its latest version) in the database at `db_path`, opened only then. Error (bad input) for a
/// malformed model, no such file, id or name; `db_hint` ends the message of a missing database
/// (" (check --db)").
ModelChoice find_model(const std::string& spec, const std::string& db_path, std::string_view db_hint = {});

/// How a program is read and compensated. The interpreter's and compensator's own options are used as
/// given, but for the dialect, the tool-centre-point codes, the offsets, the empirical terms and the
/// title, which come from the fields below and the model.
struct ProgramCompensation {
    std::string dialect;                       ///< "fanuc", "linuxcnc"; "": by extension (.ngc: linuxcnc)
    std::string controller;                    ///< its tool-centre-point codes; "": the dialect's
    std::vector<std::string> tcp_on, tcp_off;  ///< when not empty: these words instead of the controller's
    std::string offsets_json;                  ///< the work-offset and tool table; "": none
    std::string offsets_source;                ///< its name in messages
    analysis::NcInterpreterOptions interpreter;
    analysis::NcCompensateOptions options;
};

/// The dialect `settings` name, or the one of `program_name`'s extension. Error (bad input) for a name
/// that is not a dialect.
analysis::NcDialect program_dialect(const ProgramCompensation& settings, const std::string& program_name);

/// Compensates the program `text` (named `program_name` in messages) with `model`, writing it to
/// `sink` as it goes. Error (bad input) for an unknown controller, a malformed offsets table, a program
/// the interpreter or the compensator refuses (its line and why). A summary with `not_converged` > 0
/// is returned: whether to keep what was written is the caller's decision (`options.force`).
analysis::NcCompensateSummary compensate_program(const ModelChoice& model, std::string_view text,
                                                 const std::string& program_name, const ProgramCompensation& settings,
                                                 const analysis::NcSink& sink);

}  // namespace ballbar::workflow
