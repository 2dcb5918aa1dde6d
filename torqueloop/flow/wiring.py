# SPDX-License-Identifier: MIT
"""The wiring diagram of docs/hardware.md, drawn from constraints/pins.toml.

docs/wiring.svg: the DE0-CV's two 40-pin GPIO headers in the middle, every
header pin the board top uses joined to the device pin it goes to (bridges,
encoders, limit switches, the RN-XV), an arrow for the direction as the
FPGA sees it.  Power and ground are not drawn: docs/hardware.md lists them
with the electrical warnings.  ``python -m torqueloop.flow.generate`` writes
it and its ``--check`` (run by ``make lint``) fails when it is stale.
"""

from __future__ import annotations

from collections import OrderedDict
from xml.sax.saxutils import escape

from torqueloop.flow.board_files import GpioUse, load_pin_table

ROW, GAP, TOP = 22, 14, 70
HDR_W, DEV_W = 150, 250
X = {"left_dev": 20, "left_hdr": 360, "right_hdr": 590, "right_dev": 830}
WIDTH = X["right_dev"] + DEV_W + 20


def _header(g: GpioUse) -> int:
    return 0 if g.signal.startswith("GPIO_0") else 1


def _side(uses: list[GpioUse], hdr_x: int, dev_x: int, left: bool) -> tuple[list[str], int]:
    """SVG of one header and the devices wired to it; (elements, height used)."""
    out: list[str] = []
    rows = sorted(uses, key=lambda g: g.header)
    name = rows[0].signal.split("[")[0] if rows else ""
    h = ROW * (len(rows) + 1)
    out.append(f'<rect x="{hdr_x}" y="{TOP}" width="{HDR_W}" height="{h}" class="hdr"/>')
    out.append(f'<text x="{hdr_x + HDR_W / 2}" y="{TOP + 15}" class="title" text-anchor="middle">{name} header</text>')
    pin_y = {}
    for i, g in enumerate(rows):
        y = TOP + ROW * (i + 1)
        pin_y[g.signal] = y + ROW / 2
        out.append(f'<text x="{hdr_x + 8}" y="{y + 15}">pin {g.header}</text>')
        out.append(f'<text x="{hdr_x + HDR_W - 8}" y="{y + 15}" text-anchor="end">{escape(g.signal)}</text>')
    devices: OrderedDict[str, list[GpioUse]] = OrderedDict()
    for g in rows:
        devices.setdefault(g.device, []).append(g)
    y = TOP
    for dev, pins in devices.items():
        bh = ROW * (len(pins) + 1)
        out.append(f'<rect x="{dev_x}" y="{y}" width="{DEV_W}" height="{bh}" class="dev"/>')
        out.append(f'<text x="{dev_x + DEV_W / 2}" y="{y + 15}" class="title" text-anchor="middle">{escape(dev)}</text>')
        for k, g in enumerate(pins):
            ry = y + ROW * (k + 1)
            out.append(f'<text x="{dev_x + (DEV_W - 8 if left else 8)}" y="{ry + 15}" '
                       f'text-anchor="{"end" if left else "start"}">{escape(g.device_pin)}</text>')
            dy = ry + ROW / 2
            hx = hdr_x if left else hdr_x + HDR_W
            dx = dev_x + DEV_W if left else dev_x
            mid = (hx + dx) / 2 + (k - len(pins) / 2) * 3
            to_dev = g.dir == "out"
            start, end = ((hx, pin_y[g.signal]), (dx, dy)) if to_dev else ((dx, dy), (hx, pin_y[g.signal]))
            out.append(f'<polyline points="{start[0]},{start[1]} {mid},{start[1]} {mid},{end[1]} {end[0]},{end[1]}" '
                       f'class="{"out" if to_dev else "in"}" marker-end="url(#arrow)"/>')
        y += bh + GAP
    return out, max(h, y - TOP)


def svg() -> str:
    t = load_pin_table()
    left = [g for g in t.gpio if _header(g) == 0]
    right = [g for g in t.gpio if _header(g) == 1]
    a, ha = _side(left, X["left_hdr"], X["left_dev"], True)
    b, hb = _side(right, X["right_hdr"], X["right_dev"], False)
    height = TOP + max(ha, hb) + 50
    head = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        "<!-- SPDX-License-Identifier: MIT -->",
        "<!-- generated from constraints/pins.toml by torqueloop/flow/wiring.py: do not edit -->",
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" '
        f'viewBox="0 0 {WIDTH} {height}" font-family="sans-serif" font-size="12">',
        "<defs><marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"10\" refY=\"5\" markerWidth=\"7\" "
        "markerHeight=\"7\" orient=\"auto-start-reverse\"><path d=\"M 0 0 L 10 5 L 0 10 z\"/></marker></defs>",
        "<style>.hdr{fill:#eef3fb;stroke:#234}.dev{fill:#fbf6e9;stroke:#543}.title{font-weight:bold}"
        "polyline{fill:none;stroke-width:1.4}.out{stroke:#b22}.in{stroke:#226}</style>",
        f'<rect width="{WIDTH}" height="{height}" fill="white"/>',
        f'<text x="{WIDTH / 2}" y="24" font-size="16" class="title" text-anchor="middle">'
        f"{escape(t.board.name)} ({escape(t.board.device)}) wiring: signals only</text>",
        f'<text x="{WIDTH / 2}" y="44" text-anchor="middle">red: FPGA output to the device; blue: device to FPGA '
        f"input. Every wire 3.3 V ({escape(t.board.io_standard)}); power, ground and pull-downs: docs/hardware.md</text>",
    ]
    foot = [f'<text x="{WIDTH / 2}" y="{height - 16}" text-anchor="middle">DE0-CV header pins 11 = +5 V, '
            "12 = GND, 29 = +3.3 V, 30 = GND (both headers)</text>", "</svg>"]
    return "\n".join(head + a + b + foot) + "\n"


OUTPUTS = {"docs/wiring.svg": svg}
