// SPDX-License-Identifier: MIT
// Every library's errors sorted into the categories the front ends answer (workflow/error.hpp).
#include <gtest/gtest.h>

#include <new>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/device/transport.hpp"
#include "ballbar/fileio/input.hpp"
#include "ballbar/fleet/pg.hpp"
#include "ballbar/report/report.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/sqlite.hpp"
#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {
namespace {

TEST(ErrorCategory, EveryLibrarysErrorsAreSortedOnce) {
    using C = ErrorCategory;
    using SK = storage::StorageError::Kind;
    EXPECT_EQ(category_of(Error(C::interrupted, "x")), C::interrupted);
    EXPECT_EQ(category_of(fileio::FileError(fileio::FileError::Kind::refused, "no such file")), C::bad_input);
    EXPECT_EQ(category_of(fileio::FileError(fileio::FileError::Kind::failed, "disk full")), C::failed);
    EXPECT_EQ(category_of(storage::StorageError(SK::not_found, "no session \"9\"")), C::not_found);
    for (SK k : {SK::sqlite, SK::disk_full, SK::corrupt, SK::newer_schema, SK::busy, SK::invalid})
        EXPECT_EQ(category_of(storage::StorageError(k, "x")), C::failed);
    EXPECT_EQ(category_of(storage::FormatError("machine.type")), C::bad_input);
    EXPECT_EQ(category_of(fleet::FleetError(fleet::FleetError::Kind::bad_conninfo, "holds a password")), C::bad_input);
    for (auto k : {fleet::FleetError::Kind::connect, fleet::FleetError::Kind::link, fleet::FleetError::Kind::server,
                   fleet::FleetError::Kind::newer_schema})
        EXPECT_EQ(category_of(fleet::FleetError(k, "x")), C::failed);
    EXPECT_EQ(category_of(acquisition::PlanError("plan")), C::bad_input);
    EXPECT_EQ(category_of(analysis::NcError(3, "unknown G code")), C::bad_input);
    EXPECT_EQ(category_of(device::DeviceError(device::DeviceErrorKind::Timeout, "no answer")), C::device);
    EXPECT_EQ(category_of(acquisition::SourceError("lost")), C::device);
    EXPECT_EQ(category_of(acquisition::ResultFormatError("result")), C::failed);
    EXPECT_EQ(category_of(report::ReportError("report")), C::failed);
    EXPECT_EQ(category_of(std::bad_alloc()), C::failed);
    EXPECT_EQ(category_of(std::logic_error("a bug")), C::internal);
    EXPECT_EQ(to_string(C::not_found), "not found");
}

}  // namespace
}  // namespace ballbar::workflow
