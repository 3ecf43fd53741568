// SPDX-License-Identifier: MIT
// The bar on the machine must be the bar the plan was made for. The instrument tells its calibrated
// length when it identifies; the plan's poses are computed for `bar_length_mm`. A mismatch beyond the
// transducer's reach can never give a point, so it is caught as soon as the instrument has identified —
// before the operator is asked to do anything — with the two ways out named.
#pragma once

#include <string>
#include <string_view>

namespace ballbar::acquisition {

/// Empty when the calibrated length is within `tolerance_mm` of the plan's bar length; otherwise the
/// message for the operator: both lengths, and the fix (mount the plan's bar, or set the plan file's
/// "bar_length_mm" to this bar's length; `plan_file` names the file when there is one, "" for the default
/// plan, which takes --plan FILE).
std::string bar_length_mismatch(double plan_bar_length_mm, double calibrated_length_mm, double tolerance_mm,
                                std::string_view plan_file = {});

}  // namespace ballbar::acquisition
