// SPDX-License-Identifier: MIT
// Assembly of a report from the database: session, audit trail, samples (reduced for the bar-reading
// figure in one streaming pass), points (capture windows, temperatures) and the stored results.
// Result kinds and their payloads are listed in docs/report.md ("What the report reads").
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "ballbar/report/report.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::report {

struct BuildOptions {
    std::size_t trace_columns = 2000;  ///< columns of the bar-reading reduction (≤ 4 points each)
    std::string software_version;      ///< the version of the software writing the report
};

/// The report of one session. Throws storage::StorageError (not_found: no such session) and
/// ReportError for a stored result it cannot read (naming the result id and kind).
Report build_report(storage::Store& store, std::int64_t session_id, const BuildOptions& options = {});

}  // namespace ballbar::report
