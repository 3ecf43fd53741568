#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# Writes the discovery test files discovery_*.csv in `ballbar-readings/1` with code independent of
# ballbar's: its own TTTRR kinematics (readings.md's table; A- and C-axis line position errors Y0A,
# Z0A, X0C, Y0C as rotations about displaced lines), its own SSM-like plan, columns in another order,
# extra columns, quoted fields and CRLF line ends. Deterministic (fixed seed).
#   python3 discovery_make.py   (run in this directory)
import math
import random


def rx(a, v):
    c, s = math.cos(a), math.sin(a)
    return [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]]


def rz(a, v):
    c, s = math.cos(a), math.sin(a)
    return [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]


def add(a, b):
    return [x + y for x, y in zip(a, b)]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def norm(v):
    return math.sqrt(sum(x * x for x in v))


A_PIVOT = [0.0, 0.0, 0.0]
C_OFFSET = [0.0, 0.0, -80.0]
TOOL = [0.0, 0.0, 0.0]
BAR = 150.0


def table_ball(a, c, socket, err):
    """Actual table ball: C about the line through a_pivot + c_offset + (X0C, Y0C, 0), then A about the
    line through a_pivot + (0, Y0A, Z0A). With zero errors: a_pivot + Rx(A)(c_offset + Rz(C) socket)."""
    s0 = add(add(A_PIVOT, C_OFFSET), socket)
    qc = add(add(A_PIVOT, C_OFFSET), [err["X0C"], err["Y0C"], 0.0])
    sc = add(qc, rz(c, sub(s0, qc)))
    qa = add(A_PIVOT, [0.0, err["Y0A"], err["Z0A"]])
    return add(qa, rx(a, sub(sc, qa)))


def write(path, growth_mm_per_h, seed):
    rng = random.Random(seed)
    err = {"Y0A": 0.021, "Z0A": -0.034, "X0C": 0.017, "Y0C": -0.012}
    sockets = [[90.0, 30.0, 25.0], [-40.0, 95.0, 25.0], [-70.0, -60.0, 45.0], [20.0, -110.0, 35.0]]
    offsets = [[rng.uniform(-0.02, 0.02) for _ in range(3)] for _ in sockets]
    pairs = [(0, 0), (0, 120), (0, 240), (25, 45), (25, 200), (-25, 100), (-25, 300), (50, 0), (50, 180), (-50, 270)]
    cone = math.radians(60.0)
    dirs = [[0.0, 0.0, 1.0]] + [[math.sin(cone) * math.cos(math.radians(k * 72 + 10)),
                                 math.sin(cone) * math.sin(math.radians(k * 72 + 10)), math.cos(cone)] for k in range(5)]
    rows = []
    t = 3.0
    for a_deg, c_deg in pairs:
        for k, sock in enumerate(sockets):
            a, c = math.radians(a_deg), math.radians(c_deg)
            s_nom = add(A_PIVOT, rx(a, add(C_OFFSET, rz(c, sock))))
            s_act = table_ball(a, c, add(sock, offsets[k]), err)
            for i, d in enumerate(dirs):
                b_nom = add(s_nom, [BAR * x for x in d])
                cmd = sub(b_nom, TOOL)
                b_act = add(cmd, TOOL)
                b_act[2] += growth_mm_per_h * t / 3600.0
                measured = norm(sub(b_act, s_act)) + rng.gauss(0.0, 0.0004)
                temp = 20.8 + 0.3 * math.sin(t / 700.0)
                rows.append([f"{BAR:.6f}", f"{measured:.7f}", f"{c_deg:g}", f"{a_deg:g}", f"{cmd[2]:.6f}",
                             f"{cmd[1]:.6f}", f"{cmd[0]:.6f}", f"{sock[2]:g}", f"{sock[1]:g}", f"{sock[0]:g}",
                             f"{t:.1f}", f"{temp:.3f}", '"pt, ok"', str(i), f"{21.3:.1f}"])
                t += 9.5
    with open(path, "w", newline="") as f:
        f.write("# ballbar-readings/1\r\n")
        f.write('# machine: {"type":"TTTRR","name":"third-party TTTRR","a_pivot_mm":[0,0,0],'
                '"c_offset_mm":[0,0,-80],"tool_ball_mm":[0,0,0]}\r\n')
        f.write('# instrument: {"model":"other-bar","serial":"X-17","calibrated_length_mm":150.0}\r\n')
        f.write("# written by tests/data/readings/discovery_make.py, not by ballbar\r\n")
        f.write("nominal_mm,measured_mm,C_deg,A_deg,Z_mm,Y_mm,X_mm,socket_z_mm,socket_y_mm,socket_x_mm,"
                "time_s,bar_temp_C,comment,point,coolant_temp_C\r\n")
        for r in rows:
            f.write(",".join(r) + "\r\n")


write("discovery_spindle_growth.csv", 0.025, 11)
write("discovery_none.csv", 0.0, 12)
