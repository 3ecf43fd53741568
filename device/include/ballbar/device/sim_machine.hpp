// SPDX-License-Identifier: MIT
// A simulated five-axis machine with a ball-bar between its tool ball and a table socket: the true
// world the emulator measures. It uses analysis' actual kinematics with a known set of error
// parameters, so tests, the acquisition engineer and the identification demo can compare what they
// estimate with the truth (`true_errors()`, `true_distance_mm()`, `bar_reading_mm()`).
//
// Motion is a queue of straight moves in axis space (G0/G1), dwells (G4) and NC programs, timed on the
// simulated clock the caller passes in (seconds since the emulator's power-on). Thread-safe: the
// emulator samples it while another thread queues motion.
#pragma once

#include <algorithm>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::device {

/// Where a machine stands, told from outside: a controller's joint commands (trajectory.hpp).
class PoseSource {
  public:
    virtual ~PoseSource() = default;
    /// The pose at the emulator's time `t_s` (non-decreasing); empty while the source knows none yet.
    virtual std::optional<analysis::Pose> pose_at(double t_s) = 0;
};

struct MachineSetup {
    analysis::MachineGeometry geometry;
    analysis::ErrorParams errors;                              ///< the truth
    analysis::Vec3 socket_mm = analysis::Vec3(100, 0, 0);      ///< nominal socket, table frame
    analysis::Vec3 socket_offset_mm = analysis::Vec3::Zero();  ///< set-up error of the socket
    analysis::Pose start{100, 0, 150, 0, 0, 0};                ///< pose at power-on
    double rapid_mm_min = 10000;                               ///< G0 speed of the linear axes
    double rapid_deg_min = 5400;                               ///< G0 speed of the rotary axes
};

class SimulatedMachine {
  public:
    explicit SimulatedMachine(MachineSetup setup);

    const MachineSetup& setup() const { return setup_; }
    const analysis::ErrorParams& true_errors() const { return setup_.errors; }
    /// Where the socket truly is now (its nominal position at the latest time asked, plus its set-up
    /// offset).
    analysis::Vec3 actual_socket_mm() const {
        std::lock_guard lock(mutex_);
        return socket_at_locked(now_s_) + setup_.socket_offset_mm;
    }
    /// The operator moves the socket to `nominal_mm` (table frame; its set-up offset stays) once the
    /// machine has done the motion queued so far: as at a program stop, where the machine stands still.
    void set_socket_mm(const analysis::Vec3& nominal_mm) {
        std::lock_guard lock(mutex_);
        socket_moves_.push_back({std::max(queue_end_s_, now_s_), nominal_mm});
    }

    /// From now on the machine remembers every motion it made and every socket move, so a checker can
    /// ask afterwards where it truly stood at a past time (truth_at). For tests and campaigns: the
    /// memory grows with the number of moves.
    void keep_history() {
        std::lock_guard lock(mutex_);
        keep_history_ = true;
        history_start_ = current_;
    }
    struct Truth {
        analysis::Pose pose;
        analysis::Vec3 socket_mm;  ///< nominal socket position, table frame
    };
    /// Where the machine stood at `t_s`, a time it has already passed (keep_history() first); empty for
    /// a time still ahead of it.
    std::optional<Truth> truth_at(double t_s) const;

    /// G1: straight move in axis space at `feed_mm_min` (rotary axes read it as deg/min; a mixed move
    /// takes the longer of the two). Starts when the queue ahead of it is done.
    void move_to(const analysis::Pose& target, double feed_mm_min);
    /// G0 at the rapid speeds.
    void rapid_to(const analysis::Pose& target);
    /// G4.
    void dwell(double seconds);
    /// Queues every motion block of a program (modal axes carried from the end of the queue).
    void run_program(const analysis::NcProgram& program);
    void run_nc(std::string_view text, analysis::NcDialect dialect);
    /// Drops the queued motion (and a held program); the machine stops where it is at `t_s`.
    void stop(double t_s);

    /// A program stop (M0/M00/M1/M01) holds the rest of the program until the operator presses cycle
    /// start: true while the machine waits at one at `t_s`.
    bool at_program_stop(double t_s);
    /// A program's rest is held at a program stop (reached or still ahead of the machine).
    bool holding() const {
        std::lock_guard lock(mutex_);
        return held_.has_value();
    }
    /// Cycle start: the held rest of the program runs from `t_s` (no effect when nothing is held). When
    /// the comment before the stop says where the socket goes ("socket to [x, y, z]" or "socket
    /// stands at [x, y, z]"), the emulated operator has put it there.
    void cycle_start(double t_s);
    /// Feed override (1 = 100 %) applied to G1 moves queued from now on; G4 dwells keep their time.
    void set_feed_override(double factor);
    double feed_override() const { return feed_override_; }

    /// From now on the machine stands wherever `source` says (a controller drives it): its own motion
    /// queue and programs are no longer used; socket moves and the history still are. Before the source
    /// knows a pose the machine stands where it stood.
    void follow(std::shared_ptr<PoseSource> source) {
        std::lock_guard lock(mutex_);
        follow_ = std::move(source);
    }

    /// Commanded pose at time `t_s` (must not go backwards between calls).
    analysis::Pose pose_at(double t_s);
    /// The time the motion queued so far ends (≤ now when idle).
    double motion_end_s() const;
    bool idle_at(double t_s) const;

    /// |b − s| of the actual machine at `t_s` (spindle growth uses session time t_s).
    double true_distance_mm(double t_s);
    /// What a perfect transducer on this bar reads: the distance plus the bar's own errors
    /// (length calibration error, thermal expansion at `bar_temp_C`).
    double bar_reading_mm(double t_s, double bar_temp_C);

  private:
    struct Segment {
        analysis::Pose from, to;
        double t0 = 0, t1 = 0;
    };
    void enqueue(const analysis::Pose& target, double duration_s);
    analysis::Vec3 socket_at_locked(double t_s) const;
    analysis::Pose pose_locked(double t_s);
    void queue_blocks(const analysis::NcProgram& program, const std::vector<analysis::Pose>& poses, std::size_t from,
                      double feed);

    struct Held {
        analysis::NcProgram program;
        std::vector<analysis::Pose> poses;
        std::size_t next = 0;  ///< first block after the stop
        double feed = 0;       ///< modal feed at the stop
    };
    std::shared_ptr<PoseSource> follow_;
    std::optional<Held> held_;
    double feed_override_ = 1.0;
    bool keep_history_ = false;
    analysis::Pose history_start_;
    std::vector<Segment> history_;  ///< motions done (or cut short by stop), in time order
    std::vector<std::pair<double, analysis::Vec3>> socket_moves_;  ///< time, nominal position from then on

    MachineSetup setup_;
    mutable std::mutex mutex_;
    std::deque<Segment> queue_;
    analysis::Pose last_pose_;  ///< where the queue ends (or the machine stands)
    analysis::Pose current_;    ///< pose at now_
    double now_s_ = 0;
    double queue_end_s_ = 0;
};

}  // namespace ballbar::device
