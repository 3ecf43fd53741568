// SPDX-License-Identifier: MIT
// Test doubles of the acquisition's interfaces: a sample source that measures a simulated machine
// (device::SimulatedMachine, analysis kinematics with injected errors) on a simulated 1 kHz clock, with
// scripted disconnects and repeated samples; and a sink that records what it is given.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
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
    /// attempts; the machine keeps running meanwhile only if `machine_runs_while_lost`.
    std::optional<std::uint64_t> disconnect_after;
    int disconnect_reads = 3;
    /// After the reconnect, deliver the last `repeat_after_reconnect` samples again (a driver replaying
    /// its buffer), which the session must drop.
    std::size_t repeat_after_reconnect = 0;
};

class SimSource : public SampleSource {
  public:
    SimSource(device::MachineSetup setup, const Plan& plan, SimOptions opt)
        : machine_(std::move(setup)), opt_(opt), rng_(opt.seed), L_(plan.spec.bar_length_mm) {}

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
    void set_reference() override { referenced_ = true; }
    void start() override { started_ = true; }

    ReadStatus read(std::span<analysis::BarSample> out, std::size_t& n, std::chrono::milliseconds) override {
        n = 0;
        if (!started_) return ReadStatus::Timeout;
        if (lost_) return ReadStatus::Disconnected;
        if (opt_.disconnect_after && !disconnected_once_ && seq_ >= *opt_.disconnect_after) {
            disconnected_once_ = true;
            lost_ = true;
            lost_reads_ = 0;
            return ReadStatus::Disconnected;
        }
        while (replay_ > 0 && n < out.size()) out[n++] = recent(replay_--);
        for (; n < out.size(); ++n) out[n] = make_sample();
        return ReadStatus::Ok;
    }

    bool reconnect(std::chrono::milliseconds) override {
        // While the cable is out the world goes on: the bar is not read.
        for (int i = 0; i < 200; ++i) advance();
        if (++lost_reads_ < opt_.disconnect_reads) return false;
        lost_ = false;
        replay_ = std::min(opt_.repeat_after_reconnect, history_.size());
        return true;
    }

    device::SimulatedMachine& machine() { return machine_; }
    std::uint64_t produced() const { return seq_; }
    double now_s() const { return t_s_; }

  private:
    /// The k-th most recent sample (1 = the last).
    analysis::BarSample recent(std::size_t k) const {
        const std::size_t size = history_.size();
        if (size < 64) return history_[size - k];
        return history_[(hist_head_ + size - k) % size];
    }
    void advance() { t_s_ += 1.0 / opt_.rate_hz; }

    analysis::BarSample make_sample() {
        advance();
        analysis::BarSample s;
        s.seq = seq_++;
        s.device_time_us = static_cast<std::uint64_t>(std::llround(t_s_ * 1e6));
        const double reading = machine_.bar_reading_mm(t_s_, 20.0) + noise_(rng_) * opt_.noise_um * 1e-3;
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
    bool disconnected_once_ = false;
    int lost_reads_ = 0;
    std::vector<analysis::BarSample> history_;
    std::size_t hist_head_ = 0;
    std::size_t replay_ = 0;
};

/// Records everything; checks the sample stream is contiguous and never repeats.
class RecordingSink : public SessionSink {
  public:
    void on_transition(const TransitionRecord& t) override { transitions.push_back(t); }
    void on_samples(std::span<const analysis::BarSample> s) override {
        for (const auto& x : s) {
            if (next_seq && x.seq != *next_seq) ++discontinuities;
            next_seq = x.seq + 1;
            ++samples;
        }
    }
    void on_point(const CapturedPoint& p) override {
        points.push_back(p);
        if (kill_after_points && points.size() == *kill_after_points) throw Killed{};
    }
    void on_location(const LocationResult& r) override { locations.push_back(r); }
    void on_test(const TestResult& r) override { tests.push_back(r); }

    struct Killed {};
    std::optional<std::size_t> kill_after_points;
    std::vector<TransitionRecord> transitions;
    std::vector<CapturedPoint> points;
    std::vector<LocationResult> locations;
    std::vector<TestResult> tests;
    std::uint64_t samples = 0;
    std::size_t discontinuities = 0;
    std::optional<std::uint64_t> next_seq;
};

}  // namespace ballbar::acquisition::testing
