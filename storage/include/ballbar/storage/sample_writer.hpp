// SPDX-License-Identifier: MIT
// Streams a session's raw samples into the database in batches. A batch is committed as soon as it spans
// `max_batch_device_time_us` of device time (50 ms by default), its first sample has waited
// `max_batch_wall_time` (50 ms), or it holds `max_batch_samples`, so a crash loses at most the last,
// uncommitted batch. The two 50 ms leave the other half of the documented 100 ms to what is still on its
// way from the instrument when the process dies (a frame, a poll, a commit). Call flush() when the stream
// stalls or ends.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ballbar/analysis/sample.hpp"
#include "ballbar/storage/sqlite.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

struct SampleWriterOptions {
    std::uint64_t max_batch_device_time_us = 50'000;    ///< commit when a batch spans this much device time
    std::size_t max_batch_samples = 65'536;             ///< … or holds this many samples
    std::chrono::milliseconds max_batch_wall_time{50};  ///< … or its first sample came this long ago
};

class SampleWriter {
  public:
    /// Writes into `session_id`, which must be `running` and owned by `store`. Numbering continues after
    /// the last stored sample (0 for a new session, last + 1 after resume_session()).
    SampleWriter(Store& store, std::int64_t session_id, SampleWriterOptions options = {});
    /// Flushes what is pending; errors are swallowed here — call flush() first to see them.
    ~SampleWriter();
    SampleWriter(const SampleWriter&) = delete;
    SampleWriter& operator=(const SampleWriter&) = delete;

    /// Queues a sample and commits the batch when it is due. The stored seq is the writer's own,
    /// contiguous count; it is returned. The sample's `seq` (the source's numbering) is read for one
    /// thing: a jump in it, or the flag kSampleAfterGap, is a gap in the stream, recorded (Store::
    /// add_sample_gap, with the batch) and kept as kSampleAfterGap on the stored sample. Throws StorageError
    /// (Kind::disk_full: "disk full: …") when a commit fails; the failed batch stays pending and every
    /// batch committed before stays in the database.
    std::uint64_t append(const analysis::BarSample& sample);
    /// Commits everything pending (no-op when nothing is).
    void flush();
    /// The next sample starts a new segment (a new connection to the instrument). The writer starts one
    /// itself at its first sample and whenever the device clock goes back.
    void begin_segment() { segment_due_ = true; }

    std::uint64_t next_seq() const { return next_seq_; }
    std::size_t pending() const { return pending_.size(); }
    /// Samples committed by this writer.
    std::uint64_t committed() const { return committed_; }

  private:
    static constexpr int kRowsPerInsert = 64;
    void bind_row(Statement& st, int first_param, const analysis::BarSample& s, std::uint64_t seq);

    Store& store_;
    std::int64_t session_id_;
    SampleWriterOptions options_;
    Statement insert_one_;
    Statement insert_many_;
    std::vector<analysis::BarSample> pending_;
    std::uint64_t next_seq_ = 0;  ///< seq of the next appended sample
    std::uint64_t committed_ = 0;
    bool segment_due_ = true;
    std::chrono::steady_clock::time_point first_pending_at_{};
    std::uint64_t last_device_time_us_ = 0;
    std::vector<SampleSegment> pending_segments_;  ///< committed with the batch holding their first sample
    std::vector<SampleGap> pending_gaps_;          ///< committed with the batch holding the sample after them
    std::optional<std::uint64_t> last_source_seq_;
};

}  // namespace ballbar::storage
