// SPDX-License-Identifier: MIT
// An independent generator of `ballbar-readings/1` readings for testing discovery on data it did not
// make: its own plan, its own kinematics written from docs/kinematics.md and the readings format
// (rotations right-handed about +X/+Y/+Z applied in the order written; a rotary axis turns points
// about its actual line, located and tilted by its location errors, by commanded + zero offset), and
// effects outside the discovery library: a periodic angular error of a rotary axis, backlash of a
// rotary axis, a non-linear positioning error of a linear axis, a location error drifting during the
// test. It calls nothing of analysis/ to make a reading: the only use of the project's types is
// `to_reading_set()`, which fills the reading struct as the file reader would.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "ballbar/analysis/reading.hpp"

namespace indep {

using V3 = Eigen::Vector3d;
using M3 = Eigen::Matrix3d;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

inline M3 rx(double a) {
    return Eigen::AngleAxisd(a, V3::UnitX()).toRotationMatrix();
}
inline M3 ry(double a) {
    return Eigen::AngleAxisd(a, V3::UnitY()).toRotationMatrix();
}
inline M3 rz(double a) {
    return Eigen::AngleAxisd(a, V3::UnitZ()).toRotationMatrix();
}
/// x turned by `angle` about the line through q along unit d.
inline V3 turn(const V3& q, const V3& d, double angle, const V3& x) {
    return q + Eigen::AngleAxisd(angle, d.normalized()) * (x - q);
}

struct Machine {
    std::string type = "TTTRR";  // "TTTRR", "RRTTT", "RTTTR"
    V3 tool = V3::Zero(), a_pivot = V3::Zero(), c_offset = V3::Zero();
    std::map<std::string, double>
        err;  // location errors, zero offsets, EXX.., C0Y.., bar_length, bar_kappa, spindle_growth
    // Outside the library.
    char angular_axis = 0;
    int angular_order = 1;
    double angular_amp_rad = 0, angular_phase_rad = 0;  // ε = amp·cos(kθ − phase)
    char backlash_axis = 0;
    double backlash_half_rad = 0;  // +b after a positive move, −b after a negative one
    char positioning_axis = 0;
    double positioning_p2_mm = 0;  // δ = p2·(x / 100 mm)²
    std::string drift_param;       // a location error drifting: value + drift·t
    double drift_per_h = 0;
    // The instrument.
    double noise_mm = 0.0003;
    int samples = 40;
    std::vector<V3> socket_offsets;  // set-up offsets, table frame

    double e(const std::string& k) const {
        const auto it = err.find(k);
        return it == err.end() ? 0.0 : it->second;
    }
};

struct Row {
    double t = 0, X = 0, Y = 0, Z = 0, r1_deg = 0, r2_deg = 0;  // r1 = A; r2 = C (TTTRR) or B
    V3 socket = V3::Zero();
    double measured = 0, bar_T = 20, air_T = 20, std_mm = 0;
    int location = 0, point = 0, n = 0;
};

struct Readings {
    Machine m;
    std::vector<Row> rows;

    std::string machine_json() const {
        char buf[400];
        if (m.type == "TTTRR")
            std::snprintf(
                buf, sizeof buf,
                "{\"type\":\"TTTRR\",\"name\":\"indep\",\"a_pivot_mm\":[%.6f,%.6f,%.6f],\"c_offset_mm\":[%.6f,"
                "%.6f,%.6f],\"tool_ball_mm\":[%.6f,%.6f,%.6f]}",
                m.a_pivot.x(), m.a_pivot.y(), m.a_pivot.z(), m.c_offset.x(), m.c_offset.y(), m.c_offset.z(), m.tool.x(),
                m.tool.y(), m.tool.z());
        else if (m.type == "RRTTT")
            std::snprintf(buf, sizeof buf, "{\"type\":\"RRTTT\",\"name\":\"indep\",\"tool_ball_mm\":[%.6f,%.6f,%.6f]}",
                          m.tool.x(), m.tool.y(), m.tool.z());
        else
            std::snprintf(
                buf, sizeof buf,
                "{\"type\":\"RTTTR\",\"name\":\"indep\",\"tool_ball_mm\":[%.6f,%.6f,%.6f],\"a_pivot_mm\":[%.6f,"
                "%.6f,%.6f]}",
                m.tool.x(), m.tool.y(), m.tool.z(), m.a_pivot.x(), m.a_pivot.y(), m.a_pivot.z());
        return buf;
    }

    /// The file text, columns in an order of its own.
    std::string text() const {
        const char* r2 = m.type == "TTTRR" ? "C_deg" : "B_deg";
        std::string out = "# ballbar-readings/1\n# machine: " + machine_json() + "\n";
        out += std::string("measured_mm,n,std_mm,time_s,A_deg,") + r2 +
               ",X_mm,Y_mm,Z_mm,socket_x_mm,socket_y_mm,socket_z_mm,bar_temp_C,air_temp_C,location,point\n";
        char line[512];
        for (const Row& r : rows) {
            std::snprintf(line, sizeof line,
                          "%.7f,%d,%.7f,%.1f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.4f,%.4f,%d,%d\n", r.measured,
                          r.n, r.std_mm, r.t, r.r1_deg, r.r2_deg, r.X, r.Y, r.Z, r.socket.x(), r.socket.y(),
                          r.socket.z(), r.bar_T, r.air_T, r.location, r.point);
            out += line;
        }
        return out;
    }

    /// The readings as the file reader fills them (degrees to radians; values rounded as in the file).
    ballbar::analysis::ReadingSet to_reading_set() const {
        ballbar::analysis::ReadingSet s;
        s.machine.type = m.type == "TTTRR"   ? ballbar::analysis::MachineType::TTTRR
                         : m.type == "RRTTT" ? ballbar::analysis::MachineType::RRTTT
                                             : ballbar::analysis::MachineType::RTTTR;
        s.machine.name = "indep";
        s.machine.tool_ball_mm = m.tool;
        s.machine.a_pivot_mm = m.a_pivot;
        s.machine.c_offset_mm = m.c_offset;
        auto round_to = [](double v, double q) { return std::round(v / q) * q; };
        for (const Row& r : rows) {
            ballbar::analysis::Reading rd;
            rd.pose.X_mm = round_to(r.X, 1e-6);
            rd.pose.Y_mm = round_to(r.Y, 1e-6);
            rd.pose.Z_mm = round_to(r.Z, 1e-6);
            rd.pose.A_rad = round_to(r.r1_deg, 1e-6) * kDeg;
            (m.type == "TTTRR" ? rd.pose.C_rad : rd.pose.B_rad) = round_to(r.r2_deg, 1e-6) * kDeg;
            rd.socket_mm = V3(round_to(r.socket.x(), 1e-6), round_to(r.socket.y(), 1e-6), round_to(r.socket.z(), 1e-6));
            rd.measured_mm = round_to(r.measured, 1e-7);
            rd.time_s = r.t;
            rd.bar_temp_C = round_to(r.bar_T, 1e-4);
            rd.air_temp_C = round_to(r.air_T, 1e-4);
            rd.location = r.location;
            rd.point = r.point;
            rd.n = r.n;
            rd.std_mm = round_to(r.std_mm, 1e-7);
            s.readings.push_back(rd);
        }
        return s;
    }
};

/// The tool ball b and table ball s of the actual machine at one reading (machine frame).
struct Balls {
    V3 b, s;
};

inline Balls actual_balls(const Machine& m, const Row& r, double approach1, double approach2) {
    const double h = r.t / 3600.0;
    auto e = [&](const std::string& k) { return m.e(k) + (k == m.drift_param ? m.drift_per_h * h : 0.0); };
    const char ax1 = 'A', ax2 = m.type == "TTTRR" ? 'C' : 'B';
    auto angle = [&](char ax, double commanded_deg, double approach) {
        double a = commanded_deg * kDeg + e(std::string(1, ax) + "_zero");
        if (ax == m.angular_axis)
            a += m.angular_amp_rad * std::cos(m.angular_order * commanded_deg * kDeg - m.angular_phase_rad);
        if (ax == m.backlash_axis) a += m.backlash_half_rad * approach;
        return a;
    };
    const double a1 = angle(ax1, r.r1_deg, approach1), a2 = angle(ax2, r.r2_deg, approach2);
    // Linear axes: positioning error, scale, squareness (first order), spindle growth.
    double x = r.X, y = r.Y, z = r.Z;
    auto nonlinear = [&](char ax, double v) {
        return ax == m.positioning_axis ? m.positioning_p2_mm * (v / 100.0) * (v / 100.0) : 0.0;
    };
    x = x * (1 + e("EXX")) + nonlinear('X', r.X);
    y = y * (1 + e("EYY")) + nonlinear('Y', r.Y);
    z = z * (1 + e("EZZ")) + nonlinear('Z', r.Z);
    V3 p(x - y * e("C0Y") + z * e("B0Z"), y - z * e("A0Z"), z);
    p.z() += e("spindle_growth") * h;
    const V3 a_dir = rz(e("C0A")) * ry(e("B0A")) * V3::UnitX();
    const V3 b_dir = rz(e("C0B")) * rx(e("A0B")) * V3::UnitY();
    const V3 c_dir = ry(e("B0C")) * rx(e("A0C")) * V3::UnitZ();
    const V3 tool = m.tool - V3(0, 0, e("tool_length"));
    const int k = (r.location % 100000) / 1000;  // socket index
    const V3 socket =
        r.socket +
        (k < static_cast<int>(m.socket_offsets.size()) ? m.socket_offsets[static_cast<std::size_t>(k)] : V3::Zero());
    Balls out;
    if (m.type == "TTTRR") {
        const V3 qa = m.a_pivot + V3(0, e("Y0A"), e("Z0A"));
        const V3 qc = m.a_pivot + m.c_offset + V3(e("X0C"), e("Y0C"), 0);
        out.b = p + tool;
        out.s = turn(qa, a_dir, a1, turn(qc, c_dir, a2, m.a_pivot + m.c_offset + socket));
    } else if (m.type == "RRTTT") {
        const V3 qa = p + V3(0, e("Y0A"), e("Z0A"));
        const V3 qb = p + V3(e("X0B"), 0, e("Z0B"));
        out.b = turn(qa, a_dir, a1, turn(qb, b_dir, a2, p + tool));
        out.s = socket;
    } else {
        const V3 qb = p + V3(e("X0B"), 0, e("Z0B"));
        const V3 qa = m.a_pivot + V3(0, e("Y0A"), e("Z0A"));
        out.b = turn(qb, b_dir, a2, p + tool);
        out.s = turn(qa, a_dir, a1, m.a_pivot + socket);
    }
    return out;
}

/// TTTRR: the tool ball of the actual machine in the table frame (where it is on the workpiece).
inline V3 actual_tool_in_table(const Machine& m, const Row& r) {
    const Balls balls = actual_balls(m, r, 0, 0);
    const double h = r.t / 3600.0;
    auto e = [&](const std::string& k) { return m.e(k) + (k == m.drift_param ? m.drift_per_h * h : 0.0); };
    double a1 = r.r1_deg * kDeg + e("A_zero"), a2 = r.r2_deg * kDeg + e("C_zero");
    if (m.angular_axis == 'A')
        a1 += m.angular_amp_rad * std::cos(m.angular_order * r.r1_deg * kDeg - m.angular_phase_rad);
    if (m.angular_axis == 'C')
        a2 += m.angular_amp_rad * std::cos(m.angular_order * r.r2_deg * kDeg - m.angular_phase_rad);
    const V3 a_dir = rz(e("C0A")) * ry(e("B0A")) * V3::UnitX();
    const V3 c_dir = ry(e("B0C")) * rx(e("A0C")) * V3::UnitZ();
    const V3 qa = m.a_pivot + V3(0, e("Y0A"), e("Z0A"));
    const V3 qc = m.a_pivot + m.c_offset + V3(e("X0C"), e("Y0C"), 0);
    return turn(qc, c_dir, -a2, turn(qa, a_dir, -a1, balls.b)) - (m.a_pivot + m.c_offset);
}

/// The nominal table ball (machine frame) and the command that puts the nominal tool ball at `target`.
inline V3 nominal_table_ball(const Machine& m, double r1_deg, double r2_deg, const V3& socket) {
    if (m.type == "TTTRR") return m.a_pivot + rx(r1_deg * kDeg) * (m.c_offset + rz(r2_deg * kDeg) * socket);
    if (m.type == "RRTTT") return socket;
    return m.a_pivot + rx(r1_deg * kDeg) * socket;
}
inline V3 command_for(const Machine& m, double r1_deg, double r2_deg, const V3& target) {
    if (m.type == "TTTRR") return target - m.tool;
    if (m.type == "RRTTT") return target - rx(r1_deg * kDeg) * ry(r2_deg * kDeg) * m.tool;
    return target - ry(r2_deg * kDeg) * m.tool;
}

/// The plan: 3 sockets; per socket the rotary pairs in a serpentine order (the second axis up, then
/// down); per pair one bar direction along +Z and six on the 54.74° cone.
inline std::vector<std::pair<double, double>> rotary_pairs(const std::string& type) {
    std::vector<std::pair<double, double>> out;
    if (type == "TTTRR") {
        int row = 0;
        for (double a : {0.0, 30.0, -30.0}) {
            std::vector<double> cs;
            for (int c = 0; c < 12; ++c) cs.push_back(30.0 * c);
            if (row++ % 2) std::reverse(cs.begin(), cs.end());
            for (double c : cs) out.emplace_back(a, c);
        }
    } else {
        int row = 0;
        for (double a : {-40.0, -20.0, 0.0, 20.0, 40.0}) {
            std::vector<double> bs{-60, -40, -20, 0, 20, 40, 60};
            if (row++ % 2) std::reverse(bs.begin(), bs.end());
            for (double b : bs) out.emplace_back(a, b);
        }
    }
    return out;
}

inline Machine base_machine(const std::string& type, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Machine m;
    m.type = type;
    std::vector<std::string> loc_mm, loc_rad;
    if (type == "TTTRR") {
        m.c_offset = V3(0, 0, -100);
        loc_mm = {"Y0A", "Z0A", "X0C", "Y0C"};
        loc_rad = {"B0A", "C0A", "A0C", "B0C", "A_zero", "C_zero"};
    } else if (type == "RRTTT") {
        m.tool = V3(0, 0, -150);
        loc_mm = {"Y0A", "Z0A", "X0B", "Z0B"};
        loc_rad = {"B0A", "C0A", "A0B", "C0B", "A_zero", "B_zero"};
    } else {
        m.tool = V3(0, 0, -150);
        loc_mm = {"Y0A", "Z0A", "X0B", "Z0B"};
        loc_rad = {"B0A", "C0A", "A0B", "C0B", "A_zero", "B_zero"};
    }
    for (const auto& k : loc_mm) m.err[k] = 0.05 * u(rng);
    for (const auto& k : loc_rad) m.err[k] = 100e-6 * u(rng);
    for (int s = 0; s < 3; ++s) m.socket_offsets.emplace_back(0.03 * u(rng), 0.03 * u(rng), 0.03 * u(rng));
    return m;
}

inline std::vector<V3> plan_sockets(const std::string& type) {
    if (type == "TTTRR") return {V3(110, 10, 40), V3(-70, 90, 40), V3(-50, -110, 70)};
    if (type == "RRTTT") return {V3(10, 0, -400), V3(140, 110, -420), V3(-150, -70, -380)};
    return {V3(10, 110, 40), V3(110, -50, 40), V3(-90, -70, 70)};
}

/// The plan measured `repeat` times in one session, `seconds_per_reading` apart.
inline Readings generate(const Machine& m, std::mt19937_64& rng, int repeat = 1, double seconds_per_reading = 12.0,
                         double bar_mm = 100.0) {
    Readings out;
    out.m = m;
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::chi_squared_distribution<double> chi2(m.samples - 1);
    std::vector<V3> dirs{V3::UnitZ()};
    const double cone = std::acos(1.0 / std::sqrt(3.0));
    for (int k = 0; k < 6; ++k)
        dirs.emplace_back(std::sin(cone) * std::cos(60.0 * k * kDeg), std::sin(cone) * std::sin(60.0 * k * kDeg),
                          std::cos(cone));
    const auto sockets = plan_sockets(m.type);
    const auto pairs = rotary_pairs(m.type);
    double t = 0;
    double prev1 = 0, prev2 = 0, app1 = 0, app2 = 0;
    bool first = true;
    for (int rep = 0; rep < repeat; ++rep)
        for (std::size_t k = 0; k < sockets.size(); ++k)
            for (std::size_t p = 0; p < pairs.size(); ++p) {
                const auto [a1, a2] = pairs[p];
                if (!first) {
                    if (a1 != prev1) app1 = a1 > prev1 ? 1 : -1;
                    if (a2 != prev2) app2 = a2 > prev2 ? 1 : -1;
                }
                first = false;
                prev1 = a1;
                prev2 = a2;
                const V3 s_nom = nominal_table_ball(m, a1, a2, sockets[k]);
                for (std::size_t d = 0; d < dirs.size(); ++d) {
                    Row r;
                    r.t = t;
                    t += seconds_per_reading;
                    r.r1_deg = a1;
                    r.r2_deg = a2;
                    r.socket = sockets[k];
                    r.location = static_cast<int>(k * 1000 + p) + rep * 100000;
                    r.point = static_cast<int>(d);
                    const V3 cmd = command_for(m, a1, a2, s_nom + bar_mm * dirs[d]);
                    r.X = cmd.x();
                    r.Y = cmd.y();
                    r.Z = cmd.z();
                    r.bar_T = 20.4 + 0.8 * r.t / 3600.0 + 0.3 * std::sin(2 * 3.14159265358979 * r.t / 1700.0);
                    r.air_T = 20.2 + 0.5 * r.t / 3600.0 + 0.2 * std::sin(2 * 3.14159265358979 * r.t / 2300.0);
                    const Balls balls = actual_balls(m, r, app1, app2);
                    const double len = (balls.b - balls.s).norm();
                    r.measured =
                        len * (1 + m.e("bar_kappa") * (r.bar_T - 20.0)) + m.e("bar_length") + m.noise_mm * gauss(rng);
                    r.n = m.samples;
                    r.std_mm =
                        m.noise_mm * std::sqrt(static_cast<double>(m.samples)) * std::sqrt(chi2(rng) / (m.samples - 1));
                    out.rows.push_back(r);
                }
            }
    // Locations numbered from 0 in the file.
    int loc = 0;
    int last = -1;
    for (Row& r : out.rows) {
        if (r.location != last) {
            last = r.location;
            r.location = loc++;
        } else {
            r.location = loc - 1;
        }
    }
    return out;
}

/// One test case: the machine, and what discovery should find.
struct Scenario {
    Machine m;
    std::string kind;            // "clean", "angular", "backlash", "positioning", "drift"
    std::string family;          // the family it lives in ("C_angular", "time", ...), empty for clean
    std::string library_effect;  // the library effect hidden next to it, empty for none
};

inline const std::vector<std::string>& kinds() {
    static const std::vector<std::string> k{"angular", "backlash", "positioning", "drift"};
    return k;
}

/// `kind` outside the library on a random machine of `type`; with `with_library`, one library effect
/// (scale of X, spindle growth, bar length offset, squareness XY in turn by seed) next to it.
inline Scenario make_scenario(const std::string& type, const std::string& kind, bool with_library, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto sign = [&] { return u(rng) < 0.5 ? -1.0 : 1.0; };
    Scenario sc;
    sc.m = base_machine(type, rng);
    sc.kind = kind;
    const char second = type == "TTTRR" ? 'C' : 'B';
    if (kind == "angular") {
        // TTTRR: the table's C; RRTTT: the head's B; RTTTR: the table's A.
        sc.m.angular_axis = type == "TTTRR" ? 'C' : type == "RRTTT" ? 'B' : 'A';
        sc.m.angular_order = 1;
        sc.m.angular_amp_rad = (50 + 50 * u(rng)) * 1e-6;
        sc.m.angular_phase_rad = 2 * 3.14159265358979 * u(rng);
        sc.family = std::string(1, sc.m.angular_axis) + "_angular";
    } else if (kind == "backlash") {
        sc.m.backlash_axis = type == "RRTTT" ? 'A' : second;
        sc.m.backlash_half_rad = (15 + 15 * u(rng)) * 1e-6;
        sc.family = std::string(1, sc.m.backlash_axis) + "_backlash";
    } else if (kind == "positioning") {
        sc.m.positioning_axis = type == "RRTTT" ? 'Y' : 'X';
        sc.m.positioning_p2_mm = sign() * (0.003 + 0.004 * u(rng));
        sc.family = std::string(1, sc.m.positioning_axis) + "_positioning";
    } else if (kind == "drift") {
        sc.m.drift_param = type == "TTTRR" ? "X0C" : type == "RRTTT" ? "Z0B" : "Y0A";
        sc.m.drift_per_h = sign() * (0.008 + 0.008 * u(rng));
        sc.family = "time";
    }
    if (with_library) {
        switch (seed % 4) {
            case 0:
                sc.m.err["EXX"] = sign() * (20 + 40 * u(rng)) * 1e-6;
                sc.library_effect = "scale_X";
                break;
            case 1:
                sc.m.err["spindle_growth"] = sign() * (0.01 + 0.02 * u(rng));
                sc.library_effect = "spindle_thermal_growth";
                break;
            case 2:
                sc.m.err["bar_length"] = sign() * (0.005 + 0.015 * u(rng));
                sc.library_effect = "bar_length_offset";
                break;
            default:
                sc.m.err["C0Y"] = sign() * (20 + 40 * u(rng)) * 1e-6;
                sc.library_effect = "squareness_XY";
                break;
        }
    }
    return sc;
}

}  // namespace indep
