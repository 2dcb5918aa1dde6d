# SPDX-License-Identifier: MIT
"""The report's opening: the title question answered in words from the
report's own numbers, with their conditions and intervals; a QUICK run's
banner that it cannot answer; the stability and carrier-sweep tables; every
figure embedded with a caption.

:func:`finish` takes what :func:`torqueloop.sim.report.write` wrote
(report.json, report.md) and writes them again with these parts; the keys
it adds to report.json are ``answer`` (the paragraph and the numbers it
quotes) and ``carrier_sweep`` (:func:`torqueloop.study.carrier_sweep.summarise`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from torqueloop.study import carrier_sweep, stability, table3, uncertainty

QUICK_BANNER = ("> **QUICK RUN - a smoke test, not an answer.** T = {T:g} s, a {n}-carrier sweep of {laws} at {Ts:g} s "
                "from one start, the stability table on {nf} carriers and {np} protocols. These numbers show that "
                "every stage runs and what the report looks like; they are too short and too few to answer the "
                "title question, and none of them may be quoted as a result. `make run` without QUICK answers it.")

#: what each figure shows (file name -> caption); a figure not listed gets its file name
CAPTIONS = {
    "carrier_sweep.png": "The closed loop against the PWM carrier, each carrier with its own dead zone: every "
                         "point (start position, step size) drawn, medians joined; circles and solid lines with "
                         "PW0 at the carrier, crosses and dotted lines with PW0 off; grey: the audible band. "
                         "Both axes share each row's y range.",
    "pwm_frequency_sweep.png": "Every sweep metric against the carrier, per law and axis (the sweep's rows as "
                               "report.json holds them).",
}


#: below one encoder count apart two steady states are not told apart (the law's deadband is half a count)
ONE_COUNT = 1.0


def _axis_answer(summary: list[dict[str, Any]], law: str, axis: str, key: str) -> dict[str, Any] | None:
    rows = [r for r in summary if r["law"] == law and r["axis"] == axis and r["pw0"] and r.get(key)]
    if not rows:
        return None
    best = min(rows, key=lambda r: (r[key]["median"], r["freq_hz"]))      # on a tie: the lowest carrier,
    worst = max(rows, key=lambda r: (r[key]["median"], r["freq_hz"]))     # against the highest
    spread_between = worst[key]["median"] - best[key]["median"]
    spread_within = max(r[key]["max"] - r[key]["min"] for r in rows)
    off = [r for r in summary if r["law"] == law and r["axis"] == axis and not r["pw0"] and r.get(key)]
    return {"law": law, "axis": axis, "best_hz": best["freq_hz"], "best": best[key], "worst_hz": worst["freq_hz"],
            "worst": worst[key], "between_carriers": spread_between, "within_point_max": spread_within,
            "carrier_decides": spread_between > max(spread_within, ONE_COUNT),
            "pw0_off_median_range": None if not off else [min(r[key]["median"] for r in off),
                                                          max(r[key]["median"] for r in off)],
            "copper_best_J": None if not best.get("copper_loss_J") else best["copper_loss_J"]["median"],
            "copper_worst_J": None if not worst.get("copper_loss_J") else worst["copper_loss_J"]["median"]}


def paragraph(rep: dict[str, Any], summary: list[dict[str, Any]],
              t_check: dict[str, Any] | None = None) -> tuple[str, dict[str, Any]]:
    """The answer in words and the numbers it quotes (``t_check``:
    :func:`torqueloop.study.carrier_sweep.t_check`, whether a shorter T
    ranks the carriers the same)."""
    m, ch = rep["meta"], rep.get("characterization", {})
    numbers: dict[str, Any] = {"chosen": {a: v["achieved_hz"] for a, v in ch.get("axes", {}).items()},
                               "stability": ch.get("stability_verdict", {}).get("axes", {}), "sweep": []}
    parts = [f"**The answer on this model** (experiment plant `{m.get('experiment_plant')}`, simulated; "
             f"sweep on the fast path, T = {m.get('sweep_T_s', 0):g} s)."]
    st = numbers["stability"]
    for a, hz in numbers["chosen"].items():
        v = st.get(a)
        if v is None:
            parts.append(f"The characterisation chose {hz:.4g} Hz for axis {a}; no stability table backs it.")
        elif v.get("median_hz") is None:
            # a table, but no protocol found a carrier meeting step 5's target on the grid
            parts.append(f"The characterisation chose {hz:.4g} Hz for axis {a}, but none of the {v['n']} settle / "
                         f"sweep-order protocols found a carrier that meets step 5's target on the grid, so the "
                         f"choice is a property of the bench's timing and this study names none.")
        elif v.get("chosen", v["n"]) < v["n"]:
            parts.append(f"The characterisation chose {hz:.4g} Hz for axis {a}, but only {v['chosen']} of the "
                         f"{v['n']} settle / sweep-order protocols found a carrier ({v['min_hz']:.4g}-"
                         f"{v['max_hz']:.4g} Hz); the others found none on the grid, so the choice does not survive "
                         f"the bench protocol and this study names none.")
        elif v["stable"] and abs(math.log(hz / v["median_hz"])) <= math.log(v["tolerance_factor"]):
            parts.append(f"The characterisation chose {hz:.4g} Hz for axis {a}, and the choice survives the bench "
                         f"protocols tried ({v['n']} settle / sweep-order protocols: {v['min_hz']:.4g}-"
                         f"{v['max_hz']:.4g} Hz).")
        elif v["stable"]:
            # the protocols agree among themselves, but not with the characterisation's own (cold) readings
            parts.append(f"The characterisation chose {hz:.4g} Hz for axis {a}; the {v['n']} settle / sweep-order "
                         f"protocols agree among themselves ({v['min_hz']:.4g}-{v['max_hz']:.4g} Hz) but not with "
                         f"it (beyond a factor {v['tolerance_factor']:g} of their median, "
                         f"{v['median_hz']:.4g} Hz), so the choice depends on the bench protocol.")
        else:
            parts.append(f"The characterisation chose {hz:.4g} Hz for axis {a}, but that choice does not survive the "
                         f"bench protocol: the {v['n']} settle / sweep-order protocols chose {v['min_hz']:.4g}-"
                         f"{v['max_hz']:.4g} Hz, so the carrier is a property of the bench's timing as much as of "
                         f"the motor and this study names none.")
    u = rep.get("uncertainty")
    if u:
        for a, v in u["axes"].items():
            c = v["chosen_hz"]
            if c.get("n"):
                parts.append(f"Over {u['draws']} draws of the plant's unknown parameters within their stated ranges "
                             f"(Monte Carlo seed {u['seed']}; a parameter-uncertainty interval, not instrument noise) "
                             f"step 5 chooses {c['min']:.4g}-{c['max']:.4g} Hz for axis {a} (median {c['median']:.4g})"
                             + (f"; {v['no_choice']} draws chose none." if v["no_choice"] else "."))
    for law in sorted({r["law"] for r in summary}):
        for a in carrier_sweep.AXES:
            q = _axis_answer(summary, law, a, "steady_state_error_counts")
            if q is None:
                continue
            numbers["sweep"].append(q)
            b, w = q["best"], q["worst"]
            txt = (f"Under {law}, axis {a}, with each carrier's own dead zone: |steady-state error| "
                   f"{b['median']:.1f} counts [{b['min']:.1f}, {b['max']:.1f}] at {carrier_sweep.hz(q['best_hz'])} "
                   f"against {w['median']:.1f} [{w['min']:.1f}, {w['max']:.1f}] at {carrier_sweep.hz(q['worst_hz'])} "
                   f"(median [range over start positions and step sizes])")
            sc = [r for r in summary if r["law"] == law and r["axis"] == a and r["pw0"]
                  and r.get("screw_steady_state_error_counts")]
            by_f = {r["freq_hz"]: r["screw_steady_state_error_counts"]["median"] for r in sc}
            if q["best_hz"] in by_f and q["worst_hz"] in by_f:
                q["screw_best"], q["screw_worst"] = by_f[q["best_hz"]], by_f[q["worst_hz"]]
                txt += (f"; at the screw, beyond the gear's backlash that the motor-side encoder cannot see, "
                        f"{q['screw_best']:.1f} against {q['screw_worst']:.1f} counts")
            if q["copper_best_J"] is not None:
                txt += f", copper loss {q['copper_best_J']:.2f} J against {q['copper_worst_J']:.2f} J"
            quiet = [r for r in summary if r["law"] == law and r["axis"] == a and r["pw0"] and not r["audible"]
                     and r.get("steady_state_error_counts")]
            if quiet and quiet[0]["freq_hz"] not in (q["best_hz"], q["worst_hz"]):
                qe = quiet[0]["steady_state_error_counts"]
                txt += (f"; at {carrier_sweep.hz(quiet[0]['freq_hz'])}, above the audible band, "
                        f"{qe['median']:.1f} [{qe['min']:.1f}, {qe['max']:.1f}]")
            if q["pw0_off_median_range"] is not None:
                lo, hi = q["pw0_off_median_range"]
                txt += f"; with PW0 off the medians span {lo:.1f}-{hi:.1f} counts"
            txt += (". The carrier " + ("moves the error by more than the start position, the step size and one "
                                        f"encoder count do ({q['between_carriers']:.1f} against up to "
                                        f"{q['within_point_max']:.1f} counts)."
                                        if q["carrier_decides"] else
                                        "moves the error by no more than the start position and step size or one "
                                        f"encoder count do ({q['between_carriers']:.1f} against up to "
                                        f"{q['within_point_max']:.1f} counts): the sweep cannot rank the carriers "
                                        "by accuracy."))
            parts.append(txt)
    if t_check and t_check["rows"]:
        tc = [r for r in t_check["rows"] if r["pw0"]]
        differ = [f"{r['law']} axis {r['axis']}" for r in tc if not r["same_ranking"]]
        names = lambda fs: " / ".join(carrier_sweep.hz(f) for f in fs)
        moved = [f"{r['law']} axis {r['axis']} ({names(r['best_hz_short'])} at "
                 f"{t_check['t_short_s']:g} s, {names(r['best_hz_long'])} at {t_check['t_long_s']:g} s)"
                 for r in tc if r["best_moved"]]
        numbers["t_check"] = {"ranking_differs": differ, "best_moved": moved}
        parts.append(f"Scored as if each run had ended at T = {t_check['t_short_s']:g} s instead of "
                     f"{t_check['t_long_s']:g} s, with each carrier's own dead zone the carriers rank "
                     + ("in the same order under every law and axis." if not differ else
                        f"differently for {', '.join(differ)}"
                        + (f"; the most accurate carrier moves for {', '.join(moved)}." if moved else
                           ", though the most accurate carrier stays the same.")
                        + f" A sweep at T = {t_check['t_short_s']:g} s would not have given this answer."))
    return " ".join(parts), numbers


def finish(out: Path, quick_info: dict[str, Any] | None, stab: dict[str, Any], sweep_rows: list[dict[str, Any]],
           dz: dict[str, Any], unc: dict[str, Any] | None = None, dec: dict[str, Any] | None = None,
           t_check: dict[str, Any] | None = None) -> None:
    """Rewrite report.json and report.md with the opening, the tables and the figures."""
    rep = json.loads((out / "report.json").read_text())
    summary = carrier_sweep.summarise(sweep_rows)
    carrier_sweep.plot(summary, sweep_rows, out / "carrier_sweep.png")
    if unc is not None:
        rep["uncertainty"] = {k: v for k, v in unc.items() if k != "runs"}
    text, numbers = paragraph(rep, summary, t_check)
    rep["carrier_sweep"] = {"rows": summary, "dead_zones": dz["rows"],
                            "interval": "range over start positions and step sizes; not a confidence interval"}
    if t_check is not None:
        rep["carrier_sweep"]["t_check"] = t_check
    rep["answer"] = {"text": text, "numbers": numbers, "quick": quick_info is not None}
    if dec is not None:
        rep["table3_decomposition"] = table3.add_whole(dec, rep.get("table3", {}))
    (out / "report.json").write_text(json.dumps(rep, indent=2, default=float) + "\n")
    body = (out / "report.md").read_text().split("\n")
    head, rest = body[:3], body[3:]
    L = list(head)
    if quick_info is not None:
        L += [QUICK_BANNER.format(**quick_info), ""]
    L += [text, ""]
    L += stability.markdown(stab["rows"], stab["verdict"])
    if unc is not None:
        L += uncertainty.markdown(unc)
    if dec is not None:
        L += table3.markdown(rep["table3_decomposition"])
    L += carrier_sweep.markdown(summary, rep["meta"].get("sweep_T_s"))
    if t_check is not None:
        L += carrier_sweep.t_check_markdown(t_check)
    L += rest
    L += ["## Figures", ""]
    for p in sorted(out.glob("*.png")):
        L += [f"![{CAPTIONS.get(p.name, p.stem)}]({p.name})", "", f"*{p.name}: {CAPTIONS.get(p.name, p.stem)}*", ""]
    (out / "report.md").write_text("\n".join(L) + "\n")
