// SPDX-License-Identifier: MIT
// One monotonic clock for a session's samples. Device time restarts when the instrument does (a replug
// that powered it off, another bar) and a resumed session may come back on a clock that is behind or far
// ahead; plots and durations need one time axis. The session is cut into segments (runs on one device
// clock, sample_segments, plus any place the stored device time goes back); within a segment time is the
// device's. The first sample is at 0; each later segment starts as long after the first segment as the
// wall clock its writer recorded says (so a resume an hour later is an hour later), but never before the
// previous segment's last sample plus one sample period (a segment without a wall time: right there).
#pragma once

#include <cstdint>
#include <vector>

#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

class SessionClock {
  public:
    /// Reads the session's segments and the samples at their edges (a few point queries, one scan
    /// through the primary key for device-clock restarts no segment records).
    SessionClock(Store& store, std::int64_t session_id);

    /// Seconds since the session's first sample, for the sample with this seq and device time.
    double seconds(std::uint64_t seq, std::uint64_t device_time_us) const;
    /// Session times of the first and the last stored sample (0, 0 without samples).
    double first_s() const { return first_s_; }
    double last_s() const { return last_s_; }
    /// Device-clock runs found (stored and derived); 0 without samples.
    std::size_t segments() const { return segs_.size(); }
    /// Seconds of samples: the sum of the segments' own spans (the gaps between them left out).
    double sampled_s() const { return sampled_s_; }

  private:
    struct Seg {
        std::uint64_t first_seq = 0;
        std::uint64_t dev0_us = 0;
        double base_s = 0;
    };
    std::vector<Seg> segs_;
    double first_s_ = 0, last_s_ = 0, sampled_s_ = 0;
};

/// Seconds since the epoch of an ISO 8601 UTC time "YYYY-MM-DDTHH:MM:SS[.fff][Z]"; NaN if it is not one.
double iso8601_seconds(const std::string& text);

}  // namespace ballbar::storage
