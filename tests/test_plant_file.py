# SPDX-License-Identifier: MIT
"""The plant file (sim_models/plantfile.py) and what an encoder-only
identification can see (sim_models/identifiable.py).

The identifiable quantities are closed forms of the averaged plant; they are
checked here against the plant's own stepper driven with constant armature
voltages (the exact zero-order-hold flow of sim_models/axis.py, with every
spring, the gear efficiency form and the stick-slip modes): an independent
route to the same physics, not a second copy of the formula."""

import math

import pytest

from sim_models.identifiable import AXIS_NAMES, identifiable_plant
from sim_models.params import PlantParamError
from sim_models.plantfile import export_text, identified, load_plant_file
from sim_models.stepper import TwoAxisPlant
from sim_models.variants import load_variant, names


@pytest.mark.parametrize("variant", names())
def test_export_then_load_gives_the_same_plant(tmp_path, variant):
    p = load_variant(variant)
    f = tmp_path / "plant.toml"
    f.write_text(export_text(p, variant))
    assert load_plant_file(f) == p
    assert set(identified(f)) == set(AXIS_NAMES)


@pytest.mark.parametrize("edit, says", [
    (("resistance_ohm = 5.287", "resistance_ohm = -5.287"), "x.resistance_ohm = -5.287: must be positive"),
    (("gear_efficiency = 0.95", "gear_efficiency = 1.5"), "gear_efficiency = 1.5: an efficiency must be in (0, 1]"),
    (("lead_m = 0.004\n", ""), "axis1.lead_m: missing"),
    (("[bridge]", "[bridge]\nsupply_volts = 12.0"), "bridge.supply_volts: unknown parameter"),
    (("format = 1", "format = 7"), "format = 7: this torqueloop reads plant files of format 1"),
])
def test_a_bad_value_is_refused_in_one_line_naming_it(tmp_path, edit, says):
    text = export_text(load_variant("paper"), "paper")
    assert edit[0] in text
    f = tmp_path / "plant.toml"
    f.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(PlantParamError) as e:
        load_plant_file(f)
    msg = str(e.value)
    assert says in msg and "\n" not in msg


def _run(p, volts, seconds, dt=0.005):
    plant = TwoAxisPlant(p, seed=0)
    trace = []
    for _ in range(round(seconds / dt)):
        plant.advance_volts(dt, volts)
        trace.append((plant.motor_speed(0), plant.motor_speed(1)))
    return trace


@pytest.mark.parametrize("variant", ["paper", "lab"])
@pytest.mark.parametrize("volts", [6.0, -6.0])
def test_steady_speed_and_time_constant_match_the_stepper(variant, volts):
    p = load_variant(variant)
    ident = identifiable_plant(p)
    trace = _run(p, (volts, volts), 4.0)
    for axis, name in enumerate(AXIS_NAMES):
        i = ident[name]
        vf = i.friction_v_pos if volts > 0 else -i.friction_v_neg
        steady = i.speed_gain_rad_per_s_per_v * (volts - vf)
        predicted = steady * (1 - math.exp(-4.0 / i.time_constant_s))    # first order from rest
        final = trace[-1][axis]
        assert final == pytest.approx(predicted, rel=2e-3), (name, final, predicted)
        t63 = 0.005 * next(k + 1 for k, w in enumerate(trace) if abs(w[axis]) >= (1 - math.exp(-1)) * abs(steady))
        assert t63 == pytest.approx(i.time_constant_s, abs=0.006), (name, t63)


@pytest.mark.parametrize("axis, name", list(enumerate(AXIS_NAMES)))
@pytest.mark.parametrize("sign", [+1, -1])
def test_the_dead_zone_is_where_the_rotor_breaks_away(axis, name, sign):
    p = load_variant("lab")
    i = identifiable_plant(p)[name]
    dz = i.dead_zone_pos_pct if sign > 0 else i.dead_zone_neg_pct
    v_break = dz / 100 * p.bridge.supply_V
    for factor, moves in ((0.98, False), (1.02, True)):
        volts = [0.0, 0.0]
        volts[axis] = sign * factor * v_break
        w = _run(p, volts, 0.3)[-1][axis]
        assert (abs(w) > 1.0) == moves, (name, sign, factor, w)
        if moves:
            assert math.copysign(1, w) == sign


@pytest.mark.parametrize("sign", [+1, -1])
def test_the_dead_zone_at_a_carrier_is_where_the_pwm_driven_rotor_breaks_away(sign):
    """At 20 kHz the ripple's peak breaks the rotor away below the averaged
    breakaway; the closed form (peak of the periodic current) against the
    stepper switching the bridge pins as pwm_torque does (on: the drive,
    off: both low sides, the IBT-2's brake)."""
    from sim_models.bridge import BRAKE
    from torqueloop.spec.bridge import on_pins
    p = load_variant("lab")
    f = 20_000.0
    dz = identifiable_plant(p, f)["x"]
    dz = dz.dead_zone_pos_pct if sign > 0 else dz.dead_zone_neg_pct
    assert dz < identifiable_plant(p)["x"].dead_zone_pos_pct - 0.5     # the ripple matters at 20 kHz
    for factor, moves in ((0.98, False), (1.02, True)):
        plant = TwoAxisPlant(p, seed=0)
        t_on = factor * dz / 100 / f
        for _ in range(round(0.05 * f)):
            plant.advance(t_on, (on_pins(sign), BRAKE))
            plant.advance(1 / f - t_on, (BRAKE, BRAKE))
        w = plant.motor_speed(0)
        assert (abs(w) > 1.0) == moves, (factor, w)


def test_the_cli_exports_a_variant_and_a_plant_file_runs_the_simulated_board(tmp_path, capsys):
    from torqueloop import cli
    from torqueloop.sim.simboard import SimBoard
    from sim_models.variants import PlantSpec, plant_choice

    f = tmp_path / "my.toml"
    assert cli.main(["plant", "export", "lab", "--out", str(f)]) == 0
    assert "wrote" in capsys.readouterr().err
    spec = plant_choice(None, str(f))
    assert spec.params() == load_variant("lab") and spec.file == str(f.resolve())
    assert SimBoard(plant=spec).plant.params == load_variant("lab")
    assert cli.main(["plant", "export", "nolab"]) == 2
    assert cli.main(["plant", "export", "--plant-file", str(tmp_path / "missing.toml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "unknown plant variant 'nolab'" in err[0] and "missing.toml: cannot read" in err[1]
    with pytest.raises(PlantParamError):
        plant_choice("lab", str(f))                      # not both
    assert PlantSpec.from_file(f).label.startswith(str(f.resolve()))
