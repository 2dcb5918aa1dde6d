# SPDX-License-Identifier: MIT
"""``torqueloop shell``: one interactive session over the board.

Every line is a ``torqueloop`` command without the ``torqueloop`` (``status``,
``move 2mm --enable --wait 5``, ``set kp 0.8``, ``--json status``), run by the
CLI's own code on one connection kept for the whole session: through the
running ``torqueloop serve`` when there is one, else through a server of the
shell's own (in this process, on a free local port, with no state file), so
an axis enabled at the prompt stays enabled between commands (the server
feeds the link watchdog) and is disabled when the shell ends.

While ``move``, ``home`` or ``step-test`` runs, a live text plot of the axis
(position and set-point, following error, PWM command; torqueloop/host/termplot.py)
is drawn in the terminal and, with ``--plot-file FILE``, appended to FILE.
Line editing, history (kept in the state folder) and tab completion of the
commands, options and parameter names come from ``readline`` when the input
is a terminal.  Shell words: ``help``, ``liveplot on|off``, ``holds``, ``quit``.  The
shell ends with the exit status of its last command, as ``sh`` does.
"""

from __future__ import annotations

import argparse
import shlex
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable

from torqueloop.spec import units

from . import serve as hserve
from . import termplot
from .client import Client, ProtocolError
from .remote import RemoteClient

PROMPT = "torqueloop> "
BUILTINS = ("help", "liveplot", "holds", "quit", "exit")
#: commands a shell does not run inside itself
NOT_HERE = {"shell": "you are in the shell", "serve": "run it in its own terminal",
            "sim": "run it in its own terminal", "upload": "it needs the link to itself: quit the shell first"}
LIVE = ("move", "home", "step-test")
FRAME_EVERY_S = 0.25


class Shell:
    def __init__(self, ctx: Any, run: Callable[..., int], parser: argparse.ArgumentParser) -> None:
        """``ctx``: the CLI's context of the ``shell`` command; ``run``: the CLI's
        main (argv, client=, tick=); ``parser``: the CLI's parser (for completion)."""
        self.ctx, self.run_command, self.parser = ctx, run, parser
        self.args = ctx.args
        self.live = True
        self.records: list[dict] = []
        self.frames = 0
        self.last_frame = 0.0
        self.axis = 0
        self.mech = units.Mechanics()
        self.plot_file = Path(self.args.plot_file) if self.args.plot_file else None
        self._own: hserve.SessionServer | None = None
        self._own_client: Client | None = None
        self.remote: RemoteClient | None = None
        self.tty = sys.stdin.isatty() and not self.args.script

    # ---- the session ---------------------------------------------------------------
    def _connect(self) -> str:
        addr = self.ctx.server()
        if addr:
            self.remote = RemoteClient(addr)
            return f"through the torqueloop server at {addr}"
        if self._own is None:
            c = self.ctx.client                       # the board's own link, with the key
            assert isinstance(c, Client)
            self._own_client = c
            self._own = hserve.SessionServer(c, self.args.url, "127.0.0.1", 0)
            self._own_thread = threading.Thread(target=self._own.serve_forever, name="tl-shell-server", daemon=True)
            self._own_thread.start()
        self.remote = RemoteClient(self._own.addr)
        return f"own session on {self.args.url}"

    def _close(self) -> None:
        if self.remote is not None:
            self.remote.close()          # the server disables what this session held
            self.remote = None
        if self._own is not None:
            self._own.stop()
            deadline = time.monotonic() + 3
            while self._own.conns and time.monotonic() < deadline:   # let it release this session's axes
                time.sleep(0.02)
            self._own.stop()
            self._own_thread.join(5)
            self._own = None

    # ---- live plot ---------------------------------------------------------------------
    def tick(self) -> None:
        assert self.remote is not None
        self.records += self.remote.take_telemetry()
        del self.records[:-termplot.WIDTH * 4]
        now = time.monotonic()
        if now - self.last_frame >= FRAME_EVERY_S and self.records:
            self._draw()
            self.last_frame = now

    def _draw(self) -> None:
        self.frames += 1
        mech = self.mech
        text = termplot.frame(self.records, self.axis, "mm", lambda c: mech.from_counts(c, "mm"), self.frames)
        if self.tty:
            sys.stdout.write("\x1b[H\x1b[2J")
        print(text, flush=True)
        if self.plot_file is not None:
            with self.plot_file.open("a") as f:
                f.write(text + "\n\n")

    # ---- one line -------------------------------------------------------------------------
    def _globals(self) -> list[str]:
        a = self.args
        g = ["-u", a.url, "--timeout", str(a.timeout), "--retries", str(a.retries)]
        return g + (["-k", a.key_file] if a.key_file else [])

    def line(self, text: str) -> int | None:
        """Run one line; returns its exit status (None: the shell ends)."""
        try:
            words = shlex.split(text)
        except ValueError as e:
            print(f"torqueloop: {e}", file=sys.stderr)
            return 2
        if not words:
            return 0
        cmd = next((w for w in words if not w.startswith("-")), "")
        if words[0] in ("quit", "exit"):
            return None
        if words[0] == "help":
            print("commands: " + ", ".join(self._commands()) + "; shell: " + ", ".join(BUILTINS)
                  + ".  `COMMAND -h` for its options (docs/host.md)")
            return 0
        if words[0] == "liveplot":
            self.live = words[1:] != ["off"]
            print(f"live plot {'on' if self.live else 'off'}")
            return 0
        if words[0] == "holds":
            assert self.remote is not None
            for a, who in self.remote.holds().items():
                print(f"axis {a}: {'held by ' + ', '.join(who) if who else 'not held'}")
            return 0
        if cmd in NOT_HERE:
            print(f"torqueloop: {cmd}: not inside the shell ({NOT_HERE[cmd]})", file=sys.stderr)
            return 2
        live = self.live and cmd in LIVE
        if live:
            self.axis = _axis_of(words)
            self.records.clear()
            try:
                self.mech = units.Mechanics(self.remote.get_param("COUNTS_PER_REV", self.axis),
                                            self.remote.get_param("PITCH_UM", self.axis))
            except ProtocolError:
                self.mech = units.Mechanics()
            self.remote.set_telemetry(1)
        try:
            return self.run_command(self._globals() + words, client=self.remote, tick=self.tick if live else None)
        except SystemExit as e:          # argparse: usage errors and -h
            return int(e.code or 0) if not isinstance(e.code, str) else 2
        finally:
            if live and self.remote is not None:
                self.remote.set_telemetry(0)
                self.records += self.remote.take_telemetry()
                if self.records:
                    self._draw()

    def _commands(self) -> list[str]:
        for act in self.parser._actions:
            if isinstance(act, argparse._SubParsersAction):
                return [c for c in act.choices if c not in NOT_HERE]
        return []

    # ---- completion ------------------------------------------------------------------------
    def complete(self, text: str, state: int) -> str | None:
        import readline

        before = readline.get_line_buffer()[:readline.get_begidx()].split()
        if not before:
            opts = [*self._commands(), *BUILTINS]
        else:
            opts = []
            for act in self.parser._actions:
                if isinstance(act, argparse._SubParsersAction) and before[0] in act.choices:
                    opts = list(act.choices[before[0]]._option_string_actions)
            if before[0] in ("set", "get"):
                opts += [*units.FRIENDLY, *units.SPECIAL]
            if before[0] == "home":
                opts += ["neg", "pos", "here"]
        hits = sorted(o for o in opts if o.startswith(text))
        return hits[state] if state < len(hits) else None

    def _readline(self) -> Path | None:
        try:
            import readline
        except ImportError:          # Windows without pyreadline: plain input()
            return None
        hist = hserve.state_dir() / "shell_history"
        try:
            readline.read_history_file(hist)
        except OSError:
            pass
        readline.set_history_length(1000)
        readline.set_completer(self.complete)
        readline.set_completer_delims(" \t")
        readline.parse_and_bind("tab: complete")
        return hist

    # ---- the loop -----------------------------------------------------------------------------
    def run(self) -> int:
        how = self._connect()
        print(f"torqueloop shell, {how}; `help` lists the commands, `quit` ends "
              "(and disables the axes this session enabled)", flush=True)
        hist = self._readline() if self.tty else None
        lines = open(self.args.script) if self.args.script else None
        rc = 0
        try:
            while True:
                try:
                    text = next(lines, None) if lines else input(PROMPT)
                except EOFError:
                    text = None
                if text is None:
                    break
                if lines:
                    print(PROMPT + text.rstrip("\n"), flush=True)
                try:
                    got = self.line(text)
                except KeyboardInterrupt:
                    # a command cut short: its answer may still be on the way, so start a fresh
                    # connection (the server disables what the old one held)
                    print("\ninterrupted: the axes this session held are disabled", file=sys.stderr)
                    self.remote.close()
                    self._connect()
                    got = 130
                if got is None:
                    break
                rc = got
                if got and not self.args.json:
                    print(f"[exit {got}]", flush=True)
        except KeyboardInterrupt:
            print()
        finally:
            if lines:
                lines.close()
            if hist is not None:
                import readline

                hist.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
                try:
                    readline.write_history_file(hist)
                except OSError:
                    pass
            self._close()
        return rc


def _axis_of(words: list[str]) -> int:
    for i, w in enumerate(words):
        if w in ("-a", "--axis") and i + 1 < len(words) and words[i + 1] in ("0", "1"):
            return int(words[i + 1])
        if w.startswith("--axis="):
            return int(w.split("=", 1)[1])
    return 0
