// SPDX-License-Identifier: MIT
// Reports of sessions whose device clock does not run straight: a reconnect that restarted the
// instrument (its clock from ~0 again), a kill and a resume (a new writer, the clock far ahead). The
// report's time axis is the session clock (storage/session_clock.hpp): monotonic, capture windows where
// their samples are; the PDF renders (before, decimation refused the trace: "x decreases").
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "ballbar/report/build.hpp"
#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"
#include "poppler.hpp"
#include "synthetic.hpp"

namespace ballbar::report {
namespace {

using testing::TempDir;

/// Appends a dwell of `n` samples at `level_nm` from device time `t0_us`, and its point.
void dwell(storage::Store& store, storage::SampleWriter& w, std::int64_t id, int k, std::uint64_t t0_us,
           std::uint64_t n, std::int32_t level_nm) {
    const std::uint64_t first = w.next_seq();
    for (std::uint64_t i = 0; i < n; ++i) {
        analysis::BarSample s;
        s.device_time_us = t0_us + i * 1000;
        s.displacement_nm = level_nm + static_cast<std::int32_t>(i % 7) * 30;
        s.bar_temp_C = 20.4f;
        w.append(s);
    }
    w.flush();
    storage::PointRecord p;
    p.reading.location = k / 3;
    p.reading.point = k % 3;
    p.reading.step = (k / 3) % 2 + 1;
    p.nominal_mm = 100;
    p.reading.measured_mm = 100 + level_nm * 1e-6;
    p.reading.n = static_cast<int>(n / 2);
    p.reading.time_s = 0;  // the acquisition's own clock restarts on resume: not used for the windows
    p.first_seq = first + n / 4;
    p.last_seq = first + 3 * n / 4;
    store.add_point(id, p);
}

TEST(ReportClock, ReconnectedAndResumedSessionRendersOnOneMonotonicTimeAxis) {
    TempDir dir;
    const std::string db = (dir.path / "r.db").string();
    std::int64_t id = 0;
    {
        storage::Store store(db);
        storage::NewSession ns;
        ns.machine = testing::synthetic_machine(analysis::MachineType::TTTRR);
        ns.instrument = storage::Instrument{"BB-1E", "EMU00001", "1.0.0", 100.0, "2026-01-15", ""};
        ns.source = storage::SessionSource::emulator;
        id = store.create_session(ns);
        store.start_session(id);
        storage::SampleWriter w(store, id);
        dwell(store, w, id, 0, 7'000'000, 2000, 12'000);
        dwell(store, w, id, 1, 9'000'000, 2000, -8'000);
        // The bar was unplugged and came back restarted: its clock starts again near 0.
        dwell(store, w, id, 2, 4'000, 2000, 3'000);
    }  // the process is killed here (its Store and lock go away unfinished)
    {
        storage::Store store(db);  // recovers: interrupted
        store.resume_session(id);
        storage::SampleWriter w(store, id);
        // The same instrument, still powered: its clock went on while nobody listened.
        dwell(store, w, id, 3, 60'000'000, 2000, 20'000);
        dwell(store, w, id, 4, 62'000'000, 2000, -15'000);
        store.finish_session(id);
    }
    storage::StoreOptions ro;
    ro.read_only = true;
    storage::Store store(db, ro);
    const Report r = build_report(store, id, {400, "test"});
    ASSERT_EQ(r.trace.samples, 10'000u);
    ASSERT_FALSE(r.trace.time_s.empty());
    EXPECT_TRUE(std::is_sorted(r.trace.time_s.begin(), r.trace.time_s.end())) << "one monotonic session clock";
    EXPECT_NEAR(r.trace.time_s.front(), 0.0, 1e-9);
    // 5 dwells of 2 s on three device clocks: at least 10 s of samples, and none of the 53 s the device's
    // clock skipped while nobody listened is invented (the resume came at once, by the wall clock).
    EXPECT_GE(r.trace.time_s.back(), 9.99);
    EXPECT_LT(r.trace.time_s.back(), 40.0);
    ASSERT_EQ(r.captures.size(), 5u);
    for (std::size_t k = 0; k < r.captures.size(); ++k) {
        SCOPED_TRACE("capture " + std::to_string(k));
        EXPECT_NEAR(r.captures[k].end_s - r.captures[k].start_s, 1.0, 1e-6) << "a window of 1000 samples at 1 kHz";
        EXPECT_GE(r.captures[k].start_s, r.trace.time_s.front());
        EXPECT_LE(r.captures[k].end_s, r.trace.time_s.back());
        if (k > 0) {
            EXPECT_GT(r.captures[k].start_s, r.captures[k - 1].end_s);
        }
    }
    EXPECT_EQ(r.header.instrument_firmware, "1.0.0");
    EXPECT_EQ(r.header.instrument_calibration_date, "2026-01-15");

    const auto pdf = dir.path / "resumed.pdf";
    const int pages = render_pdf(r, pdf.string());
    EXPECT_GE(pages, 1);
    const std::string text = testing::pdf_text(pdf);
    EXPECT_NE(text.find("EMU00001"), std::string::npos);
    EXPECT_NE(text.find("2026-01-15"), std::string::npos);
    if (const char* keep = std::getenv("BALLBAR_KEEP_REPORT")) std::filesystem::copy_file(pdf, keep);
}

}  // namespace
}  // namespace ballbar::report
