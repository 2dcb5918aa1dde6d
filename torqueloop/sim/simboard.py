# SPDX-License-Identifier: MIT
"""The simulated board: the servo firmware's own C, compiled for this
machine, closing the loop around the plant model.

Firmware-in-the-loop, not RTL-in-the-loop: servo.c, tl_link.c and control.c
(every byte of the protocol and every control step) run unchanged through
the HAL in ``simboard_hal.c``; the FPGA blocks around them are modelled at
the level their reference models define:

- PWM (freq_div + pwm_torque): ``torqueloop.oracles.pwm_schedule``, the one
  event-level model of the PWM block (carrier of FDIV x 1023 clocks, eq. 1
  duty, double buffering, brake in the off phase, the BRAKE parameter's
  safe state while disabled);
- the quadrature decoder: the plant's count, with the time of its last edge,
  and its index latch (the plant's Z pulse);
- limit switches at the ends of each axis's travel (normally closed; open
  beyond ``limit_counts``), and the SoC's limit block: the bridge side that
  drives toward an open switch is held off;
- faults a test can inject: a frozen or reversed encoder (``encoder_fault``),
  a bridge fault input, the e-stop;
- the configuration flash the firmware stores its parameters in
  (``torqueloop.sim.epcs``, the EPCS command set byte by byte; with a file,
  it survives this process: a power cycle is a new process on the same file);
- the plant: ``sim_models.stepper.TwoAxisPlant`` (paper eq. 5-17), stepped
  a stretch at once (``TwoAxisPlant.run_pins``, docs/plant.md "The fast
  path") where nothing reads encoder edges; edge by edge (its ``advance`` at
  every pin change) while an index latch is armed and in the boot ROM's
  window; and, while the firmware takes the speed from the decoder's edge
  timestamps (VEL_MODE 1, the default), at once with the stretch's last
  edges stepped again edge by edge (``_run_last_edges``).  ``edges=True``
  steps every edge always: the reference the others are checked against
  (tests/test_simboard_stepping.py).  Each control period is one stretch.

UART bytes reach the firmware when they arrive and its replies leave at
once (115200 baud adds under 7 ms to a 70-byte frame; the host's timeouts
are 0.5 s).  The cycle counter the firmware reads (``hal_cycles``, mcycle
on the board) is the simulated clock, one character time apart for the
bytes of one write, and every firmware start begins from cleared RAM (crt0's
.bss): the session nonces are drawn as the board draws them.  The board is a byte pipe (:class:`BytePipe`): ``write`` /
``read`` bytes and ``advance`` time; :mod:`.server` puts any byte pipe on a
TCP port, so the RTL co-simulation can take this one's place.
"""

from __future__ import annotations

import copy
import ctypes
import hashlib
import os
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from torqueloop.flow.firmware import AUTH_SOURCES, SERVO_CORE
from torqueloop.oracles.pwm_schedule import PwmChannel, PwmSetting, run_pins_until, run_until
from torqueloop.sim.epcs import Epcs
from torqueloop.spec import auth
from torqueloop.spec.bridge import BRAKE, COAST
from torqueloop.spec.system import SYSTEM

if TYPE_CHECKING:
    from sim_models.variants import PlantSpec

REPO = Path(__file__).resolve().parents[2]
FW = REPO / "firmware"
SOURCES = [Path(__file__).with_name("simboard_hal.c"), *SERVO_CORE, FW / "protocol" / "tl_link.c", *AUTH_SOURCES]
#: every header the build can include (the cache key of the built library)
HEADERS = sorted(h for d in ("servo", "protocol", "crypto", "boot") for h in (FW / d).glob("*.h"))
BUILD = REPO / "build" / "host"
CLK_HZ = SYSTEM.clk_hz
DEFAULT_BUILD_ID = 0x51B0_0001
#: Limit switches of the simulated stage, encoder counts from the power-up
#: position: the negative end's switch opens below the first, the positive
#: end's above the second (about +-190 mm of a 4 mm lead).
LIMIT_COUNTS = (-400_000, 400_000)
LIM_NEG, LIM_POS = 0x01, 0x02
#: a stretch stepped at once while the firmware reads edge timestamps runs in this many pieces,
#: the last halved toward its end TAIL_HALVINGS times (SimBoard._run_last_edges)
TAIL_PIECES, TAIL_HALVINGS = 8, 3
#: ... if it is at least this long (5 ms); a shorter one (PERIOD_US 1000 while identifying) is stepped
#: edge by edge: its few pin changes leave the pieces nothing to batch
TAIL_MIN_CLOCKS = 250_000
#: an undercounting encoder passes one count of this many (set_encoder_fault)
UNDERCOUNT = 50
#: the simulated flash's write times: a sector erase takes up to 3 s on an EPCS64, which the
#: firmware would poll some 10^6 times through ctypes here; the logic does not depend on them
FLASH_PROGRAM_S, FLASH_ERASE_S = 0.0002, 0.002
_FLASH_SELECT = ctypes.CFUNCTYPE(None, ctypes.c_int32)
_FLASH_XFER = ctypes.CFUNCTYPE(ctypes.c_uint32, ctypes.c_uint32)


class BytePipe(Protocol):
    """What :mod:`.server` needs from a simulated board."""

    t: float   # simulated seconds

    def write(self, data: bytes) -> None: ...

    def read(self) -> bytes: ...

    def advance(self, max_dt: float) -> float:
        """Run at most ``max_dt`` simulated seconds (a natural step may be
        shorter); returns the simulated time actually run."""
        ...


def build_library() -> Path:
    """Compile the firmware and the HAL into a shared library, once per source hash."""
    h = hashlib.sha256()
    for p in SOURCES + HEADERS:
        h.update(p.read_bytes())
    BUILD.mkdir(parents=True, exist_ok=True)
    lib = BUILD / f"simboard_{h.hexdigest()[:12]}.so"
    if not lib.exists():
        tmp = lib.with_suffix(f".{os.getpid()}.tmp")   # concurrent builders (pytest -n) do not collide
        subprocess.run(["gcc", "-std=c11", "-O2", "-shared", "-fPIC", "-Wall", "-Wextra", "-Werror",
                        f"-I{FW / 'servo'}", f"-I{FW / 'protocol'}", f"-I{FW / 'crypto'}", f"-I{FW / 'boot'}",
                        *map(str, SOURCES),
                        "-o", str(tmp)],
                       check=True)
        tmp.replace(lib)
    return lib


class SimBoard:
    """Firmware + PWM + decoder + plant.  One instance per process (the
    firmware's state is the library's statics).  ``key``: the link key in
    its boot ROM's key slot (None: a board built without a key, which
    refuses motion, parameter changes and uploads; docs/security.md).
    ``edges``: step the plant edge by edge even where nothing reads the
    encoder's edges (slower; the reference for the stepping a stretch at
    once)."""

    def __init__(self, build_id: int = DEFAULT_BUILD_ID, seed: int = 0, plant: "str | PlantSpec" = "paper",
                 key: bytes | None = None, flash: Epcs | None = None, edges: bool = False) -> None:
        from sim_models.stepper import TwoAxisPlant
        from sim_models.variants import plant_of

        self._lib = ctypes.CDLL(str(build_library()))
        self._lib.sb_tx_take.restype = ctypes.c_uint32
        self._lib.sb_period_us.restype = ctypes.c_uint32
        self._lib.sb_baud_div.restype = ctypes.c_uint32
        self._lib.sb_bootloader_requested.restype = ctypes.c_int32
        self._lib.sb_index_armed.restype = ctypes.c_int32
        self._lib.sb_vel_mode.restype = ctypes.c_int32
        self.edges = edges
        self.plant = TwoAxisPlant(plant_of(plant).params(), seed=seed)
        self.tick = 0                    # 50 MHz clocks since power-up
        self._edge_tick = [0, 0]
        self._edge_interval = [0, 0]     # clocks between the last two encoder counts
        self._pwm = [PwmChannel(), PwmChannel()]   # the PWM blocks (freq_div + pwm_torque)
        self._next_tick_at = 0
        self._txbuf = ctypes.create_string_buffer(16384)
        self._drive = (ctypes.c_int32 * 7)()
        self.bridge_fault = [False, False]
        #: per axis None, "frozen" (the count stops where it is), "reversed" (counts the wrong way) or
        #: "undercounting" (one count of every UNDERCOUNT arrives)
        self.encoder_fault: list[str | None] = [None, None]
        self._fault_ref = [0, 0]
        self.limit_counts = [LIMIT_COUNTS, LIMIT_COUNTS]
        self._count = [self.plant.count(0), self.plant.count(1)]   # the decoder's count, edge by edge
        self._gray = [self._gray_index(a) for a in range(2)]
        self.build_id = build_id
        self.factory_build_id = build_id
        self.key = key
        self._slot = ctypes.create_string_buffer(auth.key_slot(key), auth.KEY_SLOT_BYTES)
        self.boot: SimBootRom | None = None
        self._boot_out = b""
        #: the configuration flash; shortened write times (the firmware polls it byte by byte here)
        self.flash = flash if flash is not None else Epcs(program_s=FLASH_PROGRAM_S, erase_s=FLASH_ERASE_S)
        self._flash_cbs = (_FLASH_SELECT(lambda on: self.flash.select(bool(on))),
                           _FLASH_XFER(lambda out: self.flash.xfer(out)))
        self._lib.sb_set_flash(*self._flash_cbs)
        self._sync_encoders()
        self._lib.sb_reset(ctypes.c_uint32(build_id), self._slot)
        self._load_drives()
        self._next_tick_at = self._period_ticks()

    # ---- byte pipe -------------------------------------------------------------
    @property
    def t(self) -> float:
        return self.tick / CLK_HZ

    def write(self, data: bytes) -> None:
        if not data:
            return
        if self.boot is not None:
            self.boot.rx(data, self.tick)
        else:
            self._lib.sb_rx(ctypes.c_uint32(self.tick & 0xFFFFFFFF), data, ctypes.c_uint32(len(data)))
            self._load_drives()

    def read(self) -> bytes:
        n = self._lib.sb_tx_take(self._txbuf, ctypes.c_uint32(len(self._txbuf)))
        out = self._txbuf.raw[:n]
        if self.boot is not None or self._boot_out:
            out, self._boot_out = out + self._boot_out, b""
        return out

    def advance(self, max_dt: float) -> float:
        """Run to the next control iteration (or ``max_dt``, whichever is first)."""
        t0 = self.tick
        if self.boot is None and self._lib.sb_bootloader_requested():
            # main.c's jump_to_bootloader: the reply is out, the firmware stops
            try:
                self.boot = SimBootRom(self.tick, self.key)
            except ImportError:      # no torqueloop.spec.bootproto: a boot stub that restarts the firmware
                self.restart(self.factory_build_id)
        if self.boot is not None:
            self._run_pwm_until(self.tick + max(1, int(max_dt * CLK_HZ)))
            started = self.boot.poll(self.tick)
            self._boot_out += self.boot.take_tx()
            if started is not None:
                self.boot = None
                self.restart(self.factory_build_id if started == "factory" else started)
            return (self.tick - t0) / CLK_HZ
        end = min(self._next_tick_at, self.tick + max(1, int(max_dt * CLK_HZ)))
        self._run_pwm_until(end)
        if self.tick == self._next_tick_at:
            self._sync_encoders()
            self._lib.sb_tick()
            self._load_drives()
            self._next_tick_at += self._period_ticks()
        return (self.tick - t0) / CLK_HZ

    def restart(self, build_id: int) -> None:
        """A firmware start (reset or the boot ROM's jump): fresh firmware state."""
        self.build_id = build_id
        self._sync_encoders()
        self._lib.sb_reset(ctypes.c_uint32(build_id), self._slot)
        self._load_drives()
        self._next_tick_at = self.tick + self._period_ticks()

    def power_cycle(self) -> None:
        """Power off and on: the flash keeps what it holds, the firmware starts afresh."""
        self.flash.power_on()
        self.boot = None
        self.restart(self.factory_build_id)

    def reset(self) -> None:
        """The reset button: drives off, the boot ROM's window (then the factory firmware, or an upload)."""
        self.restart(self.factory_build_id)
        self.boot = SimBootRom(self.tick, self.key)

    # ---- test handles -------------------------------------------------------------
    def set_estop(self, pressed: bool) -> None:
        self._lib.sb_set_estop(ctypes.c_int32(int(pressed)))
        self._load_drives()

    def bootloader_requested(self) -> bool:
        return bool(self._lib.sb_bootloader_requested())

    def drive(self, axis: int) -> dict[str, int]:
        self._lib.sb_get_drive(ctypes.c_uint32(axis), self._drive)
        return dict(zip(("cmd", "on", "brake", "fdiv", "pw0", "pwmax", "limit_block"), self._drive))

    def set_encoder_fault(self, axis: int, kind: str | None) -> None:
        """Freeze the encoder's count where it is, make it count the wrong way
        from here (a swapped A/B pair), lose all but one count of UNDERCOUNT
        from here (a dirty disc, a marginal signal), or (None) heal it."""
        if kind not in (None, "frozen", "reversed", "undercounting"):
            raise ValueError(f"encoder fault {kind!r}")
        self._fault_ref[axis] = self.plant.count(axis)
        self.encoder_fault[axis] = kind

    def encoder_count(self, axis: int) -> int:
        """The count the decoder reports (the plant's, unless a fault is injected)."""
        c, ref = self.plant.count(axis), self._fault_ref[axis]
        kind = self.encoder_fault[axis]
        if kind == "undercounting":
            return ref + (c - ref) // UNDERCOUNT
        return ref if kind == "frozen" else (2 * ref - c if kind == "reversed" else c)

    def limits(self, axis: int) -> int:
        """Limit switches open now (LIM_NEG / LIM_POS), from the plant's true position."""
        lo, hi = self.limit_counts[axis]
        c = self.plant.count(axis)
        return (LIM_NEG if c < lo else 0) | (LIM_POS if c > hi else 0)

    # ---- inside -------------------------------------------------------------------
    def _period_ticks(self) -> int:
        return int(self._lib.sb_period_us()) * (CLK_HZ // 1_000_000)

    def _sync_encoders(self) -> None:
        for a in range(2):
            self._lib.sb_set_encoder(ctypes.c_uint32(a), ctypes.c_int32(self.encoder_count(a)),
                                     ctypes.c_uint32(self._edge_tick[a] & 0xFFFFFFFF),
                                     ctypes.c_uint32(min(self._edge_interval[a], 0xFFFFFFFF)),
                                     ctypes.c_uint32(self.tick & 0xFFFFFFFF), ctypes.c_uint32(0),
                                     ctypes.c_int32(int(self.bridge_fault[a])), ctypes.c_uint32(self.limits(a)))

    def _load_drives(self) -> None:
        """What the firmware last wrote to each axis's PWM registers, as the
        PWM block takes it (torqueloop.oracles.pwm_schedule)."""
        for a, ch in enumerate(self._pwm):
            d = self.drive(a)
            cmd = d["cmd"] if d["on"] else 0
            lim = self.limits(a) if d["limit_block"] else 0
            if (cmd > 0 and lim & LIM_POS) or (cmd < 0 and lim & LIM_NEG):
                cmd = 0     # the SoC's limit block holds that bridge side off
            ch.load(PwmSetting(cmd=cmd, div=d["fdiv"], pw0=d["pw0"], pwmax=d["pwmax"],
                               enabled=bool(d["on"]), safe=BRAKE if d["brake"] else COAST))

    def _gray_index(self, axis: int) -> int:
        return self.plant.count(axis) & 3

    def _edges(self, start: int, edges: list) -> None:
        for e in edges:
            at = start + int(e.t * CLK_HZ)
            self._edge_interval[e.axis] = at - self._edge_tick[e.axis]
            self._edge_tick[e.axis] = at
            g = _GRAY_INDEX[(e.a, e.b)]
            self._count[e.axis] += 1 if (g - self._gray[e.axis]) & 3 == 1 else -1
            self._gray[e.axis] = g
            if e.z and self._lib.sb_index_armed(ctypes.c_uint32(e.axis)) and self.encoder_fault[e.axis] is None:
                self._lib.sb_index_latch(ctypes.c_uint32(e.axis), ctypes.c_int32(self._count[e.axis]))

    def _needs_edges(self) -> bool:
        """Whether every encoder edge of the stretch ahead matters: an armed
        index latch, the boot ROM's window (its jump restarts the firmware),
        or ``edges=True``."""
        return (self.edges or self.boot is not None
                or any(self._lib.sb_index_armed(ctypes.c_uint32(a)) for a in range(2)))

    def _needs_last_edges(self) -> bool:
        """Whether the firmware reads the decoder's last edge time and the
        interval before it (VEL_MODE 1 on an axis)."""
        return any(self._lib.sb_vel_mode(ctypes.c_uint32(a)) for a in range(2))

    def _run_pwm_until(self, end: int) -> None:
        if end <= self.tick:
            return
        if self._needs_edges():
            run_until(self.plant, self._pwm, self.tick, end, CLK_HZ, self._edges)
        elif self._needs_last_edges():
            if end - self.tick < TAIL_MIN_CLOCKS:
                run_until(self.plant, self._pwm, self.tick, end, CLK_HZ, self._edges)
            else:
                self._run_last_edges(end)
        else:
            self._run_pins(self.tick, end)
        self.tick = end

    def _run_pins(self, start: int, end: int) -> None:
        """The stretch at once, no edges: the decoder's count is the plant's at
        the end (where the edges would have left it); its last edge time and
        the interval before it keep their values."""
        run_pins_until(self.plant, self._pwm, start, end, CLK_HZ)
        self._decoder_from_plant()

    def _decoder_from_plant(self) -> None:
        """The decoder's count and Gray state where the plant's edges would have left them."""
        for a in range(2):
            self._count[a], self._gray[a] = self.plant.count(a), self._gray_index(a)

    def _run_last_edges(self, end: int) -> None:
        """What the decoder's last edge time and the interval before it are at
        ``end``, for less than stepping every edge: the stretch runs at once
        in TAIL_PIECES pieces, the last of them halved toward the end
        TAIL_HALVINGS times, the plant's state kept at each boundary.  From
        the latest boundary after which every axis that counted since the
        stretch began counts at least two more (or, if it had not counted
        before, counts at all) to the first after which no axis counts, the
        plant is stepped again edge by edge: its edges there are the last
        ones; then it runs at once to the end.  A count that leaves and comes
        back within a piece run at once is not seen: the interval of the next
        edge is then measured from the edge before it."""
        start = self.tick
        span = end - start
        last = start + span * (TAIL_PIECES - 1) // TAIL_PIECES
        bounds = sorted({start + span * k // TAIL_PIECES for k in range(TAIL_PIECES)}
                        | {end - ((end - last) >> j) for j in range(TAIL_HALVINGS + 1)} | {end})
        saved, counts = [], [[self.plant.count(a) for a in range(2)]]
        for lo, hi in zip(bounds, bounds[1:]):
            saved.append((self.plant.snapshot(), [copy.copy(ch) for ch in self._pwm]))
            self._run_pins(lo, hi)
            counts.append([self.plant.count(a) for a in range(2)])
        c0, c1 = counts[0], counts[-1]
        n = len(bounds) - 1
        i = next(i for i in range(n, -1, -1)
                 if all(counts[i][a] == c0[a] or abs(c1[a] - counts[i][a]) >= 2 for a in range(2)))
        if i == n:
            return                       # no axis counted (as far as the pieces' ends show)
        j = next(j for j in range(i + 1, n + 1) if counts[j] == c1)
        plant, self._pwm = saved[i]
        self.plant.restore(plant)
        self._decoder_from_plant()
        run_until(self.plant, self._pwm, bounds[i], bounds[j], CLK_HZ, self._edges)
        if j < n:
            self._run_pins(bounds[j], end)


_GRAY_INDEX = {(0, 0): 0, (1, 0): 1, (1, 1): 2, (0, 1): 3}   # sim_models.encoder's A/B Gray code


class SimBoardTransport:
    """The simulated board as a :class:`~torqueloop.host.client.Client`'s
    transport in simulated time: it answers at once, and a read with nothing
    waiting runs the board ``step_s`` on, so the client's clock
    (``clock=lambda: board.t``) and its waits are the board's."""

    def __init__(self, board: "SimBoard", step_s: float = 0.025) -> None:
        self.b, self.step_s, self.rx = board, step_s, b""

    def write(self, data: bytes) -> int:
        self.b.write(data)
        return len(data)

    def read(self, size: int = 1) -> bytes:
        if not self.rx:
            self.rx = self.b.read()
        if not self.rx:
            self.b.advance(self.step_s)
            self.rx = self.b.read()
        out, self.rx = self.rx[:size], self.rx[size:]
        return out

    def close(self) -> None:
        pass


class SimBootRom:
    """The boot ROM's upload state machine (docs/bootloader.md) for the
    simulated board, in simulated time; frames and CRCs through
    ``torqueloop.spec.bootproto`` (the protocol's single definition).

    The simulated board cannot execute RV32 code: an accepted image
    restarts the same host-compiled servo firmware, reporting the image's
    CRC-32 as its build id, so a host sees which image "runs"; a rejected
    one restarts the factory firmware with the factory build id.  As the
    boot ROM, it checks the image's MAC under the board's ``key`` (None: the
    board has no key and refuses every upload).
    ``poll`` returns None while listening, then "factory" or the new build id.
    """

    def __init__(self, now: int, key: bytes | None) -> None:
        from torqueloop.spec import bootproto as bp

        self.bp = bp
        self.key = key
        self._tx = bytearray(b"TLBW\n")
        self._buf = bytearray()
        self._window_end = now + bp.ms_to_cycles(bp.WINDOW_MS, CLK_HZ)
        self._last_rx = now
        self._synced = False
        self._saw_bytes = False
        self._draining_since: int | None = None    # error sent: wait for a quiet line
        self.result: str | int | None = None

    def take_tx(self) -> bytes:
        out, self._tx = bytes(self._tx), bytearray()
        return out

    def rx(self, data: bytes, now: int) -> None:
        self._last_rx = now
        self._saw_bytes = True
        if self._draining_since is not None:
            return
        self._buf += data
        bp = self.bp
        if not self._synced:
            i = self._buf.find(bp.SYNC)
            if i < 0:
                del self._buf[:max(0, len(self._buf) - len(bp.SYNC) + 1)]
                return
            del self._buf[:i]
            self._synced = True
        if len(self._buf) < bp.FRAME_OVERHEAD:
            return
        try:
            _, _, length, icrc = bp.decode_header(bytes(self._buf[:bp.FRAME_OVERHEAD]))
        except bp.FrameError:
            return self._fail("H", now)
        if not 1 <= length <= bp.MAX_IMAGE_BYTES:
            return self._fail("L", now)
        if self.key is None:
            return self._fail("X", now)
        if len(self._buf) < bp.frame_bytes(length):
            return
        frame = bytes(self._buf[:bp.frame_bytes(length)])
        image = frame[bp.FRAME_OVERHEAD:bp.FRAME_OVERHEAD + length]
        if bp.crc32(image) != icrc:
            return self._fail("C", now)
        if not bp.frame_tag_ok(frame, self.key):
            return self._fail("A", now)
        self._tx += b"TLBK\n"
        self.result = bp.crc32(image)

    def _fail(self, code: str, now: int) -> None:
        self._tx += b"TLB" + code.encode() + b"\n"
        self._draining_since = now
        self._buf.clear()

    def poll(self, now: int) -> str | int | None:
        bp = self.bp
        gap = bp.ms_to_cycles(bp.GAP_MS, CLK_HZ)
        if self.result is not None:
            return self.result
        if self._draining_since is not None:
            if now - self._last_rx >= gap:
                self._tx += b"TLBF\n"
                return "factory"
            return None
        if self._synced and now - self._last_rx >= gap:
            self._fail("T", now)
            return None
        if not self._synced and now >= self._window_end:
            if self._saw_bytes:
                self._fail("G", now)
                return None
            self._tx += b"TLBF\n"
            return "factory"
        return None
