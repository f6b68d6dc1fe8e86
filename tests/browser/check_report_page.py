#!/usr/bin/python3
"""Opens a report's index.html in headless Chromium and checks that every image loads
(complete, naturalWidth > 0) and that nothing is logged as an error (console.error, an uncaught
exception, a resource that failed to load).

    check_report_page.py INDEX_HTML [--min-images N]
    check_report_page.py --self-test --combabc CLI --fake-history EXE --workdir DIR
                         [--python-path DIR]

The first form prints each problem on one line and exits 1 if there is any. The second is the
CTest test (label browser): it writes a synthetic run's report with the real CLI, checks it, and
then proves that the check can fail, on scratch copies with one image broken and with an error
logged to the console. With --python-path (where the combabc Python module is built) it also
runs a small Problem (a simulator written in Python), reports it with the CLI and checks that
the page speaks of its named bits, not of the sensor's clamps. Exit 77 (CTest
SKIP_RETURN_CODE) only when Chromium is not installed.

Chromium is driven through the DevTools protocol over --remote-debugging-pipe (fd 3: commands
in, fd 4: replies out, messages separated by NUL), so nothing listens on a port; Python stdlib
only.
"""

import argparse
import fcntl
import json
import os
import pathlib
import re
import select
import shutil
import subprocess
import sys
import tempfile
import time

SKIP = 77
TIMEOUT_S = 60.0


def moved_above(fd, lowest):
    moved = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, lowest)
    os.close(fd)
    return moved


class Browser:
    """One headless Chromium with a DevTools pipe; a context manager."""

    def __init__(self, executable, profile):
        commands_r, self._commands_w = os.pipe()
        self._replies_r, replies_w = os.pipe()
        # The child's ends moved above 10, so that dup2 onto 3 and 4 never meets its own source
        # (dup2 of an fd onto itself would keep close-on-exec, and Chromium would see no pipe).
        commands_r, replies_w = moved_above(commands_r, 10), moved_above(replies_w, 10)

        def wire_fds():  # in the child, before exec: Chromium expects the pipe on fds 3 and 4
            os.dup2(commands_r, 3)
            os.dup2(replies_w, 4)

        self._log = open(os.path.join(profile, "chromium.log"), "wb")
        self._process = subprocess.Popen(
            [executable, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
             "--no-default-browser-check", "--disable-extensions", "--mute-audio",
             f"--user-data-dir={profile}", "--remote-debugging-pipe", "about:blank"],
            stdin=subprocess.DEVNULL, stdout=self._log, stderr=self._log,
            preexec_fn=wire_fds, close_fds=False)
        os.close(commands_r)
        os.close(replies_w)
        self._buffer = b""
        self._next_id = 0
        self.events = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        try:
            self.send("Browser.close")
        except Exception:  # already gone: only cleanup is left
            pass
        try:
            self._process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
        os.close(self._commands_w)
        os.close(self._replies_r)
        self._log.close()

    def _read_message(self, deadline):
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("no reply from Chromium")
            ready, _, _ = select.select([self._replies_r], [], [], left)
            if ready:
                chunk = os.read(self._replies_r, 1 << 16)
                if not chunk:
                    raise RuntimeError("Chromium closed its DevTools pipe")
                self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method, params=None, session=None, timeout=TIMEOUT_S):
        """Sends a command and returns its result; events seen meanwhile go to self.events."""
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self._commands_w, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            reply = self._read_message(deadline)
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def wait_for(self, method, timeout=TIMEOUT_S):
        deadline = time.monotonic() + timeout
        while not any(e.get("method") == method for e in self.events):
            self.events.append(self._read_message(deadline))


IMAGES_JS = """JSON.stringify(Array.from(document.images).map(i => ({
    src: i.getAttribute("src"), complete: i.complete, width: i.naturalWidth})))"""

# The strip as drawn: each clamp section's number and rendered fill, the loads' centres and the
# plate's extent; and the answer table's rows (cell texts), which the colours must follow.
STRIP_JS = """JSON.stringify({
  strips: document.querySelectorAll("svg.strip").length,
  sections: Array.from(document.querySelectorAll("svg.strip g.section")).map(g => ({
    clamp: g.dataset.clamp, verdict: g.dataset.verdict,
    fill: getComputedStyle(g.querySelector("rect")).fill})),
  loads: Array.from(document.querySelectorAll("svg.strip g.load circle")).map(
    c => c.cx.baseVal.value),
  plate: (p => p ? [p.x.baseVal.value, p.width.baseVal.value] : null)(
    document.querySelector("svg.strip rect.plate")),
  verdict: (v => v ? v.textContent : "")(document.querySelector("p.verdict")),
  rows: Array.from(document.querySelectorAll("tr")).map(
    r => Array.from(r.cells).map(c => c.textContent))})"""

# What the page says in words: its text as rendered, and the tables' headers.
LABELS_JS = """JSON.stringify({
  text: document.body.innerText,
  headers: Array.from(document.querySelectorAll("th")).map(h => h.textContent)})"""

# The Problem the Python-run check reports: two named bits and a real; the simulator gives 5
# outputs (by index: no positions) around 40, far from a normalised profile.
PROBLEM = """
import sys
import numpy as np
import combabc
bend = np.array([4.0, 0.0, 0.0, 0.0, 4.0])
def simulate(bits, reals):
    return 40.0 + reals[:, :1] * np.arange(5.0) + bits[:, :1] * bend + bits[:, 1:2] * bend[::-1]
space = combabc.BinarySpace(dimension=2, names=["inlet valve", "pump B"])
reals = [combabc.ContinuousParameter("gain", kind="uniform", low=0.0, high=2.0)]
problem = combabc.Problem(space, simulate, simulate(np.array([[1, 0]]), np.array([[1.0]]))[0],
                          reals=reals, batch=True)
options = combabc.make_options(num_waves=2, accepted_per_wave=40, seed=3, threads=1,
                               thresholds=[6.0, 3.0])
combabc.run(problem, options, output_directory=sys.argv[1])
"""


def label_problems(index_html, drawn, must, must_not):
    """The page's words: each of `must` in its text and none of `must_not`."""
    text = drawn["text"] + " " + " ".join(drawn["headers"])
    return ([f"{index_html}: no {w!r} on the page" for w in must if w not in text] +
            [f"{index_html}: {w!r} on the page" for w in must_not if w in text])


# The documented colour scale of the strip (docs/history.md, "The strip"): P(fixed) = 0 is
# rgb(242, 242, 242), 1 is rgb(27, 120, 55), linear between them.
FREE_RGB, FIXED_RGB = (242, 242, 242), (27, 120, 55)


def find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def check_page(index_html, chromium, min_images=1, strip=None, labels=None):
    """Returns the problems found on the page, one line each; with `strip` (a dict: the page must
    draw the sensor strip, coloured by the answer's P(fixed), with loads at strip["loads"], as
    fractions of the length; False: it must not) those of the strip too; with `labels` (a pair:
    words the page must show, words it must not) those of its words."""
    url = pathlib.Path(index_html).resolve().as_uri()
    with tempfile.TemporaryDirectory(prefix="combabc-chromium-") as profile:
        with Browser(chromium, profile) as browser:
            target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
            session = browser.send("Target.attachToTarget",
                                   {"targetId": target, "flatten": True})["sessionId"]
            for domain in ("Page", "Runtime", "Log"):
                browser.send(f"{domain}.enable", session=session)
            browser.send("Page.navigate", {"url": url}, session=session)
            browser.wait_for("Page.loadEventFired")
            images = json.loads(browser.send(
                "Runtime.evaluate", {"expression": IMAGES_JS, "returnByValue": True},
                session=session)["result"]["value"])
            drawn = json.loads(browser.send(
                "Runtime.evaluate", {"expression": STRIP_JS, "returnByValue": True},
                session=session)["result"]["value"])
            words = json.loads(browser.send(
                "Runtime.evaluate", {"expression": LABELS_JS, "returnByValue": True},
                session=session)["result"]["value"])
            # A round trip after the load, so that messages logged during it have arrived.
            browser.send("Runtime.evaluate", {"expression": "1"}, session=session)
            events = list(browser.events)
    problems = [] if strip is None else strip_problems(index_html, drawn, strip)
    if labels is not None:
        problems += label_problems(index_html, words, *labels)
    if len(images) < min_images:
        problems.append(f"{index_html}: {len(images)} images, expected at least {min_images}")
    for image in images:
        if not image["complete"] or image["width"] <= 0:
            problems.append(f"{index_html}: image {image['src']} did not load")
    for event in events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            text = " ".join(str(a.get("value", a.get("description", ""))) for a in params["args"])
            problems.append(f"{index_html}: console.{params['type']}: {text}")
        elif method == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails", {})
            text = details.get("exception", {}).get("description") or details.get("text")
            problems.append(f"{index_html}: uncaught exception: {text}")
        elif method == "Log.entryAdded" and params["entry"].get("level") == "error":
            entry = params["entry"]
            problems.append(f"{index_html}: logged error: {entry.get('text')} {entry.get('url', '')}")
    return problems


def rgb(text):
    """ "rgb(12, 34, 56)" as a tuple of ints."""
    return tuple(int(v) for v in text[text.index("(") + 1:text.index(")")].split(","))


def strip_problems(index_html, drawn, expected):
    """The strip against the page's own answer table: one section per clamp, each filled with the
    colour of the P(fixed) the table prints for it (within rounding) and with its verdict."""
    if not expected:
        return [] if drawn["strips"] == 0 else [f"{index_html}: a strip where none belongs"]
    problems = []
    if drawn["strips"] != 1 or not drawn["sections"]:
        return [f"{index_html}: no strip drawn ({drawn['strips']} strips)"]
    table = {}
    for cells in drawn["rows"]:
        # The answer's rows: #, name, position, "P ± SE", verdict.
        if len(cells) == 5 and cells[0].strip().isdigit() and "±" in cells[3]:
            table[cells[0].strip()] = (float(cells[3].split("±")[0]), cells[4].strip())
    if len(table) != len(drawn["sections"]):
        problems.append(f"{index_html}: {len(drawn['sections'])} sections drawn for "
                        f"{len(table)} clamps in the answer table")
    for section in drawn["sections"]:
        p, verdict = table.get(section["clamp"], (None, None))
        if p is None:
            problems.append(f"{index_html}: section {section['clamp']} is not in the answer")
            continue
        want = tuple(a + (b - a) * p for a, b in zip(FREE_RGB, FIXED_RGB))
        got = rgb(section["fill"])
        # The table prints P to 3 decimals: 0.0005 of the scale is under 0.11 of a channel.
        if any(abs(g - w) > 1.0 for g, w in zip(got, want)):
            problems.append(f"{index_html}: clamp {section['clamp']} at P(fixed) = {p} is filled "
                            f"{section['fill']}, expected rgb{tuple(round(w) for w in want)}")
        if section["verdict"] != verdict:
            problems.append(f"{index_html}: clamp {section['clamp']} drawn {section['verdict']}, "
                            f"the table says {verdict}")
    # Not a vacuous check: the synthetic run's clamps spread over P(fixed) (0.12-0.75 at 40
    # particles a wave), so their colours differ.
    fills = {s["fill"] for s in drawn["sections"]}
    spread = [p for p, _ in table.values()]
    if len(fills) < 5 or not spread or max(spread) - min(spread) < 0.3:
        problems.append(f"{index_html}: too few colours ({len(fills)}) or too narrow a range of "
                        "P(fixed) to test the strip on")
    x, width = drawn["plate"] or (0.0, 0.0)
    loads = sorted(round((cx - x) / width, 3) for cx in drawn["loads"]) if width else []
    if len(loads) != len(expected["loads"]) or any(
            abs(a - b) > 0.005 for a, b in zip(loads, sorted(expected["loads"]))):
        problems.append(f"{index_html}: loads drawn at {loads} of the length, expected "
                        f"{expected['loads']}")
    if not drawn["verdict"].startswith("Verdict"):
        problems.append(f"{index_html}: no verdict line over the answer")
    return problems


def self_test(args, chromium):
    work = pathlib.Path(args.workdir)
    shutil.rmtree(work, ignore_errors=True)  # this test's own scratch directory in the build tree
    work.mkdir(parents=True)
    db = work / "RUN.db"
    # The sensor's 45 cm example as the run's config: the page draws its strip.
    examples = pathlib.Path(__file__).resolve().parents[2] / "examples"
    subprocess.run([args.fake_history, str(db), "--waves", "3", "--per-wave", "40", "--config",
                    str(examples / "sensor-45cm" / "least_squares.toml")], check=True)
    report = work / "report"
    subprocess.run([args.combabc, "report", str(db), "-o", str(report)], check=True)
    figures = len(list(report.glob("*.png")))
    # Its one load, at 45 of 90 cm: the middle of the plate.
    problems = check_page(report / "index.html", chromium, min_images=figures,
                          strip={"loads": [0.5]})
    for line in problems:
        print(line)
    if problems:
        return 1
    print(f"report page: {figures} images loaded, no console errors, the strip coloured by the "
          "answer's P(fixed)")

    # A Python simulator's run (the custom-simulator example's config): the same page, no strip.
    other = work / "python_simulator"
    other.mkdir()
    subprocess.run([args.fake_history, str(other / "RUN.db"), "--waves", "1", "--per-wave", "20",
                    "--no-curves", "--config",
                    str(examples / "custom-simulator" / "command.toml")], check=True)
    subprocess.run([args.combabc, "report", str(other / "RUN.db"), "-o", str(other / "report")],
                   check=True)
    # Its page read as text (a second browser would add seconds, not checks): no SVG at all, and
    # still the verdict line and the answer.
    page = (other / "report" / "index.html").read_text(encoding="utf-8")
    if "<svg" in page or 'class="verdict"' not in page or "<h2>Answer</h2>" not in page:
        print(f"{other / 'report' / 'index.html'}: a strip, or no verdict line or answer")
        return 1
    print("a Python simulator's report: no strip")

    if args.python_path:
        problems = python_run_problems(args, chromium, work)
        for line in problems:
            print(line)
        if problems:
            return 1
        print("a Python Problem's report: its bits by name, P(bit = 1), no clamps or strip")

    # The check must be able to fail: one image broken, then an error logged by the page.
    broken = work / "broken_image"
    shutil.copytree(report, broken)
    (broken / "summary.png").write_bytes(b"not a PNG")
    found = check_page(broken / "index.html", chromium, min_images=figures)
    if not any("summary.png did not load" in p for p in found):
        print(f"the check missed a broken image (it found: {found})")
        return 1
    # An error logged by the page, and (one browser start for both) the strip with two sections
    # of different P(fixed) swapped in colour.
    logged = work / "console_error"
    shutil.copytree(report, logged)
    page = (logged / "index.html").read_text(encoding="utf-8")
    page = page.replace("</body>", "<script>console.error('planted error');</script></body>")
    fills = sorted(set(re.findall(r'fill="(#[0-9a-f]{6})" stroke="#000"', page)) |
                   set(re.findall(r'fill="(#[0-9a-f]{6})" stroke="#999"', page)))
    first, last = fills[0], fills[-1]
    page = page.replace(first, "#TMPTMP").replace(last, first).replace("#TMPTMP", last)
    (logged / "index.html").write_text(page, encoding="utf-8")
    found = check_page(logged / "index.html", chromium, min_images=figures,
                       strip={"loads": [0.5]})
    if not any("planted error" in p for p in found):
        print(f"the check missed a console error (it found: {found})")
        return 1
    if not any("is filled" in p for p in found):
        print(f"the check missed swapped strip colours (it found: {found})")
        return 1
    print("negative controls: a broken image, a console error and swapped strip colours are all "
          "caught")
    return 0


def python_run_problems(args, chromium, work):
    """A Problem's run (PROBLEM), reported by the CLI and read in the browser: its bits by their
    names with P(bit = 1), no word of the sensor's. (The figures' words, which a PNG does not show
    the browser, are tests/report/report_script_test.py's, on such a run's export drawn as SVG.)"""
    run = work / "python_problem"
    env = dict(os.environ, PYTHONPATH=args.python_path, PYTHONDONTWRITEBYTECODE="1")
    subprocess.run([sys.executable, "-c", PROBLEM, str(run)], check=True, env=env)
    report = run / "report"
    subprocess.run([args.combabc, "report", str(run / "history.sqlite"), "-o", str(report)],
                   check=True)
    figures = len(list(report.glob("*.png")))
    must = ["P(bit = 1) ± SE", "inlet valve", "pump B", "Verdict — bit = 1:", "gain"]
    must_not = ["clamp", "Clamp", "P(fixed)"]
    return check_page(report / "index.html", chromium, min_images=figures, strip=False,
                      labels=(must, must_not))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("index_html", nargs="?")
    parser.add_argument("--min-images", type=int, default=1)
    parser.add_argument("--self-test", action="store_true")
    parser.add_argument("--combabc")
    parser.add_argument("--fake-history")
    parser.add_argument("--workdir")
    parser.add_argument("--python-path",
                        help="where the combabc Python module is built (adds a Problem's run)")
    args = parser.parse_args()
    chromium = find_chromium()
    if not chromium:
        print("SKIP: chromium is not installed (apt-get install chromium; scripts/setup.sh)")
        return SKIP
    if args.self_test:
        return self_test(args, chromium)
    if not args.index_html:
        parser.error("INDEX_HTML or --self-test")
    problems = check_page(args.index_html, chromium, args.min_images)
    for line in problems:
        print(line)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
