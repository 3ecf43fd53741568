// SPDX-License-Identifier: MIT
// A machine that follows a controller: the joint positions a CNC controller commands every servo cycle,
// as LinuxCNC's `halsampler -t` writes them (one line per cycle: the sample number, then the joints),
// drive the emulated machine instead of its own motion queue (SimulatedMachine::follow). The controller
// decides how the machine moves — its interpreter, trajectory planner, feeds, dwells and program stops
// — and the emulated ball-bar measures where its erroneous kinematics put the tool ball.
//
// The controller's servo clock and the emulator's clock run side by side in real time but start apart,
// and the samples arrive in bursts (halsampler's output is buffered). The feed therefore plays the
// cycles back a fixed delay behind the newest one it has when it first answers: every bar sample then
// sees the joints of exactly one servo cycle, as a physical bar on a physical machine would, at a
// constant lag the measurement cannot see. Should the samples stop coming (the controller stopped),
// the machine stands at the last one.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "ballbar/analysis/types.hpp"
#include "ballbar/device/sim_machine.hpp"

namespace ballbar::device {

/// One line of `halsampler -t` for an XYZAC table-tilting machine (ballbar's TTTRR): "N X Y Z A C",
/// X Y Z in mm, A C in degrees, any further columns ignored. Empty when the line is not one (halsampler
/// also writes "overrun" lines).
struct JointSample {
    std::uint64_t cycle = 0;
    analysis::Pose pose;
};
std::optional<JointSample> parse_xyzac_sample(std::string_view line);

class TrajectoryFeed : public PoseSource {
  public:
    /// `servo_period_s`: the controller's servo period (LinuxCNC: [EMCMOT]SERVO_PERIOD); `delay_s`: how
    /// far behind the newest cycle the playback runs (a few bursts of halsampler's output).
    explicit TrajectoryFeed(double servo_period_s = 0.001, double delay_s = 0.25);

    /// A servo cycle's joints, in cycle order (an older or repeated cycle is ignored).
    void push(const JointSample& s);
    /// Reads halsampler's lines from `fd` until end of file, an error or `stop`; returns the number of
    /// lines that were not samples. For a thread of its own.
    std::size_t read_lines(int fd, const std::atomic<bool>& stop);

    /// The joints at the emulator's time `t_s` (non-decreasing); empty before the first sample.
    std::optional<analysis::Pose> pose_at(double t_s) override;

    std::uint64_t cycles() const;  ///< servo cycles received
    /// Times the playback caught up with the newest cycle (it then stood still until the next burst).
    std::uint64_t starved() const;

  private:
    mutable std::mutex mutex_;
    double period_s_, delay_s_;
    std::deque<JointSample> queue_;   ///< cycles not yet played (the first one is the one playing)
    std::optional<double> offset_s_;  ///< emulator time − servo time of the playback
    std::uint64_t received_ = 0, starved_ = 0;
    std::optional<std::uint64_t> last_cycle_;
    bool was_starved_ = false;
};

}  // namespace ballbar::device
