# SPDX-License-Identifier: MIT
"""torqueloop tune: the tuned PID on the RTL board image against its
prediction and the fast model, and the tuned gains over a grid of plant spreads.

1. ``tune --all --verify rtl``: both axes of lab-2025 with its rotor friction
   scaled by 1.25 and its inertia by 0.8 (tests/test_tune.py's plant), tuned
   for a 0.35 s settling at a 1 ms period and a 24.4 kHz carrier, a one-turn
   step for 3 s (1 s with --quick) on the board image (Verilator, the real
   servo firmware, the plant on its pins), beside the design's prediction and
   the fast model (the firmware's law in Python).  Fails if the board image
   faults, its overshoot is more than 1 point from the prediction's or above
   2 %, or (a full run) an axis is not settled into +-2 counts or ends more
   than 2 counts off.
2. The robustness grid, per axis: the gains tuned on that plant's identifiable keys,
   run on the fast model on plants whose rotor friction is scaled by 0.7 /
   1.3, rotor inertia by 0.7 / 1.3 (the issue's +-30 %), k_t (= k_e) by 0.9 / 1.1 and breakaway
   moved by -1 / +1 point of duty (the rotor's static friction changed by
   one percent of its stall torque), every corner and the centre (17 runs;
   --quick: the centre and the two extreme corners, 1.5 s), each for 2 s
   past the design's predicted settling into +-2 counts (at least 3 s); the
   worst overshoot, settling, final error and the largest swing in the last
   second (a limit cycle, or a slow return) named.  The table goes into
   docs/identification.md.
3. The RTL loop at the grid's worst corners (``RTL_CORNERS``: the worst
   overshoot on both axes, friction 0.7, inertia 1.3, k_t 0.9, and the worst
   settling into +-2 counts on both, friction 1.3, inertia 1.3, k_t 0.9,
   breakaway +1 point): both axes tuned on the nominal plant, ``tune --verify
   rtl`` on the corner's plant for 5 s, beside the fast model on the same
   plant.  Fails on a fault, if the board image's overshoot or 2 % settling
   is off the fast model's by more than 0.1 point or 50 ms (the same law bit
   for bit: only the implementation's timing differs), or if an axis does not
   settle into +-2 counts or ends more than 2 counts off.  The +-2 counts
   settling itself is not held to the fast model's: one count's wander in the
   last counts moves it by hundreds of milliseconds either way (x at the
   worst-settling corner: 1.13 s on the board image, 1.92 s on the fast
   model).  Skipped with --quick (about 12 minutes of wall time per corner
   on the shared 2-core machine).
4. The feed-forward (KVFF_Q16, KAFF_Q16) on the one-turn trapezoid
   (``tune --verify-move trapezoid``): on the RTL board image with the nominal
   plant, its peak following error beside the fast model's and the same move's
   without the feed-forward (fails on a fault, a peak more than 2 counts off the
   fast model's, or one above half of the peak without); then on the fast
   model at the friction x inertia corners of the grid (k_t 0.9, breakaway -1
   point), with and without, so what the feed-forward buys on a plant it was
   not designed for shows.  --quick: the fast model at the nominal plant only.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time

import numpy as np

from sim_models.identifiable import identifiable_plant
from sim_models.plantfile import export_text
from sim_models.variants import PlantSpec, load_variant
from torqueloop.host.tune import tune_axis
from torqueloop.host.tunedesign import Wish
from torqueloop.sim import experiment, tuneverify
from torqueloop.spec.system import SYSTEM

SCALE_FRICTION, SCALE_INERTIA = 1.25, 0.8
WISH = Wish(settling_s=0.35, law="pid", period_s=1e-3)
MAX_OVERSHOOT_PCT, MAX_ERROR_COUNTS = 2.0, 2.0
SPREAD = {"friction": (0.7, 1.3), "inertia": (0.7, 1.3), "kt": (0.9, 1.1), "dead_zone_pts": (-1.0, 1.0)}
#: the record runs this long past the design's predicted settling into +-2 counts, so that its last second
#: (the limit-cycle column) is past the approach
SETTLED_S = 2.0
BUILD = experiment.REPO_ROOT / "build" / "bench_tune"
#: (friction, inertia, k_t, dead zone points) of the robustness grid run on the RTL loop: the worst
#: overshoot (both axes) and the worst settling into +-2 counts (both axes) on the fast model
RTL_CORNERS = ((0.7, 1.3, 0.9, -1.0), (1.3, 1.3, 0.9, 1.0))
RTL_CORNER_S = 5.0
#: the board image against the fast model on a corner: the same law bit for bit, so only the
#: implementation's timing (the link, the carrier's phase) may differ
RTL_VS_FAST_PCT, RTL_VS_FAST_S = 0.1, 0.05


def nominal():
    p = load_variant("lab-2025")
    axes = tuple(a.replace(motor_coulomb_N_m=a.motor_coulomb_N_m * SCALE_FRICTION,
                           motor_static_N_m=a.motor_static_N_m * SCALE_FRICTION,
                           rotor_inertia_kg_m2=a.rotor_inertia_kg_m2 * SCALE_INERTIA) for a in p.axes)
    return dataclasses.replace(p, axes=axes)


def spread(p, friction: float, inertia: float, kt: float, dz_pts: float):
    axes = []
    for a in p.axes:
        shift = dz_pts / 100 * a.motor_stall_torque_N_m(p.bridge)      # before k_t moves the stall torque
        static = max(a.motor_coulomb_N_m * friction, a.motor_static_N_m * friction + shift)
        axes.append(a.replace(motor_coulomb_N_m=a.motor_coulomb_N_m * friction, motor_static_N_m=static,
                              rotor_inertia_kg_m2=a.rotor_inertia_kg_m2 * inertia,
                              ke_V_s_per_rad=a.ke_V_s_per_rad * kt, km_N_m_per_A=a.km_N_m_per_A * kt))
    return dataclasses.replace(p, axes=tuple(axes))


def plant_spec(p, name: str) -> PlantSpec:
    BUILD.mkdir(parents=True, exist_ok=True)
    f = BUILD / f"{name}.toml"
    f.write_text(export_text(p, f"bench_tune {name}"))
    return PlantSpec.from_file(f)


def limit_cycle_counts(run, a: int, seconds: float = 1.0) -> float:
    """Peak-to-peak of the measured position over the record's last ``seconds``."""
    pos = run.traj.pos[:, a] / tuneverify.RAD_PER_COUNT
    k = max(1, round(seconds / (run.traj.t[1] - run.traj.t[0])))
    return float(pos[-k:].max() - pos[-k:].min())


def tuned(seconds: float):
    p = nominal()
    ident = identifiable_plant(p, SYSTEM.working_hz)
    ts = [tune_axis(a, ident[ax.name].as_dict(), WISH, SYSTEM.working_hz, "bench", p.bridge.supply_V,
                    predict_s=seconds) for a, ax in enumerate(SYSTEM.axes)]
    for t in ts:
        print(f"tuned axis {t.name}: {t.settings()}, zeta {t.design.zeta:.2f}, integral pole {t.design.alpha:g} wn, "
              f"gain margin {t.design.gain_margin_db:.1f} dB, phase margin {t.design.phase_margin_deg:.0f} deg")
    return p, ts


def main() -> int:
    return rtl_check() | robustness() | rtl_corners() | feedforward()


def rtl_check() -> int:
    from bench import QUICK

    seconds = 1.0 if QUICK else 3.0
    p, ts = tuned(seconds)
    spec = plant_spec(p, "nominal")
    rc = 0
    w0 = time.monotonic()
    rtl = tuneverify.verify(ts, spec, "rtl", seconds, log=lambda *m, **k: None)
    w_rtl = time.monotonic() - w0
    fast = tuneverify.verify(ts, spec, "model", seconds)
    print(f"\none-turn step, {seconds:g} s (RTL: {w_rtl:.0f} s wall)")
    print("| axis | metric | predicted | fast model | RTL board image |")
    print("|---|---|---|---|---|")
    for t in ts:
        pr, n = t.predicted, t.name
        rows = (("overshoot (%)", pr.overshoot_pct, "overshoot_pct", ".2f"),
                ("settling, 2 % band (s)", pr.settling_time_s, "settling_time_s", ".3f"),
                ("settling, +-2 counts (s)", t.predicted_tight_s, "settling_time_2_counts_s", ".3f"),
                ("steady-state error (counts)", pr.steady_state_error, "steady_state_error_counts", ".1f"))
        for label, pv, key, f in rows:
            cells = ["-" if v is None else format(v, f) for v in (pv, fast.tuned[n][key], rtl.tuned[n][key])]
            print(f"| {n} | {label} | {' | '.join(cells)} |")
        m = rtl.tuned[n]
        if abs(m["overshoot_pct"] - pr.overshoot_pct) > 1.0 or m["overshoot_pct"] > MAX_OVERSHOOT_PCT:
            print(f"FAIL: {n}: the RTL overshoot is more than 1 point from the prediction or above "
                  f"{MAX_OVERSHOOT_PCT:g} %")
            rc = 1
        if not QUICK and (m["settling_time_2_counts_s"] is None
                          or abs(m["steady_state_error_counts"]) > MAX_ERROR_COUNTS):
            print(f"FAIL: {n}: not settled into +-2 counts, or more than {MAX_ERROR_COUNTS:g} counts off")
            rc = 1
    if any(rtl.faults):
        print(f"FAIL: the board image faulted: {rtl.faults}")
        rc = 1
    return rc


def robustness() -> int:
    from bench import QUICK

    p, ts = tuned(6.0)
    grid = list(itertools.product(*SPREAD.values()))
    grid = [(1.0, 1.0, 1.0, 0.0)] + (grid if not QUICK else [grid[0], grid[-1]])
    for t in ts:
        a = t.axis
        grid_s = 1.5 if QUICK else round(max(3.0, (t.predicted_tight_s or 4.0) + SETTLED_S), 1)
        print(f"\nrobustness of axis {t.name} on the fast model ({len(grid)} plants, {grid_s:g} s one-turn step, "
              "the gains above)")
        print("| friction | inertia | k_t | dead zone (pts) | breakaway (% duty) | overshoot (%) | settling 2 % (s) | "
              "settling +-2 counts (s) | final error (counts) | last 1 s peak-to-peak (counts) |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        results = []
        for fr, j, kt, dz in grid:
            q = spread(p, fr, j, kt, dz)
            brk = identifiable_plant(q, SYSTEM.working_hz)[t.name].dead_zone_pos_pct
            cfg = tuneverify.config([t], plant_spec(q, f"f{fr}_j{j}_k{kt}_d{dz}"), grid_s)
            run = experiment.run_fast(cfg)
            m = tuneverify._metrics(run, cfg.target_counts, a)
            final = cfg.target_counts - run.traj.pos[-1, a] / tuneverify.RAD_PER_COUNT
            lc = limit_cycle_counts(run, a)
            results.append(((fr, j, kt, dz), m, final, lc))
            st = "-" if m["settling_time_s"] is None else f"{m['settling_time_s']:.3f}"
            st2 = "-" if m["settling_time_2_counts_s"] is None else f"{m['settling_time_2_counts_s']:.3f}"
            print(f"| {fr:g} | {j:g} | {kt:g} | {dz:+g} | {brk:.2f} | {m['overshoot_pct']:.2f} | {st} | {st2} | "
                  f"{final:.0f} | {lc:.0f} |", flush=True)
        worst_os = max(results, key=lambda r: r[1]["overshoot_pct"])
        worst_st = max(results, key=lambda r: math.inf if r[1]["settling_time_s"] is None
                       else r[1]["settling_time_s"])
        worst_lc = max(results, key=lambda r: r[3])
        print(f"{t.name}: worst overshoot {worst_os[1]['overshoot_pct']:.2f} % at {worst_os[0]}; worst settling "
              f"{worst_st[1]['settling_time_s']} s at {worst_st[0]}; largest last-1 s swing {worst_lc[3]:.0f} counts "
              f"at {worst_lc[0]} (friction, inertia, k_t, dead zone)")
    return 0


def rtl_corners(corners=RTL_CORNERS) -> int:
    from bench import QUICK

    if QUICK:
        print("\nRTL corners: skipped (--quick)")
        return 0
    p, ts = tuned(RTL_CORNER_S)
    rc = 0
    print(f"\nRTL loop at the grid's corners (both axes tuned on the nominal plant, {RTL_CORNER_S:g} s one-turn step)")
    print("| friction | inertia | k_t | dead zone (pts) | axis | overshoot (%) | settling 2 % (s) | "
          "settling +-2 counts (s) | steady-state error (counts) | max error, last 0.5 s (counts) | "
          "fast model: overshoot, settling 2 %, +-2 counts | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for corner in corners:
        spec = plant_spec(spread(p, *corner), "rtl_f{}_j{}_k{}_d{}".format(*corner))
        w0 = time.monotonic()
        rtl = tuneverify.verify(ts, spec, "rtl", RTL_CORNER_S, log=lambda *m, **k: None)
        wall = time.monotonic() - w0
        fast = tuneverify.verify(ts, spec, "model", RTL_CORNER_S)
        for t in ts:
            m, f = rtl.tuned[t.name], fast.tuned[t.name]
            cells = [format(m["overshoot_pct"], ".2f")] + \
                ["-" if m[x] is None else format(m[x], ".3f") for x in ("settling_time_s", "settling_time_2_counts_s")]
            fc = [format(f["overshoot_pct"], ".2f")] + \
                ["-" if f[x] is None else format(f[x], ".3f") for x in ("settling_time_s", "settling_time_2_counts_s")]
            print("| {:g} | {:g} | {:g} | {:+g} | ".format(*corner) + f"{t.name} | {' | '.join(cells)} | "
                  f"{m['steady_state_error_counts']:.1f} | {m['max_abs_error_last_10pct_counts']:.0f} | "
                  f"{', '.join(fc)} | {wall:.0f} |", flush=True)
            st, fst = m["settling_time_s"], f["settling_time_s"]
            if abs(m["overshoot_pct"] - f["overshoot_pct"]) > RTL_VS_FAST_PCT or (st is None) != (fst is None) or (
                    st is not None and abs(st - fst) > RTL_VS_FAST_S):
                print(f"FAIL: {t.name} at {corner}: the board image is off the fast model")
                rc = 1
            if m["settling_time_2_counts_s"] is None or abs(m["steady_state_error_counts"]) > MAX_ERROR_COUNTS:
                print(f"FAIL: {t.name} at {corner}: not settled into +-2 counts, or more than "
                      f"{MAX_ERROR_COUNTS:g} counts off")
                rc = 1
        if any(rtl.faults):
            print(f"FAIL: the board image faulted at {corner}: {rtl.faults}")
            rc = 1
    return rc


FF_S = 2.5             # the one-turn trapezoid lands by 2.25 s on z
FF_CORNER_S = 3.5      # at the corners z settles into +-2 counts later than 2.5 s
FF_CORNERS = ((1.0, 1.0, 1.0, 0.0), (0.7, 0.7, 0.9, -1.0), (0.7, 1.3, 0.9, -1.0), (1.3, 0.7, 0.9, -1.0),
              (1.3, 1.3, 0.9, -1.0))
FF_RTL_VS_FAST_COUNTS, FF_MAX_SHARE = 2.0, 0.5


def feedforward() -> int:
    from bench import QUICK

    p, ts = tuned(FF_S)
    rc = 0
    if not QUICK:
        spec = plant_spec(p, "nominal")
        rtl = tuneverify.verify(ts, spec, "rtl", FF_S, log=lambda *m, **k: None, move="trapezoid")
        print(f"\nfeed-forward on the one-turn trapezoid, RTL board image ({rtl.wall_s:.0f} s wall), nominal plant")
        print("| axis | VMAX (counts/s) | AMAX (counts/s^2) | peak following error (counts): predicted | RTL | "
              "fast model | without feed-forward (fast model) |")
        print("|---|---|---|---|---|---|---|")
        fast = tuneverify.verify(ts, spec, "model", FF_S, move="trapezoid")
        for t in ts:
            on, f, off = (v[t.name]["peak_following_error_counts"] for v in (rtl.tuned, fast.tuned, rtl.without_ff))
            print(f"| {t.name} | {t.trapezoid[0]} | {t.trapezoid[1]} | {t.predicted_following[0]:.0f} | {on:.0f} | "
                  f"{f:.0f} | {off:.0f} |")
            if abs(on - f) > FF_RTL_VS_FAST_COUNTS or on > FF_MAX_SHARE * off:
                print(f"FAIL: {t.name}: the board image's peak is off the fast model's or above half of without")
                rc = 1
        if any(rtl.faults):
            print(f"FAIL: the board image faulted: {rtl.faults}")
            rc = 1
    corners = FF_CORNERS[:1] if QUICK else FF_CORNERS
    print(f"\nfeed-forward on the one-turn trapezoid over plant spreads (fast model, {FF_CORNER_S:g} s, the gains "
          "above)")
    print("| friction | inertia | k_t | dead zone (pts) | axis | peak following error with (counts) | without | "
          "overshoot with (%) | settling +-2 counts with (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for corner in corners:
        spec = plant_spec(spread(p, *corner), "ff_f{}_j{}_k{}_d{}".format(*corner))
        v = tuneverify.verify(ts, spec, "model", FF_CORNER_S, move="trapezoid")
        for t in ts:
            m, off = v.tuned[t.name], v.without_ff[t.name]["peak_following_error_counts"]
            st = "-" if m["settling_time_2_counts_s"] is None else f"{m['settling_time_2_counts_s']:.3f}"
            print("| {:g} | {:g} | {:g} | {:+g} | ".format(*corner) + f"{t.name} | "
                  f"{m['peak_following_error_counts']:.0f} | {off:.0f} | {m['overshoot_pct']:.2f} | {st} |", flush=True)
    return rc


if __name__ == "__main__":
    raise SystemExit(main())
