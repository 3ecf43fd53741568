// SPDX-License-Identifier: MIT
// An erroneous table-tilting machine (TTTRR) written for the tests from docs/kinematics.md alone —
// Rodrigues' formula about each displaced, tilted axis line — and the controller's nominal
// tool-centre-point kinematics. Independent of analysis/ (no Eigen, no code of ours): tests of
// the compensator, `ballbar compensate` and the LinuxCNC module check against it.
#pragma once

#include <cmath>

namespace ballbar::test::tttrr {

constexpr double kPi = 3.141592653589793;
inline double rad(double deg) {
    return deg * kPi / 180;
}

struct V {
    double x = 0, y = 0, z = 0;
};
inline V operator+(V a, V b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline V operator-(V a, V b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline V operator*(double s, V a) {
    return {s * a.x, s * a.y, s * a.z};
}
inline double dot(V a, V b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline V cross(V a, V b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(V a) {
    return std::sqrt(dot(a, a));
}
/// Rodrigues: v turned by angle t about the unit axis d.
inline V turn(V d, double t, V v) {
    return std::cos(t) * v + std::sin(t) * cross(d, v) + ((1 - std::cos(t)) * dot(d, v)) * d;
}
inline V rot_x(double t, V v) {
    return turn({1, 0, 0}, t, v);
}
inline V rot_y(double t, V v) {
    return turn({0, 1, 0}, t, v);
}
inline V rot_z(double t, V v) {
    return turn({0, 0, 1}, t, v);
}

/// The machine's nominal geometry: a point of the A axis, and the C frame's origin from it.
struct Geometry {
    V a_pivot{0, 0, 0};
    V c_offset{0, 0, -100};
};

/// The error parameters these tests inject (mm, rad, mm/mm; docs/kinematics.md's table).
struct Errors {
    double Y0A = 0, Z0A = 0, B0A = 0, C0A = 0, X0C = 0, Y0C = 0, A0C = 0, B0C = 0, A_zero = 0, C_zero = 0, EXX = 0,
           EYY = 0, C0Y = 0;
};

/// Location errors of tens of µm and tilts of tens of µrad, as the seed's machine had.
inline Errors seed_like() {
    Errors e;
    e.Y0A = 0.025, e.Z0A = -0.018, e.B0A = 4e-5, e.C0A = -3e-5, e.X0C = 0.035, e.Y0C = -0.022, e.A0C = 5e-5;
    e.B0C = -3.5e-5, e.A_zero = 2e-5, e.C_zero = -3e-5, e.EXX = 8e-6, e.EYY = -6e-6, e.C0Y = 1e-5;
    return e;
}

/// Where the tool point is relative to the table (the table frame) and the tool axis there, when the
/// machine is commanded to (X, Y, Z, A, C) (mm, rad) and the tool point sits `tool` from the
/// commanded point.
struct Seen {
    V position, axis;
};
inline Seen actual_tool_in_table(const Geometry& g, const Errors& e, double X, double Y, double Z, double A, double C,
                                 V tool) {
    const double x = X * (1 + e.EXX), y = Y * (1 + e.EYY), z = Z;
    const V m = V{x - y * e.C0Y, y, z} + tool;  // the linear axes, then the tool
    const V a_dir = rot_z(e.C0A, rot_y(e.B0A, {1, 0, 0}));
    const V c_dir = rot_y(e.B0C, rot_x(e.A0C, {0, 0, 1}));
    const V qa = g.a_pivot + V{0, e.Y0A, e.Z0A};
    const V p0 = g.a_pivot + g.c_offset;
    const V qc = p0 + V{e.X0C, e.Y0C, 0};
    // Table point x is at qa + Ra(qc + Rc(x + p0 − qc) − qa); inverted for the tool point and axis.
    const double ta = A + e.A_zero, tc = C + e.C_zero;
    const V in_a = turn(a_dir, -ta, m - qa) + qa - qc;
    const V pos = turn(c_dir, -tc, in_a) + qc - p0;
    const V axis = turn(c_dir, -tc, turn(a_dir, -ta, {0, 0, 1}));
    return {pos, axis};
}

/// The controller's nominal tool-centre-point kinematics: workpiece (world = machine at A = C = 0)
/// point w to the machine position of the tool point.
inline V tcp_machine(const Geometry& g, V w, double A, double C) {
    return g.a_pivot + rot_x(A, g.c_offset + rot_z(C, w - g.a_pivot - g.c_offset));
}

/// The table-frame point (C frame origin at a_pivot + c_offset) of a world point: the world is the
/// machine frame at A = C = 0.
inline V table_point(const Geometry& g, V w) {
    return w - g.a_pivot - g.c_offset;
}

}  // namespace ballbar::test::tttrr
