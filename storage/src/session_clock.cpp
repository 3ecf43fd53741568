// SPDX-License-Identifier: MIT
#include "ballbar/storage/session_clock.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

namespace ballbar::storage {

double iso8601_seconds(const std::string& s) {
    std::tm tm{};
    int consumed = 0;
    if (std::sscanf(s.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour,
                    &tm.tm_min, &tm.tm_sec, &consumed) != 6)
        return std::nan("");
    tm.tm_year -= 1900;
    tm.tm_mon -= 1;
    double frac = 0;
    if (static_cast<std::size_t>(consumed) < s.size() && s[static_cast<std::size_t>(consumed)] == '.')
        frac = std::atof(("0" + s.substr(static_cast<std::size_t>(consumed))).c_str());
    return static_cast<double>(timegm(&tm)) + frac;
}

SessionClock::SessionClock(Store& store, std::int64_t id) {
    const std::uint64_t count = store.next_seq(id);
    if (count == 0) return;

    // Segment starts: recorded ones (with their wall time), and every place the device clock goes back.
    struct Start {
        std::uint64_t seq;
        double wall_s;  // since the session started; NaN: not recorded
    };
    std::vector<Start> starts;
    for (const auto& g : store.sample_segments(id)) {
        if (g.first_seq < count) starts.push_back({g.first_seq, iso8601_seconds(g.started_at)});
    }
    {
        auto st = store.db().prepare(
            "SELECT b.seq FROM samples a JOIN samples b ON b.session_id = a.session_id AND b.seq = a.seq + 1 "
            "WHERE a.session_id = ? AND b.device_time_us < a.device_time_us ORDER BY b.seq");
        st.bind(1, id);
        while (st.step()) starts.push_back({static_cast<std::uint64_t>(st.column_int(0)), std::nan("")});
    }
    starts.push_back({0, std::nan("")});
    std::stable_sort(starts.begin(), starts.end(), [](const Start& a, const Start& b) {
        return a.seq < b.seq || (a.seq == b.seq && std::isfinite(a.wall_s) && !std::isfinite(b.wall_s));
    });
    starts.erase(
        std::unique(starts.begin(), starts.end(), [](const Start& a, const Start& b) { return a.seq == b.seq; }),
        starts.end());

    auto sample_at = [&](std::uint64_t seq) {
        const auto v = store.samples(id, seq, 1);
        return v.empty() ? analysis::BarSample{} : v.front();
    };
    // Wall times count from the first segment's (the same writer clock), so the first sample is at 0
    // whatever the session's started_at says (an imported or back-dated one).
    const double wall0 = starts.front().wall_s;
    double prev_end = 0;
    for (std::size_t k = 0; k < starts.size(); ++k) {
        Seg g;
        g.first_seq = starts[k].seq;
        g.dev0_us = sample_at(g.first_seq).device_time_us;
        double base = 0;
        if (k > 0) {
            const Seg& p = segs_.back();
            const auto last = sample_at(g.first_seq - 1);
            double period_s = 1e-3;
            if (g.first_seq >= p.first_seq + 2) {
                const auto before = sample_at(g.first_seq - 2);
                if (last.device_time_us > before.device_time_us)
                    period_s = static_cast<double>(last.device_time_us - before.device_time_us) * 1e-6;
            }
            prev_end = p.base_s + static_cast<double>(last.device_time_us - p.dev0_us) * 1e-6;
            sampled_s_ += prev_end - p.base_s;
            base = prev_end + period_s;
        }
        if (k > 0 && std::isfinite(starts[k].wall_s) && std::isfinite(wall0))
            base = std::max(base, starts[k].wall_s - wall0);
        g.base_s = base;
        segs_.push_back(g);
    }
    const Seg& lastg = segs_.back();
    last_s_ = lastg.base_s + static_cast<double>(sample_at(count - 1).device_time_us - lastg.dev0_us) * 1e-6;
    sampled_s_ += last_s_ - lastg.base_s;
    first_s_ = segs_.front().base_s;
}

double SessionClock::seconds(std::uint64_t seq, std::uint64_t device_time_us) const {
    if (segs_.empty()) return 0;
    auto it = std::upper_bound(segs_.begin(), segs_.end(), seq,
                               [](std::uint64_t s, const Seg& g) { return s < g.first_seq; });
    const Seg& g = it == segs_.begin() ? segs_.front() : *std::prev(it);
    return g.base_s + (static_cast<double>(device_time_us) - static_cast<double>(g.dev0_us)) * 1e-6;
}

}  // namespace ballbar::storage
