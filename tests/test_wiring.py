# SPDX-License-Identifier: MIT
"""docs/wiring.svg draws every wire of constraints/pins.toml, each from the
right header pin to the right device pin, in the direction the FPGA sees it."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

from torqueloop.flow import wiring
from torqueloop.flow.board_files import load_pin_table
from torqueloop.spec.repo import REPO_ROOT

NS = {"s": "http://www.w3.org/2000/svg"}


def test_every_gpio_wire_is_drawn_once_in_its_direction() -> None:
    table = load_pin_table()
    root = ET.fromstring(wiring.svg().split("\n", 1)[1])     # past the XML declaration
    lines = root.findall(".//s:polyline", NS)
    assert len(lines) == len(table.gpio)
    texts = [t.text or "" for t in root.iter(f"{{{NS['s']}}}text")]
    for g in table.gpio:
        assert g.signal in texts and f"pin {g.header}" in texts and g.device_pin in texts, g
    # FPGA outputs are drawn header -> device (red), inputs device -> header (blue)
    outs = sum(1 for g in table.gpio if g.dir == "out")
    assert sum(1 for p in lines if p.get("class") == "out") == outs
    assert sum(1 for p in lines if p.get("class") == "in") == len(table.gpio) - outs
    for p in lines:
        xs = [float(x.split(",")[0]) for x in p.get("points").split()]
        header_x = {wiring.X["left_hdr"], wiring.X["right_hdr"] + wiring.HDR_W}
        starts_at_header = xs[0] in header_x
        assert starts_at_header == (p.get("class") == "out"), p.get("points")


def test_the_committed_diagram_is_the_generated_one() -> None:
    committed = (REPO_ROOT / "docs" / "wiring.svg").read_text()
    assert committed == wiring.svg()
    assert re.search(r"<svg [^>]*viewBox=", committed)
