# SPDX-License-Identifier: MIT
"""Host tool pieces without a board: position units, PWM frequency, step
figures against closed-form first- and second-order responses, CSV round
trip, and the config file's validation and write order."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from torqueloop.spec import protocol as P
from torqueloop.host import analysis
from torqueloop.spec import units
from torqueloop.host import config as hc
from torqueloop.oracles import freq_div

MECH = units.Mechanics(8400, 4000)


@pytest.mark.parametrize("text,counts", [("6.283185307rad", 8400), ("4mm", 8400), ("-2mm", -4200),
                                         ("1rev", 8400), ("0.5 rev", 4200), ("90deg", 2100),
                                         ("1234", 1234), ("1234counts", 1234), ("1e3", 1000)])
def test_positions(text: str, counts: int) -> None:
    assert units.parse_position(text, MECH) == counts


def test_bad_positions_are_named() -> None:
    for bad in ("4 furlongs", "mm", "1..2rad"):
        with pytest.raises(ValueError):
            units.parse_position(bad, MECH)


@pytest.mark.parametrize("f", [200.0, 450.0, 1000.0, 20_000.0])
def test_pwm_frequency_goes_through_the_divider_of_eq_4(f: float) -> None:
    fdiv = units.divider_for(f)
    # the carrier the frequency-divider and PWM cores really make (their reference model)
    got = freq_div.carrier_hz(fdiv)
    assert abs(got - f) <= abs(freq_div.carrier_hz(fdiv + 1) - f) and abs(got - f) <= abs(
        freq_div.carrier_hz(max(1, fdiv - 1)) - f)
    assert units.carrier_hz(fdiv) == pytest.approx(got)


def test_friendly_parameters_scale_to_the_protocol() -> None:
    assert units.to_raw("kp", "0.82") == ("KP_UNM_RAD", 820_000)
    assert units.to_raw("period", "0.025") == ("PERIOD_US", 25_000)
    assert units.to_raw("law", "PID") == ("LAW", 3)
    assert units.to_raw("KP_Q16", "0x10000") == ("KP_Q16", 65536)
    assert units.from_raw("tau_max", 2080) == (2.08, "N m")
    with pytest.raises(ValueError, match="friendly names"):
        units.resolve("kq")
    for f in units.FRIENDLY.values():
        assert f.param in P.PARAMS


def test_first_order_step_figures_match_closed_form() -> None:
    tau, T = 0.2, 3.0
    t = np.linspace(0, T, 3001)
    x = 1000 * (1 - np.exp(-t / tau))
    f = analysis.step_figures(t, x, np.full_like(t, 1000.0), 0, 1000, band_frac=0.02, band_min_counts=0)
    assert f.overshoot_pct == 0
    assert f.rise_time_s == pytest.approx(tau * math.log(9), rel=1e-3)
    assert f.settling_time_s == pytest.approx(tau * math.log(50), abs=2e-3)
    rmse = 1000 * math.sqrt(tau / (2 * T) * (1 - math.exp(-2 * T / tau)))
    assert f.rmse == pytest.approx(rmse, rel=1e-4)


def test_second_order_overshoot_and_direction() -> None:
    z, wn = 0.4, 10.0
    wd = wn * math.sqrt(1 - z * z)
    t = np.linspace(0, 4, 8001)
    y = 1 - np.exp(-z * wn * t) * (np.cos(wd * t) + z / math.sqrt(1 - z * z) * np.sin(wd * t))
    expect = 100 * math.exp(-math.pi * z / math.sqrt(1 - z * z))
    for start, target in ((0, 500), (300, -700)):          # a step down measures the same
        x = start + (target - start) * y
        f = analysis.step_figures(t, x, np.full_like(t, target), start, target)
        assert f.overshoot_pct == pytest.approx(expect, rel=1e-3)
        assert f.peak == pytest.approx(start + (target - start) * (1 + expect / 100), rel=1e-3)


def test_a_response_that_never_settles_says_so() -> None:
    t = np.linspace(0, 1, 101)
    x = 100 * t
    assert analysis.step_figures(t, x, np.full_like(t, 200.0), 0, 200).settling_time_s is None


def _records(n: int) -> list[dict]:
    rng = np.random.default_rng(3)
    out = []
    for k in range(n):
        ax = [{"setpoint": int(rng.integers(-9999, 9999)), "position": int(rng.integers(-9999, 9999)),
               "velocity_q8": int(rng.integers(-10**6, 10**6)), "error": int(rng.integers(-99, 99)),
               "pwm_cmd": int(rng.integers(-1023, 1023)), "faults": int(rng.integers(0, 4)), "enabled": 1}
              for _ in range(2)]
        # time_us wraps at 2^32 in the middle of the capture
        out.append({"time_us": (2**32 - 50_000 + 25_000 * k) % 2**32, "axes": ax})
    return out


def test_capture_unwraps_time_and_csv_round_trips(tmp_path) -> None:
    cap = analysis.to_capture(_records(6))
    assert np.allclose(np.diff(cap.t), 0.025)
    p = tmp_path / "c.csv"
    analysis.write_csv(p, cap, MECH, "mm")
    back = analysis.read_csv(p)
    for fld in analysis.FIELDS:
        assert np.allclose(back.data[fld], cap.data[fld], atol=0.01), fld


def _doc() -> dict:
    axes = [{k: P.PARAMS[k].default for k in hc.AXIS_PARAMS} for _ in range(2)]
    return {"schema": hc.SCHEMA, "schema_version": 1,
            "firmware": {"build_id": "0x51b00001", "proto_version": 1},
            "global": {k: P.PARAMS[k].default for k in hc.GLOBAL_PARAMS}, "axes": axes}


def test_config_round_trip_and_validation() -> None:
    cfg = hc.parse(_doc())
    assert cfg.build_id == 0x51B00001 and "BAUD_DIV" not in cfg.globals
    again = hc.parse(json.loads(hc.to_json(cfg)))
    assert again == cfg
    for mutate, field in ((lambda d: d["axes"][0].pop("KP_Q16"), "missing KP_Q16"),
                          (lambda d: d["axes"][1].update(CMD_LIMIT=2000), "axes[1].CMD_LIMIT"),
                          (lambda d: d["axes"][1].update(KP_Q16=1.5), "must be an integer"),
                          (lambda d: d["global"].update(BAUD_DIV=433), "global.BAUD_DIV"),
                          (lambda d: d["axes"][0].update(SOFT_MIN=10, SOFT_MAX=5), "SOFT_MIN 10 > SOFT_MAX"),
                          (lambda d: d.update(schema="x"), "schema"),
                          (lambda d: d["axes"].pop(), "list of 2")):
        d = _doc()
        mutate(d)
        with pytest.raises(hc.HostConfigError, match=field.replace("[", r"\[").replace("]", r"\]")):
            hc.parse(d)


def test_write_order_satisfies_the_firmware_soft_limit_rule() -> None:
    # firmware (params.c param_allowed): SOFT_MIN <= SOFT_MAX must hold after every write
    d = _doc()
    d["axes"][0].update(SOFT_MIN=2_000_000, SOFT_MAX=3_000_000)
    d["axes"][1].update(SOFT_MIN=-3_000_000, SOFT_MAX=-2_000_000)
    board = [{"SOFT_MIN": -1_000_000, "SOFT_MAX": 1_000_000} for _ in range(2)]
    for axis, name, value in hc.apply_order(hc.parse(d)):
        if name in ("SOFT_MIN", "SOFT_MAX"):
            new = dict(board[axis], **{name: value})
            assert new["SOFT_MIN"] <= new["SOFT_MAX"], (axis, name, value)
            board[axis] = new
    assert board == [{"SOFT_MIN": 2_000_000, "SOFT_MAX": 3_000_000},
                     {"SOFT_MIN": -3_000_000, "SOFT_MAX": -2_000_000}]


@pytest.mark.parametrize("text,dim,counts", [("5mm/s", 1, 10_500), ("1rev/s", 1, 8400), ("-90deg", 0, -2100),
                                             ("50mm/s^2", 2, 105_000), ("50 mm/s2", 2, 105_000),
                                             ("8400counts/s", 1, 8400), ("700", 1, 700), ("10mm", 0, 21_000)])
def test_positions_speeds_and_accelerations_take_every_unit(text: str, dim: int, counts: int) -> None:
    assert units.parse_quantity(text, MECH, dim) == counts


def test_a_quantity_of_the_wrong_kind_is_refused() -> None:
    for text, dim in (("5mm", 1), ("5mm/s", 0), ("5mm/s", 2), ("1rev/s^2", 1)):
        with pytest.raises(units.BadValue, match="is not a"):
            units.parse_quantity(text, MECH, dim)
    # limits and speeds through `set`: the board's mechanics convert them
    assert units.to_raw("soft_max", "40mm", mech=MECH) == ("SOFT_MAX", 84_000)
    assert units.to_raw("vmax", "2rev/s", mech=MECH) == ("VMAX", 16_800)
    with pytest.raises(units.BadValue, match="not a speed"):
        units.to_raw("home_vel", "3mm", mech=MECH)


def test_a_carrier_the_divider_cannot_make_is_refused_unless_nearest() -> None:
    with pytest.raises(units.BadValue) as e:
        units.to_raw("pwm_freq", "20000")
    assert "16292 Hz (FDIV 3)" in str(e.value) and "24438 Hz (FDIV 2)" in str(e.value)
    assert units.to_raw("pwm_freq", "20000", nearest=True) == ("FDIV", 3)
    assert units.to_raw("pwm_freq", "24438") == ("FDIV", 2)
    # below about 1 kHz every request is within PWM_FREQ_TOL of a carrier the divider makes
    for f in range(50, 1000, 7):
        param, div = units.to_raw("pwm_freq", str(f))
        assert abs(units.carrier_hz(div) - f) <= units.PWM_FREQ_TOL * f


def test_the_terminal_plot_puts_each_series_where_it_belongs() -> None:
    from torqueloop.host import termplot

    recs = [{"time_us": 25_000 * k, "axes": [{"position": 100 * k, "setpoint": 1000, "error": 1000 - 100 * k,
                                              "pwm_cmd": 5 * (10 - k)}, {}]} for k in range(11)]
    text = termplot.frame(recs, 0, "counts", float, n=3, width=11, height=5)
    lines = text.splitlines()
    assert lines[0].startswith("frame 3  axis 0  t 0.250 s  (11 records)")
    chart = [ln.split("|")[1] for ln in lines[2:7]]          # the position chart, newest on the right
    assert chart[4][0] == "*" and chart[0][10] == "*"        # from the bottom-left to the top-right
    assert set(chart[0][:9]) == {"-"}                        # the set-point on the top row
    assert "* position 1000" in lines[1] and "- set-point 1000" in lines[1]


def test_status_names_overruns() -> None:
    """`torqueloop status` prints the board's timing: the overrun count is named
    (with what to do) only when there is one."""
    from torqueloop.cli import _timing_text
    st = {"loop_cycles_max": 1077, "jitter_cycles_max": 139, "overruns": 0}
    assert _timing_text(st).endswith("no control period overrun") and "1077 cycles" in _timing_text(st)
    text = _timing_text({**st, "overruns": 7})
    assert "7 control periods OVERRUN" in text and "PERIOD_US" in text
