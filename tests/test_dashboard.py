# SPDX-License-Identifier: MIT
"""The browser dashboard of ``torqueloop serve --http``, in a real browser:
the simulated board, the server with its dashboard, Debian's headless
Chromium driven through chromedriver (selenium).  A user's session: enable
an axis, move it, see the position plot's data reach the target within the
settle time, press STOP and see the axis disabled.  Who may do what: on
0.0.0.0 (reached here through 127.0.0.1 only) a page without the token
watches nothing and commands nothing, a watch token watches and may STOP
only; nothing served to a page carries the link key.  And the fan-out: a
page that does not take its rows loses its own oldest rows, counted, and
no other page loses one."""

from __future__ import annotations

import asyncio
import base64
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from simproc import sim_board
from torqueloop.flow import terminal
from torqueloop.host import serve as hserve
from torqueloop.host.dash.access import Access
from torqueloop.host.dash.hub import ROW, Hub, Page
from torqueloop.host.dash.listen import listen
from torqueloop.spec import auth

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")
STEP_MM = 2.0
SETTLE_S = 4.0        # the step's settling time on the simulated board is about 1.2 s (docs/host.md, Dashboard)


@pytest.fixture(scope="module")
def env(tmp_path_factory) -> dict[str, str]:
    d = tmp_path_factory.mktemp("dash")
    key = d / "lab.key"
    auth.write_key_file(key, auth.new_key())
    e = dict(os.environ, TORQUELOOP_KEY_FILE=str(key), TORQUELOOP_STATE_DIR=str(d / "state"))
    e.pop(hserve.SERVER_ENV, None)
    return e


@pytest.fixture(scope="module")
def url(env):
    with sim_board("sim", "--port", "0", env=env) as u:
        yield u


def _serve(url: str, env: dict[str, str], http: str) -> tuple[subprocess.Popen, list[str]]:
    """``torqueloop serve --http``: the process and the lines it printed up to its dashboard's address."""
    p = terminal.cli(["-u", url, "serve", "--port", "0", "--quiet", "--http", http], env,
                     stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    lines = [p.stdout.readline()]
    assert "torqueloop server for" in lines[0], lines[0] + (p.stderr.read() if p.poll() is not None else "")
    lines.append(p.stdout.readline())
    assert lines[-1].startswith("dashboard"), lines + [p.stderr.read() if p.poll() is not None else ""]
    if "needs a token" in lines[-1]:
        lines += [p.stdout.readline(), p.stdout.readline()]
    return p, lines


def _stop(p: subprocess.Popen) -> None:
    p.send_signal(signal.SIGINT)
    try:
        p.wait(15)
    except subprocess.TimeoutExpired:
        p.kill()
        raise


@pytest.fixture(scope="module")
def browser():
    if not (CHROMIUM and CHROMEDRIVER):
        pytest.skip("Debian's chromium and chromium-driver are not installed (make setup installs them)")
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    o = Options()
    o.binary_location = CHROMIUM
    for a in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
              "--window-size=1400,1400"):
        o.add_argument(a)
    d = webdriver.Chrome(service=Service(CHROMEDRIVER), options=o)
    yield d
    d.quit()


@pytest.fixture(scope="module")
def dash(url, env):
    """``serve --http 0.0.0.0:0``, reached through 127.0.0.1 only: (base URL, {role: token})."""
    srv, lines = _serve(url, env, "0.0.0.0:0")
    try:
        tokens = {ln.split()[0].rstrip(":"): ln.split("token=")[1].strip() for ln in lines[2:]}
        assert set(tokens) == {"command", "watch"}, lines
        port = lines[1].split("http://0.0.0.0:")[1].split("/")[0]
        yield f"http://127.0.0.1:{port}", tokens
    finally:
        _stop(srv)


def _until(fn, timeout: float, what: str):
    t0 = time.monotonic()
    print(f"[{time.strftime('%X')}] waiting: {what}", flush=True)
    while True:
        got = fn()
        if got:
            return got
        if time.monotonic() - t0 > timeout:
            raise AssertionError(f"{what}: not within {timeout} s (last: {got!r})")
        time.sleep(0.1)


def _click(d, css: str, text: str | None = None) -> None:
    from selenium.webdriver.common.by import By
    els = [e for e in d.find_elements(By.CSS_SELECTOR, css) if text is None or e.text == text]
    assert els, f"no {css} {text or ''} on the page"
    d.execute_script("arguments[0].click()", els[0])      # the button's own click event, as a mouse gives it


def _get(url: str, headers: dict[str, str] | None = None) -> tuple[int, bytes]:
    req = urllib.request.Request(url, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=20) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


async def _ws_session(ws_url: str, requests: list[dict], seconds: float) -> tuple[list[str], str | None]:
    """The messages a WebSocket client gets in ``seconds`` after sending ``requests``
    (or the reason the handshake was refused)."""
    got, err = await listen(ws_url, seconds, requests)
    return [m for _, m in got], err


def _key_forms(env: dict[str, str]) -> list[bytes]:
    key = auth.read_key_file(Path(env["TORQUELOOP_KEY_FILE"]))
    return [key, key.hex().encode(), key.hex().upper().encode(), base64.b64encode(key),
            base64.urlsafe_b64encode(key).rstrip(b"=")]


def test_on_all_addresses_a_page_needs_its_token(dash, url, env, browser) -> None:
    base, tokens = dash
    d = browser
    d.delete_all_cookies()
    d.get(base + "/")                                     # no token: the page is refused, nothing streams
    assert "needs its token" in d.find_element("tag name", "body").text
    assert d.execute_script("return typeof window.tl") == "undefined"
    for path in ("/", "/api/config", "/static/dash/dash.js", "/static/bokeh/js/bokeh.min.js", "/?token=nope"):
        assert _get(base + path)[0] == 401, path
    ws = base.replace("http", "ws") + "/ws"
    msgs, err = asyncio.run(_ws_session(ws, [{"id": 1, "op": "enable", "params": {"axis": 0}}], 1.0))
    assert err is not None and "401" in err and not msgs  # the WebSocket is refused: no rows, no command
    msgs, err = asyncio.run(_ws_session(ws + "?token=" + "x" * 24, [{"id": 1, "op": "stop"}], 1.0))
    assert err is not None and not msgs
    # the watch token: rows, and STOP, but no command
    msgs, err = asyncio.run(_ws_session(ws + "?token=" + tokens["watch"],
                                        [{"id": 1, "op": "enable", "params": {"axis": 0}},
                                         {"id": 2, "op": "stop"}], 2.0))
    got = [json.loads(m) for m in msgs]
    replies = {m["id"]: m for m in got if m["t"] == "reply"}
    assert replies[1]["ok"] is False and "only watch" in replies[1]["error"]
    assert replies[2]["ok"] is True
    assert any(m["t"] == "rows" and m["rows"] for m in got) or got[0]["rows"]
    holds = subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "--json", "status"], env=env,
                           capture_output=True, text=True, timeout=60)
    assert not json.loads(holds.stdout)["0"]["enabled"]


def test_enable_move_and_stop_from_the_page(dash, env, browser) -> None:
    base, tokens = dash
    d = browser
    d.get(base + "/?token=" + tokens["command"])     # the cookie carries the token on
    _until(lambda: d.execute_script("return !!(window.tl && tl.ready && tl.received > 10 && tl.status)"),
           30, "the page streaming telemetry")
    _click(d, "#axis0 button", "enable")
    _until(lambda: d.execute_script("return tl.rows[tl.rows.length - 1][1][tl.ix.enabled0] === 1"), 10,
           "axis 0 enabled (its telemetry)")
    start_mm = d.execute_script("const p = tl.src[0].data.position; return p[p.length - 1]")
    seq0 = d.execute_script("return tl.lastSeq")
    d.execute_script(f"document.getElementById('target0').value = '{STEP_MM}'")
    _click(d, "#move0")
    target = start_mm + STEP_MM

    def settled():     # the plot's own data: set-point at the target, position within 2 % of the step
        return d.execute_script(
            """const [lo, goal, tol] = arguments; const out = [];
               for (const [t, r] of tl.rows) if (r[0] > lo) out.push([t, r]);
               const ix = tl.ix, sc = tl.cfg.scales[0].mm, src = tl.src[0].data;
               const n = src.t.length;
               const moved = out.find(([t, r]) => Math.abs(r[ix.setpoint0] * sc - goal) < tol);
               if (!moved) return null;
               let last = null;
               for (const [t, r] of out) if (Math.abs(r[ix.position0] * sc - goal) > tol) last = t;
               const inPlot = Math.abs(src.position[n - 1] - goal) <= tol;
               return inPlot && last !== null && out[out.length - 1][0] - last > 0.5
                      ? [moved[0], last] : null;""", seq0, target, 0.02 * STEP_MM)
    reply = _until(lambda: d.execute_script("return tl.replies.find(r => r.id === tl.id)"), 30, "the move's reply")
    assert reply["ok"], reply
    # the page may draw late on a loaded machine; the settling time is measured in the board's time
    t_step, t_last_out = _until(settled, 60, f"the plotted position reaching {target:.3f} mm")
    assert t_last_out - t_step <= SETTLE_S, f"settled {t_last_out - t_step:.2f} s after the step"
    assert d.execute_script("return tl.gaps + tl.dropped") == 0, "the page lost telemetry rows"
    _click(d, "#stop")
    _until(lambda: d.execute_script("return tl.status.axes[0].enabled === false && "
                                    "tl.rows[tl.rows.length - 1][1][tl.ix.enabled0] === 0"),
           10, "axis 0 disabled after STOP (state line and telemetry)")
    assert "disabled" in d.find_element("id", "state0").text
    d.save_screenshot(str(Path(env["TORQUELOOP_STATE_DIR"]).parent / "dashboard.png"))
    # nothing a page gets carries the link key: the page, its scripts, its config and its messages
    auth_hdr = {"Authorization": "Bearer " + tokens["command"]}
    served = [_get(base + p, auth_hdr)[1] for p in ("/", "/api/config", "/static/dash/dash.js",
                                                    "/static/dash/dash.css", "/static/bokeh/js/bokeh.min.js")]
    msgs, err = asyncio.run(_ws_session(base.replace("http", "ws") + "/ws?since=0&token=" + tokens["command"],
                                        [{"id": 1, "op": "params", "params": {"axis": 0}}], 2.0))
    assert err is None and any('"t": "reply"' in m for m in msgs) and any('"rows"' in m for m in msgs)
    blob = b"\n".join(served) + "\n".join(msgs).encode()
    for form in _key_forms(env):
        assert form not in blob, "the link key reached the page"
    assert "token" not in d.current_url and d.execute_script("return tl.role") == "command"


def test_a_page_that_does_not_keep_up_loses_only_its_own_rows() -> None:
    hub = Hub(history_rows=1000)
    woken: list[str] = []
    slow, quick = Page("slow", lambda: woken.append("slow"), 50), Page("quick", lambda: woken.append("quick"), 50)
    hub.attach(slow, None, 0)
    hub.attach(quick, None, 0)
    rec = {"time_us": 0, "axes": [{f: 0 for f in ("setpoint", "position", "velocity_q8", "error", "pwm_cmd",
                                                  "faults", "enabled")}] * 2}
    got: list[list] = []
    for k in range(200):
        hub.feed([dict(rec, time_us=k * 25_000)], time.time())
        got += hub.take(quick)                 # the quick page takes its rows as they come
    assert [r[0] for r in got] == list(range(1, 201)) and quick.dropped == 0
    late = hub.take(slow)                      # the slow one: its newest 50, and 150 counted as dropped
    assert [r[0] for r in late] == list(range(151, 201)) and slow.dropped == 150
    assert len(ROW) == len(got[0])
    # a page that reconnects after row 120 gets every row after it from the history
    back = Page("back", lambda: None)
    rows, lost = hub.attach(back, 120, 0)
    assert [r[0] for r in rows] == list(range(121, 201)) and lost == 0


def test_an_open_loopback_page_answers_only_to_its_own_name() -> None:
    """Without tokens (127.0.0.1) everyone here commands, but a request whose Host names
    another site (a DNS name pointed at 127.0.0.1 by a web page) is refused."""
    open_ = Access({}, "127.0.0.1", 7131)
    assert open_.role(None) == "command"
    assert all(open_.host_ok(h) for h in ("127.0.0.1:7131", "localhost:7131", "[::1]:7131"))
    assert not any(open_.host_ok(h) for h in ("evil.example:7131", "", None))
    closed = Access({"command": "c" * 24, "watch": "w" * 24}, "0.0.0.0", 7131)
    assert closed.role(None) is None and closed.role("x" * 24) is None
    assert closed.role("w" * 24) == "watch" and closed.role("c" * 24) == "command"
    assert Access.may("watch", "stop") and not Access.may("watch", "move") and Access.may("command", "move")


@pytest.mark.parametrize("spec, says", [("notanaddress", "not an address"), ("127.0.0.1:99999", "outside 0..65535"),
                                        ("1.2.3:x", "give ADDR:PORT")])
def test_a_bad_dashboard_address_is_refused_before_the_board_is_touched(spec: str, says: str, capsys) -> None:
    from torqueloop import cli

    # port 9 on loopback: nothing listens there, so reaching the board would fail with another message
    rc = cli.main(["-u", "socket://127.0.0.1:9", "serve", "--port", "0", "--http", spec])
    err = capsys.readouterr().err
    assert rc == 2 and says in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
