# SPDX-License-Identifier: MIT
"""Host side of the servo link over a simulated UART: the frames of
torqueloop.spec.protocol (the same code the host tool uses), with the board and
the plant advancing while the host waits for a reply.  After
:meth:`Link.open_session` every command but the reads carries the session's
MAC, as the host tool sends it (docs/security.md)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from torqueloop.spec import auth
from torqueloop.spec import protocol as tp


class LinkError(RuntimeError):
    pass


@dataclass
class Telemetry:
    cycle: int                 # clock of the start bit of the frame's first byte after its 0x00
    time_us: int               # firmware time of the control sample (ticks x period)
    axes: list[dict]           # per axis: setpoint, position, velocity_q8, error, pwm_cmd, faults, enabled


@dataclass
class Link:
    """``send(bytes)`` puts bytes on the line to the FPGA, ``recv()`` returns
    what arrived and the clock of each byte's start bit, ``advance(cycles)`` runs board and plant that much further,
    ``now()`` is the clock count."""

    send: Callable[[bytes], None]
    recv: Callable[[], tuple[bytes, list[int]]]
    advance: Callable[[int], None]
    now: Callable[[], int]
    seq: int = 1
    telemetry: list[Telemetry] = field(default_factory=list)
    errors: list[tp.FrameError] = field(default_factory=list)
    _dec: tp.FrameDecoder = field(default_factory=tp.FrameDecoder)
    _replies: dict[int, tp.Frame] = field(default_factory=dict)
    _chunk_cycle: int = -1
    session: auth.Session | None = None

    def open_session(self, key: bytes, host_nonce: bytes | None = None) -> None:
        """SESSION, and the board's proof checked: later commands carry their MAC.
        ``host_nonce``: a fixed one for runs that must repeat byte for byte
        (a fresh random one otherwise, as a real host must)."""
        hn = auth.new_host_nonce() if host_nonce is None else host_nonce
        self.session = auth.open_session(key, hn, self.call("SESSION", host_nonce=hn))

    def poll(self) -> None:
        data, cycles = self.recv()
        for byte, cyc in zip(data, cycles):
            if byte and self._chunk_cycle < 0:
                self._chunk_cycle = cyc
            for f in self._dec.feed(bytes((byte,))):
                if isinstance(f, tp.FrameError):
                    self.errors.append(f)
                elif f.cmd == tp.TELEMETRY_CMD:
                    d = tp.decode_telemetry(f)
                    self.telemetry.append(Telemetry(self._chunk_cycle, d["time_us"], d["axes"]))
                else:
                    self._replies[f.seq] = f
            if not byte:
                self._chunk_cycle = -1

    def post(self, name: str, **fields: int) -> int:
        """Send a request without waiting; returns its seq."""
        seq = self.seq
        self.seq = (self.seq + 1) & 0xFFFF or 1
        tagged = self.session is not None and not tp.COMMANDS[name].untagged
        self.send(self.session.request(name, seq, **fields) if tagged else tp.request(name, seq, **fields))
        return seq

    def wait(self, seq: int, timeout_cycles: int = 5_000_000, step: int = 20_000) -> dict[str, int]:
        end = self.now() + timeout_cycles
        while self.now() < end:
            self.advance(step)
            self.poll()
            f = self._replies.pop(seq, None)
            if f is not None:
                return tp.decode_reply(f)
        raise LinkError(f"no reply to seq {seq} within {timeout_cycles} clocks")

    def call(self, name: str, check: bool = True, **fields: int) -> dict[str, int]:
        r = self.wait(self.post(name, **fields))
        if check and r["status"] != tp.STATUS["OK"]:
            raise LinkError(f"{name} {fields}: status {tp.STATUS_NAME.get(r['status'], r['status'])}")
        return r

    def set_param(self, axis: int, name: str, value: int) -> int:
        return self.call("SET_PARAM", axis=axis, param=tp.PARAMS[name].id, value=value)["value"]

    def get_param(self, axis: int, name: str) -> int:
        return self.call("GET_PARAM", axis=axis, param=tp.PARAMS[name].id)["value"]
