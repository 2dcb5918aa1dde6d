# SPDX-License-Identifier: MIT
"""The dashboard's figures, built with Bokeh and drawn in the page by
BokehJS (served from the bokeh wheel): per axis, position and set-point,
following error, PWM command with the duty limit (CMD_LIMIT, both signs, from the
last status),
the velocity estimate, and the current where the telemetry carries one.

Each axis has one ColumnDataSource (``ax0``, ``ax1``) that the page's glue
script streams rows into (``source.stream(..., rollover)``); all figures
share one time axis that follows the newest ``WINDOW_S`` seconds while the
view is live.  The toolbar's zoom, pan and save (PNG) work on a paused view.
"""

from __future__ import annotations

from typing import Any

from bokeh.embed import json_item
from bokeh.layouts import gridplot
from bokeh.models import ColumnDataSource, DataRange1d
from bokeh.plotting import figure

from torqueloop.spec import protocol as P

from .hub import AXIS_FIELDS

WINDOW_S = 20.0             # the live view's width
#: the columns of an axis's source (``t`` in s; positions in the page's unit; velocity per s)
COLUMNS = ("t", "setpoint", "position", "error", "pwm_cmd", "limit_hi", "limit_lo", "velocity") + tuple(
    f for f in AXIS_FIELDS if f.startswith("current"))
TOOLS = "xpan,xwheel_zoom,box_zoom,reset,save"


def layout(unit_label: str = "mm") -> dict[str, Any]:
    """The figures as a Bokeh JSON item (``Bokeh.embed.embed_item`` in the page)."""
    x_range = DataRange1d(follow="end", follow_interval=WINDOW_S, range_padding=0, name="x_range")
    cols = []
    for a in range(P.AXIS_COUNT):
        src = ColumnDataSource({c: [] for c in COLUMNS}, name=f"ax{a}")

        def fig(title: str, y: str, name: str) -> Any:
            f = figure(title=f"axis {a}: {title}", height=170, sizing_mode="stretch_width", x_range=x_range,
                       tools=TOOLS, active_scroll="xwheel_zoom", name=f"{name}{a}", y_axis_label=y,
                       output_backend="canvas")
            f.toolbar.logo = None
            f.title.text_font_size = "11px"
            return f

        pos = fig("position and set-point", unit_label, "pos")
        pos.line("t", "setpoint", source=src, color="#888888", line_dash="dashed", legend_label="set-point")
        pos.line("t", "position", source=src, color="#1f77b4", line_width=2, legend_label="position")
        pos.legend.location = "top_left"
        pos.legend.label_text_font_size = "9px"
        err = fig("following error", unit_label, "err")
        err.line("t", "error", source=src, color="#d62728")
        pwm = fig("PWM command (dashed: the limit CMD_LIMIT)", "steps of 1023", "pwm")
        pwm.line("t", "pwm_cmd", source=src, color="#2ca02c")
        for lim in ("limit_hi", "limit_lo"):
            pwm.line("t", lim, source=src, line_dash="dashed", color="#ff7f0e")
        vel = fig("velocity estimate", f"{unit_label}/s", "vel")
        vel.line("t", "velocity", source=src, color="#9467bd")
        vel.xaxis.axis_label = "time (s, board clock)"
        figs = [pos, err, pwm, vel]
        for c in COLUMNS:
            if c.startswith("current"):
                cur = fig("current", c, "cur")
                cur.line("t", c, source=src, color="#8c564b")
                figs.append(cur)
        cols.append(figs)
    rows = [list(r) for r in zip(*cols)]
    grid = gridplot(rows, sizing_mode="stretch_width", merge_tools=True, toolbar_location="right")
    return json_item(grid)
