// SPDX-License-Identifier: MIT
#include "ballbar/device/trajectory.hpp"

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <numbers>
#include <string>

namespace ballbar::device {

namespace {

std::string_view next_field(std::string_view& s) {
    const auto b = s.find_first_not_of(" \t\r");
    if (b == std::string_view::npos) return s = {}, std::string_view{};
    s.remove_prefix(b);
    const auto e = s.find_first_of(" \t\r");
    const std::string_view f = s.substr(0, e);
    s.remove_prefix(e == std::string_view::npos ? s.size() : e);
    return f;
}

bool to_double(std::string_view f, double& v) {
    const auto r = std::from_chars(f.data(), f.data() + f.size(), v);
    return r.ec == std::errc() && r.ptr == f.data() + f.size() && std::isfinite(v);
}

}  // namespace

std::optional<JointSample> parse_xyzac_sample(std::string_view line) {
    JointSample s;
    const std::string_view n = next_field(line);
    if (n.empty() || std::from_chars(n.data(), n.data() + n.size(), s.cycle).ptr != n.data() + n.size())
        return std::nullopt;
    double v[5];
    for (double& x : v)
        if (!to_double(next_field(line), x)) return std::nullopt;
    constexpr double kRad = std::numbers::pi / 180.0;
    s.pose = {v[0], v[1], v[2], v[3] * kRad, 0.0, v[4] * kRad};
    return s;
}

TrajectoryFeed::TrajectoryFeed(double servo_period_s, double delay_s) : period_s_(servo_period_s), delay_s_(delay_s) {}

void TrajectoryFeed::push(const JointSample& s) {
    std::lock_guard lock(mutex_);
    if (last_cycle_ && s.cycle <= *last_cycle_) return;
    last_cycle_ = s.cycle;
    queue_.push_back(s);
    ++received_;
}

std::size_t TrajectoryFeed::read_lines(int fd, const std::atomic<bool>& stop) {
    std::size_t rejected = 0;
    std::string pending;
    char buf[8192];
    while (!stop) {
        pollfd p{fd, POLLIN, 0};
        const int r = ::poll(&p, 1, 100);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) break;
        if (r == 0) continue;
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
        if (n <= 0) break;  // the writer closed its end (the controller stopped)
        pending.append(buf, static_cast<std::size_t>(n));
        std::size_t start = 0;
        for (std::size_t nl; (nl = pending.find('\n', start)) != std::string::npos; start = nl + 1) {
            if (const auto s = parse_xyzac_sample(std::string_view(pending).substr(start, nl - start)))
                push(*s);
            else
                ++rejected;
        }
        pending.erase(0, start);
    }
    return rejected;
}

std::optional<analysis::Pose> TrajectoryFeed::pose_at(double t_s) {
    std::lock_guard lock(mutex_);
    if (queue_.empty()) return std::nullopt;
    const auto servo_time = [this](const JointSample& s) { return static_cast<double>(s.cycle) * period_s_; };
    if (!offset_s_) offset_s_ = t_s - (servo_time(queue_.back()) - delay_s_);
    const double want = t_s - *offset_s_;  // the servo time played now
    while (queue_.size() > 1 && servo_time(queue_[1]) <= want) queue_.pop_front();
    const bool starved = queue_.size() == 1 && servo_time(queue_.front()) < want;
    if (starved && !was_starved_) ++starved_;
    was_starved_ = starved;
    return queue_.front().pose;
}

std::uint64_t TrajectoryFeed::cycles() const {
    std::lock_guard lock(mutex_);
    return received_;
}

std::uint64_t TrajectoryFeed::starved() const {
    std::lock_guard lock(mutex_);
    return starved_;
}

}  // namespace ballbar::device
