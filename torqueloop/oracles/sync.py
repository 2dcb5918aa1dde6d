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


class DebounceModel:
    """WIDTH debounce filters (rtl/common/tl_debounce): a bit of the output
    takes the input's value once the input has differed from it on
    ``stable_clks`` consecutive edges."""

    def __init__(self, width: int, stable_clks: int, reset_val: int) -> None:
        self.width, self.stable = width, stable_clks
        self.reset_word = (1 << width) - 1 if reset_val & 1 else 0
        self.reset()

    def reset(self) -> None:
        self.q = self.reset_word
        self.cnt = [0] * self.width

    def clock(self, sync_in: int) -> int:
        """One rising edge with ``sync_in`` at it; returns q after the edge."""
        q = self.q
        for i in range(self.width):
            bit, cur = (sync_in >> i) & 1, (self.q >> i) & 1
            if bit == cur:
                self.cnt[i] = 0
            elif self.cnt[i] == self.stable - 1:
                q = (q & ~(1 << i)) | (bit << i)
                self.cnt[i] = 0
            else:
                self.cnt[i] += 1
        self.q = q
        return q


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
