# SPDX-License-Identifier: MIT
"""The one rule the host applies before sending (MOVE's, torqueloop.host.session.move_refusal)
against the firmware's own (cmd_move, the servo C on the simulated board): for a table of
board states and every MOVE around each of its bounds, both refuse exactly the same moves,
with the same status and the same rule; and a refusal the board sends names its rule."""

from __future__ import annotations

import itertools

import pytest

from torqueloop.host.client import Client, CommandRejected
from torqueloop.host.session import MoveLimits, Session, move_refusal
from torqueloop.sim.simboard import SimBoard, SimBoardTransport
from torqueloop.spec import auth
from torqueloop.spec import protocol as P

PERIOD_S = 0.025


def client() -> Client:
    b = SimBoard(key=auth.TEST_KEY)
    c = Client(SimBoardTransport(b, PERIOD_S), timeout=1.0, retries=0, clock=lambda: b.t, key=auth.TEST_KEY)
    c.connect()
    return c


def _enabled(c: Client) -> None:
    c.enable(1)


def _homed(c: Client) -> None:
    c.set_param("LIMIT_SW", 0, 0)       # home here: only on an axis without switches
    c.home(0, "here")
    c.enable(1)


def _homing(c: Client) -> None:
    c.home(0, "neg")                    # from disabled: homing to a switch enables its axis


def _tight(c: Client) -> None:
    c.set_param("SOFT_MIN", -1000, 0)
    c.set_param("SOFT_MAX", 1500, 0)
    c.set_param("FOLLOW_LIMIT", 400, 0)
    c.enable(1)


def _outside(c: Client) -> None:
    """Enabled beyond its soft limit (the power-up position 0 above SOFT_MAX)."""
    c.set_param("SOFT_MIN", -3000, 0)
    c.set_param("SOFT_MAX", -2000, 0)
    c.enable(1)


STATES = {"disabled": lambda c: None, "enabled": _enabled, "homed": _homed, "homing": _homing,
          "tight limits": _tight, "beyond SOFT_MAX": _outside}


def _targets(st: dict[str, int], lim: MoveLimits) -> list[int]:
    """Each bound of MOVE's rule and one count either side of it."""
    pos = st["position"]
    edges = (lim.soft_min, lim.soft_max, pos + lim.follow_limit, pos - lim.follow_limit, pos)
    return sorted({e + d for e in edges for d in (-1, 0, 1) if -2**31 < e + d < 2**31})


def _board_refusal(c: Client, axis: int, target: int, trapezoid: bool, unhomed: bool) -> tuple[str, str] | None:
    try:
        c.move(axis, target, trapezoid, unhomed)
    except CommandRejected as e:
        return P.STATUS_NAME[e.status], e.rule
    c.stop(1 << axis)              # hold where it is: the next case starts from the same state
    return None


@pytest.mark.parametrize("state", list(STATES))
def test_host_and_firmware_refuse_the_same_moves(state: str) -> None:
    c = client()
    STATES[state](c)
    st = c.status(0)
    lim = Session(c).move_limits(0)
    cases = 0
    refused = set()
    for target, trapezoid, unhomed in itertools.product(_targets(st, lim), (False, True), (False, True)):
        st = c.status(0)
        host = move_refusal(st, lim, target, trapezoid, unhomed)
        board = _board_refusal(c, 0, target, trapezoid, unhomed)
        assert host == board, f"{state}: MOVE {target} trapezoid={trapezoid} unhomed={unhomed} from {st}"
        cases += 1
        refused.add(board[1] if board else "accepted")
    print(f"{state}: {cases} moves, outcomes {sorted(refused)}")
    assert cases >= 20


def test_the_table_reaches_every_rule_the_host_applies() -> None:
    """The states above between them give every outcome of MOVE's rule but
    LIMIT, which only a limit switch gives (a soft-limit side blocks only
    targets beyond that soft limit, refused as OUTSIDE_SOFT first); the plant
    would have to drive onto a switch: tests/test_safety_simboard.py does."""
    seen = set()
    for state, setup in STATES.items():
        c = client()
        setup(c)
        st, lim = c.status(0), Session(c).move_limits(0)
        for target, trapezoid, unhomed in itertools.product(_targets(st, lim), (False, True), (False, True)):
            r = move_refusal(st, lim, target, trapezoid, unhomed)
            seen.add(r[1] if r else "accepted")
    assert seen == {"DISABLED", "HOMING", "NOT_HOMED", "OUTSIDE_SOFT", "FOLLOW", "accepted"}, seen


def test_a_refusal_names_its_rule() -> None:
    c = client()
    c.set_param("PWMAX", 800, 0)
    with pytest.raises(CommandRejected) as e:
        c.set_param("PW0", 801, 0)
    assert (P.STATUS_NAME[e.value.status], e.value.rule) == ("RANGE", "PW_ORDER")
    assert "PW0 would be above PWMAX" in str(e.value)
    c.enable(1)
    with pytest.raises(CommandRejected) as e:
        c.home(0, "neg")                                   # homing moves the soft-limit window
    assert e.value.rule == "AXES_ENABLED"
    c.enable(1, False)
    with pytest.raises(CommandRejected) as e:
        c.home(0, "here")                                  # the home of an axis with switches is a switch
    assert e.value.rule == "HAS_SWITCHES"
    c.set_param("LIMIT_SW", 0, 0)
    with pytest.raises(CommandRejected) as e:
        c.home(0, "neg")
    assert e.value.rule == "NO_SWITCHES"
    c.enable(1)
    with pytest.raises(CommandRejected) as e:
        c.set_param("FOLLOW_LIMIT", P.PARAMS["FOLLOW_LIMIT"].default + 1, 0)   # looser while enabled
    assert (P.STATUS_NAME[e.value.status], e.value.rule) == ("LOOSEN", "TIGHTEN")
    with pytest.raises(CommandRejected) as e:
        c.transact("GET_PARAM", axis=0, param=P.PARAMS["PERIOD_US"].id)         # a global one, axis 0
    assert e.value.rule == "SCOPE"


def test_host_and_firmware_refuse_the_same_parameter_values() -> None:
    """The other check the host makes before sending: a value outside the
    parameter's [min, max] (Client.set_param).  Each parameter at and either
    side of both ends, on a board with every axis disabled (no tighten-only
    refusal): the host refuses exactly the values the firmware refuses, with
    the same rule.  Bounds between parameters are left to the board."""
    c = client()
    cases = 0
    for p in P.PARAMS.values():
        axis = P.GLOBAL_AXIS if p.scope == "global" else 0
        for v in (p.min - 1, p.min, p.max, p.max + 1):
            if not -2**31 <= v < 2**31:
                continue                                   # not a 32-bit value: nothing to send
            try:
                c.set_param(p.name, v, axis)
                host = None
            except CommandRejected as e:
                host = e.rule
            try:
                c.transact("SET_PARAM", axis=axis, param=p.id, value=v)   # straight to the board
                board = None
            except CommandRejected as e:
                board = e.rule
            if host is None and board is not None:
                assert board not in ("BELOW_MIN", "ABOVE_MAX"), (p.name, v, board)   # a bound between parameters
            else:
                assert host == board, (p.name, v, host, board)
            cases += 1
    print(f"{cases} values of {len(P.PARAMS)} parameters")
    assert cases > 3 * len(P.PARAMS)
