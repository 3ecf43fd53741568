// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/session.hpp"

#include <cmath>
#include <sstream>

#include "ballbar/acquisition/compute.hpp"

namespace ballbar::acquisition {

using namespace ballbar::analysis;

namespace {

std::string where(const PlannedPoint& p) {
    return "test " + std::to_string(p.test + 1) + " step " + std::to_string(p.step) + " point " +
           std::to_string(p.point + 1);
}

std::string fmt(double v, int precision = 4) {
    std::ostringstream os;
    os.setf(std::ios::fixed);
    os.precision(precision);
    os << v;
    return os.str();
}

}  // namespace

Session::Session(const Plan& plan, SampleSource& source, SessionSink& sink, Operator& op, SessionOptions options)
    : plan_(plan), source_(source), sink_(sink), op_(op), options_(options) {
    captured_.reserve(plan.points.size());
}

void Session::restore(std::span<const CapturedPoint> done) {
    if (done.size() > plan_.points.size()) throw PlanError("resume: the session has more points than its plan");
    captured_.assign(done.begin(), done.end());
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
    // Before every read of the instrument and every question to the operator: a Ctrl-C that came
    // while neither was waiting is seen here (one that comes during either cuts it short, EINTR).
    if (stop_requested()) end(Event::Abort, "interrupted by the operator");
}

void Session::end(Event e, const std::string& reason) {
    // Whatever ends the session once a stop was requested (a prompt or a read cut short by the
    // signal) is the operator's interruption, not a failure of the instrument.
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

SessionSummary Session::run() {
    try {
        try {
            status_ = source_.connect();
        } catch (const SourceError& err) {
            end(Event::Fail, std::string("cannot open the instrument: ") + err.what());
        }
        fire(Event::Connected, status_.description);
        check_instrument();
        set_up();
        try {
            source_.start();
        } catch (const SourceError& err) {
            end(Event::Fail, std::string("the instrument does not stream: ") + err.what());
        }
        check_stop();
        op_.run_program(captured_.size());
        for (int t = 0; t < plan_.test_count(); ++t) measure_test(t);
        check_stop();
        const bool ok = op_.confirm("accept", "Accept the results?");
        if (!ok) end(Event::Abort, "results not accepted by the operator");
        fire(Event::Accepted);
    } catch (const Stop&) {
    }
    summary_.final_state = sm_.state();
    return summary_;
}

void Session::check_instrument() {
    if (status_.battery_pct < 5)
        end(Event::Fail, "battery at " + fmt(status_.battery_pct, 0) + " %: charge the bar before measuring");
    check_stop();
    if (!status_.bar_temp_C &&
        !op_.confirm("temperature", "The bar's temperature sensor failed. Measure without bar temperature?"))
        end(Event::Fail, "bar temperature sensor failed");
    if (!status_.referenced) {
        check_stop();
        if (!op_.confirm("reference", "Put the bar in its calibrator to set the reference (zero). Ready?"))
            end(Event::Abort, "reference not set");
        try {
            source_.set_reference();
        } catch (const SourceError& err) {
            end(Event::Fail, std::string("setting the reference failed: ") + err.what());
        }
    }
    if (std::abs(status_.calibrated_length_mm - plan_.spec.bar_length_mm) > plan_.spec.capture.tolerance_mm)
        end(Event::Fail, "the plan's bar length " + fmt(plan_.spec.bar_length_mm, 3) +
                             " mm differs from the instrument's calibrated length " +
                             fmt(status_.calibrated_length_mm, 3) + " mm");
    DwellSettings ds;
    ds.window = std::max<std::size_t>(
        3, static_cast<std::size_t>(std::lround(plan_.spec.capture.window_s * status_.sample_rate_hz)));
    ds.still_std_mm = 4 * plan_.spec.capture.max_std_mm;
    ds.still_drift_mm = 4 * plan_.spec.capture.max_drift_mm;
    ds.tolerance_mm = plan_.spec.capture.tolerance_mm;
    ds.calibrated_length_mm = status_.calibrated_length_mm;
    detector_.emplace(ds);
    std::string detail = "battery " + fmt(status_.battery_pct, 0) + " %";
    if (status_.bar_temp_C) detail += ", bar " + fmt(*status_.bar_temp_C, 2) + " °C";
    fire(Event::CheckPassed, detail);
}

void Session::set_up() {
    const MachineGeometry& g = plan_.machine.geometry;
    std::ostringstream os;
    os << to_string(g.type) << " two-step SSM, " << plan_.test_count() << " tests, " << to_string(plan_.spec.layout)
       << " layout (" << plan_.points_per_step << " points a step), bar " << plan_.spec.bar_length_mm << " mm.\n";
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
    os << "\nSocket at (" << s.x() << ", " << s.y() << ", " << s.z() << ") mm in the table frame.";
    if (!captured_.empty()) os << "\nResuming after " << captured_.size() << " captured points.";
    check_stop();
    if (!op_.confirm("setup", os.str())) end(Event::Abort, "set-up not confirmed");
    fire(Event::SetUpConfirmed, std::string(to_string(g.type)) + ", " + std::to_string(plan_.test_count()) + " tests");
}

void Session::measure_test(int test) {
    capture_step(test, 1);
    fire(Event::StepComplete, "test " + std::to_string(test + 1) + " step 1");
    const TestSpec& t = plan_.spec.tests[static_cast<std::size_t>(test)];
    std::string rot = "Rotate to " + std::string(1, rotary_axes(plan_.machine.geometry.type).first) + " = " +
                      fmt(rad_to_deg(t.first_rad), 3) + "°, " +
                      std::string(1, rotary_axes(plan_.machine.geometry.type).second) + " = " +
                      fmt(rad_to_deg(t.second_rad), 3) + "°";
    if (t.kind == TestKind::TableAlpha) rot += " (the reference is the turning table's socket)";
    op_.message(rot);
    capture_step(test, 2);
    fire(Event::StepComplete, "test " + std::to_string(test + 1) + " step 2");
    compute(test);
    if (test + 1 < plan_.test_count())
        fire(Event::NextTest, "test " + std::to_string(test + 2));
    else
        fire(Event::AllTestsDone);
}

void Session::capture_step(int test, int step) {
    const std::size_t first = plan_.index(test, step, 0);
    const std::size_t last = first + static_cast<std::size_t>(plan_.points_per_step);
    if (captured_.size() >= last) {
        fire(Event::InPosition, "restored from the interrupted session");
        return;
    }
    bool positioning = true;
    if (captured_.size() > first) {
        fire(Event::InPosition, "resuming at " + where(plan_.points[captured_.size()]));
        positioning = false;
    }
    while (captured_.size() < last) {
        capture_point(plan_.points[captured_.size()], positioning);
        positioning = false;
    }
}

void Session::capture_point(const PlannedPoint& planned, bool positioning) {
    const CaptureSettings& cs = plan_.spec.capture;
    int attempts = 0;
    for (;;) {
        const WindowStats w = *wait_for_window(planned, positioning);
        positioning = false;
        CapturedPoint cp;
        cp.planned = planned;
        cp.measured_mm = w.mean_mm;
        cp.std_mm = w.std_mm;
        cp.drift_mm = w.drift_mm;
        cp.n = w.n;
        cp.first_seq = w.first_seq;
        cp.last_seq = w.last_seq;
        cp.bar_temp_C = w.bar_temp_C;
        cp.time_s = 1e-6 * static_cast<double>((w.first_time_us + w.last_time_us) / 2 - first_time_us_.value_or(0));
        std::string why;
        if (w.std_mm > cs.max_std_mm)
            why = "std " + fmt(w.std_mm * 1e3, 2) + " µm above " + fmt(cs.max_std_mm * 1e3, 2) + " µm";
        else if (std::abs(w.drift_mm) > cs.max_drift_mm)
            why = "drift " + fmt(w.drift_mm * 1e3, 2) + " µm above " + fmt(cs.max_drift_mm * 1e3, 2) + " µm";
        else if (std::abs(w.mean_mm - planned.nominal_mm) > cs.tolerance_mm)
            why = "reads " + fmt(w.mean_mm) + " mm, expected " + fmt(planned.nominal_mm) + " mm";
        else if (w.flagged)
            why = "samples flagged by the instrument (reference or temperature)";
        if (why.empty() || attempts >= cs.retries) {
            if (!why.empty()) {
                fire(Event::PointRejected, where(planned) + ": " + why);
                check_stop();
                switch (op_.point_failed(cp, why)) {
                    case PointFailureAction::Retry:
                        attempts = 0;
                        detector_->reset(true);
                        continue;
                    case PointFailureAction::Abort:
                        end(Event::Abort, where(planned) + " failed: " + why);
                        break;
                    case PointFailureAction::Accept:
                        cp.operator_accepted = true;
                        break;
                }
            }
            captured_.push_back(cp);
            sink_.on_point(cp);
            fire(Event::PointCaptured, where(planned) + ": " + fmt(cp.measured_mm, 5) + " mm, std " +
                                           fmt(cp.std_mm * 1e3, 3) + " µm, n " + std::to_string(cp.n));
            return;
        }
        ++attempts;
        ++summary_.recaptures;
        fire(Event::PointRejected, where(planned) + ": " + why + "; capturing again");
        detector_->reset(true);
    }
}

std::optional<WindowStats> Session::wait_for_window(const PlannedPoint& planned, bool positioning) {
    DwellDetector& det = *detector_;
    det.set_expected(planned.nominal_mm);
    if (plan_.spec.capture.manual) {
        check_stop();
        op_.wait_at_point(planned);
        if (positioning) fire(Event::InPosition, where(planned));
        det.capture_now();
    }
    std::size_t since_progress = 0;
    for (;;) {
        if (buffer_pos_ >= buffer_n_) {
            fetch();
            // A gap or a pause voids the window being averaged: the point starts again.
            if (broken_) {
                broken_ = false;
                det.reset(true);
            }
            continue;
        }
        const BarSample& s = buffer_[buffer_pos_++];
        const DwellDetector::Result r = det.push(s);
        if (++since_progress >= options_.progress_every) {
            since_progress = 0;
            report_progress(planned);
        }
        if (r == DwellDetector::Result::Settled && positioning) {
            fire(Event::InPosition, where(planned));
            positioning = false;
        }
        if (r == DwellDetector::Result::Captured) return det.stats();
    }
}

void Session::fetch() {
    check_stop();
    buffer_pos_ = buffer_n_ = 0;
    std::size_t n = 0;
    const ReadStatus st = source_.read(buffer_, n, options_.read_timeout);
    if (st == ReadStatus::Disconnected) {
        pause();
        return;
    }
    if (st == ReadStatus::Timeout || n == 0) {
        if (++silent_reads_ > options_.max_silent_reads)
            end(Event::Fail, "no samples from the instrument for " +
                                 std::to_string(silent_reads_ * options_.read_timeout.count() / 1000) + " s");
        return;
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
        if (last_seq_ && s.seq != *last_seq_ + 1) {
            ++summary_.gaps;
            broken_ = true;
        }
        if (!first_time_us_) first_time_us_ = s.device_time_us;
        last_seq_ = s.seq;
        buffer_[kept++] = s;
    }
    buffer_n_ = kept;
    summary_.samples += kept;
    if (kept > 0) sink_.on_samples(std::span<const BarSample>(buffer_.data(), kept));
}

void Session::pause() {
    ++summary_.pauses;
    const std::string at = captured_.size() < plan_.points.size() ? where(plan_.points[captured_.size()]) : "the end";
    fire(Event::DeviceLost, "instrument lost at " + at);
    op_.message("Instrument lost: plug it back in; the session continues at " + at + ".");
    broken_ = true;
    for (int i = 0; i < options_.max_reconnect_attempts; ++i) {
        check_stop();
        bool back = false;
        try {
            back = source_.reconnect(options_.read_timeout);
        } catch (const SourceError& err) {
            end(Event::Fail, std::string("the instrument came back unusable: ") + err.what());
        }
        if (back) {
            silent_reads_ = 0;
            fire(Event::DeviceBack, "continuing at " + at);
            op_.message("Instrument back: continuing at " + at + ".");
            check_stop();
            op_.run_program(std::min(captured_.size(), plan_.points.size() - 1));
            return;
        }
    }
    end(Event::Fail, "the instrument did not come back");
}

void Session::compute(int test) {
    try {
        const std::size_t a = plan_.index(test, 1, 0);
        const std::size_t b = plan_.index(test, 2, 0);
        const std::size_t k = static_cast<std::size_t>(plan_.points_per_step);
        const std::span<const CapturedPoint> all(captured_);
        const LocationResult l1 = compute_location(plan_, test, 1, all.subspan(a, k));
        sink_.on_location(l1);
        const LocationResult l2 = compute_location(plan_, test, 2, all.subspan(b, k));
        sink_.on_location(l2);
        // ΔV = ±e: the sign does not change a covariance.
        TestResult r = compute_test(plan_, test, l1.dV_mm, l2.dV_mm, l1.ssm.cov_mm2, l2.ssm.cov_mm2);
        sink_.on_test(r);
        summary_.tests.push_back(std::move(r));
    } catch (const AnalysisError& err) {
        end(Event::Fail, "test " + std::to_string(test + 1) + ": " + err.what());
    }
}

void Session::report_progress(const PlannedPoint& planned) {
    Progress p;
    p.state = sm_.state();
    p.test = planned.test;
    p.step = planned.step;
    p.point = planned.point;
    p.done = captured_.size();
    p.total = plan_.points.size();
    p.live_mm = detector_->last_length_mm();
    p.expected_mm = planned.nominal_mm;
    p.fill = detector_->fill();
    op_.progress(p);
}

}  // namespace ballbar::acquisition
