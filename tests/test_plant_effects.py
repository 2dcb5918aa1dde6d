"""The ``lab`` plant's effects beyond ``lab-2025`` (sim_models.variants
NEW_EFFECTS), each switched on alone and checked against a closed form or a
limit, and ``lab`` with all of them off against ``lab-2025``, bit for bit
(docs/plant.md, "The lab variant")."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sim_models import axis as ax
from sim_models.bridge import Pins
from sim_models.dyno import DynamometerBench, RopeBenchConfig, RopeDynamometer
from sim_models.stepper import FastAxis, TwoAxisPlant
from sim_models.variants import EFFECTS, NEW_EFFECTS, load_variant

FWD, BRAKE = Pins(1, 0, 1, 1), Pins(0, 0, 1, 1)
ON, OFF = (1, 0, 1, 1), (0, 0, 1, 1)


def only(effect: str):
    """The paper plant with one new effect on (and, for the brush law, the
    drop it shapes)."""
    keep = {effect, "brush_drop"} if effect == "brush_law" else {effect}
    return load_variant("lab", tuple(e for e in EFFECTS if e not in keep))


def held(p, axis: int) -> FastAxis:
    """A stage axis whose rotor and gearbox output cannot move (the closed
    forms' stalled motor)."""
    c = ax.AxisConsts.build(p.axes[axis], p.bridge)
    return FastAxis(p.axes[axis], p, axis, energy=True,
                    consts=dataclasses.replace(c, inertia=np.array([1e9, 1e9, 1.0, 1.0, 1.0, 1.0])))


def test_lab_with_the_new_effects_off_is_lab_2025_bit_for_bit() -> None:
    assert load_variant("lab", NEW_EFFECTS) == load_variant("lab-2025")
    runs = []
    for p in (load_variant("lab-2025"), load_variant("lab", NEW_EFFECTS)):
        plant = TwoAxisPlant(p, seed=1, energy=True)
        for k in range(60):
            on = 0.3 + 0.4 * ((k * 7) % 5) / 5
            plant.advance(on / 450, (FWD, Pins(0, 1, 1, 1)))
            plant.advance((1 - on) / 450, (BRAKE, BRAKE))
        runs.append(np.concatenate([plant.state(0), plant.state(1), [plant.current_sq_integral(0)]]))
        rope = RopeDynamometer(p.axes[0], p, RopeBenchConfig(ramp_s=0.02, settle_s=0.02, window_s=0.01))
        runs.append(np.array(dataclasses.astuple(rope.trace([(0.0, ON), (1 / 900, OFF)], 1 / 450))))
    assert np.array_equal(runs[0], runs[2]) and np.array_equal(runs[1], runs[3])


@pytest.mark.parametrize("effect", NEW_EFFECTS)
def test_each_new_effect_changes_the_plant_and_lab_has_it(effect: str) -> None:
    assert only(effect) != load_variant("paper")
    assert load_variant("lab", (effect,)) != load_variant("lab")


# ---------------------------------------------------------------- bridge timing

@pytest.mark.parametrize("freq, duty", [(1000.0, 0.5), (25000.0, 0.2), (25000.0, 0.07)])
def test_bridge_delays_shorten_each_pulse_as_the_closed_form(freq: float, duty: float) -> None:
    """Stalled rotor, brake PWM: the output pulse starts 3.6 us and ends
    2.9 us after the input's edges, so the mean current is the R-L closed
    form's with the pulse 0.7 us shorter (DynamometerBench applies exactly
    that); without the effect the plant's is 0.7 us x f of duty higher.
    (Carriers of whole 10 ns ticks: the closed form knows no tick rounding.)"""
    got = {}
    for name, p in (("timing", only("bridge_timing")), ("ideal", load_variant("paper"))):
        fa = held(p, 0)
        per = 1.0 / freq
        n = int(0.004 / per) + 20        # 20 L/R to settle
        for k in range(2 * n):
            if k == n:
                q0, t0 = fa.q_i, k * per
            fa.set_pins(FWD)
            fa.advance(duty * per, [])
            fa.set_pins(BRAKE)
            fa.advance((1 - duty) * per, [])
        got[name] = (fa.q_i - q0) / (n * per)
    p = only("bridge_timing")
    closed = DynamometerBench(p.axes[0], p.bridge).measure(freq, duty).current_A
    assert got["timing"] == pytest.approx(closed, rel=1e-6)
    shift = (p.bridge.turn_on_delay_s - p.bridge.turn_off_delay_s) * freq
    assert got["ideal"] == pytest.approx(closed * duty / (duty - shift), rel=1e-6)


def test_bridge_drops_pulses_shorter_than_its_minimum() -> None:
    """An input pulse whose output would be shorter than min_pulse_s gives
    no current at all; one just longer does."""
    p = only("bridge_timing")
    b = p.bridge
    shortest_in = b.min_pulse_s + b.turn_on_delay_s - b.turn_off_delay_s
    for width, moves in ((0.9 * shortest_in, False), (1.1 * shortest_in, True)):
        fa = held(p, 0)
        for _ in range(50):
            fa.set_pins(FWD)
            fa.advance(width, [])
            fa.set_pins(BRAKE)
            fa.advance(1 / 24414 - width, [])
        assert (fa.q_i > 0) == moves, (width, fa.q_i)


# ---------------------------------------------------------------- brush law

def test_continuous_brush_law_is_ohmic_below_the_knee_and_the_drop_above() -> None:
    """Stalled rotor, DC: i = V / (R + V_b / i_k) while that is below the
    knee i_k, else (V - V_b) / R; lab-2025's hard drop would give no current
    at all below V_b."""
    p = only("brush_law")
    a = p.axes[0]
    c = ax.AxisConsts.build(a, p.bridge)
    rb = a.brush_drop_V / a.brush_knee_A
    for volts in (0.3 * a.brush_drop_V, 0.9 * a.brush_knee_A * (c.R + rb), 12.0):
        pv = dataclasses.replace(p, bridge=dataclasses.replace(p.bridge, supply_V=volts))
        fa = held(pv, 0)
        fa.set_pins(FWD)
        fa.advance(0.01, [])
        ohmic = volts / (c.R + rb)
        expect = ohmic if ohmic < a.brush_knee_A else (volts - a.brush_drop_V) / c.R
        assert fa.x[ax.I_] == pytest.approx(expect, rel=1e-9), volts


def test_brush_law_tends_to_the_hard_drop_as_the_knee_closes() -> None:
    """The limit knee -> 0 is lab-2025's constant drop: a PWM reading on the
    stalled rotor converges to the hard-drop plant's."""
    def mean_current(p) -> float:
        fa = held(p, 0)
        for _ in range(40):
            fa.set_pins(FWD)
            fa.advance(0.3 / 1000, [])
            fa.set_pins(BRAKE)
            fa.advance(0.7 / 1000, [])
        q0 = fa.q_i
        for _ in range(10):
            fa.set_pins(FWD)
            fa.advance(0.3 / 1000, [])
            fa.set_pins(BRAKE)
            fa.advance(0.7 / 1000, [])
        return (fa.q_i - q0) / 0.01
    hard = mean_current(load_variant("lab", tuple(e for e in EFFECTS if e != "brush_drop")))
    errs = [abs(mean_current(load_variant("lab", tuple(e for e in EFFECTS if e not in ("brush_drop", "brush_law")),
                                          tweak={"brush_law": {"knee_A": k}})) - hard) / hard
            for k in (0.5, 0.05, 0.005)]
    assert errs[0] > errs[1] > errs[2] and errs[2] < 2e-3, errs


def test_brush_law_fast_stepper_matches_the_radau_reference() -> None:
    """The brush regions are modes like any other: a 1 kHz PWM with brake and
    coast off-phases (the current crosses the knee and, coasting, stops at
    zero) through the fast stepper and scipy's Radau agree to 1e-6."""
    from sim_models.reference import simulate

    p = only("brush_law")
    a = p.axes[0].replace(table_coulomb_N=0.0)
    sched = []
    for k in range(20):
        sched += [(k * 1e-3, FWD), (k * 1e-3 + (0.3 + 0.02 * k) * 1e-3, Pins(0, 0, 0, 0) if k % 2 else BRAKE)]
    t_end = 0.02
    _, xr, n_ref = simulate(a, p.bridge, sched, t_end)
    fa = FastAxis(a, p, 0)
    xf = [fa.x.copy()]
    for (t0, pins), t1 in zip(sched, [t for t, _ in sched[1:]] + [t_end]):
        fa.set_pins(pins)
        fa.advance(t1 - t0, [])
        xf.append(fa.x.copy())
    xf = np.array(xf)
    assert n_ref >= 20 and fa.events >= 20
    for k in (ax.I_, ax.PHI_M, ax.W_M):
        assert np.abs(xf[:, k] - xr[:, k]).max() <= 1e-6 * np.abs(xr[:, k]).max(), k


# ---------------------------------------------------------------- winding R(T)

def test_winding_heats_as_its_first_order_model() -> None:
    """Stalled rotor, DC 12 V: the winding's rise theta follows
    tau theta' = R_th i^2 R(theta) - theta with i = V / (R(theta) + R_path)
    (L/R = 0.2 ms is instantaneous against tau), integrated by scipy; the
    current falls with R(theta).  The plant holds R in steps of 0.1 %
    (FastAxis.R_REBUILD_FRAC), the tolerance here.  A small thermal
    resistance keeps the rise, and the test's cost, small."""
    tau = 0.5
    p = load_variant("lab", tuple(e for e in EFFECTS if e != "winding_thermal"),
                     tweak={"winding_thermal": {"tau_s": tau, "thermal_K_per_W": 1.0}})
    a = p.axes[0]
    rp = 2 * p.bridge.r_on_ohm
    fa = held(p, 0)
    fa.set_pins(FWD)

    def r(th: float) -> float:
        return a.resistance_ohm * (1 + a.winding_alpha_per_K * th)

    def f(_t, th):
        i = p.bridge.supply_V / (r(th[0]) + rp)
        return [(a.winding_thermal_K_per_W * i * i * r(th[0]) - th[0]) / tau]

    times = (0.1, 0.4)
    sol = solve_ivp(f, (0, times[-1]), [0.0], t_eval=times, rtol=1e-10, atol=1e-10)
    t = 0.0
    for want, th in zip(times, sol.y[0]):
        while t < want - 1e-12:
            fa.advance(1e-3, [])
            t += 1e-3
        assert fa.theta == pytest.approx(th, rel=2e-3)
        assert fa.x[ax.I_] == pytest.approx(p.bridge.supply_V / (r(th) + rp), rel=1.5e-3)
    assert fa.theta > 8.0            # 27 W into 1 K/W for 0.8 tau
    assert fa.winding_ohm > a.resistance_ohm * 1.03


# ---------------------------------------------------------------- gear backlash

def test_backlash_is_motion_the_encoder_sees_and_the_screw_does_not() -> None:
    """Axis x with its gearbox output held: a small voltage one way, then
    the other, winds the mesh each way by the same torque; the motor-side
    encoder moves between the two rests by that windup, and with backlash
    by exactly 2 delta G more (1 degree of play at the screw: 23.3 counts),
    none of which reaches the screw or the table."""
    def travel(p) -> tuple[float, float]:
        a = p.axes[0]
        c = ax.AxisConsts.build(a, p.bridge)
        inertia = c.inertia.copy()
        inertia[1] = 1e9
        fa = FastAxis(a, p, 0, consts=dataclasses.replace(c, inertia=inertia))
        rest = []
        for v in (0.5, -0.5):
            fa.set_voltage(v)
            fa.advance(0.4, [])
            rest.append((fa.x[ax.PHI_M] / p.encoder.rad_per_count, fa.x[ax.PHI_S]))
        return rest[0][0] - rest[1][0], rest[0][1] - rest[1][1]
    p = only("gear_backlash")
    play = 2 * p.axes[0].gear_backlash_rad * p.axes[0].gear_ratio / p.encoder.rad_per_count
    assert play == pytest.approx(131.25 * 64 / 360, rel=1e-12)
    (enc, screw), (enc0, screw0) = travel(p), travel(load_variant("paper"))
    assert enc - enc0 == pytest.approx(play, rel=1e-6)
    assert abs(screw) < 1e-9 and abs(screw0) < 1e-9


def test_table_counts_is_the_table_position_in_encoder_counts() -> None:
    """TwoAxisPlant.table_counts: chi_l through the lead and the gear ratio
    (8400 counts per screw turn of 4 mm)."""
    plant = TwoAxisPlant(load_variant("paper"), seed=0)
    plant.axes[0].z[ax.CHI_L] = 0.004
    assert plant.table_counts(0) == pytest.approx(131.25 * 64, rel=1e-12)
