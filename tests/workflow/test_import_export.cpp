// SPDX-License-Identifier: MIT
// Import and export as use cases, in process: the example files of the two formats' documents (written
// by hand from docs/formats/, not by ballbar) into sessions, the duplicate refused or said, the geometry
// that disagrees with a file's nominal lengths said, and a stored session out again in each format.
#include <gtest/gtest.h>

#include <string>

#include "../scratch_dir.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/import_export.hpp"

namespace ballbar::workflow {
namespace {

const std::string kReadingsDir = std::string(BALLBAR_TEST_DATA_DIR) + "/readings/";
const std::string kTracesDir = std::string(BALLBAR_TEST_DATA_DIR) + "/traces/";

TEST(ImportUseCase, AReadingsFileBecomesASessionAndTheSameContentIsRefusedThenAllowed) {
    test::ScratchDir d{"import-wf"};
    const std::string db = d.file("test.db");
    const ImportResult first = import_file(kReadingsDir + "spec_example.csv", db);
    EXPECT_FALSE(first.trace);
    EXPECT_EQ(first.readings, 1u);  // the example has one row
    EXPECT_EQ(first.sha256.size(), 64u);
    EXPECT_TRUE(first.duplicate_of.empty());
    try {
        import_file(kReadingsDir + "spec_example.csv", db);
        ADD_FAILURE() << "a duplicate was imported";
    } catch (const Error& e) {
        EXPECT_EQ(e.category(), ErrorCategory::bad_input);
        EXPECT_NE(std::string(e.what()).find("session " + std::to_string(first.session)), std::string::npos)
            << e.what();
    }
    ImportOptions again;
    again.allow_duplicate = true;
    const ImportResult second = import_file(kReadingsDir + "spec_example.csv", db, again);
    EXPECT_NE(second.session, first.session);
    ASSERT_EQ(second.duplicate_of.size(), 1u);
    EXPECT_EQ(second.duplicate_of[0], first.session);
    ASSERT_FALSE(second.warnings.empty());
    EXPECT_NE(second.warnings.back().find("imported again"), std::string::npos);
    storage::Store store(db);
    EXPECT_EQ(store.sessions().size(), 2u);
}

TEST(ImportUseCase, NominalLengthsTheGeometryDisagreesWithAreSaid) {
    test::ScratchDir d{"import-wf"};
    const ImportResult r = import_file(kReadingsDir + "rtttr_nominal_mismatch.csv", d.file("test.db"));
    EXPECT_GT(r.nominal_mismatches, 0u);
    bool said = false;
    for (const auto& w : r.warnings) said = said || w.find("nominal_mm") != std::string::npos;
    EXPECT_TRUE(said);
}

TEST(ImportUseCase, ATraceFileBecomesACircularSessionThatExportsAgain) {
    test::ScratchDir d{"import-wf"};
    const std::string db = d.file("test.db");
    const ImportResult r = import_file(kTracesDir + "spec_example.csv", db);
    EXPECT_TRUE(r.trace);
    EXPECT_GT(r.samples, 0u);
    storage::Store store(db);
    const std::string trace = export_session(store, r.session, ExportFormat::trace);
    EXPECT_EQ(trace.rfind("# ballbar-trace/1", 0), 0u) << trace.substr(0, 200);
    try {  // a circular test has no SSM points
        export_session(store, r.session, ExportFormat::readings);
        ADD_FAILURE();
    } catch (const Error& e) {
        EXPECT_EQ(e.category(), ErrorCategory::failed) << e.what();
    }
}

TEST(ImportUseCase, AnInvalidFileStoresNothing) {
    test::ScratchDir d{"import-wf"};
    const std::string bad = d.write("bad.csv", "# ballbar-readings/1\nnot a header\n");
    EXPECT_THROW(import_file(bad, d.file("test.db")), Error);
    storage::Store store(d.file("test.db"));
    EXPECT_TRUE(store.sessions().empty());
}

TEST(ExportUseCase, AnImportedSessionExportsAsTheReadingsItWasGiven) {
    test::ScratchDir d{"export-wf"};
    const std::string db = d.file("test.db");
    const ImportResult r = import_file(kReadingsDir + "spec_example.csv", db);
    storage::Store store(db);
    const std::string readings = export_session(store, r.session, ExportFormat::readings);
    EXPECT_EQ(readings.rfind("# ballbar-readings/1", 0), 0u);
    EXPECT_NE(readings.find("100.0021"), std::string::npos) << readings;
    const std::string json = export_session(store, r.session, ExportFormat::json);
    EXPECT_NE(json.find(r.uuid), std::string::npos);
}

}  // namespace
}  // namespace ballbar::workflow
