# SPDX-License-Identifier: MIT
"""Build and run one core's cocotb test bench on one simulator.

The pytest entry of every test bench calls :func:`run`.  Verilog cores run
on Icarus and Verilator, their VHDL twins on GHDL, all from the same cocotb
test module.  Each (core, simulator, parameter set) builds into its own
folder under build/sim/, so runs can go in parallel (pytest-xdist).

Environment:
  TORQUELOOP_SIM   comma-separated simulators to keep (make sim SIM=...)
  WAVES=1          dump waveforms into the build folder
  COCOTB_RANDOM_SEED  rerun a randomised test with the seed it printed
"""

from __future__ import annotations

import fcntl
import hashlib
import os
from pathlib import Path
from typing import Iterable, Mapping

from cocotb_tools.check_results import get_results
from cocotb_tools.runner import get_runner

from torqueloop.flow.manifest import REPO_ROOT, Core, core as manifest_core
from torqueloop.flow.tools import use_project_tools

#: simulator -> HDL language it simulates here
SIMULATORS: dict[str, str] = {"icarus": "verilog", "verilator": "verilog", "ghdl": "vhdl"}

BUILD_ROOT = REPO_ROOT / "build" / "sim"
#: the test benches, one folder per core or system (tb/<bench>/test_<bench>.py)
TB_ROOT = REPO_ROOT / "tb"


def selected_sims() -> list[str]:
    """Simulators allowed by TORQUELOOP_SIM (all when unset)."""
    env = os.environ.get("TORQUELOOP_SIM", "").strip()
    if not env:
        return list(SIMULATORS)
    wanted = [s.strip() for s in env.split(",") if s.strip()]
    bad = [s for s in wanted if s not in SIMULATORS]
    if bad:
        raise ValueError(f"TORQUELOOP_SIM names unknown simulator(s) {bad}; known: {list(SIMULATORS)}")
    return wanted


def sims_for(c: Core | str, langs: Iterable[str] = ("verilog", "vhdl")) -> list[str]:
    """Simulators that apply to a core (VHDL only if it has a VHDL twin)."""
    if isinstance(c, str):
        c = manifest_core(c)
    out = []
    for sim in selected_sims():
        lang = SIMULATORS[sim]
        if lang not in langs:
            continue
        if lang == "vhdl" and not c.has_vhdl:
            continue
        if lang == "verilog" and not c.verilog:
            continue
        out.append(sim)
    return out


def _search_bench(runner, folder: Path) -> None:
    """Put ``folder`` and tb/ first on the simulator's module search path.
    The runner sets PYTHONPATH from this process's sys.path when a test
    starts (cocotb_tools.runner ``_set_env_common``); this adds to what it
    set, and leaves this process's sys.path alone."""
    if not folder.is_dir():
        raise FileNotFoundError(f"{folder}: no such test bench folder")
    common = runner._set_env_common

    def set_env() -> None:
        common()
        runner.env["PYTHONPATH"] = os.pathsep.join([str(folder), str(TB_ROOT), runner.env.get("PYTHONPATH", "")])

    runner._set_env_common = set_env


def _tag(parameters: Mapping[str, object], extra: str) -> str:
    if not parameters and not extra:
        return "default"
    text = ",".join(f"{k}={v}" for k, v in sorted(parameters.items())) + extra
    return hashlib.sha1(text.encode()).hexdigest()[:10]


def _reads(path: Path) -> str:
    try:
        return path.read_text()
    except OSError:
        return ""


def _inputs_digest(sim: str, top: str, build_kwargs: Mapping[str, object]) -> str:
    """What a build depends on: the simulator, top and arguments, and the
    contents of every source and of every file in the include folders."""
    h = hashlib.sha1(repr((sim, top, sorted((k, str(v)) for k, v in build_kwargs.items()))).encode())
    files = [Path(f) for f in build_kwargs.get("sources", [])]       # type: ignore[union-attr]
    for d in build_kwargs.get("includes", []):                       # type: ignore[union-attr]
        files += sorted(p for p in Path(d).iterdir() if p.is_file())
    for f in files:
        h.update(str(f).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def run(
    core_name: str,
    sim: str,
    test_module: str,
    parameters: Mapping[str, object] | None = None,
    toplevel: str | None = None,
    extra_verilog: Iterable[Path] = (),
    extra_vhdl: Iterable[Path] = (),
    testcase: str | None = None,
    extra_env: Mapping[str, str] | None = None,
    build_tag: str = "",
    bench: str | None = None,
) -> None:
    """Build ``core_name`` for ``sim`` and run the cocotb tests of ``test_module``.

    ``bench``: the test bench folder (tb/<bench>) that holds ``test_module``,
    for a caller that is not pytest in that folder (a benchmark, the ELF
    runner): the simulator's Python then finds the module and tb/tbutil,
    and the caller imports nothing from tb/.

    Raises AssertionError if a cocotb test fails or if no test ran at all.
    """
    c = manifest_core(core_name)
    parameters = dict(parameters or {})
    lang = SIMULATORS[sim]
    top = toplevel or c.top
    build_dir = BUILD_ROOT / core_name / sim / (_tag(parameters, build_tag + (top if toplevel else "")))
    waves = os.environ.get("WAVES", "") == "1"
    use_project_tools()
    runner = get_runner(sim)
    if bench is not None:
        _search_bench(runner, TB_ROOT / bench)

    build_kwargs: dict = dict(
        hdl_toplevel=top,
        parameters=parameters,
        build_dir=build_dir,
        waves=waves,
        timescale=("1ns", "1ps"),
    )
    test_kwargs: dict = {}
    if lang == "verilog":
        build_kwargs["sources"] = [*c.verilog_sources, *extra_verilog]
        build_kwargs["includes"] = list(c.include_dirs)
        if sim == "verilator":
            # Lint is make lint's job (-Wall there); here only build.
            build_kwargs["build_args"] = ["-Wno-fatal", "-O2"]
    else:
        build_kwargs["sources"] = [*c.vhdl, *extra_vhdl]
        build_kwargs["build_args"] = ["--std=08"]
        test_kwargs["test_args"] = ["--std=08"]
        # GHDL applies generics at elaboration, which the runner does at test time.
        test_kwargs["parameters"] = parameters
        del build_kwargs["timescale"]

    build_dir.mkdir(parents=True, exist_ok=True)
    # A Verilator run simulates in a folder of its own (results, log, waves),
    # named by what it runs, so runs of one build can go at once: the parts of
    # a bench split for pytest-xdist, two benches on one model.  A build is
    # made under an exclusive lock; a Verilator run whose build is up to date
    # (its inputs' digest is the one the last build recorded) simulates under
    # a shared lock, so no run rebuilds a model another is simulating (make
    # test in two shells on one tree).  Icarus and GHDL runs hold the lock
    # exclusively throughout and simulate in the build folder (GHDL finds its
    # library there; their runners may write it on every call).  The same run
    # twice at once waits on its folder's lock.
    what = f"{test_module}|{testcase or ''}|{sorted((extra_env or {}).items())}"
    run_dir = build_dir / "run" / f"{test_module}-{hashlib.sha1(what.encode()).hexdigest()[:8]}"
    run_dir.mkdir(parents=True, exist_ok=True)
    stamp = build_dir / ".inputs"
    digest = _inputs_digest(sim, top, build_kwargs)
    with open(build_dir.parent / f".{build_dir.name}.lock", "w") as lock, \
            open(run_dir.parent / f".{run_dir.name}.lock", "w") as run_lock:
        fcntl.flock(run_lock, fcntl.LOCK_EX)
        vlt = sim == "verilator"
        fcntl.flock(lock, fcntl.LOCK_SH if vlt else fcntl.LOCK_EX)     # SH: waits out a build under way
        exclusive = not (vlt and _reads(stamp) == digest)
        if exclusive:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if _reads(stamp) != digest:          # (another run may have built it while this one waited)
                stamp.unlink(missing_ok=True)
        # when up to date, Verilator skips the generation and make finds nothing to do
        runner.build(**build_kwargs)
        if exclusive:
            stamp.write_text(digest)
            if vlt:
                fcntl.flock(lock, fcntl.LOCK_SH)
        results = runner.test(
            test_module=test_module,
            hdl_toplevel=top,
            hdl_toplevel_lang=lang,
            # the test module is found through PYTHONPATH (the runner passes pytest's sys.path on)
            test_dir=run_dir if sim == "verilator" else build_dir,
            build_dir=build_dir,
            testcase=testcase,
            extra_env=dict(extra_env or {}),
            waves=waves,
            **test_kwargs,
        )
    n_tests, n_failed = get_results(Path(results))
    assert n_tests > 0, f"{core_name} on {sim}: no cocotb test ran"
    assert n_failed == 0, f"{core_name} on {sim}: {n_failed} of {n_tests} cocotb tests failed"
