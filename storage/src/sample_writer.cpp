// SPDX-License-Identifier: MIT
#include "ballbar/storage/sample_writer.hpp"

#include <cmath>
#include <string>

namespace ballbar::storage {
namespace {

std::string multi_row_insert(int rows) {
    std::string sql =
        "INSERT INTO samples(session_id, seq, device_time_us, displacement_nm, flags, bar_temp_mC) VALUES ";
    for (int i = 0; i < rows; ++i) sql += i ? ",(?,?,?,?,?,?)" : "(?,?,?,?,?,?)";
    return sql;
}

}  // namespace

SampleWriter::SampleWriter(Store& store, std::int64_t session_id, SampleWriterOptions options)
    : store_(store),
      session_id_(session_id),
      options_(options),
      insert_one_(store.db(), multi_row_insert(1)),
      insert_many_(store.db(), multi_row_insert(kRowsPerInsert)) {
    const SessionState state = store_.session(session_id).state;
    if (state != SessionState::running) {
        throw StorageError(StorageError::Kind::invalid, "cannot write samples into session " +
                                                            std::to_string(session_id) + ": it is " +
                                                            std::string(to_string(state)) + ", not running");
    }
    if (options_.max_batch_samples == 0) options_.max_batch_samples = 1;
    pending_.reserve(options_.max_batch_samples);
    next_seq_ = store_.next_seq(session_id);
}

SampleWriter::~SampleWriter() {
    try {
        flush();
    } catch (...) {  // NOLINT(bugprone-empty-catch): documented — callers flush() explicitly to see errors
    }
}

std::uint64_t SampleWriter::append(const analysis::BarSample& in) {
    const std::uint64_t seq = next_seq_++;
    analysis::BarSample sample = in;
    // A gap: the driver's flag, or the source's numbering jumped (a source leaves a hole where it lost
    // samples; a resume or a reconnect that restarts the numbering is no jump).
    if (last_source_seq_) {  // a sample of this writer before it
        if ((sample.flags & analysis::kSampleAfterGap) || sample.seq > *last_source_seq_ + 1) {
            SampleGap g;
            g.before_seq = seq;
            const bool clock_went_back = sample.device_time_us < last_device_time_us_;
            if (!clock_went_back)
                g.duration_s = 1e-6 * static_cast<double>(sample.device_time_us - last_device_time_us_);
            g.cause = clock_went_back ? "reconnect" : "lost frames";
            pending_gaps_.push_back(std::move(g));
            sample.flags = static_cast<std::uint16_t>(sample.flags | analysis::kSampleAfterGap);
        }
    } else {
        sample.flags = static_cast<std::uint16_t>(sample.flags & ~analysis::kSampleAfterGap);  // nothing before it
    }
    last_source_seq_ = sample.seq;
    if (segment_due_ || sample.device_time_us < last_device_time_us_) {
        SampleSegment g;
        g.first_seq = seq;
        g.device_time_us = sample.device_time_us;
        g.started_at = store_.now_iso8601();
        pending_segments_.push_back(std::move(g));
        segment_due_ = false;
    }
    last_device_time_us_ = sample.device_time_us;
    const auto now = std::chrono::steady_clock::now();
    if (pending_.empty()) first_pending_at_ = now;
    pending_.push_back(sample);
    const std::uint64_t first_t = pending_.front().device_time_us;
    // Device time bounds what a batch holds; wall time bounds how long a slow trickle (a stalling
    // link, a burst after a pause) waits uncommitted.
    const bool time_due = sample.device_time_us < first_t ||  // device clock restarted
                          sample.device_time_us - first_t >= options_.max_batch_device_time_us ||
                          now - first_pending_at_ >= options_.max_batch_wall_time;
    if (time_due || pending_.size() >= options_.max_batch_samples) flush();
    return seq;
}

void SampleWriter::bind_row(Statement& st, int p, const analysis::BarSample& s, std::uint64_t seq) {
    st.bind(p, session_id_);
    st.bind(p + 1, static_cast<std::int64_t>(seq));
    st.bind(p + 2, static_cast<std::int64_t>(s.device_time_us));
    st.bind(p + 3, std::int64_t{s.displacement_nm});
    st.bind(p + 4, std::int64_t{s.flags});
    const double mC = std::isfinite(s.bar_temp_C) ? std::round(static_cast<double>(s.bar_temp_C) * 1000.0) : -273150.0;
    st.bind(p + 5, static_cast<std::int64_t>(mC));
}

void SampleWriter::flush() {
    if (pending_.empty()) return;
    std::uint64_t seq = next_seq_ - pending_.size();
    const std::size_t n = pending_.size();
    {
        Transaction tx(store_.db());
        std::size_t i = 0;
        try {
            for (; i + kRowsPerInsert <= n; i += kRowsPerInsert) {
                for (int r = 0; r < kRowsPerInsert; ++r) {
                    bind_row(insert_many_, 1 + 6 * r, pending_[i + static_cast<std::size_t>(r)], seq++);
                }
                insert_many_.run();
            }
            for (; i < n; ++i) {
                bind_row(insert_one_, 1, pending_[i], seq++);
                insert_one_.run();
            }
            for (const auto& g : pending_segments_) store_.add_sample_segment(session_id_, g);
            for (const auto& g : pending_gaps_) store_.add_sample_gap(session_id_, g);
            tx.commit();
        } catch (const StorageError& e) {
            if (e.kind() == StorageError::Kind::disk_full) {
                throw StorageError(StorageError::Kind::disk_full,
                                   std::string(e.what()) + " — session " + std::to_string(session_id_) + ": " +
                                       std::to_string(committed_) + " samples committed before are kept, the last " +
                                       std::to_string(n) + " were not stored",
                                   e.sqlite_code());
            }
            throw;
        }
    }
    committed_ += n;
    pending_.clear();
    pending_segments_.clear();
    pending_gaps_.clear();
}

}  // namespace ballbar::storage
