// SPDX-License-Identifier: MIT
// Streamed import (issue 15): a readings file goes into the database reading by reading, in batches,
// and stores exactly what the whole-file parse and import_readings store — or nothing at all.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/store.hpp"
#include "test_util.hpp"

using namespace ballbar::storage;
using ballbar::storage::test::slurp;
using ballbar::storage::test::TempDir;

namespace {

const std::string kDir = std::string(BALLBAR_TEST_DATA_DIR) + "/readings/";

TEST(ImportStream, StoresWhatTheWholeFileImportStoresInAnyBatchSize) {
    TempDir d;
    Store store(d.file("s.db"));
    const std::string file = kDir + "discovery_spindle_growth.csv";  // 240-odd readings, optional columns
    const auto whole = import_readings(store, read_readings_file(file), "whole");
    const auto reference = store.points(whole);
    for (std::size_t batch : {1u, 7u, 4096u}) {
        ReadingsStream stream = ReadingsStream::open(file);
        const ImportedReadings r = import_readings_stream(store, stream, "stream", batch);
        EXPECT_EQ(r.readings, reference.size()) << batch;
        const auto points = store.points(r.session);
        ASSERT_EQ(points.size(), reference.size()) << batch;
        for (std::size_t i = 0; i < points.size(); ++i) {
            EXPECT_EQ(points[i].index, static_cast<std::int64_t>(i));
            EXPECT_EQ(points[i].reading.pose.X_mm, reference[i].reading.pose.X_mm);
            EXPECT_EQ(points[i].reading.measured_mm, reference[i].reading.measured_mm);
            EXPECT_EQ(points[i].nominal_mm, reference[i].nominal_mm);
            EXPECT_EQ(points[i].reading.bar_temp_C, reference[i].reading.bar_temp_C);
        }
        EXPECT_EQ(store.session(r.session).state, SessionState::completed);
    }
}

TEST(ImportStream, AnInvalidLastLineStoresNothing) {
    TempDir d;
    std::string text = slurp(kDir + "discovery_none.csv");
    text += "1,2,3\n";  // too few fields, after every good row
    std::ofstream(d.file("bad.csv")) << text;
    Store store(d.file("s.db"));
    ReadingsStream stream = ReadingsStream::open(d.file("bad.csv"));
    try {
        import_readings_stream(store, stream, "bad", 16);
        FAIL() << "no error";
    } catch (const ReadingsFileError& e) {
        EXPECT_GT(e.line(), 200);
    }
    EXPECT_TRUE(store.sessions().empty()) << "one transaction: nothing of the file is stored";
}

TEST(ImportStream, MismatchesAreCountedNotKept) {
    TempDir d;
    Store store(d.file("s.db"));
    ReadingsStream stream = ReadingsStream::open(kDir + "rtttr_nominal_mismatch.csv");
    const ImportedReadings r = import_readings_stream(store, stream);
    const ReadingsFile whole = read_readings_file(kDir + "rtttr_nominal_mismatch.csv");
    EXPECT_EQ(r.nominal_mismatches, whole.nominal_mismatches.size());
    ASSERT_FALSE(r.first_mismatch_lines.empty());
    EXPECT_EQ(r.first_mismatch_lines[0], whole.nominal_mismatches[0].line);
    EXPECT_GT(r.worst_mismatch_mm, kNominalTolerance_mm);
}

}  // namespace
