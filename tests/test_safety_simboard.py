# SPDX-License-Identifier: MIT
"""Safety on the simulated board (the servo firmware's C around the plant,
torqueloop/sim/simboard.py): the faults a real motor needs, shown with the
plant moving.

  - encoder loss and runaway: the encoder frozen, or counting the wrong way,
    during the paper's one-turn step (Table 1 P gains): the firmware stops the
    bridge within STALL_MS (+ two periods) and latches RUNAWAY; the stage's
    travel until then is printed;
  - limit switches: an axis driven onto its switch stops, latches LIMIT_POS,
    can be enabled again and driven back out but not further in;
  - homing to the negative switch (and on to the encoder index): afterwards
    the position reads HOME_POS at the home point, the soft limits are
    absolute, and MOVE needs no UNHOMED flag.
"""

from __future__ import annotations

import pytest

from torqueloop.sim.model_loop import TABLE1
from torqueloop.sim.simboard import LIM_POS, SimBoard
from torqueloop.spec import auth
from torqueloop.spec import protocol as P

PERIOD_S = 0.025           # the paper's, the firmware's default


class Host:
    """Commands straight into the simulated board's UART in an authenticated
    session (the test key; docs/security.md), replies decoded."""

    def __init__(self, board: SimBoard) -> None:
        self.b, self.seq, self.dec = board, 0, P.FrameDecoder()
        hn = auth.new_host_nonce()
        self.b.write(P.request("SESSION", 0, host_nonce=hn))
        self.sess = auth.open_session(auth.TEST_KEY, hn, self._reply("SESSION"))

    def _reply(self, name: str) -> dict[str, int]:
        for f in self.dec.feed(self.b.read()):
            if isinstance(f, P.Frame) and f.cmd == P.COMMANDS[name].cmd | P.REPLY_FLAG:
                return P.decode_reply(f)
        raise AssertionError(f"no reply to {name}")

    def cmd(self, name: str, **fields: int) -> dict[str, int]:
        self.seq += 1
        tagged = not P.COMMANDS[name].untagged   # as the host tool: everything but the reads carries a MAC
        self.b.write(self.sess.request(name, self.seq, **fields) if tagged else P.request(name, self.seq, **fields))
        return self._reply(name)

    def ok(self, name: str, **fields: int) -> dict[str, int]:
        r = self.cmd(name, **fields)
        assert r["status"] == P.STATUS["OK"], f"{name} {fields}: {P.STATUS_NAME[r['status']]}"
        return r

    def set(self, axis: int, name: str, value: int) -> None:
        self.ok("SET_PARAM", axis=axis, param=P.PARAMS[name].id, value=value)

    def run(self, seconds: float, until=None) -> float:
        """Run the board ``seconds`` (feeding the link watchdog); returns the time
        ``until()`` first held, or -1."""
        end, k = self.b.t + seconds, 0
        while self.b.t < end:
            self.b.advance(PERIOD_S)
            self.b.read()
            k += 1
            if k % 8 == 0:
                self.ok("HEARTBEAT")
            if until is not None and until():
                return self.b.t
        return -1.0


@pytest.fixture()
def host() -> Host:
    h = Host(SimBoard(key=auth.TEST_KEY))
    for ax in (0, 1):
        h.set(ax, "KP_UNM_RAD", round(TABLE1["P"][ax].kp * 1e6))
    return h


@pytest.mark.parametrize("kind", ["frozen", "reversed"])
@pytest.mark.parametrize("axis", [0, 1])
def test_a_lost_encoder_stops_the_motor(host: Host, kind: str, axis: int) -> None:
    b = host.b
    host.ok("ENABLE", mask=1 << axis, enable=1)
    host.run(0.1)
    b.set_encoder_fault(axis, kind)
    start = b.plant.count(axis)
    host.ok("MOVE", axis=axis, mode=P.MOVE_UNHOMED, target=b.encoder_count(axis) + 8400)
    t0 = b.t
    t_off = host.run(3.0, until=lambda: not b.drive(axis)["on"])
    st = host.ok("STATUS", axis=axis)
    travel = b.plant.count(axis) - start
    stall_s = P.PARAMS["STALL_MS"].default / 1000
    print(f"axis {axis}, {kind} encoder: bridge off {t_off - t0:.3f} s after the step, the stage ran "
          f"{travel} counts ({travel / 8400:.2f} turns) meanwhile")
    assert st["faults"] == P.FAULT["RUNAWAY"] and not st["enabled"], st
    assert stall_s <= t_off - t0 <= stall_s + 3 * PERIOD_S, t_off - t0
    assert b.drive(axis)["cmd"] == 0
    # without the check the step would have run away for the whole 3 s
    assert abs(travel) < 8400 * 1.5


def test_limit_switch_stops_then_lets_the_axis_out(host: Host) -> None:
    b = host.b
    b.limit_counts[0] = (-100_000, 3000)            # the positive switch 3000 counts ahead
    host.ok("ENABLE", mask=1, enable=1)
    host.ok("MOVE", axis=0, mode=P.MOVE_UNHOMED | P.MOVE_TRAPEZOID, target=8000)
    t = host.run(3.0, until=lambda: not b.drive(0)["on"])
    assert t > 0 and b.limits(0) == LIM_POS
    st = host.ok("STATUS", axis=0)
    assert st["faults"] == P.FAULT["LIMIT_POS"] and st["limits"] == P.LIMIT_BITS["pos"], st
    overrun = b.plant.count(0) - 3000
    assert 0 < overrun < 400, f"ran {overrun} counts past the switch"
    assert host.cmd("CLEAR_FAULT", mask=1)["status"] == P.STATUS["STATE"]   # still on the switch
    host.ok("ENABLE", mask=1, enable=1)                                     # a direction fault: allowed
    pos = host.ok("STATUS", axis=0)["position"]
    assert host.cmd("MOVE", axis=0, mode=P.MOVE_UNHOMED, target=pos + 100)["status"] == P.STATUS["RANGE"]
    host.ok("MOVE", axis=0, mode=P.MOVE_UNHOMED | P.MOVE_TRAPEZOID, target=pos - 1500)
    host.run(2.0)
    st = host.ok("STATUS", axis=0)
    assert st["enabled"] and st["limits"] == 0 and b.plant.count(0) < 3000, st
    host.ok("CLEAR_FAULT", mask=1)
    assert host.ok("STATUS", axis=0)["faults"] == 0


@pytest.mark.parametrize("index", [0, 1])
def test_homing_to_the_switch_makes_positions_absolute(host: Host, index: int) -> None:
    b = host.b
    b.limit_counts[0] = (-2500, 100_000)            # the negative switch 2500 counts behind
    host.set(0, "HOME_VEL", 8400)
    host.set(0, "HOME_POS", -100)
    host.ok("ENABLE", mask=1, enable=1)
    assert host.cmd("MOVE", axis=0, mode=0, target=100)["status"] == P.STATUS["NOT_HOMED"]
    host.ok("HOME", axis=0, mode=P.HOME_MODES["neg"], index=index)
    t = host.run(10.0, until=lambda: host.ok("STATUS", axis=0)["home"] != 1)
    st = host.ok("STATUS", axis=0)
    assert t > 0 and st["home"] == 2 and st["faults"] == 0 and st["enabled"], st
    # the home point reads HOME_POS: the switch edge at -2500 raw (or the next index, every 64 counts, above it)
    ref = -2500 if not index else (-2500 // 64 + 1) * 64
    raw = b.plant.count(0)
    assert abs(st["position"] - (raw - ref - 100)) <= 3 + (1 if index else 40), (st["position"], raw, ref)
    # absolute soft limits: -500 is 400 counts beyond the home point, toward the switch
    host.set(0, "SOFT_MIN", -500)           # raising it while enabled: tightening, allowed
    assert host.cmd("MOVE", axis=0, mode=0, target=-501)["status"] == P.STATUS["RANGE"]
    host.ok("MOVE", axis=0, mode=P.MOVE_TRAPEZOID, target=2000)
    host.run(2.0)
    st = host.ok("STATUS", axis=0)
    assert abs(st["position"] - 2000) < 200 and st["faults"] == 0, st   # P law: friction leaves tens of counts
