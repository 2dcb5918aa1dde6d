# SPDX-License-Identifier: MIT
"""Reference model of the board-level drive interlock (rtl/board/drive_interlock).

Written from the behaviour the board needs (docs/hardware.md), not from the
RTL: the H-bridge inputs pass only while the drives are armed; arming is a
fresh up-move of the arm switch with no stop and no fault while the SoC's
watchdog is alive; a stop, a fault that lasted ``fault_filter_clks`` clocks,
the watchdog not alive, or the switch going down disarms; a stop, a fault or
the watchdog expiring (alive falling) latches ``tripped``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields


@dataclass
class BridgeLines:
    """The four IBT-2 logic lines of every axis, a bit per axis (one axis's
    are torqueloop.spec.bridge.Pins): the demand going in, and out again
    only while the drives are armed."""

    rpwm: int = 0
    lpwm: int = 0
    r_en: int = 0
    l_en: int = 0

    def gated(self, mask: int) -> dict[str, int]:
        """Each line ANDed with ``mask`` (all axes' bits, or none)."""
        return {f.name: getattr(self, f.name) & mask for f in fields(BridgeLines)}


@dataclass
class InterlockInputs(BridgeLines):
    estop: bool = False
    arm_sw: bool = False
    fault: int = 0          # bit per axis
    alive: bool = True      # the SoC's watchdog armed and not expired


@dataclass
class InterlockOutputs(BridgeLines):
    armed: bool = False
    tripped: bool = False
    fault_latched: int = 0


@dataclass
class DriveInterlockModel:
    """Cycle model: :meth:`clock` takes the inputs present at a rising edge
    and returns the outputs just after it."""

    axes: int = 2
    fault_filter_clks: int = 250
    _fault_run: list[int] = field(default_factory=list)   # consecutive fault clocks per axis
    _switch_was_up: bool = True
    _was_alive: bool = False
    _out: InterlockOutputs = field(default_factory=InterlockOutputs)

    def __post_init__(self) -> None:
        self.reset()

    def reset(self) -> InterlockOutputs:
        self._fault_run = [0] * self.axes
        # A switch already up when reset ends must not arm the drives.
        self._switch_was_up = True
        self._was_alive = False
        self._out = InterlockOutputs()
        return self._out

    def _fault_confirmed(self) -> int:
        return sum(1 << i for i, n in enumerate(self._fault_run) if n >= self.fault_filter_clks)

    def clock(self, i: InterlockInputs) -> InterlockOutputs:
        prev = self._out
        confirmed = self._fault_confirmed()          # from the clocks before this edge
        armed, tripped, latched = prev.armed, prev.tripped, prev.fault_latched
        stop = bool(i.estop or confirmed)
        if stop or not i.alive:
            lost = self._was_alive and not i.alive
            armed, tripped, latched = False, tripped or stop or lost, latched | confirmed
        elif not i.arm_sw:
            armed = False
        elif not self._switch_was_up:
            armed, tripped, latched = True, False, 0
        gate = (1 << self.axes) - 1 if prev.armed else 0
        self._out = InterlockOutputs(**i.gated(gate), armed=armed, tripped=tripped, fault_latched=latched)
        self._switch_was_up = i.arm_sw
        self._was_alive = i.alive
        for a in range(self.axes):
            self._fault_run[a] = self._fault_run[a] + 1 if (i.fault >> a) & 1 else 0
        return self._out
