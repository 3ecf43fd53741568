// SPDX-License-Identifier: MIT
// Test doubles of the acquisition's interfaces: a sample source that measures a simulated machine
// (device::SimulatedMachine, analysis kinematics with injected errors) on a simulated clock, with the
// faults a driver passes on (disconnects for a time, frames lost to drops or CRC errors, frames
// delivered twice); an operator who runs the programs on that machine (late, at a feed override,
// answering after a delay); and a sink that records what it is given and checks the stream. The source
// remembers the machine's true pose at every recent sample, so a test can tell whether a stored point's
// window was taken where the plan says.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <utility>
#include <vector>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/device/sim_machine.hpp"

namespace ballbar::acquisition::testing {

struct SimOptions {
    double noise_um = 0.1;
    double rate_hz = 1000;
    std::uint64_t seed = 7;
    /// Disconnect when this many samples have been delivered (once), for `disconnect_reads` reconnect
    /// attempts (each one read timeout of simulated time).
    std::optional<std::uint64_t> disconnect_after;
    int disconnect_reads = 3;
    /// After the reconnect, deliver the last `repeat_after_reconnect` samples again (a driver replaying
    /// its buffer), which the session must drop.
    std::size_t repeat_after_reconnect = 0;
    /// Disconnects on the simulated clock: (start s, duration s). The machine keeps moving.
    std::vector<std::pair<double, double>> disconnects;
    std::size_t frame_samples = 13;       ///< samples per stream frame
    double drop_frame_probability = 0;    ///< a frame never arrives (dropped, or rejected by its CRC)
    double replay_frame_probability = 0;  ///< a frame arrives twice
    bool referenced = false;              ///< the bar starts referenced
    bool record_poses = true;             ///< remember the true pose of every sample (pose_of)
};

class SimSource : public SampleSource {
  public:
    SimSource(device::MachineSetup setup, const Plan& plan, SimOptions opt)
        : machine_(std::move(setup)), opt_(std::move(opt)), rng_(opt_.seed), L_(plan.spec.bar_length_mm) {
        referenced_ = opt_.referenced;
    }

    InstrumentStatus connect() override {
        InstrumentStatus s;
        s.description = "simulated bar";
        s.battery_pct = 90;
        s.bar_temp_C = 20.0;
        s.referenced = referenced_;
        s.calibrated_length_mm = L_;
        s.sample_rate_hz = opt_.rate_hz;
        return s;
    }
    void set_reference() override {
        if (started_) throw SourceError("set reference while streaming");
        referenced_ = true;
        ++references;
    }
    void start() override { started_ = true; }
    void stop() override { started_ = false; }

    ReadStatus read(std::span<analysis::BarSample> out, std::size_t& n, std::chrono::milliseconds timeout) override {
        n = 0;
        if (lost_) return ReadStatus::Disconnected;
        if (!started_) {
            idle(1e-3 * static_cast<double>(timeout.count()));
            return ReadStatus::Timeout;
        }
        if (opt_.disconnect_after && !disconnected_once_ && seq_ >= *opt_.disconnect_after) {
            disconnected_once_ = true;
            return lose(0);
        }
        while (replay_ > 0 && n < out.size()) out[n++] = recent(replay_--);
        while (n < out.size()) {
            if (next_disconnect_ < opt_.disconnects.size() && t_s_ >= opt_.disconnects[next_disconnect_].first) {
                const double until =
                    opt_.disconnects[next_disconnect_].first + opt_.disconnects[next_disconnect_].second;
                ++next_disconnect_;
                if (n > 0) {
                    pending_loss_ = until;
                    break;
                }
                return lose(until);
            }
            if (pending_loss_) {
                const double until = *pending_loss_;
                pending_loss_.reset();
                if (n > 0) break;
                return lose(until);
            }
            // One frame at a time: dropped, delivered, or delivered twice.
            if (seq_ % opt_.frame_samples == 0) {
                frame_dropped_ = opt_.drop_frame_probability > 0 && uniform() < opt_.drop_frame_probability;
                frame_replayed_ = opt_.replay_frame_probability > 0 && uniform() < opt_.replay_frame_probability;
            }
            const analysis::BarSample s = make_sample();
            if (frame_dropped_) {
                ++dropped_samples;
                continue;
            }
            out[n++] = s;
            if (frame_replayed_ && (seq_ % opt_.frame_samples == 0)) {
                // The frame's samples once more (the driver saw the frame twice).
                const std::size_t k = std::min<std::size_t>(opt_.frame_samples, out.size() - n);
                for (std::size_t i = k; i > 0 && n < out.size(); --i) out[n++] = recent(i);
                replayed_samples += k;
            }
        }
        return ReadStatus::Ok;
    }

    bool reconnect(std::chrono::milliseconds timeout) override {
        idle(1e-3 * static_cast<double>(timeout.count()));  // the world goes on; the bar is not read
        if (++lost_reads_ < opt_.disconnect_reads || t_s_ < lost_until_) return false;
        lost_ = false;
        started_ = false;
        replay_ = std::min(opt_.repeat_after_reconnect, history_.size());
        return true;
    }

    /// Simulated time passes without samples (the stream is stopped, an operator thinks).
    void idle(double seconds) {
        const double end = t_s_ + seconds;
        while (t_s_ < end) t_s_ += 1.0 / opt_.rate_hz;
        machine_.pose_at(t_s_);
    }

    device::SimulatedMachine& machine() { return machine_; }
    std::uint64_t produced() const { return seq_; }
    double now_s() const { return t_s_; }

    /// The machine's true pose when sample `seq` was taken.
    std::optional<analysis::Pose> pose_of(std::uint64_t seq) const {
        if (seq >= poses_.size()) return std::nullopt;
        return poses_[seq];
    }

    int references = 0;
    std::uint64_t dropped_samples = 0;
    std::uint64_t replayed_samples = 0;

  private:
    ReadStatus lose(double until_s) {
        lost_ = true;
        lost_reads_ = 0;
        lost_until_ = until_s;
        started_ = false;
        return ReadStatus::Disconnected;
    }
    double uniform() { return std::uniform_real_distribution<double>(0, 1)(rng_); }
    /// The k-th most recent sample (1 = the last).
    analysis::BarSample recent(std::size_t k) const {
        const std::size_t size = history_.size();
        if (size < 64) return history_[size - k];
        return history_[(hist_head_ + size - k) % size];
    }

    analysis::BarSample make_sample() {
        t_s_ += 1.0 / opt_.rate_hz;
        analysis::BarSample s;
        s.seq = seq_;
        if (opt_.record_poses)
            poses_.push_back(machine_.pose_at(t_s_));
        else
            machine_.pose_at(t_s_);
        ++seq_;
        s.device_time_us = static_cast<std::uint64_t>(std::llround(t_s_ * 1e6));
        const double reading =
            machine_.bar_reading_mm(t_s_, 20.0) + noise_(rng_) * opt_.noise_um * 1e-3 + (referenced_ ? 0.0 : 0.0237);
        double d_mm = reading - L_;
        if (std::abs(d_mm) > 1.0) {
            s.flags |= analysis::kSampleOutOfRange;
            d_mm = std::copysign(1.0, d_mm);
        }
        if (!referenced_) s.flags |= analysis::kSampleNotReferenced;
        s.displacement_nm = static_cast<std::int32_t>(std::lround(d_mm * 1e6));
        s.bar_temp_C = 20.0f;
        if (history_.size() < 64) {
            history_.push_back(s);
        } else {
            history_[hist_head_] = s;
            hist_head_ = (hist_head_ + 1) % history_.size();
        }
        return s;
    }

    device::SimulatedMachine machine_;
    SimOptions opt_;
    std::mt19937_64 rng_;
    std::normal_distribution<double> noise_{0.0, 1.0};
    double L_;
    double t_s_ = 0;
    std::uint64_t seq_ = 0;
    bool referenced_ = false;
    bool started_ = false;
    bool lost_ = false;
    double lost_until_ = 0;
    std::optional<double> pending_loss_;
    std::size_t next_disconnect_ = 0;
    bool disconnected_once_ = false;
    bool frame_dropped_ = false, frame_replayed_ = false;
    int lost_reads_ = 0;
    std::vector<analysis::BarSample> history_;
    std::size_t hist_head_ = 0;
    std::size_t replay_ = 0;
    std::vector<analysis::Pose> poses_;
};

struct SimOperatorOptions {
    double late_start_s = 0;     ///< the program starts this long after the operator is told
    double feed_override = 1.0;  ///< the machine's feed override while it runs the programs
    /// Seconds the operator takes to answer a question or act at a program stop.
    std::function<double()> answer_delay_s = [] { return 0.0; };
};

/// Runs each program on the source's machine (late, at the feed override), acts at every program stop,
/// answers like the plan's scripted answers after a delay.
class SimOperator : public ScriptedOperator {
  public:
    SimOperator(SimSource* source, Answers answers = {}, SimOperatorOptions opt = {})
        : ScriptedOperator(std::move(answers)), source_(source), opt_(std::move(opt)) {}
    void run_program(const analysis::NcProgram& program, std::span<const std::size_t> points, bool retry) override {
        ++programs;
        last_points.assign(points.begin(), points.end());
        retries += retry;
        if (!source_) return;
        auto& m = source_->machine();
        m.stop(source_->now_s());
        m.set_feed_override(opt_.feed_override);
        if (opt_.late_start_s > 0) m.dwell(opt_.late_start_s);
        m.run_program(program);
    }
    void program_stop(const ProgramStop& stop) override {
        stops.push_back(stop.what);
        if (!source_) return;
        think();
        if (stop.socket_mm) source_->machine().set_socket_mm(*stop.socket_mm);
        source_->machine().cycle_start(source_->now_s());
    }
    bool confirm(std::string_view what, std::string_view prompt) override {
        asked.emplace_back(what);
        think();
        return ScriptedOperator::confirm(what, prompt);
    }
    std::size_t choose(const Choice& c) override {
        asked.push_back(c.what);
        think();
        return ScriptedOperator::choose(c);
    }
    void think() {
        if (source_) source_->idle(opt_.answer_delay_s());
    }
    int programs = 0;
    int retries = 0;
    std::vector<std::size_t> last_points;
    std::vector<std::string> stops;
    std::vector<std::string> asked;

  private:
    SimSource* source_;
    SimOperatorOptions opt_;
};

/// Records everything; checks the sample stream is contiguous and never repeats.
class RecordingSink : public SessionSink {
  public:
    void on_transition(const TransitionRecord& t) override { transitions.push_back(t); }
    void on_samples(std::span<const analysis::BarSample> s) override {
        for (const auto& x : s) {
            if (next_seq && x.seq < *next_seq) ++repeated;
            if (next_seq && x.seq != *next_seq) ++discontinuities;
            next_seq = x.seq + 1;
            ++samples;
        }
    }
    void on_point(const CapturedPoint& p) override {
        points.push_back(p);
        if (check_point) check_point(p);
        if (kill_after_points && points.size() == *kill_after_points) throw Killed{};
    }
    void on_location(const LocationResult& r) override { locations.push_back(r); }
    void on_test(const TestResult& r) override { tests.push_back(r); }

    struct Killed {};
    std::optional<std::size_t> kill_after_points;
    std::function<void(const CapturedPoint&)> check_point;
    std::vector<TransitionRecord> transitions;
    std::vector<CapturedPoint> points;
    std::vector<LocationResult> locations;
    std::vector<TestResult> tests;
    std::uint64_t samples = 0;
    std::size_t discontinuities = 0;
    std::size_t repeated = 0;
    std::optional<std::uint64_t> next_seq;
};

/// Did every sample of the point's window come from the machine standing at the planned pose?
inline bool window_at_planned_pose(const SimSource& src, const CapturedPoint& p, double tol_mm = 1e-4,
                                   double tol_rad = 1e-6) {
    for (std::uint64_t q = p.first_seq; q <= p.last_seq; ++q) {
        const auto pose = src.pose_of(q);
        if (!pose) return false;
        const analysis::Pose& w = p.planned.pose;
        if ((pose->linear_mm() - w.linear_mm()).norm() > tol_mm || std::abs(pose->A_rad - w.A_rad) > tol_rad ||
            std::abs(pose->B_rad - w.B_rad) > tol_rad || std::abs(pose->C_rad - w.C_rad) > tol_rad)
            return false;
    }
    return true;
}

}  // namespace ballbar::acquisition::testing
