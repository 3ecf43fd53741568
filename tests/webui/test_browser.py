#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""`ballbar serve` in a real browser: headless Chromium, driven by Selenium, clicks through a whole
circular demo and a whole SSM demo as an operator would, and checks what the operator sees: each step
and its question, the live reading moving, the points and their verdicts, the results and the polar plot
drawn, the session in the list, the PDF report downloaded, and no error on the browser's console.
Screenshots of every step are kept in --out for a person to look at (docs/webui.md shows them).

Exit 0: passed; 1: failed (the message says what); 77: skipped (no Chromium, driver or Selenium).
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.request

SKIP = 77


def skip(why):
    print("SKIP: " + why)
    sys.exit(SKIP)


try:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
except ImportError:
    skip("python3-selenium is not installed (scripts/install-deps.sh)")

CHROMIUM = shutil.which("chromium")
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
if not CHROMIUM or not os.path.exists(DRIVER):
    skip("chromium or chromium-driver is not installed (scripts/install-deps.sh)")


class Failed(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Failed(what)
    print("  ok: " + what)


def wait(cond, what, timeout=60.0, every=0.05):
    until = time.monotonic() + timeout
    while time.monotonic() < until:
        try:
            v = cond()
        except Exception:  # noqa: BLE001 — a page between two renders
            v = None
        if v:
            return v
        time.sleep(every)
    raise Failed("timed out waiting for " + what)


class Page:
    def __init__(self, url, out, downloads):
        self.url = url
        self.out = out
        self.shots = 0
        opts = webdriver.ChromeOptions()
        opts.binary_location = CHROMIUM
        for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                  "--no-first-run", "--disable-extensions", "--window-size=1280,1000"):
            opts.add_argument(a)
        opts.set_capability("goog:loggingOptions", {"browser": "ALL"})
        opts.add_experimental_option("prefs", {"download.default_directory": downloads,
                                               "download.prompt_for_download": False})
        self.d = webdriver.Chrome(service=Service(DRIVER), options=opts)
        # The viewport itself (--window-size is the window, not the page).
        self.d.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                               {"width": 1280, "height": 1000, "deviceScaleFactor": 1, "mobile": False})
        self.d.execute_cdp_cmd("Page.setDownloadBehavior", {"behavior": "allow", "downloadPath": downloads})

    def js(self, script, *args):
        return self.d.execute_script(script, *args)

    def shot(self, name):
        self.shots += 1
        path = os.path.join(self.out, "%02d-%s.png" % (self.shots, name))
        # The whole page, not only the viewport.
        h = self.js("return document.documentElement.scrollHeight")
        self.d.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                               {"width": 1280, "height": max(1000, int(h)), "deviceScaleFactor": 1, "mobile": False})
        self.d.save_screenshot(path)
        self.d.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                               {"width": 1280, "height": 1000, "deviceScaleFactor": 1, "mobile": False})
        return path

    def by_id(self, id_):
        return self.d.find_element(By.ID, id_)

    def visible(self, id_):
        return self.by_id(id_).is_displayed()

    def console_errors(self):
        return [e for e in self.d.get_log("browser") if e.get("level") == "SEVERE"]

    def question(self):
        """The question on screen once its buttons are armed: (what the state says, its buttons)."""
        s = self.js("return window.__state ? JSON.stringify(window.__state) : null")
        if not s:
            return None
        state = json.loads(s)
        q = state.get("question")
        if not q:
            return None
        buttons = [b for b in self.d.find_elements(By.CSS_SELECTOR, "#answers button") if b.is_displayed()]
        if not buttons or any(not b.is_enabled() for b in buttons):
            return None
        if self.by_id("answers").get_attribute("data-q") != str(q["id"]):
            return None
        return q, buttons


def run_procedure(p, start_button, name, expect_whats):
    """Starts a demo with its button and answers every question with its first option, as an operator;
    returns the final state."""
    p.js("""
      window.__live = 0;
      new MutationObserver(() => { window.__live++; }).observe(document.getElementById('live-um'),
        {childList: true, characterData: true, subtree: true});""")
    p.by_id(start_button).click()
    wait(lambda: p.visible("run"), "the procedure's screen")
    seen = []
    first = True
    while True:
        got = wait(lambda: p.question() or (not json.loads(p.js("return JSON.stringify(window.__state)"))["running"]
                                             and "end"), name + ": the next question or the end", timeout=120)
        if got == "end":
            break
        q, buttons = got
        what = q["what"]
        step = p.by_id("step-title").text
        if what not in seen:
            p.shot("%s-%s" % (name, what))
            seen.append(what)
            print("  step: %s | %s | %s" % (step, what, q["prompt"][:90].replace("\n", " ")))
        check(re.match(r"Step \d of 6: ", step) is not None, "%s: the step is shown (%s)" % (what, step))
        if first:
            first = False
            # "Not yet" answers nothing: the same question stays, with a note.
            not_yet = [b for b in buttons if b.get_attribute("id") == "not-yet"]
            check(len(not_yet) == 1, "the first question has a Not yet button")
            not_yet[0].click()
            time.sleep(0.5)
            again = p.question()
            check(again is not None and again[0]["id"] == q["id"] and p.visible("not-yet-note"),
                  "Not yet keeps the question and the session")
        buttons[0].click()
        wait(lambda: p.by_id("answers").get_attribute("data-q") != str(q["id"]) or not p.question(),
             "the answer to be taken")
    state = json.loads(p.js("return JSON.stringify(window.__state)"))
    for w in expect_whats:
        check(w in seen, "%s: the question '%s' was asked on the page" % (name, w))
    return state


def observe(p, client):
    """The page's last state in window.__state for the checks (a hook of the test, fed by the stream's own
    events); opened again when a navigation reloaded the page."""
    p.js("""if (!window.__observer) {
          window.__state = null;
          window.__observer = new EventSource('/api/events?client=' + arguments[0]);
          window.__observer.addEventListener('state', (e) => { window.__state = JSON.parse(e.data); });
        }""", client)
    wait(lambda: p.js("return window.__state !== null"), "the observer's state")


def answer_until(p, name, stop_at):
    """Answers the page's questions with their first option until the question `stop_at` is asked (returns
    it) or the procedure ends (returns None). At "run the part program" the program is downloaded from
    the page's link, as the operator carries it to the controller (written where the emulated machine
    loads it)."""
    while True:
        got = wait(lambda: p.question() or (not json.loads(p.js("return JSON.stringify(window.__state)"))["running"]
                                             and "end"), name + ": the next question or the end", timeout=120)
        if got == "end":
            return None
        q, buttons = got
        if q["what"] == stop_at:
            return q
        if q["what"] == "run-part-program":
            link = p.by_id("program-download")
            check(p.visible("program-link"), name + ": the program's download link is shown")
            with urllib.request.urlopen(link.get_attribute("href")) as r:
                program = r.read()
            with open(p.program_file, "wb") as f:
                f.write(program)
        buttons[0].click()
        wait(lambda: p.by_id("answers").get_attribute("data-q") != str(q["id"]) or not p.question(),
             "the answer to be taken")


def run_device_stop_and_resume(p, url, ballbar, scratch, env):
    """The circular test on `ballbar emulate --pty` (the ball-bar's own protocol on a pseudo-terminal),
    typed into the start panel as an operator would; Stop (asked twice) at the program's question; the
    session's page resumes it on the same instrument to its end. Returns the session's id."""
    p.program_file = os.path.join(scratch, "circle.ngc")
    cfg = os.path.join(scratch, "emulator.json")
    with open(cfg, "w") as f:
        json.dump({"instrument": {"calibrated_length_mm": 100, "noise_um": 0.15},
                   "machine": {"start": {"X_mm": 100.8, "Y_mm": 0, "Z_mm": 0}},
                   "program": {"file": p.program_file, "dialect": "linuxcnc"},
                   "continuous": {"backlash_um": {"X": 4}, "squareness_um_per_m": {"XY": 40}}}, f)
    emu = subprocess.Popen([ballbar, "emulate", "--pty", "--fast", "--config", cfg], stdout=subprocess.PIPE,
                           stderr=subprocess.DEVNULL, text=True, env=env)
    try:
        pty = emu.stdout.readline().strip()
        check(pty.startswith("/dev/pts/"), "ballbar emulate serves the bar on " + pty)
        p.d.get(url + "#/")
        observe(p, "test-observer-3")
        wait(lambda: p.visible("start") or p.visible("new-procedure"), "the start panel or the last result")
        if not p.visible("start"):
            p.by_id("new-procedure").click()
        p.by_id("c-device").send_keys("serial:" + pty)
        p.js("document.getElementById('c-dialect').value = 'linuxcnc'")
        feed = p.by_id("c-feed")
        feed.clear()
        feed.send_keys("2000")
        p.by_id("start-circular").click()
        wait(lambda: p.visible("run"), "the procedure's screen")
        q = answer_until(p, "instrument", "run-part-program")
        check(q is not None, "the instrument's procedure asks to run the part program")
        check(p.visible("program-link"), "the program's download link is shown with the question")
        p.shot("instrument-run-program")
        session = json.loads(p.js("return JSON.stringify(window.__state)"))["session"]
        # Stop asks twice: "No, go on" keeps it running; "Yes, stop it" stops it, resumable.
        p.by_id("stop").click()
        wait(lambda: p.visible("confirm-stop"), "the stop's confirmation")
        p.shot("instrument-stop-confirm")
        p.by_id("stop-no").click()
        time.sleep(0.3)
        check(json.loads(p.js("return JSON.stringify(window.__state)"))["running"], "No, go on: the procedure goes on")
        p.by_id("stop").click()
        wait(lambda: p.visible("confirm-stop"), "the stop's confirmation again")
        p.by_id("stop-yes").click()
        wait(lambda: json.loads(p.js("return JSON.stringify(window.__state)"))["state"] == "interrupted", "interrupted")
        p.shot("instrument-stopped")
        # The session's page offers Resume; the same instrument, typed in.
        p.d.get(url + "#/session/%d" % session)
        observe(p, "test-observer-4")
        wait(lambda: p.visible("resume"), "the Resume panel of the interrupted session")
        check("runs again" in p.by_id("resume-note").text, "the resume says what it does (%s)" % p.by_id("resume-note").text)
        p.by_id("resume-device").send_keys("serial:" + pty)
        p.shot("instrument-resume")
        p.by_id("resume-go").click()
        wait(lambda: p.visible("run"), "the resumed procedure's screen")
        answer_until(p, "instrument (resumed)", None)
        state = json.loads(p.js("return JSON.stringify(window.__state)"))
        check(state["state"] == "completed" and state["session"] == session,
              "the resumed session completed (%s)" % state.get("message"))
        check(len(state["result"]["runs"]) == 2, "both runs measured after the resume")
        p.shot("instrument-resumed-finished")
        return session
    finally:
        emu.send_signal(2)
        try:
            emu.wait(timeout=10)
        except subprocess.TimeoutExpired:
            emu.kill()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ballbar", required=True)
    ap.add_argument("--out", required=True, help="directory for the screenshots (kept)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    for f in os.listdir(a.out):
        if f.endswith(".png"):
            os.remove(os.path.join(a.out, f))
    scratch = tempfile.mkdtemp(prefix="ballbar-browser-")
    env = dict(os.environ, TMPDIR=scratch)  # Chromium's profile goes there, and is removed with it
    downloads = os.path.join(scratch, "downloads")
    os.makedirs(downloads)
    server = subprocess.Popen([a.ballbar, "--db", os.path.join(scratch, "sessions.db"), "serve", "--port", "0"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    page = None
    try:
        line = server.stdout.readline()
        m = re.search(r"http://\S+", line)
        if not m:
            raise Failed("ballbar serve printed no address: " + line + server.stderr.read())
        url = m.group(0)
        os.environ["TMPDIR"] = scratch
        page = Page(url, a.out, downloads)
        page.d.get(url)
        wait(lambda: page.js("return document.readyState") == "complete", "the page to load")
        load_ms = page.js("const n = performance.getEntriesByType('navigation')[0]; return n.loadEventEnd - n.startTime;")
        print("  page load, the browser's first: %.0f ms" % load_ms)
        warm = []
        for _ in range(5):  # the page opened again in a running browser, as at the machine
            page.d.get(url + "#/sessions")
            page.d.get(url)
            wait(lambda: page.js("return document.readyState") == "complete", "the page to load")
            warm.append(page.js("const n = performance.getEntriesByType('navigation')[0]; return n.loadEventEnd - n.startTime;"))
        print("  page load, opened again: median %.0f ms of %s" % (sorted(warm)[2], ", ".join("%.0f" % w for w in warm)))
        wait(lambda: page.by_id("link").text == "connected", "the event stream")
        # The page keeps its last state for the checks (a hook of the test, set from the stream's own events).
        page.js("""window.__state = null;
          const es = new EventSource('/api/events?client=test-observer');
          es.addEventListener('state', (e) => { window.__state = JSON.parse(e.data); });""")
        wait(lambda: page.js("return window.__state !== null"), "the observer's first state")
        page.shot("start")

        # ---- the circular demo ----
        state = run_procedure(page, "start-circular-demo", "circular",
                              ["reference", "setup", "run-part-program", "review"])
        check(state["state"] == "completed", "the circular demo completed (%s)" % state.get("message"))
        check(page.js("return window.__live") >= 5, "the live reading moved (%d updates seen)" % page.js("return window.__live"))
        wait(lambda: page.visible("finished"), "the finished panel")
        page.shot("circular-finished")
        page.by_id("open-session").click()
        wait(lambda: page.visible("circular-results") and len(page.d.find_elements(By.CSS_SELECTOR, "#diagnostics tbody tr")) > 0,
             "the circular results")
        drawn = page.js("""const c = document.getElementById('polar'), g = c.getContext('2d');
          const d = g.getImageData(0, 0, c.width, c.height).data; let n = 0;
          for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++; return n;""")
        check(drawn > 2000, "the polar plot is drawn (%d pixels)" % drawn)
        model = page.js("""const c = document.getElementById('polar'), g = c.getContext('2d');
          const d = g.getImageData(0, 0, c.width, c.height).data; let n = 0;
          for (let i = 0; i < d.length; i += 4)  // the ccw run's model colour, #0b2f66
            if (d[i + 3] > 200 && d[i] < 40 && d[i + 1] > 25 && d[i + 1] < 70 && d[i + 2] > 80 && d[i + 2] < 125) n++;
          return n;""")
        check(model > 200, "the diagnosed model is drawn over the ccw run (%d pixels of its colour)" % model)
        rows = page.d.find_elements(By.CSS_SELECTOR, "#diagnostics tbody tr")
        check(len(rows) >= 5, "the ranked diagnostics are listed (%d)" % len(rows))
        check(rows[0].find_elements(By.TAG_NAME, "td")[0].text == "1", "the first diagnostic is ranked 1")
        page.by_id("tolerance").send_keys("80\n")
        page.by_id("tolerance").click()
        page.js("document.getElementById('tolerance').dispatchEvent(new Event('change'))")
        wait(lambda: "PASS" in page.by_id("circular-figures").text or "FAIL" in page.by_id("circular-figures").text,
             "the verdict against the tolerance")
        page.shot("circular-session")
        circular_id = state["session"]

        # The PDF report, downloaded as the operator clicks it.
        page.by_id("report-pdf").click()
        pdf = os.path.join(downloads, "ballbar-session-%d.pdf" % circular_id)
        wait(lambda: os.path.exists(pdf) and os.path.getsize(pdf) > 1000, "the PDF download", timeout=30)
        with open(pdf, "rb") as f:
            check(f.read(5) == b"%PDF-", "the report downloads as a PDF (%d bytes)" % os.path.getsize(pdf))

        # ---- the SSM demo ----
        page.d.get(url + "#/")
        wait(lambda: page.by_id("link").text == "connected", "the event stream again")
        page.js("""window.__state = null;
          const es = new EventSource('/api/events?client=test-observer-2');
          es.addEventListener('state', (e) => { window.__state = JSON.parse(e.data); });""")
        wait(lambda: page.js("return window.__state !== null"), "the observer's state")
        wait(lambda: page.visible("start") or page.visible("new-procedure"), "the start panel or the last result")
        if not page.visible("start"):
            page.by_id("new-procedure").click()
        state = run_procedure(page, "start-ssm-demo", "ssm", ["reference", "setup", "run-program", "program-stop", "review"])
        check(state["state"] == "completed", "the SSM demo completed (%s)" % state.get("message"))
        npoints = len(page.d.find_elements(By.CSS_SELECTOR, "#points tbody tr"))
        check(npoints == 24, "each point with its verdict (%d rows)" % npoints)
        verdicts = {td.text for td in page.d.find_elements(By.CSS_SELECTOR, "#points tbody tr td:last-child")}
        check(verdicts == {"ok"}, "every point's verdict is ok (%s)" % verdicts)
        page.shot("ssm-finished")
        page.by_id("open-session").click()
        wait(lambda: page.visible("ssm-results") and len(page.d.find_elements(By.CSS_SELECTOR, "#locations tbody tr")) == 8,
             "the SSM results (8 locations)")
        check(len(page.d.find_elements(By.CSS_SELECTOR, "#orientation tbody tr")) >= 4, "the orientation errors")
        page.by_id("location-tolerance").send_keys("30")
        page.by_id("angle-tolerance").send_keys("50")
        page.js("document.getElementById('angle-tolerance').dispatchEvent(new Event('change'))")
        wait(lambda: {"PASS", "FAIL"} <= {td.text for td in page.d.find_elements(By.CSS_SELECTOR, "#locations tbody td:last-child, #orientation tbody td:last-child")},
             "the SSM verdicts against the tolerances typed in")
        page.shot("ssm-session")

        # ---- an instrument on its real protocol (`ballbar emulate --pty`), stopped, then resumed ----
        real_id = run_device_stop_and_resume(page, url, a.ballbar, scratch, env)

        # ---- the sessions ----
        page.by_id("nav-sessions").click()
        wait(lambda: len(page.d.find_elements(By.CSS_SELECTOR, "#demo-sessions tbody tr")) == 2, "both sessions listed")
        ids = [r.get_attribute("data-session") for r in page.d.find_elements(By.CSS_SELECTOR, "#demo-sessions tbody tr")]
        check(str(circular_id) in ids and str(state["session"]) in ids, "the sessions appear in the list (demo sessions apart)")
        real = [r.get_attribute("data-session") for r in page.d.find_elements(By.CSS_SELECTOR, "#sessions tbody tr")]
        check(real == [str(real_id)], "the instrument's session is listed apart from the demos (%s)" % real)
        page.shot("sessions")
        # The trend of the circular demo's machine, from the machine filter.
        sel = page.by_id("f-machine")
        label = [o.text for o in sel.find_elements(By.TAG_NAME, "option") if "circular" in o.text][0]
        page.js("const s = document.getElementById('f-machine'); s.value = arguments[0]; s.dispatchEvent(new Event('change'));", label)
        wait(lambda: len(page.d.find_elements(By.CSS_SELECTOR, "#trend-charts svg")) >= 3, "the machine's trend charts")
        page.shot("sessions-trend")

        errors = page.console_errors()
        check(not errors, "no error on the browser's console" + ("" if not errors else ": %s" % errors))

        # SIGTERM with the page still open: the server stops cleanly, exit 0.
        server.terminate()
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            raise Failed("ballbar serve did not stop within 20 s of SIGTERM")
        err = server.stderr.read()
        check(server.returncode == 0 and "stopped" in err,
              "SIGTERM stops the server cleanly (exit %s)%s" % (server.returncode, "" if server.returncode == 0 else ": " + err[-2000:]))
        print("PASS: %d screenshots in %s" % (page.shots, a.out))
        return 0
    except Failed as e:
        print("FAIL: " + str(e))
        if page:
            try:
                page.shot("failure")
                print("  console: %s" % page.d.get_log("browser"))
            except Exception:  # noqa: BLE001
                pass
        return 1
    finally:
        if page:
            page.d.quit()
        server.terminate()
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
