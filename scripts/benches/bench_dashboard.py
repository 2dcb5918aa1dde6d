# SPDX-License-Identifier: MIT
"""The dashboard of `torqueloop serve --http`: telemetry latency from the
server's reading a board frame to the page's drawing it (median, 99th
percentile), and whether 1, 4 and 8 pages at once each get every frame.

The simulated board (real time, the paper's 25 ms period: 40 records/s),
`torqueloop serve --http` on 127.0.0.1, Debian's headless Chromium with one
window per page.  Each row carries the time (time.time()) at which the
session server read it from the link; the page stamps it again in the first
animation frame after it handed the row to BokehJS (window.tl.lat).  Both
clocks are this machine's.  A page's lost rows are its gaps in the sequence
plus the rows its own bounded queue dropped on the server.  Axis 0 moves a turn
back and forth meanwhile (`move` from a CLI client of the same server) so the plots have something to draw.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from torqueloop.flow import terminal
from torqueloop.spec import auth
from torqueloop.spec.repo import REPO_ROOT

PAGES = (1, 4, 8)


def _quick() -> bool:
    return bool(getattr(sys.modules.get("bench"), "QUICK", False))


def _start(args: list[str], env: dict[str, str]) -> subprocess.Popen:
    return terminal.cli(args, env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)


def _browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    o = Options()
    o.binary_location = shutil.which("chromium")
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
              "--window-size=1200,900"):
        o.add_argument(a)
    return webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=o)


def _measure(d, page: str, n: int, seconds: float) -> dict:
    handles = [d.current_window_handle]
    d.get(page)
    while len(handles) < n:
        d.switch_to.new_window("window")
        d.get(page)
        handles.append(d.current_window_handle)
    for h in handles:
        d.switch_to.window(h)
        t0 = time.monotonic()
        while not d.execute_script("return !!(window.tl && tl.ready && tl.received > 0)"):
            if time.monotonic() - t0 > 60:
                raise RuntimeError("a page did not start streaming within 60 s")
            time.sleep(0.2)
    base = {}
    for h in handles:
        d.switch_to.window(h)
        base[h] = d.execute_script("tl.lat = []; return [tl.received, tl.gaps + tl.dropped, tl.lastSeq]")
    time.sleep(seconds)
    ends = {}
    for h in handles:
        d.switch_to.window(h)
        ends[h] = d.execute_script("return tl.lastSeq")
    last = max(ends.values())
    lat: list[float] = []
    got, lost, behind = [], [], []
    for h in handles:               # a page behind the others catches up (its rows were late, not lost)
        d.switch_to.window(h)
        t0 = time.monotonic()
        while d.execute_script("return tl.lastSeq") < last and time.monotonic() - t0 < 60:
            time.sleep(0.2)
        r, l, _ = d.execute_script("return [tl.received, tl.gaps + tl.dropped, tl.lastSeq]")
        lat += d.execute_script("return tl.lat")
        got.append(r - base[h][0])
        lost.append(l - base[h][1])
        behind.append(last - ends[h])
    for h in handles[1:]:
        d.switch_to.window(h)
        d.close()
    d.switch_to.window(handles[0])
    a = np.array(lat)
    return {"pages": n, "seconds": seconds, "rows_per_page": got, "lost_per_page": lost,
            "rows_behind_at_the_end": behind,
            "latency_ms_median": round(float(np.median(a)), 1), "latency_ms_p99": round(float(np.percentile(a, 99)), 1),
            "latency_ms_max": round(float(a.max()), 1), "samples": int(a.size)}


def _socket_latency(page: str, seconds: float) -> dict:
    """The same latency to a WebSocket client in Python (no drawing): the server's share."""
    import asyncio

    from torqueloop.host.dash.listen import listen

    got, err = asyncio.run(listen(page.replace("http", "ws").rstrip("/") + "/ws", seconds))
    if err:
        raise RuntimeError(f"the dashboard refused the WebSocket: {err}")
    lat = [now - r[1] for now, m in got if (o := json.loads(m)).get("t") == "rows" for r in o["rows"]]
    a = np.array(lat)
    return {"pages": 0, "client": "python websocket", "seconds": seconds, "samples": int(a.size),
            "latency_ms_median": round(float(np.median(a)), 1), "latency_ms_p99": round(float(np.percentile(a, 99)), 1),
            "latency_ms_max": round(float(a.max()), 1)}


def main() -> int:
    if not (shutil.which("chromium") and shutil.which("chromedriver")):
        print("bench_dashboard: Debian's chromium and chromium-driver are missing (make setup installs them)")
        return 1
    seconds = 8.0 if _quick() else 30.0
    tmp = Path(tempfile.mkdtemp(prefix="tl-dash-bench-"))
    key = tmp / "bench.key"
    auth.write_key_file(key, auth.new_key())
    env = dict(os.environ, TORQUELOOP_KEY_FILE=str(key), TORQUELOOP_STATE_DIR=str(tmp / "state"))
    env.pop("TORQUELOOP_SERVER", None)
    procs: list[subprocess.Popen] = []
    results = []
    try:
        sim = _start(["sim", "--port", "0"], env)
        procs.append(sim)
        url = next(w for w in sim.stdout.readline().split() if w.startswith("socket://"))
        srv = _start(["-u", url, "serve", "--port", "0", "--quiet", "--http", "127.0.0.1:0"], env)
        procs.append(srv)
        srv.stdout.readline()
        page = srv.stdout.readline().split()[1]
        # something to draw: axis 0 moved a turn back and forth by a CLI client of the same server
        mv = f"{sys.executable} -m torqueloop.cli -u {url} move --relative --unhomed --enable --wait 5 --tolerance 40"
        mover = subprocess.Popen(["bash", "-c", f"for i in $(seq 200); do {mv} 1rev; {mv} -- -1rev; done"],
                                 env=env, start_new_session=True, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)
        procs.append(mover)
        r = _socket_latency(page, seconds / 2)
        results.append(r)
        print(f"WebSocket client in Python (the server's share), {r['seconds']:g} s: latency median "
              f"{r['latency_ms_median']} ms, p99 {r['latency_ms_p99']} ms, max {r['latency_ms_max']} ms "
              f"({r['samples']} rows)", flush=True)
        d = _browser()
        try:
            for n in PAGES:
                r = _measure(d, page, n, seconds)
                results.append(r)
                print(f"{n} page(s), {seconds:g} s: rows per page {r['rows_per_page']}, lost {r['lost_per_page']}, "
                      f"behind at the end {r['rows_behind_at_the_end']}; "
                      f"latency median {r['latency_ms_median']} ms, p99 {r['latency_ms_p99']} ms, "
                      f"max {r['latency_ms_max']} ms ({r['samples']} rows drawn)", flush=True)
        finally:
            d.quit()
    finally:
        for p in reversed(procs):
            try:
                if p is procs[-1] and p.args[0] == "bash":
                    os.killpg(p.pid, signal.SIGTERM)
                else:
                    p.send_signal(signal.SIGINT)
                p.wait(15)
            except (subprocess.TimeoutExpired, ProcessLookupError):
                p.kill()
        shutil.rmtree(tmp, ignore_errors=True)
    out = REPO_ROOT / "build" / "bench" / "dashboard.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    pages = [r for r in results if r["pages"]]
    worst = max([r["pages"] for r in pages if sum(r["lost_per_page"]) == 0], default=0)
    print(f"pages at once without a lost frame (of {PAGES}): up to {worst}; wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
