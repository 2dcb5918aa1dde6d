# SPDX-License-Identifier: MIT
"""The RTL board image as a :class:`~torqueloop.sim.simboard.BytePipe`, so
``torqueloop sim --rtl`` serves the co-simulated SoC (
torqueloop/sim: the Verilator model of the whole board image running the
real servo firmware, the plant closing the loop through its pins) on the
same TCP port as the firmware-in-the-loop board.

Only an adapter: the board, its reset/arming sequence and the plant bridge
are torqueloop.sim's.  Slow - the RTL runs far below real time - so the
server falls behind the wall clock; the host tool's replies still come
(raise ``--timeout``), but the firmware's link watchdog counts simulated
time, which is what keeps it quiet.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from torqueloop.spec.system import SYSTEM

if TYPE_CHECKING:
    from sim_models.variants import PlantSpec

CLK_HZ = SYSTEM.clk_hz


class RtlBoard:
    def __init__(self, seed: int = 0, plant: "str | PlantSpec" = "paper", key: bytes | None = None) -> None:
        """``key``: the link key in the image's boot-ROM key slot (None: a board without one)."""
        from sim_models.stepper import TwoAxisPlant
        from sim_models.variants import plant_of
        from torqueloop.sim.experiment import firmware_image
        from torqueloop.sim.native import NativeBoard
        from torqueloop.sim.pins import PlantOnPins

        img = firmware_image(key)
        self.board = NativeBoard.create(img.rom_hex, img.ram_hex)
        self.bridge = PlantOnPins(TwoAxisPlant(plant_of(plant).params(), seed=seed), self.board)
        # the cosim's power-up: reset with the arm switch down, release, arm (SW[0] rising edge)
        self.board.set_board(0, 1, 0)
        self.bridge.run_to(20)
        self.board.set_board(1, 1, 0)
        self.bridge.run_to(40_000)
        self.board.set_board(1, 1, 1)
        self.build_id = None

    @property
    def t(self) -> float:
        return self.board.cycle / CLK_HZ

    def write(self, data: bytes) -> None:
        self.board.uart_send(data)

    def read(self) -> bytes:
        return self.board.uart_recv()[0]

    def advance(self, max_dt: float) -> float:
        n = max(1, int(max_dt * CLK_HZ))
        c0 = self.board.cycle
        self.bridge.run_to(c0 + n)
        return (self.board.cycle - c0) / CLK_HZ
