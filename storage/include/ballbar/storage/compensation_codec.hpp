// SPDX-License-Identifier: MIT
// The stored result "compensation": a compensation's before/after on a test path (`demo --compensate`
// stores it with the session; the report and `sessions show` read it), one writer and one reader.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ballbar::storage {

inline constexpr std::string_view kCompensationResultKind = "compensation";

struct CompensationRecord {
    std::string metric;  ///< what was measured, in words ("RMS tool-ball error over a 400-block test path, …")
    struct Axis {
        std::string axis;  ///< "X", "Y", "Z"
        double before_um = 0, after_um = 0;
    };
    std::vector<Axis> axes;
};

/// {"metric", "axes": [{"axis", "before_um", "after_um"}]} (docs/cli.md's vocabulary).
std::string compensation_to_json(const CompensationRecord& record);
/// Strict (FormatError naming the key). Also reads what sessions stored before the vocabulary: each
/// axis's "before" and "after" in its "unit" ("µm" or "um"; another unit is refused).
CompensationRecord compensation_from_json(std::string_view json);

}  // namespace ballbar::storage
