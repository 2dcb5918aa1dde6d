# SPDX-License-Identifier: MIT
"""The title question's sweep without the confound: at each carrier the
dead zone measured at that carrier, not the one measured at the chosen
carrier carried across.

* :func:`~torqueloop.study.dead_zones.dead_zones` - the paper's dead zone
  per axis and carrier, as PW0 counts (in its own module, so that its cache
  outlives changes to this one's report code).
* :func:`summarise` - the sweep's points grouped by (carrier, PW0, law, axis):
  the median and the range over the points' start positions and step sizes.
  That range is the spread across start positions and step sizes of one
  deterministic plant, not a confidence interval: nothing is sampled.
* :func:`markdown`, :func:`plot` - the report's table (audible carriers
  marked) and figure (every point drawn, the median joined; the y range
  shared between the axes where a trend is read).
* :class:`RunCache` - each sweep run's result kept in
  build/characterize/sweep_runs/ under a key of everything it depends on
  (the board settings it runs with, the law, T, step, start, plant, and the
  sources of the plant, the firmware's law and the PWM model), so a second
  ``make run``, or a plan with a carrier added, runs only what is new.
* :func:`truncated`, :func:`t_check` - a run's metrics as if it had ended
  earlier (the fast path is deterministic and a run's first 10 s are the
  10 s run), and the sweep's answer at two T side by side: whether the T
  of the sweep changes it, measured without running the sweep twice.
"""

from __future__ import annotations

import dataclasses
import hashlib
import pickle
import statistics
from pathlib import Path
from typing import Any, Sequence

from torqueloop.spec.repo import REPO_ROOT
from torqueloop.sim.report import run_metrics, save_figure
from torqueloop.study.dead_zones import AXES, dead_zones, pw0_counts  # noqa: F401 - the sweep's PW0, re-exported

#: carriers below this are in the audible band (20 Hz - 20 kHz)
AUDIBLE_HZ = 20_000.0


#: what a fast-path run's result depends on beyond its configuration: the plant, the firmware law's oracle,
#: the PWM block's event model, the run itself and the specs they read
RUN_SOURCES = ("sim_models", "torqueloop/oracles", "torqueloop/spec", "torqueloop/sim/experiment.py",
               "torqueloop/sim/model_loop.py")


def sources_digest(roots: Sequence[str] = RUN_SOURCES) -> str:
    h = hashlib.sha256()
    for r in roots:
        p = REPO_ROOT / r
        files = sorted(x for x in ([p] if p.is_file() else p.rglob("*"))
                       if x.is_file() and x.suffix in (".py", ".toml", ".h", ".c"))
        for f in files:
            h.update(str(f.relative_to(REPO_ROOT)).encode())
            h.update(f.read_bytes())
    return h.hexdigest()


class RunCache:
    """Sweep runs kept one file each in ``root``, keyed by
    :meth:`key`: the configuration with the characterisation file replaced
    by the board settings it resolves to (what the run actually uses), and
    :func:`sources_digest`."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.digest = sources_digest()

    def key(self, cfg: Any) -> str:
        plain = dataclasses.replace(cfg, char_config=None, progress=False)
        return hashlib.sha256(f"{self.digest}|{plain!r}|{cfg.board()!r}".encode()).hexdigest()[:40]

    def get(self, cfg: Any) -> Any | None:
        f = self.root / f"{self.key(cfg)}.pkl"
        if not f.exists():
            return None
        try:
            with open(f, "rb") as fh:
                return pickle.load(fh)
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError):
            return None

    def put(self, cfg: Any, result: Any) -> None:
        self.root.mkdir(parents=True, exist_ok=True)
        f = self.root / f"{self.key(cfg)}.pkl"
        tmp = f.with_suffix(".tmp")
        with open(tmp, "wb") as fh:
            pickle.dump(result, fh)
        tmp.replace(f)


def truncated(run: Any, t_end_s: float) -> Any:
    """``run`` as if it had ended at ``t_end_s`` (every sample up to it): a
    deterministic run's first samples are the shorter run's."""
    tr = run.traj
    n = int((tr.t <= t_end_s + 1e-9).sum())
    cut = {f.name: (None if getattr(tr, f.name) is None else getattr(tr, f.name)[:n])
           for f in dataclasses.fields(tr)}
    return dataclasses.replace(run, traj=dataclasses.replace(tr, **cut))


def short_rows(sweep: Sequence[tuple], t_end_s: float, target_rad: float) -> list[dict[str, Any]]:
    """The sweep's report rows (as torqueloop.sim.report.build writes them)
    for every run cut at ``t_end_s``."""
    out = []
    for f, pw0, law, r, *extra in sweep:
        ex = extra[0] if extra else {}
        for ax, mm in run_metrics(truncated(r, t_end_s), ex.get("target_rad", target_rad)).items():
            out.append({"freq_hz": f, "pw0": pw0, "law": law, "axis": ax, **ex.get(ax, {}), **mm})
    return out


#: two medians this close are a tie: one encoder count (the law's deadband is half a count)
TIE_COUNTS = 1.0


def t_check(long_rows: Sequence[dict[str, Any]], short_rows_: Sequence[dict[str, Any]], t_long: float,
            t_short: float) -> dict[str, Any]:
    """Per (law, axis, PW0): the carriers with the lowest median |error at the
    encoder| at each T (every carrier within :data:`TIE_COUNTS` of the
    lowest), and the medians side by side; ``same_ranking``: no two carriers
    are ordered one way at one T and the other way at the other, beyond a
    tie; ``best_moved``: the best carriers at the two T have none in common."""
    a, b = summarise(long_rows), summarise(short_rows_)
    rows = []
    for law in sorted({r["law"] for r in a}):
        for axis in AXES:
            for pw0 in (True, False):
                la = [r for r in a if (r["law"], r["axis"], r["pw0"]) == (law, axis, pw0)]
                lb = [r for r in b if (r["law"], r["axis"], r["pw0"]) == (law, axis, pw0)]
                if not la or not lb:
                    continue
                med = lambda rr: {r["freq_hz"]: r["steady_state_error_counts"]["median"] for r in rr}
                ma, mb = med(la), med(lb)
                fs = sorted(set(ma) & set(mb))
                best = lambda m: [f for f in fs if m[f] <= min(m[g] for g in fs) + TIE_COUNTS]
                order = lambda m, f, g: 0 if abs(m[f] - m[g]) <= TIE_COUNTS else (1 if m[f] > m[g] else -1)
                opposite = any(order(ma, f, g) * order(mb, f, g) < 0 for f in fs for g in fs)
                rows.append({"law": law, "axis": axis, "pw0": pw0, "t_long_s": t_long, "t_short_s": t_short,
                             "median_error_long": ma, "median_error_short": mb,
                             "best_hz_long": best(ma), "best_hz_short": best(mb),
                             "best_moved": not set(best(ma)) & set(best(mb)), "same_ranking": not opposite})
    return {"rows": rows, "t_long_s": t_long, "t_short_s": t_short,
            "how": f"each T = {t_long:g} s run's first {t_short:g} s, scored as a T = {t_short:g} s run"}


def hz(f: float) -> str:
    """A carrier as people read it: 50 Hz, 1.7 kHz, 24.4 kHz."""
    return f"{f / 1000:.3g} kHz" if f >= 1000 else f"{f:.3g} Hz"


def t_check_markdown(tc: dict[str, Any]) -> list[str]:
    if not tc or not tc["rows"]:
        return []
    fs = sorted({f for r in tc["rows"] for f in r["median_error_long"]})
    L = [f"### Does the sweep's T change its answer? (T = {tc['t_short_s']:g} s against {tc['t_long_s']:g} s)", "",
         f"The same runs scored at both T ({tc['how']}). Median |steady-state error| at the encoder (counts), "
         f"T = {tc['t_short_s']:g} s -> {tc['t_long_s']:g} s:", "",
         "| law | axis | PW0 | " + " | ".join(hz(f) for f in fs) + " | best carrier | same ranking |",
         "|---|---|---|" + "---|" * len(fs) + "---|---|"]
    for r in tc["rows"]:
        cells = [f"{r['median_error_short'][f]:.1f} -> {r['median_error_long'][f]:.1f}"
                 if f in r["median_error_long"] and f in r["median_error_short"] else "-" for f in fs]
        names = lambda fs: " / ".join(hz(f) for f in fs)
        best = (names(r["best_hz_long"]) if r["best_hz_long"] == r["best_hz_short"] else
                f"{names(r['best_hz_short'])} -> {names(r['best_hz_long'])}")
        L.append(f"| {r['law']} | {r['axis']} | {'at the carrier' if r['pw0'] else 'off'} | " + " | ".join(cells)
                 + f" | {best} | {'yes' if r['same_ranking'] else 'no'} |")
    return L + [""]


METRICS = ("steady_state_error_counts", "screw_steady_state_error_counts", "overshoot_pct", "settling_time_s",
           "copper_loss_J", "current_ripple_A_rms")


def summarise(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Group the sweep's rows by (carrier, PW0 on/off, law, axis): per metric
    the median and [min, max] over start positions and step sizes (|error|
    for the errors)."""
    groups: dict[tuple, list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["freq_hz"], r["pw0"], r["law"], r["axis"]), []).append(r)
    out = []
    for (f, pw0, law, axis), rr in sorted(groups.items(), key=lambda kv: (kv[0][2], kv[0][3], not kv[0][1], kv[0][0])):
        row: dict[str, Any] = {"freq_hz": f, "pw0": pw0, "law": law, "axis": axis, "points": len(rr),
                               "pw0_counts": rr[0].get("pw0_counts"), "audible": f < AUDIBLE_HZ,
                               "interval": "range over start positions and step sizes (not a confidence interval)"}
        for m in METRICS:
            v = [abs(x[m]) if "error" in m else x[m] for x in rr if x.get(m) is not None]
            row[m] = None if not v else {"median": statistics.median(v), "min": min(v), "max": max(v)}
        out.append(row)
    return out


def _cell(d: dict[str, Any] | None, spec: str) -> str:
    if d is None:
        return "-"
    if len({round(d["min"], 9), round(d["max"], 9)}) == 1:
        return format(d["median"], spec)
    return f"{format(d['median'], spec)} [{format(d['min'], spec)}, {format(d['max'], spec)}]"


def markdown(summary: Sequence[dict[str, Any]], t_end_s: float | None) -> list[str]:
    if not summary:
        return []
    n = max(r["points"] for r in summary)
    L = [f"## The title question: the PWM carrier and the closed loop, each carrier with its own dead zone", "",
         f"Fast path, experiment plant, T = {t_end_s:g} s. At each carrier PW0 is the paper's dead zone measured at "
         f"that carrier (the duty below which the stage stops), or off. Each cell: the median and, in brackets, the "
         f"range over the {n} start positions and step sizes of the point - the spread of one deterministic plant "
         f"over its set-up, not a confidence interval. Errors are |steady-state error| in encoder counts, at the "
         f"encoder and at the screw (beyond the gearbox's backlash). Carriers marked * are audible (below 20 kHz).",
         "", "| law | axis | carrier | PW0 (counts) | error at the encoder | error at the screw | overshoot (%) | "
         "copper loss (J) | current ripple (A rms) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in summary:
        L.append(f"| {r['law']} | {r['axis']} | {hz(r['freq_hz'])}{' *' if r['audible'] else ''} | "
                 f"{r['pw0_counts'] if r['pw0'] else 'off'} | {_cell(r['steady_state_error_counts'], '.1f')} | "
                 f"{_cell(r['screw_steady_state_error_counts'], '.1f')} | {_cell(r['overshoot_pct'], '.1f')} | "
                 f"{_cell(r['copper_loss_J'], '.2f')} | {_cell(r['current_ripple_A_rms'], '.3f')} |")
    return L + [""]


def plot(summary: Sequence[dict[str, Any]], rows: Sequence[dict[str, Any]], path: Path) -> None:
    """Every point's |error| at the encoder and copper loss against the
    carrier, PW0 at the carrier and off, one colour per law; the medians
    joined; the audible band shaded; y shared between the axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = (("steady_state_error_counts", "|steady-state error| at the encoder (counts)"),
            ("screw_steady_state_error_counts", "|steady-state error| at the screw (counts)"),
            ("copper_loss_J", "copper loss (J)"))
    laws = sorted({r["law"] for r in rows})
    fig, axs = plt.subplots(len(keys), 2, figsize=(12, 11), sharex=True, sharey="row")
    for i, axis in enumerate(AXES):
        for j, (k, label) in enumerate(keys):
            p = axs[j, i]
            p.axvspan(20.0, AUDIBLE_HZ, color="0.93", lw=0)
            for c, law in enumerate(laws):
                for pw0, mk in ((True, "o"), (False, "x")):
                    pts = [r for r in rows if r["axis"] == axis and r["law"] == law and r["pw0"] == pw0
                           and r.get(k) is not None]
                    if not pts:
                        continue
                    p.scatter([r["freq_hz"] for r in pts], [abs(r[k]) for r in pts], marker=mk, s=18,
                              color=f"C{c}", alpha=0.7)
                    med = [s for s in summary if s["axis"] == axis and s["law"] == law and s["pw0"] == pw0 and s[k]]
                    p.plot([s["freq_hz"] for s in med], [s[k]["median"] for s in med], "-" if pw0 else ":",
                           color=f"C{c}", label=f"{law}, PW0 {'at the carrier' if pw0 else 'off'}")
            p.set_xscale("log")
            if i == 0:
                p.set_ylabel(label)
            if j == 0:
                p.set_title(f"axis {axis} (grey: audible band)")
                if p.get_legend_handles_labels()[0]:
                    p.legend(fontsize=7)
    save_figure(fig, axs, "PWM carrier (Hz)", path)
