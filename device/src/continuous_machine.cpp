// SPDX-License-Identifier: MIT
// Continuous motion for the circular test: the part program's path, each axis's servo lag and the
// trace format's effects (docs/emulator.md, docs/formats/trace.md).
#include "ballbar/device/continuous_machine.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "ballbar/analysis/nc_lexer.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::device {

namespace circ = analysis::circular;
using analysis::kPi;

namespace {

constexpr double kStepS = 1e-4;         ///< integration step of the lag while the command moves
constexpr double kSpikeTauS = 0.015;    ///< trace.md: a reversal spike decays with 15 ms
constexpr double kMovingMmPerS = 1e-6;  ///< below this an axis counts as standing (direction kept)
constexpr double kTwoPi = 2.0 * kPi;

struct Words {
    std::vector<int> g;
    std::optional<double> x, y, z, i, j, k, f, p;
};

Words parse_words(std::string_view line, int line_no) {
    Words w;
    std::size_t pos = 0;
    auto skip_space = [&] {
        while (pos < line.size() && std::isspace(static_cast<unsigned char>(line[pos]))) ++pos;
    };
    while (true) {
        skip_space();
        if (pos >= line.size()) break;
        const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(line[pos])));
        if (!std::isalpha(static_cast<unsigned char>(letter)))
            throw analysis::NcError(line_no, std::string("unexpected character '") + line[pos] + "'");
        ++pos;
        skip_space();
        const std::size_t begin = pos;
        const double value = analysis::read_nc_number(line, pos, line_no, letter);  // nc_lexer.hpp
        const std::string text(line.substr(begin, pos - begin));
        switch (letter) {
            case 'G': {
                if (value != std::floor(value))
                    throw analysis::NcError(line_no, "unsupported G code G" + text + " (ballbar runs G0-G4)");
                w.g.push_back(static_cast<int>(value));
                break;
            }
            case 'X':
                w.x = value;
                break;
            case 'Y':
                w.y = value;
                break;
            case 'Z':
                w.z = value;
                break;
            case 'I':
                w.i = value;
                break;
            case 'J':
                w.j = value;
                break;
            case 'K':
                w.k = value;
                break;
            case 'F':
                w.f = value;
                break;
            case 'P':
                w.p = value;
                break;
            case 'N':
            case 'M':
            case 'S':
            case 'T':
            case 'H':
            case 'D':
                break;  // not motion
            default:
                throw analysis::NcError(line_no, std::string("unsupported word ") + letter + text);
        }
    }
    return w;
}

/// The program line without its comments ("( … )", "; …": nc_lexer.hpp), trimmed.
std::string strip(std::string_view raw, int line_no) {
    std::string buffer, comment;
    const std::string_view code =
        analysis::split_nc_comments(raw, line_no, /*semicolon_comments=*/true, buffer, comment);
    const auto b = code.find_first_not_of(" \t\r");
    if (b == std::string_view::npos) return {};
    const auto e = code.find_last_not_of(" \t\r");
    return std::string(code.substr(b, e - b + 1));
}

double dist(const Xyz& a, const Xyz& b) {
    return std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
}

Xyz segment_at(const PathSegment& s, double u) {
    u = std::clamp(u, 0.0, 1.0);
    if (s.kind == PathSegment::Kind::Dwell) return s.from;
    Xyz out{};
    for (int a = 0; a < 3; ++a)
        out[static_cast<std::size_t>(a)] =
            s.from[static_cast<std::size_t>(a)] +
            (s.to[static_cast<std::size_t>(a)] - s.from[static_cast<std::size_t>(a)]) * u;
    if (s.kind == PathSegment::Kind::Arc) {
        if (u >= 1.0) return s.to;
        const double th = s.start_rad + s.sweep_rad * u;
        const double r = s.r0 + (s.r1 - s.r0) * u;
        out[static_cast<std::size_t>(s.p)] = s.centre[static_cast<std::size_t>(s.p)] + r * std::cos(th);
        out[static_cast<std::size_t>(s.q)] = s.centre[static_cast<std::size_t>(s.q)] + r * std::sin(th);
    }
    return out;
}

int sign(double v) {
    return v > 0 ? 1 : v < 0 ? -1 : 0;
}

}  // namespace

std::vector<PathSegment> parse_motion_program(std::string_view text, analysis::NcDialect dialect, const Xyz& start_mm,
                                              double rapid_mm_min, double feed_override) {
    if (!(feed_override > 0)) throw std::invalid_argument("feed override must be positive");
    std::vector<PathSegment> out;
    Xyz pos = start_mm;
    int motion = -1;
    int p = 0, q = 1;  // G17
    double feed = 0;
    int line_no = 0;
    std::size_t at = 0;
    while (at <= text.size()) {
        const std::size_t nl = text.find('\n', at);
        const std::string_view raw = text.substr(at, nl == std::string_view::npos ? std::string_view::npos : nl - at);
        at = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
        ++line_no;
        const std::string line = strip(raw, line_no);
        if (line.empty() || line == "%") continue;
        if ((line[0] == 'O' || line[0] == 'o') && line.size() > 1 && std::isdigit(static_cast<unsigned char>(line[1])))
            continue;
        const Words w = parse_words(line, line_no);
        bool dwell = false;
        for (int g : w.g) {
            switch (g) {
                case 0:
                case 1:
                case 2:
                case 3:
                    motion = g;
                    break;
                case 4:
                    dwell = true;
                    break;
                case 17:
                    p = 0, q = 1;
                    break;
                case 18:
                    p = 2, q = 0;
                    break;
                case 19:
                    p = 1, q = 2;
                    break;
                case 20:
                    throw analysis::NcError(line_no, "G20 (inch) is not supported: programs are in mm (G21)");
                case 91:
                    throw analysis::NcError(line_no, "G91 (incremental) is not supported: ballbar runs G90");
                case 21:
                case 90:
                case 94:
                case 40:
                case 49:
                case 80:
                case 54:
                case 61:
                case 64:
                    break;
                default:
                    throw analysis::NcError(line_no, "unsupported G code G" + std::to_string(g) +
                                                         " (the circular test runs G0-G4, G17-G19 in G90/G21)");
            }
        }
        if (w.f) {
            if (!(*w.f > 0)) throw analysis::NcError(line_no, "F must be positive");
            feed = *w.f;
        }
        if (dwell) {
            if (!w.p || *w.p < 0) throw analysis::NcError(line_no, "G4 needs a dwell P >= 0");
            PathSegment s;
            s.kind = PathSegment::Kind::Dwell;
            s.from = s.to = pos;
            s.duration_s = dialect == analysis::NcDialect::Fanuc ? *w.p / 1000.0 : *w.p;
            out.push_back(s);
            continue;
        }
        const bool axes = w.x || w.y || w.z;
        if (!axes) {
            if (w.i || w.j || w.k) throw analysis::NcError(line_no, "centre words without an end point");
            continue;
        }
        if (motion < 0) throw analysis::NcError(line_no, "axis words without G0, G1, G2 or G3");
        Xyz to = pos;
        if (w.x) to[0] = *w.x;
        if (w.y) to[1] = *w.y;
        if (w.z) to[2] = *w.z;
        PathSegment s;
        s.from = pos;
        s.to = to;
        if (motion == 0) {
            s.duration_s = dist(pos, to) / rapid_mm_min * 60.0;
        } else {
            if (!(feed > 0))
                throw analysis::NcError(line_no, "G" + std::to_string(motion) + " without a feed rate (F)");
            const double speed = feed * feed_override / 60.0;  // mm/s
            if (motion == 1) {
                s.duration_s = dist(pos, to) / speed;
            } else {
                const std::optional<double> off[3] = {w.i, w.j, w.k};
                if (!off[p] && !off[q])
                    throw analysis::NcError(
                        line_no, "G" + std::to_string(motion) + " needs centre words (I J K) of the plane's axes");
                s.kind = PathSegment::Kind::Arc;
                s.has_centre = true;
                s.p = p;
                s.q = q;
                const auto up = static_cast<std::size_t>(p), uq = static_cast<std::size_t>(q);
                s.centre = pos;
                s.centre[up] = pos[up] + off[p].value_or(0.0);
                s.centre[uq] = pos[uq] + off[q].value_or(0.0);
                s.r0 = std::hypot(pos[up] - s.centre[up], pos[uq] - s.centre[uq]);
                s.r1 = std::hypot(to[up] - s.centre[up], to[uq] - s.centre[uq]);
                if (!(s.r0 > 1e-6)) throw analysis::NcError(line_no, "arc of zero radius");
                if (std::abs(s.r1 - s.r0) > 0.01 + 1e-3 * s.r0)
                    throw analysis::NcError(line_no, "arc end point is not on the circle (radius " +
                                                         std::to_string(s.r0) + " vs " + std::to_string(s.r1) + ")");
                s.start_rad = std::atan2(pos[uq] - s.centre[uq], pos[up] - s.centre[up]);
                const double end_rad = std::atan2(to[uq] - s.centre[uq], to[up] - s.centre[up]);
                double sweep = end_rad - s.start_rad;
                if (motion == 3) {
                    while (sweep <= 1e-12) sweep += kTwoPi;
                    while (sweep > kTwoPi + 1e-12) sweep -= kTwoPi;
                } else {
                    while (sweep >= -1e-12) sweep -= kTwoPi;
                    while (sweep < -kTwoPi - 1e-12) sweep += kTwoPi;
                }
                s.sweep_rad = sweep;
                const int h = 3 - p - q;
                const double along = std::abs(sweep) * 0.5 * (s.r0 + s.r1);
                const double rise = to[static_cast<std::size_t>(h)] - pos[static_cast<std::size_t>(h)];
                s.duration_s = std::hypot(along, rise) / speed;
            }
        }
        out.push_back(s);
        pos = to;
    }
    return out;
}

ContinuousMachine::ContinuousMachine(ContinuousSetup setup)
    : setup_(std::move(setup)), rest_mm_(setup_.start_mm), socket_(setup_.socket_mm), axis_(setup_.start_mm) {
    if (!(setup_.rapid_mm_min > 0)) throw std::invalid_argument("rapid speed must be positive");
}

void ContinuousMachine::set_feed_override(double factor) {
    if (!(factor > 0)) throw std::invalid_argument("feed override must be positive");
    std::lock_guard lock(mutex_);
    feed_override_ = factor;
}

void ContinuousMachine::run_program(std::string_view text, analysis::NcDialect dialect, double t_s) {
    std::lock_guard lock(mutex_);
    const double t = std::max(t_s, now_);
    advance_locked(t);
    const Xyz here = command_locked(t);
    std::vector<PathSegment> path = parse_motion_program(text, dialect, here, setup_.rapid_mm_min, feed_override_);
    path_ = std::move(path);
    rest_mm_ = here;
    t0_.clear();
    double at = t;
    for (const auto& s : path_) {
        t0_.push_back(at);
        at += s.duration_s;
    }
    for (const auto& s : path_)
        if (s.has_centre) {
            socket_ = s.centre;
            break;
        }
}

Xyz ContinuousMachine::command_locked(double t_s) const {
    if (path_.empty() || t_s <= t0_.front()) return rest_mm_;
    const auto it = std::upper_bound(t0_.begin(), t0_.end(), t_s);
    const auto k = static_cast<std::size_t>(it - t0_.begin()) - 1;
    const PathSegment& s = path_[k];
    if (s.duration_s <= 0) return s.to;
    return segment_at(s, (t_s - t0_[k]) / s.duration_s);
}

Xyz ContinuousMachine::commanded_mm(double t_s) const {
    std::lock_guard lock(mutex_);
    return command_locked(t_s);
}

double ContinuousMachine::program_end_s() const {
    std::lock_guard lock(mutex_);
    if (path_.empty()) return 0;
    return t0_.back() + path_.back().duration_s;
}

Xyz ContinuousMachine::socket_mm() const {
    std::lock_guard lock(mutex_);
    return socket_;
}

void ContinuousMachine::advance_locked(double t_s) {
    const auto& E = setup_.errors;
    while (now_ < t_s) {
        // The piece of path the clock is in, and where it ends.
        double seg_end = 1e300;
        bool moving = false;
        if (!path_.empty()) {
            if (now_ < t0_.front()) {
                seg_end = t0_.front();
            } else {
                const auto it = std::upper_bound(t0_.begin(), t0_.end(), now_);
                const auto k = static_cast<std::size_t>(it - t0_.begin()) - 1;
                const double end = t0_[k] + path_[k].duration_s;
                if (now_ < end) {
                    seg_end = end;
                    moving = path_[k].kind != PathSegment::Kind::Dwell;
                } else if (k + 1 < t0_.size()) {
                    seg_end = t0_[k + 1];  // a zero-length piece: stand until the next
                }
            }
        }
        const double until = std::min(t_s, seg_end);
        const Xyz c0 = command_locked(now_);
        if (!moving) {
            // The command stands still: the lag's exact response in one step (no reversal can happen).
            const double h = until - now_;
            for (std::size_t a = 0; a < 3; ++a) {
                const double tau = E.axis[a].servo_lag_ms * 1e-3;
                if (tau > 0) {
                    axis_[a] = c0[a] + (axis_[a] - c0[a]) * std::exp(-h / tau);
                    velocity_[a] = (c0[a] - axis_[a]) / tau;
                } else {
                    axis_[a] = c0[a];
                    velocity_[a] = 0;
                }
            }
            now_ = until;
            continue;
        }
        const double h = std::min(kStepS, until - now_);
        const double t1 = h == until - now_ ? until : now_ + h;
        const Xyz c1 = command_locked(t1);
        for (std::size_t a = 0; a < 3; ++a) {
            const double tau = E.axis[a].servo_lag_ms * 1e-3;
            const double r = (c1[a] - c0[a]) / h;  // the command's rate over the step (first-order hold)
            const double v_old = velocity_[a];
            if (tau > 0) {
                axis_[a] = c1[a] - r * tau + (axis_[a] - c0[a] + r * tau) * std::exp(-h / tau);
                velocity_[a] = (c1[a] - axis_[a]) / tau;
            } else {
                axis_[a] = c1[a];
                velocity_[a] = r;
            }
            const double v = velocity_[a];
            if (std::abs(v) > kMovingMmPerS) {
                const int d = sign(v);
                if (direction_[a] != 0 && d != direction_[a]) {
                    // The axis reversed: when its velocity crossed zero inside the step.
                    const double frac = (sign(v_old) == direction_[a] && v_old != v) ? v_old / (v_old - v) : 1.0;
                    reversal_t_[a] = now_ + h * std::clamp(frac, 0.0, 1.0);
                    reversal_old_[a] = direction_[a];
                }
                direction_[a] = d;
            }
        }
        now_ = t1;
    }
}

Xyz ContinuousMachine::actual_locked() const {
    const auto& E = setup_.errors;
    Xyz e{0, 0, 0};
    for (std::size_t a = 0; a < 3; ++a) {
        const AxisErrors& ax = E.axis[a];
        e[a] -= direction_[a] * ax.backlash_um * 1e-3 / 2.0;
        if (reversal_old_[a] != 0 && ax.reversal_spike_um != 0)
            e[a] += reversal_old_[a] * ax.reversal_spike_um * 1e-3 * std::exp(-(now_ - reversal_t_[a]) / kSpikeTauS);
        e[a] += ax.scale_ppm * 1e-6 * axis_[a];
        if (ax.cyclic_pitch_mm > 0)
            e[a] += ax.cyclic_um * 1e-3 *
                    std::sin(kTwoPi * axis_[a] / ax.cyclic_pitch_mm + analysis::deg_to_rad(ax.cyclic_phase_deg));
        for (std::size_t b = 0; b < 3; ++b) {  // axis b's motion bows in axis a
            const double k = E.straightness_um_per_m2[b][a];
            if (k != 0 && a != b) {
                const double d_m = (axis_[b] - socket_[b]) * 1e-3;
                e[a] += k * d_m * d_m * 1e-3;
            }
        }
    }
    // Squareness in each plane's own convention: XY e_x = α·y, YZ e_y = α·z, ZX e_z = α·x.
    e[0] += E.squareness_um_per_m[0] * 1e-6 * axis_[1];
    e[1] += E.squareness_um_per_m[1] * 1e-6 * axis_[2];
    e[2] += E.squareness_um_per_m[2] * 1e-6 * axis_[0];
    return {axis_[0] + e[0], axis_[1] + e[1], axis_[2] + e[2]};
}

Xyz ContinuousMachine::actual_mm(double t_s) {
    std::lock_guard lock(mutex_);
    advance_locked(t_s);
    return actual_locked();
}

double ContinuousMachine::bar_length_mm(double t_s) {
    std::lock_guard lock(mutex_);
    advance_locked(t_s);
    const Xyz a = actual_locked();
    const Xyz& o = setup_.socket_offset_mm;
    const double len = std::hypot(a[0] - socket_[0] - o[0], a[1] - socket_[1] - o[1], a[2] - socket_[2] - o[2]);
    const auto& E = setup_.errors;
    double vib = 0;
    if (E.vibration_hz > 0 && E.vibration_um != 0)
        vib = E.vibration_um * 1e-3 *
              std::sin(kTwoPi * E.vibration_hz * now_ + analysis::deg_to_rad(E.vibration_phase_deg));
    return len + vib;
}

std::vector<std::pair<circ::Diag, double>> ContinuousMachine::truth(circ::Plane plane, double radius_mm) const {
    const auto ax = circ::plane_axis_index(plane);
    const auto p = static_cast<std::size_t>(ax[0]), q = static_cast<std::size_t>(ax[1]);
    const auto& E = setup_.errors;
    const auto& P = E.axis[p];
    const auto& Q = E.axis[q];
    const std::size_t plane_index = plane == circ::Plane::XY ? 0 : plane == circ::Plane::YZ ? 1 : 2;
    const double r_m = radius_mm * 1e-3;
    std::vector<std::pair<circ::Diag, double>> t = {
        {circ::Diag::BacklashP, P.backlash_um},
        {circ::Diag::BacklashQ, Q.backlash_um},
        {circ::Diag::SpikeP, P.reversal_spike_um},
        {circ::Diag::SpikeQ, Q.reversal_spike_um},
        {circ::Diag::Squareness, E.squareness_um_per_m[plane_index]},
        {circ::Diag::ScaleMismatch, P.scale_ppm - Q.scale_ppm},
        {circ::Diag::ServoMismatch, P.servo_lag_ms - Q.servo_lag_ms},
        {circ::Diag::CyclicP, P.cyclic_pitch_mm > 0 ? P.cyclic_um : 0.0},
        {circ::Diag::CyclicQ, Q.cyclic_pitch_mm > 0 ? Q.cyclic_um : 0.0},
        {circ::Diag::StraightnessP, E.straightness_um_per_m2[p][q] * r_m * r_m},
        {circ::Diag::StraightnessQ, E.straightness_um_per_m2[q][p] * r_m * r_m},
        {circ::Diag::Vibration, E.vibration_hz > 0 ? E.vibration_um : 0.0},
    };
    if (P.cyclic_pitch_mm > 0 && P.cyclic_um != 0) t.emplace_back(circ::Diag::CyclicPitchP, P.cyclic_pitch_mm);
    if (Q.cyclic_pitch_mm > 0 && Q.cyclic_um != 0) t.emplace_back(circ::Diag::CyclicPitchQ, Q.cyclic_pitch_mm);
    if (E.vibration_hz > 0 && E.vibration_um != 0) t.emplace_back(circ::Diag::VibrationHz, E.vibration_hz);
    return t;
}

std::vector<TruthComparison> compare_with_truth(const circ::CircularResult& result,
                                                const std::vector<std::pair<circ::Diag, double>>& truth) {
    std::vector<TruthComparison> out;
    const circ::TestSpec& test = result.test;
    for (const auto& [diag, value] : truth) {
        TruthComparison c;
        c.diag = diag;
        c.key = circ::diagnostic_key(diag, test.plane);
        c.truth = value;
        c.injected = value != 0;
        const bool rate =
            diag == circ::Diag::CyclicPitchP || diag == circ::Diag::CyclicPitchQ || diag == circ::Diag::VibrationHz;
        const double unit = circ::radial_um_per_unit(diag, test);
        const circ::DiagnosticResult* d = result.find(diag);
        if (d && (d->detected || !rate)) {
            c.measured = d->detected ? d->value : 0.0;
            c.std_uncertainty = d->std_uncertainty;
        }
        bool unseparable = false;
        for (const auto& g : result.unseparable)
            if (std::find(g.keys.begin(), g.keys.end(), c.key) != g.keys.end()) unseparable = true;
        if (rate) {
            c.allowed = 0.05 * std::abs(value);
        } else {
            const double floor_units = unit > 0 ? 0.25 / unit : 0.0;
            c.allowed = c.injected ? std::max(0.2 * std::abs(value), floor_units) : 2.0 * floor_units;
        }
        if (!c.measured) {
            c.note = unseparable ? "not separable on this data" : "not found";
            c.pass = !c.injected;
        } else if (c.injected) {
            c.pass = std::abs(*c.measured - value) <= c.allowed;
        } else {
            c.pass = std::abs(*c.measured) <= c.allowed;
        }
        out.push_back(c);
    }
    return out;
}

}  // namespace ballbar::device
