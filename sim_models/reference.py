# SPDX-License-Identifier: MIT
"""Reference integration: scipy's stiff Radau solver at tight tolerance.

Advances one axis through a schedule of bridge pin states with the same
hybrid-mode logic as the fast stepper (sim_models.axis), but integrates the
right-hand side :func:`sim_models.axis.rhs` directly with ``solve_ivp``
(Radau, analytic Jacobian) and locates mode switches with solve_ivp's own
event root finder.  It is slow and exists to check the fast stepper.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from scipy.integrate import solve_ivp

from sim_models import axis as ax
from sim_models.bridge import Pins, armature_voltages
from sim_models.params import AxisParams, BridgeParams

# absolute tolerances per state: A, rad (motor, gear, coupling, screw), m, m,
# then the velocities
ATOL = np.array([1e-9, 1e-9, 1e-11, 1e-11, 1e-11, 1e-14, 1e-13,
                 1e-7, 1e-9, 1e-9, 1e-9, 1e-12, 1e-11])


def simulate(a: AxisParams, bridge: BridgeParams, schedule: Sequence[tuple[float, Pins]],
             t_end: float, x0: np.ndarray | None = None, rtol: float = 1e-10,
             atol: np.ndarray = ATOL, max_events: int = 100_000,
             consts: ax.AxisConsts | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """Integrate from t = 0 to ``t_end``; ``schedule`` lists (t_start, pins)
    in time order, the first at t = 0.  Returns (times, states, n_events)
    where times are the schedule boundaries plus t_end and states the state
    at each of them.  ``consts``: another load for the same motor
    (AxisConsts.build_dyno)."""
    c = consts or ax.AxisConsts.build(a, bridge)
    x = np.zeros(ax.N_STATE) if x0 is None else np.array(x0, dtype=float)
    e_pos, e_neg = ax.terminal_levels(c, *armature_voltages(schedule[0][1], bridge))
    mode = ax.initial_mode(c, x, e_pos, e_neg)
    times, states = [0.0], [x.copy()]
    n_events = 0
    bounds = [s[0] for s in schedule[1:]] + [t_end]
    for (t0, pins), t1 in zip(schedule, bounds):
        e_pos, e_neg = ax.terminal_levels(c, *armature_voltages(pins, bridge))
        mode = mode._replace(se=ax.elec_mode(c, x, e_pos, e_neg))
        t = t0
        while t1 - t > 1e-15:
            gl = ax.guards(c, mode, e_pos, e_neg)
            amat, bvec = ax.affine(c, mode, e_pos, e_neg)
            m = mode

            def f(_t: float, y: np.ndarray, m: ax.Mode = m) -> np.ndarray:
                return ax.rhs(c, y, m, e_pos, e_neg)

            evs = []
            for g in gl:
                # The mesh-torque guard is identically zero while the drivetrain
                # rests unloaded, which solve_ivp reports as a crossing at every
                # step: it counts below -tol (as the fast stepper's test does).
                off = g.tol if g.part == "mesh" else 0.0

                def ev(_t: float, y: np.ndarray, row: np.ndarray = g.row, off: float = off) -> float:
                    return float(row[:-1] @ y + row[-1]) + off
                ev.terminal = True  # type: ignore[attr-defined]
                ev.direction = -1   # type: ignore[attr-defined]
                evs.append(ev)
            sol = solve_ivp(f, (t, t1), x, method="Radau", rtol=rtol, atol=atol,
                            jac=lambda _t, _y, a_=amat: a_, events=evs or None)
            if not sol.success:
                raise RuntimeError(sol.message)
            if sol.status == 1:      # an event ended the integration
                hit = [(te[0], k) for k, te in enumerate(sol.t_events) if len(te)]
                te, k = min(hit)
                x = np.array(sol.y_events[k][0])
                mode = ax.next_mode(c, x, mode, gl[k], e_pos, e_neg)
                t = float(te)
                n_events += 1
                if n_events > max_events:
                    raise RuntimeError("too many mode switches")
            else:
                x = sol.y[:, -1].copy()
                t = t1
        times.append(t1)
        states.append(x.copy())
    return np.array(times), np.array(states), n_events
