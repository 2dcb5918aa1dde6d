# SPDX-License-Identifier: MIT
"""The simulated board's plant stepping (torqueloop/sim/simboard.py): a
stretch at once (``TwoAxisPlant.run_pins``) where nothing reads encoder
edges, with the last edges stepped edge by edge where the firmware takes the
speed from edge timestamps (VEL_MODE 1, the default), against stepping every
edge (``SimBoard(edges=True)``, the reference).

On the paper's plant (no winding heating, whose per-stretch update moves the
lab plant by parts in 1e5) the firmware sees the same thing either way: the
same position, speed estimate and command at every control period, through
a step, a reversal half way and the hold after it, PD on both axes (the law
that reads the speed).
"""

from __future__ import annotations

import pytest

from torqueloop.sim.model_loop import TABLE1
from torqueloop.sim.simboard import SimBoard
from torqueloop.spec import auth
from torqueloop.spec import protocol as P

from test_safety_simboard import Host

PERIOD_S = 0.025


def trace(edges: bool, vel_mode: int) -> list[tuple[int, ...]]:
    """(position, speed estimate, command) of both axes at every period."""
    host = Host(SimBoard(key=auth.TEST_KEY, plant="paper", edges=edges))
    for ax in (0, 1):
        g = TABLE1["PD"][ax]
        host.set(ax, "LAW", 2)
        host.set(ax, "VEL_MODE", vel_mode)
        host.set(ax, "KP_UNM_RAD", round(g.kp * 1e6))
        host.set(ax, "KD_UNMS_RAD", round(g.kd * 1e6))
    host.ok("ENABLE", mask=3, enable=1)
    out = []
    for target, seconds in [(8400, 0.6), (-2000, 1.0), (0, 0.5)]:
        for ax in (0, 1):
            host.ok("MOVE", axis=ax, mode=P.MOVE_UNHOMED, target=target)
        end = host.b.t + seconds
        while host.b.t < end:
            host.b.advance(PERIOD_S)
            host.b.read()
            host.ok("HEARTBEAT")
            row: tuple[int, ...] = ()
            for ax in (0, 1):
                st = host.ok("STATUS", axis=ax)
                row += (st["position"], st["velocity_q8"], st["pwm_cmd"])
            out.append(row)
    return out


@pytest.mark.parametrize("vel_mode", [0, 1])
def test_stepping_a_stretch_at_once_shows_the_firmware_what_every_edge_does(vel_mode: int) -> None:
    ref = trace(True, vel_mode)
    got = trace(False, vel_mode)
    moving = sum(1 for a, b in zip(ref, ref[1:]) if a[0] != b[0])
    assert moving > 40, f"only {moving} periods with motion: the script no longer moves the axes"
    diff = [(k, r, g) for k, (r, g) in enumerate(zip(ref, got)) if r != g]
    assert not diff, f"{len(diff)} of {len(ref)} periods differ, first {diff[:3]}"
