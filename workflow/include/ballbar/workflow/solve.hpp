// SPDX-License-Identifier: MIT
// The numerical services as JSON (`ballbar solve ssm|orientation|compensate`, and any front end): one
// request in, one answer out. docs/analysis.md and docs/compensation.md document every shape and range.
#pragma once

#include <string>
#include <string_view>

#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {

enum class SolveService {
    ssm,          ///< the total position error of one location from n ≥ 3 bar readings
    orientation,  ///< the rotary axes' orientation errors (RRTTT, TTTRR, RTTTR)
    compensate,   ///< the Lei & Hsu X'Y'ZA'C' correction du for a pose error dv
};

/// A request the service refuses (bad input): what is wrong, and the field, a JSON path such as
/// "points_mm[2]" or "spindle.beta_rad" ("" when it is the request as a whole).
class SolveError : public Error {
  public:
    SolveError(const std::string& message, std::string field)
        : Error(ErrorCategory::bad_input, message), field_(std::move(field)) {}
    const std::string& field() const { return field_; }

  private:
    std::string field_;
};

/// Answers the JSON `request` (at most the caller's cap; nesting checked by the caller) with the JSON
/// answer on one line. SolveError when the request is malformed, incomplete, out of range or refused by
/// the solver (the field it blames).
std::string solve(SolveService service, std::string_view request);

}  // namespace ballbar::workflow
