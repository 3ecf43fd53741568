// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/session.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "ballbar/acquisition/bar_check.hpp"
#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/verdict.hpp"
#include "ballbar/analysis/rounding.hpp"
#include "instrument_link.hpp"

namespace ballbar::acquisition {

using namespace ballbar::analysis;

namespace {

std::string fmt(double v, int precision = 4) {
    std::ostringstream os;
    os.setf(std::ios::fixed);
    os.precision(precision);
    os << v;
    return os.str();
}

}  // namespace

Session::Session(const Plan& plan, SampleSource& source, SessionSink& sink, Operator& op, SessionOptions options)
    : plan_(plan),
      source_(source),
      sink_(sink),
      op_(op),
      options_(options),
      captured_(plan.points.size()),
      failures_(plan.points.size(), 0),
      best_failed_(plan.points.size()),
      failure_why_(plan.points.size()) {
    link_ = std::make_unique<detail::InstrumentLink>(
        source, op,
        detail::InstrumentLink::Settings{options.read_timeout, options.max_reconnect_attempts,
                                         std::chrono::seconds(10)},
        [this] { check_stop(); }, [this](const std::string& reason) { end_interrupted(reason); });
}

Session::~Session() = default;

void Session::restore(std::span<const CapturedPoint> done) {
    for (const CapturedPoint& c : done) {
        const PlannedPoint& p = c.planned;
        if (p.test < 0 || p.test >= plan_.test_count() || p.step < 1 || p.step > 2 || p.point < 0 ||
            p.point >= plan_.points_per_step)
            throw PlanError("resume: a stored point is not in the session's plan");
        captured_[plan_.index(p.test, p.step, p.point)] = c;
    }
}

std::vector<std::size_t> Session::missing() const {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < captured_.size(); ++i)
        if (!captured_[i]) out.push_back(i);
    return out;
}

void Session::fire(Event e, std::string detail) {
    const State from = sm_.state();
    const State to = sm_.apply(e);
    sink_.on_transition({from, to, e, std::move(detail)});
}

bool Session::stop_requested() const {
    return options_.stop && options_.stop->load();
}

void Session::check_stop() {
    if (stop_requested()) end(Event::Abort, "interrupted by the operator");
}

void Session::end(Event e, const std::string& reason) {
    summary_.missing = missing();
    if (stop_requested()) {
        summary_.interrupted = true;
        summary_.reason = "interrupted by the operator";
        fire(Event::Abort, summary_.reason);
        throw Stop{};
    }
    summary_.reason = reason;
    fire(e, reason);
    throw Stop{};
}

void Session::end_interrupted(const std::string& reason) {
    summary_.missing = missing();
    summary_.interrupted = true;
    summary_.reason = reason;
    fire(Event::Abort, "interrupted: " + reason);
    throw Stop{};
}

SessionSummary Session::run() {
    try {
        try {
            status_ = source_.connect();
        } catch (const InstrumentUnfit& err) {
            end(Event::Fail, std::string("cannot use the instrument: ") + err.what());
        } catch (const SourceError& err) {
            // Nothing was measured in this run: the session stays resumable (interrupted, never failed),
            // whatever the link did (a busy or absent instrument, another bar answering).
            end_interrupted(std::string("cannot open the instrument: ") + err.what());
        }
        fire(Event::Connected, status_.description);
        check_instrument();
        set_up();
        for (;;) {
            measure_missing();
            fire(Event::AllPointsCaptured, std::to_string(plan_.points.size()) + " points");
            compute_all();
            fire(Event::ResultsReady, std::to_string(summary_.tests.size()) + " tests");
            if (review()) break;
        }
        fire(Event::Accepted);
    } catch (const Stop&) {
    }
    link_->stream_off();
    summary_.final_state = sm_.state();
    return summary_;
}

void Session::check_instrument() {
    // The bar length first: nothing is asked of the operator for a bar that cannot measure this plan
    // (the same check and message `measure` gives as soon as the instrument identifies).
    if (const std::string mismatch = bar_length_mismatch(plan_.spec.bar_length_mm, status_.calibrated_length_mm,
                                                         plan_.spec.capture.tolerance_mm);
        !mismatch.empty())
        end(Event::Fail, mismatch);
    if (status_.battery_pct < 5)
        end(Event::Fail, "battery at " + fmt(status_.battery_pct, 0) + " %: charge the bar before measuring");
    check_stop();
    if (status_.has_thermometer && !status_.bar_temp_C &&
        !op_.confirm("temperature", "The bar's temperature sensor failed. Measure without bar temperature?"))
        end(Event::Fail, "bar temperature sensor failed");
    if (!status_.referenced) link_->reference();
    AttributionSettings as;
    as.point_count = plan_.points.size();
    as.sample_rate_hz = status_.sample_rate_hz;
    as.code = code_for_rate(status_.sample_rate_hz);  // the programs below write the same code timing
    as.bar_length_mm = plan_.spec.bar_length_mm;
    as.plateau_std_mm = std::max(0.008, 4 * plan_.spec.capture.max_std_mm);
    as.dwell.window = std::max<std::size_t>(
        3, static_cast<std::size_t>(std::lround(plan_.spec.capture.window_s * status_.sample_rate_hz)));
    as.dwell.still_std_mm = 4 * plan_.spec.capture.max_std_mm;
    as.dwell.still_drift_mm = 4 * plan_.spec.capture.max_drift_mm;
    as.dwell.tolerance_mm = plan_.spec.capture.tolerance_mm;
    as.dwell.calibrated_length_mm = status_.calibrated_length_mm;
    as.measuring_dwell_s = plan_.spec.dwell_s;
    as.dwell.window_s = plan_.spec.capture.window_s;
    attribution_settings_ = as;
    attributor_.emplace(as);
    std::vector<double> expected;
    for (const PlannedPoint& p : plan_.points) expected.push_back(p.nominal_mm);
    attributor_->set_expected(expected);
    std::string detail = "battery " + fmt(status_.battery_pct, 0) + " %";
    if (status_.bar_temp_C) detail += ", bar " + fmt(*status_.bar_temp_C, 2) + " °C";
    fire(Event::CheckPassed, detail);
}

void Session::set_up() {
    const MachineGeometry& g = plan_.machine.geometry;
    std::ostringstream os;
    os << to_string(g.type) << " two-step SSM, " << plan_.test_count()
       << (plan_.test_count() == 1 ? " test, " : " tests, ") << to_string(plan_.spec.layout) << " layout ("
       << plan_.points_per_step << " points a step), bar " << plan_.spec.bar_length_mm << " mm.\n";
    switch (g.type) {
        case MachineType::RRTTT:
            os << "Mount the magnetic socket on the machine table (the reference); the tool ball rides in the spindle.";
            break;
        case MachineType::TTTRR:
            os << "Mount the socket on the turning table; the spindle's ball end is the reference, the table "
                  "makes the rotations.";
            break;
        case MachineType::RTTTR:
            os << "Mount the socket on the table as the regular set-up: Δβ tests turn the spindle, Δα tests turn "
                  "the table (the socket then sits on the turning table).";
            break;
    }
    const Vec3& s = plan_.spec.tests.front().socket_mm;
    os << "\nSocket at (" << s.x() << ", " << s.y() << ", " << s.z() << ") mm in the table frame; the bar is "
       << "mounted when the program stops for it.";
    const std::size_t have = plan_.points.size() - missing().size();
    if (have > 0) os << "\nResuming with " << have << " of " << plan_.points.size() << " points captured.";
    check_stop();
    if (!op_.confirm("setup", os.str())) end(Event::Abort, "set-up not confirmed");
}

double Session::entry_time_s(const ProgramEntry& e) const {
    return e.feed_s + e.dwell_s + 60.0 * e.rapid_mm / 10000.0;
}

double Session::entry_timeout_s(const ProgramEntry& e) const {
    const double slow =
        e.feed_s / options_.slowest_feed_override + 60.0 * e.rapid_mm / options_.slowest_rapid_mm_min + e.dwell_s;
    return 1.5 * slow + 10.0;
}

void Session::measure_missing() {
    bool retry = summary_.programs > 0 || missing().size() < plan_.points.size();
    for (;;) {
        if (missing().empty()) return;
        if (sm_.state() == State::Retry) {
            if (!decide_failed_points()) continue;
            const auto miss = missing();
            if (miss.empty()) return;
            std::string list;
            for (std::size_t k = 0; k < miss.size(); ++k) {
                if (k == 6) {
                    list += ", …";
                    break;
                }
                list += (k ? ", " : "") + point_label(plan_.points[miss[k]]);
            }
            if (summary_.programs >= static_cast<std::size_t>(options_.max_programs))
                end_interrupted(std::to_string(miss.size()) + " points still missing after " +
                                std::to_string(summary_.programs) + " programs");
            check_stop();
            const std::size_t c = op_.choose({"missing",
                                              std::to_string(miss.size()) + " point" + (miss.size() > 1 ? "s" : "") +
                                                  " missing (" + list +
                                                  "). Run a retry program for exactly these points, or stop here "
                                                  "(resumable)?",
                                              {"retry", "stop"},
                                              0});
            if (c == 1) end_interrupted(std::to_string(miss.size()) + " points missing");
            fire(Event::RetryStarted, std::to_string(miss.size()) + " points: " + list);
        }
        const RunEnd r = run_program(missing(), retry);
        retry = true;
        if (r == RunEnd::Complete && missing().empty()) return;
        const auto miss = missing();
        if (!miss.empty() && sm_.state() == State::Running)
            fire(Event::ProgramEnded, std::to_string(miss.size()) + " points missing" +
                                          (r == RunEnd::Lost ? " (the instrument was lost)" : ""));
        else if (!miss.empty() && sm_.state() == State::ProgramStop)
            fire(Event::ProgramEnded, std::to_string(miss.size()) + " points missing");
    }
}

bool Session::decide_failed_points() {
    // Points that failed their checks on every attempt: the operator decides.
    const int limit = plan_.spec.capture.retries + 1;
    for (std::size_t i = 0; i < captured_.size(); ++i) {
        if (captured_[i] || failures_[i] < limit || !best_failed_[i]) continue;
        check_stop();
        const PointFailureAction a = op_.point_failed(*best_failed_[i], failure_why_[i]);
        failures_[i] = 0;
        if (a == PointFailureAction::Abort)
            end(Event::Abort, point_label(plan_.points[i]) + " failed: " + failure_why_[i]);
        if (a == PointFailureAction::Accept) {
            CapturedPoint cp = *best_failed_[i];
            cp.operator_accepted = true;
            captured_[i] = cp;
            sink_.on_point(cp);
            fire(Event::PointCaptured, point_label(cp.planned) + ": kept by the operator despite: " + failure_why_[i]);
        }
    }
    return true;
}

void Session::stream_on() {
    if (!link_->stream_on()) return;
    silent_reads_ = 0;
    stream_now_us_.reset();
}

void Session::program_stops(const ProgramEntry& entry) {
    for (const ProgramStop& stop : entry.stops_before) {
        const std::string& what = stop.what;
        if (!link_->streaming()) stream_on();  // each stop follows a cycle start
        link_->stream_off();
        if (attributor_) {
            const AttributionEvent ev = attributor_->reset("program stop");
            if (ev.kind == AttributionEvent::Kind::Void) on_void(ev);
        }
        fire(Event::ProgramStopReached, what);
        check_stop();
        op_.program_stop(stop);
        check_stop();
        fire(Event::CycleStart, what);
    }
}

Session::RunEnd Session::run_program(const std::vector<std::size_t>& points, bool retry) {
    NcOptions nco;
    if (attribution_settings_) nco.code = attribution_settings_->code;  // tags the attribution can see at this rate
    MeasuringProgram prog;
    try {
        prog = make_measuring_program(plan_, points, nco);
    } catch (const PlanError& e) {
        end(Event::Fail, e.what());
    }
    if (retry) {
        // The bar may still be on its socket wherever the machine stands: it comes off before the rapid.
        prog.entries.front().stops_before.insert(
            prog.entries.front().stops_before.begin(),
            ProgramStop{"remove the bar from its socket and check the socket "
                        "stands at [" +
                            fmt(plan_.points[points.front()].socket_mm.x(), 3) + ", " +
                            fmt(plan_.points[points.front()].socket_mm.y(), 3) + ", " +
                            fmt(plan_.points[points.front()].socket_mm.z(), 3) +
                            "] mm; the machine then moves to the first missing point "
                            "in rapid; then cycle start",
                        plan_.points[points.front()].socket_mm});
        NcBlock c;
        c.comment = "PROGRAM STOP: " + prog.entries.front().stops_before.front().what;
        NcBlock m;
        m.raw = "M0";
        prog.nc.blocks.insert(prog.nc.blocks.begin() + 1, {c, m});
    }
    ++summary_.programs;
    link_->stream_off();
    check_stop();
    if (sm_.state() == State::SetUp)
        fire(Event::SetUpConfirmed, std::string(to_string(plan_.machine.geometry.type)) + ", " +
                                        std::to_string(plan_.test_count()) + " tests, program of " +
                                        std::to_string(points.size()) + " points");
    op_.run_program(prog.nc, points, retry);
    stream_on();  // the operator started the program (cycle start)
    program_ = &prog;
    cursor_ = 0;
    struct Clear {
        const MeasuringProgram*& p;
        ~Clear() { p = nullptr; }
    } clear{program_};
    std::vector<std::size_t> entry_of(plan_.points.size(), prog.entries.size());
    for (std::size_t k = 0; k < prog.entries.size(); ++k) entry_of[prog.entries[k].point] = k;

    double deadline_s = 0;     // stream time by which the entry at cursor_ is due ...
    double armed_at_s = 0;     // ... counted from here (the machine's first motion, or the last point) ...
    bool armed = false;        // ... once the machine moves after a start or cycle start
    bool still_seen = false;   // a first sample after the (cycle) start came: the bar length ...
    double still_mm = 0;       // ... it stood at ...
    double still_since_s = 0;  // ... since this time
    auto arm = [&](double from_s, double extra_s) {
        deadline_s = from_s + extra_s + (cursor_ < prog.entries.size() ? entry_timeout_s(prog.entries[cursor_]) : 0);
        armed_at_s = from_s;
        armed = true;
    };
    bool need_stops = true;
    std::size_t since_progress = 0;
    double progress_at_s = -1e300;
    const CaptureSettings& cs = plan_.spec.capture;
    std::size_t manual_at = prog.entries.size();
    for (;;) {
        if (cursor_ >= prog.entries.size()) return RunEnd::Complete;
        if (need_stops && !prog.entries[cursor_].stops_before.empty()) {
            program_stops(prog.entries[cursor_]);
            armed = false;
            still_seen = false;
        }
        need_stops = false;
        if (cs.manual && manual_at != cursor_) {
            manual_at = cursor_;
            // Manual capture: the operator says when the machine stands at the point.
            link_->stream_off();
            const PlannedPoint& pp = plan_.points[prog.entries[cursor_].point];
            check_stop();
            op_.wait_at_point(pp);
            manual_.emplace(attribution_settings_->dwell);
            manual_->set_expected(pp.nominal_mm);
            manual_->capture_now();
        }
        stream_on();
        if (!fetch()) return RunEnd::Lost;
        if (buffer_n_ == 0) {
            if (silent_reads_ > options_.max_silent_reads) {
                op_.message("The instrument sends nothing: the program's missing points go to a retry program.");
                return RunEnd::Ended;
            }
            continue;
        }
        for (std::size_t i = 0; i < buffer_n_; ++i) {
            const BarSample& s = buffer_[i];
            const double t_s = 1e-6 * static_cast<double>(s.device_time_us);
            if (!armed) {  // after a start or a cycle start: from the first motion on
                const double len_mm = 1e-6 * static_cast<double>(s.displacement_nm);
                if (cs.manual) {
                    arm(t_s, options_.start_grace_s);
                } else if (!still_seen) {
                    still_seen = true;
                    still_mm = len_mm;
                    still_since_s = t_s;
                } else if (std::abs(len_mm - still_mm) > options_.motion_start_mm ||
                           t_s - still_since_s > options_.max_standstill_s) {
                    arm(t_s, options_.start_grace_s);
                }
            }
            AttributionEvent ev;
            if (cs.manual) {
                // Manual capture: the operator's word is the evidence; a window is averaged now.
                if (manual_->push(s) == DwellDetector::Result::Captured) {
                    ev.kind = AttributionEvent::Kind::Captured;
                    ev.point = prog.entries[cursor_].point;
                    ev.stats = manual_->stats();
                    ev.evidence = "the operator confirmed the machine at the point";
                }
            } else {
                ev = attributor_->push(s);
            }
            if (ev.kind == AttributionEvent::Kind::Captured) {
                const std::size_t k = ev.point ? entry_of[*ev.point] : prog.entries.size();
                if (k >= prog.entries.size()) {
                    ++summary_.void_dwells;
                    fire(Event::PointRejected, point_label(plan_.points[*ev.point]) + ": " + ev.evidence +
                                                   "; the point is not in the running program: not stored");
                } else if (k < cursor_) {
                    ++summary_.void_dwells;
                    fire(Event::PointRejected, point_label(plan_.points[*ev.point]) + ": " + ev.evidence +
                                                   "; the program is already past that point: not stored");
                } else {
                    on_captured(ev, k);
                    cursor_ = k + 1;
                    need_stops = true;
                    arm(t_s, 0);
                }
            } else if (ev.kind == AttributionEvent::Kind::Void) {
                on_void(ev);
                if (ev.point && entry_of[*ev.point] < prog.entries.size() && entry_of[*ev.point] >= cursor_) {
                    cursor_ = entry_of[*ev.point] + 1;
                    need_stops = true;
                    arm(t_s, 0);
                }
            }
            if (++since_progress >= options_.progress_every || t_s - progress_at_s >= options_.progress_interval_s ||
                t_s < progress_at_s) {  // the device clock restarted (a reconnect)
                since_progress = 0;
                progress_at_s = t_s;
                if (armed)
                    report_progress(std::nullopt, deadline_s - t_s, t_s - armed_at_s);
                else if (still_seen && !cs.manual)
                    report_progress(options_.max_standstill_s - (t_s - still_since_s));
                else
                    report_progress();
            }
            if (cursor_ >= prog.entries.size()) return RunEnd::Complete;
            if (need_stops && !prog.entries[cursor_].stops_before.empty()) break;
            // Nothing attributable came in time: the entry at the cursor is lost; the next is due later.
            while (armed && t_s > deadline_s && !attributor_->measuring()) {
                const std::size_t lost = prog.entries[cursor_].point;
                fire(Event::PointRejected, point_label(plan_.points[lost]) + ": no attributable dwell by " +
                                               fmt(deadline_s, 1) + " s (the program's timing): missing");
                ++cursor_;
                if (cursor_ >= prog.entries.size()) return RunEnd::Complete;
                deadline_s += entry_timeout_s(prog.entries[cursor_]);
                if (!prog.entries[cursor_].stops_before.empty()) {
                    need_stops = true;
                    break;
                }
            }
            if (need_stops && !prog.entries[cursor_].stops_before.empty()) break;
        }
    }
}

void Session::on_void(const AttributionEvent& ev) {
    ++summary_.void_dwells;
    std::string who = ev.point ? point_label(plan_.points[*ev.point]) + ": " : std::string("a dwell: ");
    fire(Event::PointRejected, who + ev.evidence + "; not stored");
}

void Session::on_captured(const AttributionEvent& ev, std::size_t /*entry*/) {
    const CaptureSettings& cs = plan_.spec.capture;
    const std::size_t index = *ev.point;
    const PlannedPoint& planned = plan_.points[index];
    const WindowStats& w = ev.stats;
    CapturedPoint cp;
    cp.planned = planned;
    cp.measured_mm = w.mean_mm;
    cp.std_mm = w.std_mm;
    cp.drift_mm = w.drift_mm;
    cp.n = w.n;
    cp.first_seq = w.first_seq;
    cp.last_seq = w.last_seq;
    cp.bar_temp_C = w.bar_temp_C;
    cp.time_s = analysis::decimal_round(
        1e-6 * static_cast<double>((w.first_time_us + w.last_time_us) / 2 - first_time_us_.value_or(0)), 6);
    cp.evidence = ev.evidence;
    std::string why;
    if (w.std_mm > cs.max_std_mm)
        why = "std " + fmt(w.std_mm * 1e3, 2) + " µm above " + fmt(cs.max_std_mm * 1e3, 2) + " µm";
    else if (std::abs(w.drift_mm) > cs.max_drift_mm)
        why = "drift " + fmt(w.drift_mm * 1e3, 2) + " µm above " + fmt(cs.max_drift_mm * 1e3, 2) + " µm";
    else if (std::abs(w.mean_mm - planned.nominal_mm) > cs.tolerance_mm)
        why = "reads " + fmt(w.mean_mm) + " mm, the plan predicts " + fmt(planned.nominal_mm) + " mm";
    else if (w.flagged)
        why = "samples flagged by the instrument (not referenced, or after a gap)";
    if (captured_[index]) {
        fire(Event::PointRejected, point_label(planned) + ": captured already; this dwell is not stored");
        return;
    }
    if (!why.empty()) {
        ++summary_.recaptures;
        ++failures_[index];
        if (!best_failed_[index] || w.std_mm < best_failed_[index]->std_mm) best_failed_[index] = cp;
        failure_why_[index] = why;
        fire(Event::PointRejected, point_label(planned) + ": " + why + " (" + ev.evidence + "); measured again later");
        return;
    }
    captured_[index] = cp;
    sink_.on_point(cp);
    fire(Event::PointCaptured, point_label(planned) + ": " + fmt(cp.measured_mm, 5) + " mm, std " +
                                   fmt(cp.std_mm * 1e3, 3) + " µm, n " + std::to_string(cp.n) + "; " + ev.evidence);
    op_.point_captured(cp);
}

bool Session::fetch() {
    check_stop();
    buffer_n_ = 0;
    std::size_t n = 0;
    const ReadStatus st = source_.read(buffer_, n, options_.read_timeout);
    if (st == ReadStatus::Disconnected) {
        ++summary_.pauses;
        link_->lost();
        const AttributionEvent ev = attributor_->reset("the instrument was lost");
        if (ev.kind == AttributionEvent::Kind::Void) on_void(ev);
        fire(Event::DeviceLost, "instrument lost; " + std::to_string(missing().size()) + " points missing");
        op_.message(
            "Instrument lost: plug it back in. The running program cannot finish the measurement: "
            "stop it (reset) once the instrument is back; the points it misses go to a retry program.");
        link_->wait_for_instrument();
        op_.message("Instrument back. Stop the NC program now (reset): the bar is re-referenced first.");
        link_->reference();
        fire(Event::DeviceBack, "re-referenced");
        return false;
    }
    if (st == ReadStatus::Timeout || n == 0) {
        ++silent_reads_;
        return true;
    }
    silent_reads_ = 0;
    // Drop repeats, count gaps; keep the new samples at the front of the buffer.
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const BarSample& s = buffer_[i];
        if (last_seq_ && s.seq <= *last_seq_) {
            ++summary_.duplicates_dropped;
            continue;
        }
        if (last_seq_ && s.seq != *last_seq_ + 1) ++summary_.gaps;
        if (!first_time_us_) first_time_us_ = s.device_time_us;
        last_seq_ = s.seq;
        stream_now_us_ = s.device_time_us;
        buffer_[kept++] = s;
    }
    buffer_n_ = kept;
    summary_.samples += kept;
    if (kept > 0) sink_.on_samples(std::span<const BarSample>(buffer_.data(), kept));
    return true;
}

void Session::compute_all() {
    summary_.tests.clear();
    std::vector<CapturedPoint> all;
    for (const auto& c : captured_) all.push_back(*c);
    const std::span<const CapturedPoint> span(all);
    const std::size_t k = static_cast<std::size_t>(plan_.points_per_step);
    for (int test = 0; test < plan_.test_count(); ++test) {
        try {
            const LocationResult l1 = compute_location(plan_, test, 1, span.subspan(plan_.index(test, 1, 0), k));
            sink_.on_location(l1);
            const LocationResult l2 = compute_location(plan_, test, 2, span.subspan(plan_.index(test, 2, 0), k));
            sink_.on_location(l2);
            TestResult r = compute_test(plan_, test, l1.dV_mm, l2.dV_mm, l1.ssm.cov_mm2, l2.ssm.cov_mm2);
            r.dV1_std_mm = l1.ssm.std_mm;
            r.dV2_std_mm = l2.ssm.std_mm;
            sink_.on_test(r);
            summary_.tests.push_back(std::move(r));
        } catch (const AnalysisError& err) {
            end(Event::Fail, "test " + std::to_string(test + 1) + ": " + err.what());
        }
    }
}

bool Session::review() {
    const MachineType type = plan_.machine.geometry.type;
    std::ostringstream os;
    os << "Results:\n";
    for (const TestResult& t : summary_.tests) {
        os << "  test " << t.test + 1 << ": ΔV1 (" << fmt(t.dV1_mm.x() * 1e3, 2) << ", " << fmt(t.dV1_mm.y() * 1e3, 2)
           << ", " << fmt(t.dV1_mm.z() * 1e3, 2) << ") µm, ΔV2 (" << fmt(t.dV2_mm.x() * 1e3, 2) << ", "
           << fmt(t.dV2_mm.y() * 1e3, 2) << ", " << fmt(t.dV2_mm.z() * 1e3, 2) << ") µm";
        if (t.orientation.exact) {
            const auto& e = *t.orientation.exact;
            auto ang = [&](const char* name, double v, std::optional<double> sd) {
                os << "; " << name << " " << fmt(rad_to_arcsec(v), 2) << "″";
                if (sd) os << " ± " << fmt(rad_to_arcsec(*sd), 2) << "″";
            };
            const analysis::MeasuredAngles angles = measured_angles(type, t.kind);
            if (angles.alpha)
                ang("Δα", e.d_alpha_rad, t.std_rad ? std::optional(t.std_rad->d_alpha_rad) : std::nullopt);
            if (angles.beta) ang("Δβ", e.d_beta_rad, t.std_rad ? std::optional(t.std_rad->d_beta_rad) : std::nullopt);
            if (angles.gamma)
                ang("Δγ", e.d_gamma_rad, t.std_rad ? std::optional(t.std_rad->d_gamma_rad) : std::nullopt);
        } else {
            os << "; orientation: " << t.orientation.singular;
        }
        os << "\n";
    }
    // The machine file's tolerances (none: no verdict): judged here, before the operator accepts.
    if (const SsmVerdict v = judge_ssm(type, plan_.machine.tolerances, plan_.spec.tests, summary_.tests); v.judged())
        os << v.summary() << "\n";
    os << "Accept these results, measure every point again, or abort?";
    check_stop();
    const std::size_t c = op_.choose({"review", os.str(), {"accept", "measure-again", "abort"}, 0});
    if (c == 0) return true;
    if (c == 2) end(Event::Abort, "results not accepted by the operator");
    for (auto& p : captured_) p.reset();
    std::fill(failures_.begin(), failures_.end(), 0);
    for (auto& b : best_failed_) b.reset();
    fire(Event::Rejected, "every point is measured again");
    return false;
}

void Session::report_progress(std::optional<double> start_wait_left_s, std::optional<double> point_due_s,
                              double entry_elapsed_s) {
    Progress p;
    p.state = sm_.state();
    p.total = plan_.points.size();
    p.done = p.total - missing().size();
    if (program_ && cursor_ < program_->entries.size()) {
        const PlannedPoint& pl = plan_.points[program_->entries[cursor_].point];
        p.test = pl.test;
        p.step = pl.step;
        p.point = pl.point;
        p.expected_mm = pl.nominal_mm;
        for (std::size_t k = cursor_; k < program_->entries.size(); ++k)
            p.time_left_s += entry_time_s(program_->entries[k]);
        // The entry under way counts down as the machine runs it (not below the rest of the program).
        p.time_left_s -= std::min(std::max(entry_elapsed_s, 0.0), entry_time_s(program_->entries[cursor_]));
    }
    if (start_wait_left_s) p.start_wait_left_s = std::max(0.0, *start_wait_left_s);
    if (point_due_s) p.point_due_s = std::max(0.0, *point_due_s);
    p.live_mm = attributor_->last_length_mm();
    p.range_mm = status_.range_mm.value_or(0.0);
    p.out_of_range = std::abs(p.live_mm - plan_.spec.bar_length_mm) >= status_.range_mm.value_or(1.0);
    p.fill = attributor_->fill();
    op_.progress(p);
}

}  // namespace ballbar::acquisition
