// SPDX-License-Identifier: MIT
#include "ballbar/workflow/error.hpp"

#include <new>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/device/transport.hpp"
#include "ballbar/fileio/input.hpp"
#include "ballbar/fleet/pg.hpp"
#include "ballbar/report/report.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/sqlite.hpp"
#include "ballbar/storage/trace_file.hpp"

namespace ballbar::workflow {

std::string_view to_string(ErrorCategory c) {
    switch (c) {
        case ErrorCategory::bad_input:
            return "bad input";
        case ErrorCategory::not_found:
            return "not found";
        case ErrorCategory::device:
            return "device";
        case ErrorCategory::failed:
            return "failed";
        case ErrorCategory::interrupted:
            return "interrupted";
        case ErrorCategory::internal:
            return "internal";
    }
    return "internal";
}

ErrorCategory category_of(const std::exception& e) {
    if (const auto* x = dynamic_cast<const Error*>(&e)) return x->category();
    if (const auto* x = dynamic_cast<const fileio::FileError*>(&e))
        return x->kind() == fileio::FileError::Kind::refused ? ErrorCategory::bad_input : ErrorCategory::failed;
    if (const auto* x = dynamic_cast<const storage::StorageError*>(&e)) {
        switch (x->kind()) {
            case storage::StorageError::Kind::not_found:
                return ErrorCategory::not_found;
            default:  // the database or its disk failed, or a request its state refuses: what was committed stays
                return ErrorCategory::failed;
        }
    }
    if (const auto* x = dynamic_cast<const fleet::FleetError*>(&e))  // a server unreachable, refusing, newer
        return x->kind() == fleet::FleetError::Kind::bad_conninfo ? ErrorCategory::bad_input : ErrorCategory::failed;
    // A file or document the user gave that is not what it should be.
    if (dynamic_cast<const storage::FormatError*>(&e) || dynamic_cast<const storage::ReadingsFileError*>(&e) ||
        dynamic_cast<const storage::TraceFileError*>(&e) || dynamic_cast<const acquisition::PlanError*>(&e) ||
        dynamic_cast<const analysis::AnalysisError*>(&e) || dynamic_cast<const analysis::circular::CircularError*>(&e))
        return ErrorCategory::bad_input;
    if (dynamic_cast<const device::DeviceError*>(&e) || dynamic_cast<const acquisition::SourceError*>(&e))
        return ErrorCategory::device;
    // What ballbar stored and cannot read back, a report it cannot make: the operation failed.
    if (dynamic_cast<const acquisition::ResultFormatError*>(&e) || dynamic_cast<const report::ReportError*>(&e) ||
        dynamic_cast<const std::bad_alloc*>(&e))
        return ErrorCategory::failed;
    return ErrorCategory::internal;
}

}  // namespace ballbar::workflow
