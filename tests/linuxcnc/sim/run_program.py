#!/usr/bin/python3
"""The test's 'display': machine on, home, run the program named by BALLBAR_PROGRAM, wait for its
end, let the sampler drain, exit 0 (or 2 on a timeout, 3 on an error message from LinuxCNC).
`linuxcnc -r` returns this exit status."""
import os
import subprocess
import sys
import time

import linuxcnc

stat, command, errors = linuxcnc.stat(), linuxcnc.command(), linuxcnc.error_channel()


def until(done, seconds, what):
    end = time.time() + seconds
    while time.time() < end:
        stat.poll()
        if done():
            return
        time.sleep(0.01)
    print("run_program: timed out waiting for " + what, flush=True)
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
command.feedrate(float(os.environ.get("BALLBAR_FEED_OVERRIDE", "1")))
command.program_open(os.environ["BALLBAR_PROGRAM"])
command.auto(linuxcnc.AUTO_RUN, 0)
until(lambda: stat.interp_state != linuxcnc.INTERP_IDLE, 10, "the program to start")
until(lambda: stat.interp_state == linuxcnc.INTERP_IDLE, 120, "the program to end")
message = errors.poll()
time.sleep(0.3)  # halsampler drains its FIFO
if os.environ.get("BALLBAR_SHOW_PINS"):  # the module's pins at the end, for the test to read
    shown = subprocess.run(["halcmd", "-s", "show", "pin", os.environ["BALLBAR_SHOW_PINS"]],
                           capture_output=True, text=True)
    print(shown.stdout, flush=True)
if message:
    print("run_program: LinuxCNC reported: %r" % (message,), flush=True)
    sys.exit(3)
print("run_program: done", flush=True)
sys.exit(0)
