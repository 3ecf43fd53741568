// SPDX-License-Identifier: MIT
// The circular test's guided procedure (circular_session.hpp, docs/procedure.md).
#include "ballbar/acquisition/circular_session.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "instrument_link.hpp"

namespace ballbar::acquisition {

namespace circ = analysis::circular;
using analysis::BarSample;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string fixed_text(double v, int digits) {
    std::ostringstream os;
    os << std::fixed << std::setprecision(digits) << v;
    return os.str();
}

/// The deepest feed-in the bar's range holds: the machine stands at radius + feed-in before each run,
/// where the bar reads that less its calibrated length, and that must stay within 95 % of the range.
double feed_in_room_mm(const circ::TestSpec& test, const InstrumentStatus& status, double range) {
    return 0.95 * range - (test.radius_mm - status.calibrated_length_mm);
}

}  // namespace

std::string circular_instrument_mismatch(const circ::TestSpec& test, const InstrumentStatus& status) {
    const double L = status.calibrated_length_mm;
    const double R = test.radius_mm;
    const double range = status.range_mm.value_or(1.0);
    if (std::abs(R - L) > 0.5 * range)
        return "the bar is calibrated at " + fixed_text(L, 3) + " mm but the test's radius is " + fixed_text(R, 3) +
               " mm: plan the test with --radius " + fixed_text(L, 3) +
               " (the bar's length) or fit the extension that makes " + fixed_text(R, 3) + " mm";
    const double room = feed_in_room_mm(test, status, range);
    if (status.range_mm && test.feed_in_mm > room + 1e-6)  // (1 nm: rounding, not range)
        return "the feed-in of " + fixed_text(test.feed_in_mm, 3) + " mm leaves the bar's ±" + fixed_text(range, 3) +
               " mm range (the machine stands at " + fixed_text(R + test.feed_in_mm - L, 3) +
               " mm from the calibrated length before it): plan the test with --feed-in " +
               fixed_text(std::floor(room * 100.0) / 100.0, 2) + " or less";
    if (status.sample_rate_hz > 0) {
        const circ::SamplingLimit lim = circ::sampling_limit(test, status.sample_rate_hz);
        if (test.feed_mm_min > lim.max_feed_mm_min * (1.0 + 1e-9)) {
            const double highest = std::floor(lim.max_feed_mm_min + 1e-6);
            return "the feed of " + fixed_text(test.feed_mm_min, 0) + " mm/min is too fast for the instrument's " +
                   fixed_text(status.sample_rate_hz, 1) + " readings/s: its samples would lie " +
                   fixed_text(test.feed_mm_min / (60.0 * status.sample_rate_hz), 3) +
                   " mm apart along the path and the diagnosis needs at most " + fixed_text(lim.max_spacing_mm, 3) +
                   " mm (" + lim.binding + "); the highest usable feed is " + fixed_text(highest, 0) +
                   " mm/min (plan with --feed " + fixed_text(highest, 0) + ")";
        }
    }
    return {};
}

CircularSession::CircularSession(circ::TestSpec test, SampleSource& source, CircularSink& sink, Operator& op,
                                 CircularOptions options)
    : test_(std::move(test)), source_(source), sink_(sink), op_(op), options_(options) {
    link_ = std::make_unique<detail::InstrumentLink>(
        source, op,
        detail::InstrumentLink::Settings{options.read_timeout, options.max_reconnect_attempts,
                                         std::chrono::seconds(10)},
        [this] { check_stop(); }, [this](const std::string& reason) { end_interrupted(reason); });
}

CircularSession::~CircularSession() = default;

void CircularSession::fire(Event e, const std::string& detail) {
    const State from = sm_.state();
    const State to = sm_.apply(e);
    sink_.on_transition({from, to, e, detail});
}

void CircularSession::end(Event e, const std::string& reason) {
    // A stop asked for while a question waited (a page's stop button) ends resumable, whatever the
    // answer the question got: what was measured is kept.
    if (options_.stop && options_.stop->load() && !summary_.interrupted) {
        summary_.interrupted = true;
        summary_.reason = "interrupted by the operator";
        if (sm_.can_apply(Event::Abort)) fire(Event::Abort, summary_.reason);
        throw Stop{};
    }
    summary_.reason = reason;
    if (sm_.can_apply(e)) fire(e, reason);
    throw Stop{};
}

void CircularSession::end_interrupted(const std::string& reason) {
    summary_.interrupted = true;
    end(Event::Abort, reason);
}

void CircularSession::check_stop() {
    if (options_.stop && options_.stop->load()) end_interrupted("interrupted by the operator");
}

void CircularSession::fit_feed_in() {
    const double range = *status_.range_mm;
    const double fitted = std::floor(feed_in_room_mm(test_, status_, range) * 20.0 + 1e-9) / 20.0;
    if (!(test_.feed_in_mm > fitted) || fitted < kMinFittedFeedIn_mm) return;  // fits, or the check refuses
    op_.message("Feed-in " + fixed_text(fitted, 2) + " mm instead of " + fixed_text(test_.feed_in_mm, 2) +
                " mm: the stand before each run stays within the bar's ±" + fixed_text(range, 3) +
                " mm range (--feed-in sets it).");
    test_.feed_in_mm = fitted;
    sink_.on_test_fitted(test_);
}

double CircularSession::run_duration_s(std::size_t run) const {
    const circ::RunSpec& r = test_.runs[run];
    const double v = test_.feed_mm_min / 60.0;
    return (2.0 * r.overshoot_deg + r.data_arc_deg) * kPi / 180.0 * test_.radius_mm / v;
}

bool CircularSession::attempt(int number) {
    CircularAttempt a;
    a.attempt = number;
    const bool retry = number > options_.first_attempt;
    std::ostringstream what;
    what << (retry ? "Run the circular test's part program again from its start"
                   : "Start the circular test's part program")
         << " (" << circ::plane_name(test_.plane) << ", radius " << test_.radius_mm << " mm, feed " << test_.feed_mm_min
         << " mm/min, " << test_.runs.size() << " run" << (test_.runs.size() == 1 ? "" : "s")
         << "): load it and press cycle start now.";
    op_.run_part_program(what.str(), retry);
    link_->stream_on();
    ++summary_.attempts;

    const double L = status_.calibrated_length_mm;
    const double v = test_.feed_mm_min / 60.0;
    const double feed_in_s = test_.feed_in_mm / v;
    std::vector<circ::TraceSample> samples;
    std::vector<std::uint64_t> seqs;
    struct Hole {
        std::size_t after;   // index of the first sample after the hole
        std::uint64_t lost;  // samples missing, by sequence number
    };
    std::vector<Hole> holes;                // lost frames
    std::vector<std::size_t> breaks;        // the device clock went back: never inside a run
    std::vector<std::size_t> out_of_range;  // samples beyond the transducer's range
    std::optional<circ::FeedIn> fi;
    std::size_t run = 0, from = 0, trace_first = 0;
    double searched_at = -1e300;
    int silent = 0;
    std::size_t since_progress = 0;
    double progress_at_s = -1e300;
    std::array<BarSample, 256> buf{};
    const auto give_up = [&](const std::string& why) {
        a.good = false;
        a.why = why;
        if (!seqs.empty()) a.first_seq = seqs.front(), a.last_seq = seqs.back();
        link_->stream_off();
        sink_.on_attempt(a);
        fire(Event::ProgramEnded, "attempt " + std::to_string(number) + ": " + why);
        op_.message("This run of the program cannot be used: " + why + ".");
        return false;
    };
    const auto run_name = [&](std::size_t k) {
        return "run " + std::to_string(k + 1) + " (" + circ::direction_name(test_.runs[k].direction) + ")";
    };
    for (;;) {
        check_stop();
        std::size_t n = 0;
        const ReadStatus st = source_.read(buf, n, options_.read_timeout);
        if (st == ReadStatus::Disconnected) {
            ++summary_.pauses;
            link_->lost();
            fire(Event::DeviceLost, "instrument lost during " + (run < test_.runs.size() ? run_name(run) : "the test"));
            op_.message(
                "Instrument lost: plug it back in. The running program cannot finish the test: stop it (reset) "
                "once the instrument is back; it is run again from its start.");
            link_->wait_for_instrument();
            link_->reference();
            fire(Event::DeviceBack, "re-referenced");
            a.good = false;
            a.why = "the instrument was lost during " + (run < test_.runs.size() ? run_name(run) : "the test");
            if (!seqs.empty()) a.first_seq = seqs.front(), a.last_seq = seqs.back();
            sink_.on_attempt(a);
            fire(Event::ProgramEnded, "attempt " + std::to_string(number) + ": " + a.why);
            return false;
        }
        if (st == ReadStatus::Timeout || n == 0) {
            const double silent_s = ++silent * static_cast<double>(options_.read_timeout.count()) * 1e-3;
            if (silent_s > 30.0) return give_up("the instrument sent nothing for 30 s");
            continue;
        }
        silent = 0;
        std::size_t kept = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const BarSample& s = buf[i];
            if (last_seq_ && s.seq <= *last_seq_) {
                ++summary_.duplicates_dropped;
                continue;
            }
            if (last_seq_ && s.seq != *last_seq_ + 1) {
                ++summary_.gaps;
                summary_.lost_samples += s.seq - *last_seq_ - 1;
                holes.push_back({samples.size(), s.seq - *last_seq_ - 1});
            }
            last_seq_ = s.seq;
            const double t = static_cast<double>(s.device_time_us) * 1e-6;
            if (!samples.empty() && !(t > samples.back().time_s)) {
                breaks.push_back(samples.size());  // the device clock went back: a new stream, not one trace
                continue;
            }
            if (s.flags & analysis::kSampleOutOfRange) out_of_range.push_back(samples.size());
            samples.push_back({t, s.length_mm(L)});
            seqs.push_back(s.seq);
            buf[kept++] = s;
        }
        if (kept == 0) continue;
        sink_.on_samples(std::span<const BarSample>(buf.data(), kept));
        summary_.samples += kept;
        const double now = samples.back().time_s;
        since_progress += kept;
        if (since_progress >= 200 || now - progress_at_s >= 0.02 || now < progress_at_s) {  // a screen: 50 Hz
            since_progress = 0;
            progress_at_s = now;
            Progress p;
            p.state = sm_.state();
            p.done = run;
            p.total = test_.runs.size();
            p.live_mm = samples.back().measured_mm;
            p.expected_mm = test_.radius_mm;
            p.range_mm = status_.range_mm.value_or(0.0);
            p.out_of_range = !out_of_range.empty() && out_of_range.back() + 1 == samples.size();
            // Where the tool is and what is left of the test at 100 % feed: the run's arc from the end of its
            // feed-in (found in the data), then the later runs with their feed-ins and dwells.
            if (run < test_.runs.size()) {
                const circ::RunSpec& r = test_.runs[run];
                const double sweep_deg = 2.0 * r.overshoot_deg + r.data_arc_deg;
                double left_s = run_duration_s(run) + feed_in_s;
                if (fi) {
                    const double done_deg =
                        std::clamp((now - fi->command_end_s) * v / test_.radius_mm * 180.0 / kPi, 0.0, sweep_deg);
                    p.angle_deg = r.start_deg + (r.direction == circ::Direction::Ccw ? 1.0 : -1.0) * done_deg;
                    left_s = std::max(0.0, fi->command_end_s + run_duration_s(run) + feed_in_s - now);
                } else {  // the countdown to the start timeout: no feed-in found by then gives the run up
                    const double allowed_s = options_.start_grace_s + options_.dwell_s * static_cast<double>(run + 1) +
                                             (run > 0 ? run_duration_s(run - 1) + 2 * feed_in_s : 0.0);
                    p.start_wait_left_s = std::max(0.0, allowed_s - (now - samples.front().time_s));
                }
                for (std::size_t k = run + 1; k < test_.runs.size(); ++k)
                    left_s += options_.dwell_s + 2.0 * feed_in_s + run_duration_s(k);
                p.time_left_s = left_s;
            }
            op_.progress(p);
        }
        if (!fi) {
            if (now - samples.front().time_s > options_.start_grace_s +
                                                   options_.dwell_s * static_cast<double>(run + 1) +
                                                   (run > 0 ? run_duration_s(run - 1) + 2 * feed_in_s : 0.0))
                return give_up("no feed-in of " + run_name(run) + " was found in the data");
            if (now - searched_at < 0.25) continue;
            searched_at = now;
            const auto f = circ::find_feed_in(test_, samples, from);
            if (!f || now <= f->command_end_s + 0.3) continue;
            // A feed-in ends on the circle: the bar stays near the radius after it. A fall that comes back
            // (a rapid approach that cuts inside the circle) is not one: search on after it.
            bool on_circle = true;
            for (std::size_t i = f->index; i < samples.size(); ++i) {
                const double t = samples[i].time_s;
                if (t < f->command_end_s + 5.0 * f->lag_s + 0.05) continue;
                if (t > f->command_end_s + 0.3) break;
                if (std::abs(samples[i].measured_mm - test_.radius_mm) > 0.25 * test_.feed_in_mm) on_circle = false;
            }
            if (on_circle)
                fi = f;
            else
                from = f->index + 1;
            continue;
        }
        const double lag_margin = 5.0 * fi->lag_s + 0.2;
        const double end_s = fi->command_end_s + run_duration_s(run) + feed_in_s + lag_margin;
        if (now < end_s) continue;
        const double start_s = fi->command_end_s - feed_in_s - lag_margin;
        if (run == 0) {  // the trace starts on the stand before the first feed-in
            const double stand_s = start_s - 0.5 * options_.dwell_s;
            trace_first = static_cast<std::size_t>(
                std::lower_bound(samples.begin(), samples.end(), stand_s,
                                 [](const circ::TraceSample& s, double t) { return s.time_s < t; }) -
                samples.begin());
        }
        const auto first = static_cast<std::size_t>(
            std::lower_bound(samples.begin() + static_cast<std::ptrdiff_t>(from), samples.end(), start_s,
                             [](const circ::TraceSample& s, double t) { return s.time_s < t; }) -
            samples.begin());
        auto last = static_cast<std::size_t>(
            std::upper_bound(samples.begin(), samples.end(), end_s,
                             [](double t, const circ::TraceSample& s) { return t < s.time_s; }) -
            samples.begin());
        last = last == 0 ? 0 : last - 1;
        // Holes inside the run: a short one loses a few samples, which the analysis does not need; a
        // long one, or too many samples lost in all, voids the run.
        const double period_s =
            last > first ? (samples[last].time_s - samples[first].time_s) / static_cast<double>(last - first) : 0.0;
        const double max_hole_s = std::max(options_.max_gap_s, 3.0 * period_s);
        std::size_t long_holes = 0;
        std::uint64_t lost_in_run = 0;
        double longest_s = 0;
        for (const Hole& h : holes) {
            if (h.after <= first || h.after > last) continue;
            const double hole_s = samples[h.after].time_s - samples[h.after - 1].time_s;
            longest_s = std::max(longest_s, hole_s);
            lost_in_run += h.lost;
            if (hole_s > max_hole_s) ++long_holes;
        }
        const auto broken =
            std::count_if(breaks.begin(), breaks.end(), [&](std::size_t g) { return g > first && g <= last; });
        const bool too_many =
            static_cast<double>(lost_in_run) > options_.max_lost_fraction * static_cast<double>(last - first + 1);
        const auto beyond = std::count_if(out_of_range.begin(), out_of_range.end(),
                                          [&](std::size_t g) { return g >= first && g <= last; });
        if (broken > 0 || long_holes > 0 || too_many || beyond > 0) {
            std::string why = run_name(run);
            if (broken > 0)
                why += " has a restart of the instrument's clock in it";
            else if (long_holes > 0)
                why += " has a hole of " + fixed_text(longest_s * 1e3, 0) + " ms in its stream (at most " +
                       fixed_text(max_hole_s * 1e3, 0) + " ms can be bridged)";
            else if (too_many)
                why += " lost " + std::to_string(lost_in_run) + " of its " + std::to_string(last - first + 1) +
                       " samples (at most " + fixed_text(options_.max_lost_fraction * 100, 1) + " % can be missing)";
            else
                why += " left the bar's range in " + std::to_string(beyond) + " samples";
            fire(Event::PointRejected, why);
            return give_up(why);
        }
        CircularRun r;
        r.direction = test_.runs[run].direction;
        r.feed_in_end_s = fi->command_end_s;
        r.lag_s = fi->lag_s;
        r.first_seq = seqs[first];
        r.last_seq = seqs[last];
        a.runs.push_back(r);
        fire(Event::PointCaptured, run_name(run) + " captured: feed-in ends at " + fixed_text(fi->command_end_s, 3) +
                                       " s, lag " + fixed_text(fi->lag_s * 1e3, 1) + " ms");
        op_.message(run_name(run) + " captured.");
        from = last;
        fi.reset();
        ++run;
        if (run < test_.runs.size()) continue;
        link_->stream_off();
        a.good = true;
        a.first_seq = seqs[trace_first];
        a.last_seq = seqs[last];
        sink_.on_attempt(a);
        summary_.good = a;
        summary_.trace.assign(samples.begin() + static_cast<std::ptrdiff_t>(trace_first),
                              samples.begin() + static_cast<std::ptrdiff_t>(last + 1));
        return true;
    }
}

CircularSummary CircularSession::run() {
    try {
        try {
            status_ = source_.connect();
        } catch (const InstrumentUnfit& e) {
            end(Event::Fail, std::string("cannot use the instrument: ") + e.what());
        } catch (const SourceError& e) {
            // Nothing was measured in this run: the session stays resumable (interrupted, never failed),
            // whatever the link did (a busy or absent instrument, another bar answering).
            end_interrupted(std::string("cannot open the instrument: ") + e.what());
        }
        fire(Event::Connected, status_.description);
        if (options_.fit_feed_in && status_.range_mm) fit_feed_in();
        if (const std::string bad = test_.validate(); !bad.empty()) {
            summary_.refused = true;
            end(Event::Fail, "the test: " + bad);
        }
        if (const std::string mismatch = circular_instrument_mismatch(test_, status_); !mismatch.empty()) {
            summary_.refused = true;
            end(Event::Fail, mismatch);
        }
        if (status_.battery_pct < 5)
            end(Event::Fail,
                "battery at " + fixed_text(status_.battery_pct, 0) + " %: charge the bar before measuring");
        sink_.on_instrument_accepted(status_);
        if (!status_.referenced) link_->reference();
        fire(Event::CheckPassed, "bar " + fixed_text(status_.calibrated_length_mm, 3) + " mm, " +
                                     fixed_text(status_.sample_rate_hz, 0) + " readings/s");
        std::ostringstream setup;
        setup << "Circular test in " << circ::plane_name(test_.plane) << ": mount the socket at the circle centre X"
              << test_.centre_mm[0] << " Y" << test_.centre_mm[1] << " Z" << test_.centre_mm[2]
              << " and the bar between it and the tool ball; the program stands at radius "
              << test_.radius_mm + test_.feed_in_mm << " mm before each feed-in. Ready?";
        if (!op_.confirm("setup", setup.str())) end(Event::Abort, "set-up not confirmed");
        fire(Event::SetUpConfirmed, "circular test, " + std::to_string(test_.runs.size()) + " runs");
        int number = options_.first_attempt;
        for (;;) {
            bool good = false;
            for (; number < options_.first_attempt + options_.max_attempts; ++number) {
                if (sm_.state() == State::Retry) fire(Event::RetryStarted, "attempt " + std::to_string(number));
                if (attempt(number)) {
                    good = true;
                    ++number;
                    break;
                }
            }
            if (!good)
                end_interrupted(std::to_string(options_.max_attempts) +
                                " runs of the program could not be used; resume the session to run it again");
            fire(Event::AllPointsCaptured, "every run captured");
            try {
                summary_.result = circ::analyze_circular(test_, summary_.trace);
            } catch (const circ::CircularError& e) {
                end(Event::Fail, std::string("the analysis of the captured runs failed: ") + e.what());
            }
            std::ostringstream review;
            review << "Circular deviation G:";
            for (const auto& r : summary_.result->runs)
                review << " " << circ::direction_name(r.direction) << " " << fixed_text(r.circularity_um, 2) << " µm";
            if (summary_.result->bidirectional_um)
                review << ", G(b) " << fixed_text(*summary_.result->bidirectional_um, 2) << " µm";
            if (summary_.result->hysteresis_um)
                review << ", H " << fixed_text(*summary_.result->hysteresis_um, 2) << " µm";
            review << ". Accept the test?";
            fire(Event::ResultsReady, review.str());
            if (op_.confirm("review", review.str())) {
                fire(Event::Accepted, "accepted");
                break;
            }
            fire(Event::Rejected, "rejected: the program is run again");
            summary_.result.reset();
            summary_.good.reset();
            summary_.trace.clear();
        }
    } catch (const Stop&) {
        link_->stream_off();
    }
    summary_.final_state = sm_.state();
    return summary_;
}

}  // namespace ballbar::acquisition
