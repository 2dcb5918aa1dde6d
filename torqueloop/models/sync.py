# SPDX-License-Identifier: MIT
"""Reference models of the synchronisers (rtl/common)."""

from __future__ import annotations

from collections import deque


class Sync2ffModel:
    """WIDTH-bit two-flop synchroniser: the output after clock edge k is the
    input sampled at edge k-1 (two registers, reset to the idle level)."""

    def __init__(self, width: int, reset_val: int) -> None:
        self.mask = (1 << width) - 1
        self.reset_word = self.mask if reset_val & 1 else 0
        self.pipe: deque[int] = deque([self.reset_word, self.reset_word], maxlen=2)

    def reset(self) -> None:
        self.pipe.extend([self.reset_word, self.reset_word])

    def clock(self, async_in: int) -> int:
        """Advance one rising edge with ``async_in`` stable at the edge; return sync_out."""
        self.pipe.appendleft(async_in & self.mask)
        return self.pipe[1]


class ResetSyncModel:
    """Asynchronous assert, STAGES-edge synchronous release."""

    def __init__(self, stages: int) -> None:
        self.stages = stages
        self.edges_since_release: int | None = None  # None: held in reset

    def assert_reset(self) -> None:
        self.edges_since_release = None

    def release(self) -> None:
        self.edges_since_release = 0

    def clock(self) -> None:
        if self.edges_since_release is not None:
            self.edges_since_release += 1

    @property
    def rst_out(self) -> int:
        if self.edges_since_release is None:
            return 1
        return 1 if self.edges_since_release < self.stages else 0
