// SPDX-License-Identifier: MIT
// The headless LinuxCNC configuration the loop runs (linuxcnc_loop.cpp writes it into its work
// directory, where a shop can read it): an XYZAC table-tilting machine with `ballbarkins`, a perfect
// servo loop, a sampler streaming the joints of every servo cycle to the emulated machine, and a display
// that is ballbar's operator at the console.
#pragma once

namespace ballbar::workflow::lcnc_config {

/// @KINEMATICS@, @HALCMDS@ are filled in per run.
inline constexpr const char* kIni =
    R"ini(# ballbar's LinuxCNC loop (ballbar demo --controller linuxcnc, docs/linuxcnc.md "The loop"):
# a headless XYZAC table-tilting machine with ballbarkins in its servo loop.
[EMC]
VERSION = 1.1
MACHINE = ballbar-loop
DEBUG = 0

[DISPLAY]
DISPLAY = ./ballbar_display.py

[RS274NGC]
PARAMETER_FILE = loop.var

[EMCMOT]
EMCMOT = motmod
COMM_TIMEOUT = 4.0
SERVO_PERIOD = 1000000

[TASK]
TASK = milltask
CYCLE_TIME = 0.001

[HAL]
HALFILE = ballbar-loop.hal
@HALCMDS@

[EMCIO]
EMCIO = io
CYCLE_TIME = 0.100
TOOL_TABLE = loop.tbl

[KINS]
KINEMATICS = @KINEMATICS@
JOINTS = 5

[TRAJ]
COORDINATES = XYZAC
LINEAR_UNITS = mm
ANGULAR_UNITS = degree
DEFAULT_LINEAR_VELOCITY = 50
MAX_LINEAR_VELOCITY = 400
MAX_LINEAR_ACCELERATION = 4000
NO_FORCE_HOMING = 1

[AXIS_X]
MIN_LIMIT = -400
MAX_LIMIT = 400
MAX_VELOCITY = 400
MAX_ACCELERATION = 4000
[AXIS_Y]
MIN_LIMIT = -400
MAX_LIMIT = 400
MAX_VELOCITY = 400
MAX_ACCELERATION = 4000
[AXIS_Z]
MIN_LIMIT = -400
MAX_LIMIT = 400
MAX_VELOCITY = 400
MAX_ACCELERATION = 4000
[AXIS_A]
MIN_LIMIT = -120
MAX_LIMIT = 120
MAX_VELOCITY = 360
MAX_ACCELERATION = 3600
[AXIS_C]
MIN_LIMIT = -36000
MAX_LIMIT = 36000
MAX_VELOCITY = 360
MAX_ACCELERATION = 3600

[JOINT_0]
TYPE = LINEAR
HOME = 0
MIN_LIMIT = -500
MAX_LIMIT = 500
MAX_VELOCITY = 400
MAX_ACCELERATION = 4000
FERROR = 10
MIN_FERROR = 10
HOME_SEARCH_VEL = 0
HOME_SEQUENCE = 0
[JOINT_1]
TYPE = LINEAR
HOME = 0
MIN_LIMIT = -500
MAX_LIMIT = 500
MAX_VELOCITY = 400
MAX_ACCELERATION = 4000
FERROR = 10
MIN_FERROR = 10
HOME_SEARCH_VEL = 0
HOME_SEQUENCE = 0
[JOINT_2]
TYPE = LINEAR
HOME = 0
MIN_LIMIT = -500
MAX_LIMIT = 500
MAX_VELOCITY = 400
MAX_ACCELERATION = 4000
FERROR = 10
MIN_FERROR = 10
HOME_SEARCH_VEL = 0
HOME_SEQUENCE = 0
[JOINT_3]
TYPE = ANGULAR
HOME = 0
MIN_LIMIT = -120
MAX_LIMIT = 120
MAX_VELOCITY = 360
MAX_ACCELERATION = 3600
FERROR = 10
MIN_FERROR = 10
HOME_SEARCH_VEL = 0
HOME_SEQUENCE = 0
[JOINT_4]
TYPE = ANGULAR
HOME = 0
MIN_LIMIT = -36000
MAX_LIMIT = 36000
MAX_VELOCITY = 360
MAX_ACCELERATION = 3600
FERROR = 10
MIN_FERROR = 10
HOME_SEARCH_VEL = 0
HOME_SEQUENCE = 0
)ini";

inline constexpr const char* kHal =
    R"hal(# ballbarkins, motion with a perfect servo loop (each joint's command is its feedback: the emulated
# machine is the servo), the tool-change handshakes closed, and the joints of every servo cycle to the
# emulated machine: sampler -> halsampler -> the FIFO ballbar reads (joints.fifo).
loadrt [KINS]KINEMATICS
loadrt [EMCMOT]EMCMOT servo_period_nsec=[EMCMOT]SERVO_PERIOD num_joints=[KINS]JOINTS
addf motion-command-handler servo-thread
addf motion-controller servo-thread

net j0 joint.0.motor-pos-cmd => joint.0.motor-pos-fb
net j1 joint.1.motor-pos-cmd => joint.1.motor-pos-fb
net j2 joint.2.motor-pos-cmd => joint.2.motor-pos-fb
net j3 joint.3.motor-pos-cmd => joint.3.motor-pos-fb
net j4 joint.4.motor-pos-cmd => joint.4.motor-pos-fb

net estop-loop iocontrol.0.user-enable-out => iocontrol.0.emc-enable-in
net tool-prep iocontrol.0.tool-prepare => iocontrol.0.tool-prepared
net tool-change iocontrol.0.tool-change => iocontrol.0.tool-changed
net tool-offset motion.tooloffset.z => ballbarkins.tool-offset

loadrt sampler depth=16000 cfg=fffff
addf sampler.0 servo-thread
net j0 => sampler.0.pin.0
net j1 => sampler.0.pin.1
net j2 => sampler.0.pin.2
net j3 => sampler.0.pin.3
net j4 => sampler.0.pin.4
loadusr halsampler -t joints.fifo
)hal";

inline constexpr const char* kToolTable = "T1 P1 Z0 ;ball-bar's tool ball\n";

/// The display: ballbar's operator at LinuxCNC's console. Commands on its standard input, events on its
/// standard output (prefixed, among LinuxCNC's own lines).
inline constexpr const char* kDisplay = R"py(#!/usr/bin/python3
"""ballbar's operator at LinuxCNC's console (ballbar demo --controller linuxcnc; docs/linuxcnc.md).

It switches the machine on and homes it, then takes commands on its standard input, one per line:
  run PATH   open the program and start it (cycle start)
  resume     cycle start at a program stop (M0)
  abort      stop the program
  quit       leave (LinuxCNC then shuts down; so does the end of the input)
and says what LinuxCNC does on its standard output, each line starting "ballbar-display: ":
  ready, started, paused LINE, resumed, idle, error TEXT.
"""
import select
import sys
import time

import linuxcnc

stat, command, errors = linuxcnc.stat(), linuxcnc.command(), linuxcnc.error_channel()


def say(*words):
    print("ballbar-display:", *words, flush=True)


def until(done, seconds, what):
    end = time.time() + seconds
    while time.time() < end:
        stat.poll()
        if done():
            return
        time.sleep(0.01)
    say("error", "timed out waiting for " + what)
    sys.exit(2)


command.state(linuxcnc.STATE_ESTOP_RESET)
command.wait_complete()
command.state(linuxcnc.STATE_ON)
command.wait_complete()
until(lambda: stat.task_state == linuxcnc.STATE_ON, 10, "machine on")
command.mode(linuxcnc.MODE_MANUAL)
command.wait_complete()
command.home(-1)
command.wait_complete()
until(lambda: all(stat.homed[i] for i in range(stat.joints)), 10, "homing")
command.mode(linuxcnc.MODE_AUTO)
command.wait_complete()
say("ready")

state = "idle"
while True:
    ready, _, _ = select.select([sys.stdin], [], [], 0.01)
    if ready:
        line = sys.stdin.readline()
        if not line:
            break
        words = line.split(None, 1)
        if not words:
            continue
        if words[0] == "run" and len(words) == 2:
            command.mode(linuxcnc.MODE_AUTO)
            command.wait_complete()
            command.program_open(words[1].strip())
            command.auto(linuxcnc.AUTO_RUN, 0)
            state = "starting"
        elif words[0] == "resume":
            command.auto(linuxcnc.AUTO_RESUME)
        elif words[0] == "abort":
            command.abort()
            command.wait_complete()
        elif words[0] == "quit":
            break
        else:
            say("error", "unknown command " + line.strip())
    stat.poll()
    message = errors.poll()
    if message:
        say("error", message[1].replace("\n", " "))
    paused = stat.task_paused or stat.interp_state == linuxcnc.INTERP_PAUSED
    busy = stat.interp_state != linuxcnc.INTERP_IDLE
    if state == "starting" and busy:
        state = "running"
        say("started")
    if state == "running" and paused:
        state = "paused"
        say("paused", stat.motion_line)
    elif state == "paused" and not paused:
        state = "running"
        say("resumed")
    if state in ("running", "paused") and not busy:
        state = "idle"
        say("idle")
time.sleep(0.3)
sys.exit(0)
)py";

}  // namespace ballbar::workflow::lcnc_config
