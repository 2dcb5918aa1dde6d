"""Plant variants (sim_models.variants) and each lab effect checked alone
against a closed form or a limiting case (docs/plant.md, "The lab variant")."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from sim_models import axis as ax
from sim_models.bridge import Pins
from sim_models.dyno import DynamometerBench, RopeBenchConfig, RopeDynamometer
from sim_models.params import PlantParamError, load_params, params_from_dict, read_toml
from sim_models.stepper import FastAxis, TwoAxisPlant
from sim_models.variants import EFFECTS, NEW_EFFECTS, PlantSpec, PlantVariantError, load_variant, names, plant_of

FWD, BRAKE = Pins(1, 0, 1, 1), Pins(0, 0, 1, 1)
ON, OFF = (1, 0, 1, 1), (0, 0, 1, 1)


def test_the_variants_and_what_distinguishes_them() -> None:
    assert names() == ("paper-printed", "paper", "lab-2025", "lab")
    printed, paper, lab2025, lab = (load_variant(n) for n in names())
    assert lab2025 == load_variant("lab", NEW_EFFECTS)
    assert printed == load_params()                      # Table 2 as printed
    assert printed.axes[1].rotor_inertia_kg_m2 == 9.655e-5
    assert paper.axes[1].rotor_inertia_kg_m2 == 9.655e-6
    assert paper.axes[0] == printed.axes[0]
    for a in lab.axes:
        assert a.ke_V_s_per_rad == pytest.approx(a.kt_motor_N_m_per_A)   # energy-consistent
        assert a.motor_static_N_m > a.motor_coulomb_N_m > 0
        assert a.brush_drop_V > 0 and a.gear_efficiency_back is not None


def test_lab_with_every_effect_off_is_paper_to_the_steppers_tolerance() -> None:
    assert load_variant("lab", EFFECTS) == load_variant("paper")
    # and simulated: the same PWM drive through both, state for state
    runs = []
    for p in (load_variant("paper"), load_variant("lab", EFFECTS)):
        plant = TwoAxisPlant(p, seed=1)
        for k in range(60):
            on = 0.3 + 0.4 * ((k * 7) % 5) / 5
            plant.advance(on / 450, (FWD, FWD))
            plant.advance((1 - on) / 450, (BRAKE, BRAKE))
        runs.append(np.concatenate([plant.state(0), plant.state(1)]))
    assert np.array_equal(runs[0], runs[1])


@pytest.mark.parametrize("effect", EFFECTS)
def test_each_effect_alone_changes_the_paper_plant(effect: str) -> None:
    only = load_variant("lab", tuple(e for e in EFFECTS if e != effect))
    assert only != load_variant("paper")


def _dc_axis(p, axis: int, volts: float, t: float, **changes) -> np.ndarray:
    """One stage axis from rest, bridge constantly forward at ``volts``."""
    p = dataclasses.replace(p, bridge=dataclasses.replace(p.bridge, supply_V=volts))
    a = p.axes[axis].replace(**changes)
    fa = FastAxis(a, p, axis)
    fa.set_pins(FWD)
    fa.advance(t, [])
    return fa.x


def test_motor_friction_no_motion_below_breakaway_and_motion_above() -> None:
    """DC drive: the rotor stays put while k_t V / R is below the breakaway
    torque T_s and turns once it is above (brush drop off, table free)."""
    p = load_variant("lab-2025", ("brush_drop", "gear_efficiency", "energy_consistent"))
    a = p.axes[0]
    c = ax.AxisConsts.build(a, p.bridge)
    v_break = a.motor_static_N_m * c.R / c.kt
    below = _dc_axis(p, 0, 0.97 * v_break, 0.05, table_coulomb_N=0.0)
    above = _dc_axis(p, 0, 1.03 * v_break, 0.05, table_coulomb_N=0.0)
    assert below[ax.PHI_M] == 0.0 and below[ax.W_M] == 0.0
    assert above[ax.PHI_M] > 1e-3
    # and with the paper's frictionless motor the same small voltage turns it
    assert _dc_axis(load_variant("paper"), 0, 0.97 * v_break, 0.05, table_coulomb_N=0.0)[ax.PHI_M] > 1e-3


def test_pwm_ripple_lowers_the_apparent_breakaway() -> None:
    """The same mean voltage that cannot start the motor as DC starts it as a
    200 Hz PWM: each pulse reaches the full supply current, above T_s."""
    p = load_variant("lab-2025", ("brush_drop", "gear_efficiency", "energy_consistent"))
    a = p.axes[0].replace(table_coulomb_N=0.0)
    c = ax.AxisConsts.build(a, p.bridge)
    duty = 0.5 * a.motor_static_N_m * c.R / c.kt / p.bridge.supply_V     # half the DC breakaway
    fa = FastAxis(a, p, 0)
    for _ in range(20):
        fa.set_pins(FWD)
        fa.advance(duty / 200, [])
        fa.set_pins(BRAKE)
        fa.advance((1 - duty) / 200, [])
    assert fa.x[ax.PHI_M] > 1e-3
    dc = _dc_axis(p, 0, duty * p.bridge.supply_V, 0.1, table_coulomb_N=0.0)
    assert dc[ax.PHI_M] == 0.0


def test_brush_drop_lowers_the_stall_current_by_vb_over_r() -> None:
    """Rotor held (the paper's closed form), DC: i = (V - V_b) / R."""
    for name in ("paper", "lab-2025"):
        p = load_variant(name, () if name == "paper" else ("motor_friction", "gear_efficiency", "energy_consistent"))
        a = p.axes[1]
        c = ax.AxisConsts.build(a, p.bridge)
        fa = FastAxis(a, p, 1, consts=dataclasses.replace(c, inertia=np.array([1e9, 1e9, 1.0, 1.0, 1.0, 1.0])))
        fa.set_pins(FWD)
        fa.advance(0.01, [])
        assert fa.x[ax.I_] == pytest.approx((p.bridge.supply_V - a.brush_drop_V) / c.R, rel=1e-9)


def test_back_driving_efficiency_sets_the_lowering_speed() -> None:
    """Axis z lowered by gravity with the motor shorted (both low sides on):
    the steady rotor speed is omega = x_b F_g R_n R / (G k_t k_e), where the
    paper's symmetric form would give omega = F_g R_n R / (xi G k_t k_e)."""
    for effects_off, factor in ((EFFECTS, None), (tuple(e for e in EFFECTS if e != "gear_efficiency"), "xi_b")):
        p = load_variant("lab", effects_off)
        a = p.axes[1].replace(table_coulomb_N=0.0, nut_damping_N_s_per_m=200.0, screw_axial_damping_N_s_per_m=200.0)
        c = ax.AxisConsts.build(a, p.bridge)
        fa = FastAxis(a, p, 1)
        fa.set_pins(BRAKE)
        fa.advance(6.0, [])
        t_load = a.table_mass_kg * a.gravity_m_s2 * c.rn          # screw torque of the table's weight
        passed = a.gear_efficiency_back * t_load / c.G if factor else t_load / (c.xi * c.G)
        expect = -passed * c.R / (c.kt * c.ke)
        assert fa.x[ax.W_M] == pytest.approx(expect, rel=2e-3), (effects_off, fa.x[ax.W_M], expect)


def test_rope_bench_matches_the_closed_form_with_the_effects_off() -> None:
    """Rotor held by a very stiff rope, no friction, no brush drop: the mean
    current and the torque are the stalled R-L closed form's (DynamometerBench)."""
    p = load_variant("paper")
    a = p.axes[0]
    cfg = RopeBenchConfig(rope_N_per_m=1e9, rope_N_s_per_m=4e5, ramp_s=0.02, settle_s=0.05, window_s=0.02)
    rope = RopeDynamometer(a, p, cfg)
    closed = DynamometerBench(a, p.bridge)
    for f in (200.0, 450.0):
        per = 1 / f
        tr = rope.trace([(0.0, ON), (per * 0.5, OFF)], per)
        cf = closed.measure(f, 0.5)
        # the closed form shortens each pulse by the bridge's 0.7 us; the pins here do not
        corr = 1 + 0.7e-6 * f / 0.5
        assert tr.current_mean_A * 1 == pytest.approx(cf.current_A * corr, rel=2e-3)
        assert tr.force_mean_N * cfg.wheel_radius_m == pytest.approx(a.km_N_m_per_A * tr.current_mean_A, rel=2e-3)


def test_unknown_variant_and_effect_are_refused_in_one_line() -> None:
    with pytest.raises(PlantVariantError, match=r"unknown plant variant 'lbа'|unknown plant variant"):
        load_variant("lbа")
    with pytest.raises(PlantVariantError, match="unknown effect 'brushes'"):
        plant_of("lab-no-brushes")
    p = plant_of("lab-no-brush_drop-no-motor_friction")
    assert p == PlantSpec("lab", ("brush_drop", "motor_friction")) and p.label == "lab-no-brush_drop-no-motor_friction"
    assert plant_of(p) is p and p.without("gear_efficiency").label == p.label + "-no-gear_efficiency"


@pytest.mark.parametrize("section, key, value, rule", [
    ("axis1", "rotor_inertia_kg_m2", -1e-6, "must be positive"),
    ("axis2", "gear_efficiency", 1.2, "efficiency must be in (0, 1]"),
    ("axis1", "motor_static_N_m", 0.5, "at or above the stall torque"),
    ("axis1", "motor_coulomb_N_m", float("nan"), "must be a finite number"),
    ("axis2", "resistance_ohm", None, "missing"),
    ("axis1", "inertia_typo", 1.0, "unknown parameter"),
])
def test_a_parameter_file_with_a_bad_value_is_refused_naming_the_key(section, key, value, rule, tmp_path: Path) -> None:
    d = read_toml(Path(__file__).resolve().parent.parent / "sim_models" / "params" / "table2.toml")
    if value is None:
        del d[section][key]
    else:
        d[section][key] = value
        if key == "motor_static_N_m":
            d[section]["motor_coulomb_N_m"] = 0.1
    with pytest.raises(PlantParamError) as e:
        params_from_dict(d, "bad.toml")
    msg = str(e.value)
    assert key in msg and rule in msg and "\n" not in msg, msg


def test_a_bad_variant_overlay_is_refused(monkeypatch, tmp_path: Path) -> None:
    import sim_models.variants as V

    text = (Path(V.VARIANTS_FILE).read_text().replace("static_frac = 0.042", "static_frac = 0.01"))
    f = tmp_path / "variants.toml"
    f.write_text(text)
    monkeypatch.setattr(V, "VARIANTS_FILE", f)
    with pytest.raises(PlantParamError, match="motor_static_N_m .* breakaway below the Coulomb level"):
        V.load_variant("lab")
    assert not math.isnan(V.load_variant("paper").axes[0].gear_efficiency)
