#!/usr/bin/python3
"""End-to-end test of `gapflow serve` in headless Chromium (ctest live_view_chromium, label slow).

Starts the server on a free port, loads the page with ?set=obstruction.distance_mm=150 (the page
applies it through the same path as its controls), takes a screenshot and checks that
 * the screenshot is not empty and shows spheres (viridis colours) and the obstruction (its colour),
 * the served state shows the change (settings and overrides), and the run restarted,
 * a bad value is rejected with the loader's --set message (HTTP 400).
Usage: live_view_test.py GAPFLOW SCENARIO.  Exit 77 (skipped) when chromium is not installed."""
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

from PIL import Image

if not shutil.which("chromium"):
    print("SKIP: chromium is not installed (scripts/setup.sh installs it)")
    sys.exit(77)

gapflow, scenario = sys.argv[1], sys.argv[2]
with socket.socket() as s:
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
base = f"http://127.0.0.1:{port}"
server = subprocess.Popen([gapflow, "serve", scenario, "--port", str(port), "--exit-after", "120"])
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def get(path):
    with urllib.request.urlopen(base + path, timeout=10) as r:
        return json.load(r)


try:
    for _ in range(100):
        try:
            get("/state")
            break
        except OSError:
            time.sleep(0.1)
    before = get("/state")["generation"]
    with tempfile.TemporaryDirectory() as tmp:
        shot = os.path.join(tmp, "shot.png")

        def screenshot(wait_ms):
            subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                            "--no-first-run", "--disable-background-networking", "--disable-component-update",
                            "--disable-sync", f"--user-data-dir={tmp}/profile", "--window-size=800,1000",
                            f"--virtual-time-budget={wait_ms}", f"--screenshot={shot}",
                            base + "/?set=obstruction.distance_mm=150"],
                           check=True, timeout=120, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            img = Image.open(shot).convert("RGB")
            if os.environ.get("GAPFLOW_KEEP_SHOT"):
                shutil.copy(shot, os.environ["GAPFLOW_KEEP_SHOT"])
            return img, img.getcolors(maxcolors=1 << 20) or []

        def count(colours, rgb, tol):
            return sum(n for n, c in colours if all(abs(a - b) <= tol for a, b in zip(c, rgb)))

        def spheres(colours):
            return sum(count(colours, c, 40) for c in [(68, 1, 84), (33, 145, 140), (253, 231, 37)])

        # Headless Chromium shoots at the load event unless given a virtual-time budget: the page's
        # 100 ms polling timers then run (each waits for its real fetch) until the budget is spent.
        for wait_ms in (2000, 6000):
            img, colours = screenshot(wait_ms)
            if spheres(colours) > 2000:
                break
            print(f"no spheres after {wait_ms} ms: trying a longer wait")
        check(img.size == (800, 1000), f"screenshot size {img.size}")
        check(len(colours) > 20, f"screenshot not blank ({len(colours)} colours)")
        check(spheres(colours) > 2000, f"spheres drawn ({spheres(colours)} px in viridis colours)")
        check(count(colours, (140, 90, 50), 2) > 1000, f"obstruction drawn ({count(colours, (140, 90, 50), 2)} px)")
    geometry = get("/geometry")
    check(geometry["settings"]["obstruction.distance_mm"] == 150, "served scenario has distance 150 mm")
    check(geometry["overrides"] == ["obstruction.distance_mm=150"], f"overrides {geometry['overrides']}")
    check(abs(geometry["obstruction"]["c"][1] - 150) < 1e-9, "obstruction centre moved to y = 150 mm")
    check(get("/state")["generation"] > before, "the run restarted")
    try:
        urllib.request.urlopen(urllib.request.Request(base + "/set", data=b"bottleneck.gap_mm=-3"), timeout=10)
        check(False, "a negative gap is rejected")
    except urllib.error.HTTPError as e:
        body = e.read().decode()
        check(e.code == 400 and "--set:2:19" in body and "gap_mm" in body, f"rejected with the loader's message: {body}")
    # A setting the model refuses (the 2D rolling reduction on a 45 deg board: the spheres would
    # slip) is an error for the page, not a crash of the run thread.
    try:
        urllib.request.urlopen(urllib.request.Request(base + "/set", data=b"plane.incline_deg=45"), timeout=10)
        check(False, "a 45 deg board with rolling spheres is rejected")
    except urllib.error.HTTPError as e:
        body = e.read().decode()
        check(e.code == 400 and "incline_deg" in body, f"rejected with the model's message: {body}")
    check(server.poll() is None, "the server still runs")
    check(get("/state")["generation"] >= 0, "and answers")
finally:
    server.terminate()
    server.wait(timeout=10)
sys.exit(1 if failures else 0)
