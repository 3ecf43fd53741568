// SPDX-License-Identifier: MIT
#include "ballbar/device/sim_machine.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ballbar::device {

using analysis::Pose;

namespace {

Pose lerp(const Pose& a, const Pose& b, double u) {
    auto mix = [u](double x, double y) { return x + (y - x) * u; };
    return {mix(a.X_mm, b.X_mm),   mix(a.Y_mm, b.Y_mm),   mix(a.Z_mm, b.Z_mm),
            mix(a.A_rad, b.A_rad), mix(a.B_rad, b.B_rad), mix(a.C_rad, b.C_rad)};
}

double linear_dist_mm(const Pose& a, const Pose& b) {
    return (b.linear_mm() - a.linear_mm()).norm();
}

double rotary_dist_deg(const Pose& a, const Pose& b) {
    const double da = b.A_rad - a.A_rad, db = b.B_rad - a.B_rad, dc = b.C_rad - a.C_rad;
    return analysis::rad_to_deg(std::sqrt(da * da + db * db + dc * dc));
}

}  // namespace

SimulatedMachine::SimulatedMachine(MachineSetup setup)
    : setup_(std::move(setup)), last_pose_(setup_.start), current_(setup_.start) {
    if (!(setup_.rapid_mm_min > 0) || !(setup_.rapid_deg_min > 0)) {
        throw std::invalid_argument("machine rapid speeds must be positive");
    }
}

void SimulatedMachine::enqueue(const Pose& target, double duration_s) {
    const double t0 = std::max(queue_end_s_, now_s_);
    queue_.push_back({last_pose_, target, t0, t0 + std::max(duration_s, 0.0)});
    queue_end_s_ = t0 + std::max(duration_s, 0.0);
    last_pose_ = target;
}

void SimulatedMachine::move_to(const Pose& target, double feed_mm_min) {
    if (!(feed_mm_min > 0)) throw std::invalid_argument("feed must be positive (G1 needs F)");
    std::lock_guard lock(mutex_);
    const double minutes =
        std::max(linear_dist_mm(last_pose_, target), rotary_dist_deg(last_pose_, target)) / feed_mm_min;
    enqueue(target, minutes * 60.0);
}

void SimulatedMachine::rapid_to(const Pose& target) {
    std::lock_guard lock(mutex_);
    const double minutes = std::max(linear_dist_mm(last_pose_, target) / setup_.rapid_mm_min,
                                    rotary_dist_deg(last_pose_, target) / setup_.rapid_deg_min);
    enqueue(target, minutes * 60.0);
}

void SimulatedMachine::dwell(double seconds) {
    if (!(seconds >= 0)) throw std::invalid_argument("dwell must not be negative");
    std::lock_guard lock(mutex_);
    enqueue(last_pose_, seconds);
}

void SimulatedMachine::run_program(const analysis::NcProgram& program) {
    Pose start;
    {
        std::lock_guard lock(mutex_);
        start = last_pose_;
        held_.reset();
    }
    queue_blocks(program, analysis::resolve_poses(program, start), 0, 0);
}

void SimulatedMachine::queue_blocks(const analysis::NcProgram& program, const std::vector<Pose>& poses,
                                    std::size_t from, double feed) {
    for (std::size_t i = from; i < program.blocks.size(); ++i) {
        const auto& block = program.blocks[i];
        if (block.feed_mm_min) feed = *block.feed_mm_min;
        switch (block.motion) {
            case analysis::NcMotion::Rapid:
                rapid_to(poses[i]);
                break;
            case analysis::NcMotion::Feed:
                if (!(feed > 0)) throw analysis::NcError(block.line, "G1 without a feed rate (F)");
                move_to(poses[i], feed * feed_override_);
                break;
            case analysis::NcMotion::Dwell:
                dwell(block.dwell_s);
                break;
            case analysis::NcMotion::None: {
                // M0/M00/M1/M01: the rest waits for cycle start.
                std::string words = block.extra_words.empty() ? block.raw : block.extra_words;
                for (char& c : words)
                    if (c == '(' || c == ';') c = ' ';
                bool stop = false;
                std::size_t pos = 0;
                while ((pos = words.find('M', pos)) != std::string::npos) {
                    std::size_t end = pos + 1;
                    while (end < words.size() && std::isdigit(static_cast<unsigned char>(words[end]))) ++end;
                    const std::string num = words.substr(pos + 1, end - pos - 1);
                    if (!num.empty() && (std::stoi(num) == 0 || std::stoi(num) == 1)) stop = true;
                    pos = end;
                }
                if (stop) {
                    std::lock_guard lock(mutex_);
                    held_ = Held{program, poses, i + 1, feed};
                    return;
                }
                break;
            }
        }
    }
}

bool SimulatedMachine::at_program_stop(double t_s) {
    std::lock_guard lock(mutex_);
    pose_locked(t_s);
    return held_.has_value() && queue_end_s_ <= now_s_;
}

void SimulatedMachine::cycle_start(double t_s) {
    std::optional<Held> h;
    {
        std::lock_guard lock(mutex_);
        pose_locked(t_s);
        h.swap(held_);
    }
    if (!h) return;
    // The operator did what the stop said: a socket position in its comment is where the socket is now.
    if (h->next >= 2) {
        const std::string& c = h->program.blocks[h->next - 2].comment;
        for (const char* key : {"socket to [", "socket stands at ["}) {
            const auto at = c.find(key);
            if (at == std::string::npos) continue;
            double v[3] = {0, 0, 0};
            std::size_t pos = at + std::string(key).size();
            bool ok = true;
            for (double& x : v) {
                try {
                    std::size_t used = 0;
                    x = std::stod(c.substr(pos), &used);
                    pos += used;
                    while (pos < c.size() && (c[pos] == ',' || c[pos] == ' ')) ++pos;
                } catch (const std::exception&) {
                    ok = false;
                    break;
                }
            }
            if (ok) set_socket_mm(analysis::Vec3(v[0], v[1], v[2]));
            break;
        }
    }
    queue_blocks(h->program, h->poses, h->next, h->feed);
}

void SimulatedMachine::set_feed_override(double factor) {
    if (!(factor > 0)) throw std::invalid_argument("feed override must be positive");
    feed_override_ = factor;
}

void SimulatedMachine::run_nc(std::string_view text, analysis::NcDialect dialect) {
    run_program(analysis::parse_nc_program(text, dialect));
}

void SimulatedMachine::stop(double t_s) {
    std::lock_guard lock(mutex_);
    const Pose here = pose_locked(t_s);
    if (keep_history_ && !queue_.empty() && queue_.front().t0 < now_s_)
        history_.push_back({queue_.front().from, here, queue_.front().t0, now_s_});  // cut short here
    queue_.clear();
    held_.reset();
    last_pose_ = here;
    queue_end_s_ = now_s_;
}

Pose SimulatedMachine::pose_locked(double t_s) {
    now_s_ = std::max(now_s_, t_s);
    if (follow_) {
        const std::optional<Pose> p = follow_->pose_at(now_s_);
        if (p && keep_history_) {
            const auto& c = current_;
            if (p->X_mm != c.X_mm || p->Y_mm != c.Y_mm || p->Z_mm != c.Z_mm || p->A_rad != c.A_rad ||
                p->B_rad != c.B_rad || p->C_rad != c.C_rad)
                history_.push_back({*p, *p, now_s_, now_s_});  // a step: the pose from now on
        }
        if (p) current_ = *p;
        return current_;
    }
    while (!queue_.empty() && queue_.front().t1 <= now_s_) {
        current_ = queue_.front().to;
        if (keep_history_) history_.push_back(queue_.front());
        queue_.pop_front();
    }
    if (!queue_.empty() && queue_.front().t0 < now_s_) {
        const auto& s = queue_.front();
        current_ = lerp(s.from, s.to, (now_s_ - s.t0) / (s.t1 - s.t0));
    }
    return current_;
}

analysis::Vec3 SimulatedMachine::socket_at_locked(double t_s) const {
    // Moves are appended in time order (each at the end of the motion queued when it was made).
    for (auto it = socket_moves_.rbegin(); it != socket_moves_.rend(); ++it)
        if (it->first <= t_s) return it->second;
    return setup_.socket_mm;
}

std::optional<SimulatedMachine::Truth> SimulatedMachine::truth_at(double t_s) const {
    std::lock_guard lock(mutex_);
    if (!keep_history_ || t_s > now_s_) return std::nullopt;
    Truth out;
    out.socket_mm = socket_at_locked(t_s);
    // The pose: the last motion started at or before t_s, done or in progress.
    auto in = [t_s](const Segment& g) {
        return t_s <= g.t1 ? (g.t1 > g.t0 ? lerp(g.from, g.to, (t_s - g.t0) / (g.t1 - g.t0)) : g.to) : g.to;
    };
    if (!queue_.empty() && queue_.front().t0 <= t_s) {
        out.pose = in(queue_.front());
        return out;
    }
    auto it =
        std::upper_bound(history_.begin(), history_.end(), t_s, [](double t, const Segment& g) { return t < g.t0; });
    out.pose = it == history_.begin() ? history_start_ : in(*std::prev(it));
    return out;
}

Pose SimulatedMachine::pose_at(double t_s) {
    std::lock_guard lock(mutex_);
    return pose_locked(t_s);
}

double SimulatedMachine::motion_end_s() const {
    std::lock_guard lock(mutex_);
    return queue_end_s_;
}

bool SimulatedMachine::idle_at(double t_s) const {
    return motion_end_s() <= t_s;
}

double SimulatedMachine::true_distance_mm(double t_s) {
    const Pose pose = pose_at(t_s);
    const analysis::Vec3 socket = actual_socket_mm();  // at t_s: pose_at moved the clock there
    const auto balls = analysis::actual_balls(setup_.geometry, setup_.errors, pose, socket, {t_s, 20.0});
    return (balls.tool - balls.table).norm();
}

double SimulatedMachine::bar_reading_mm(double t_s, double bar_temp_C) {
    const Pose pose = pose_at(t_s);
    const analysis::Vec3 socket = actual_socket_mm();  // at t_s: pose_at moved the clock there
    return analysis::predicted_reading(setup_.geometry, setup_.errors, pose, socket, {t_s, bar_temp_C});
}

}  // namespace ballbar::device
