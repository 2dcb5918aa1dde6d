# SPDX-License-Identifier: MIT
"""A study's table kept in a JSON file and reused while what it was computed
from is unchanged: the inputs' digest (the plant, the bench, the method:
:func:`torqueloop.study.characterization.inputs_digest`) with the computing
module's own source, and the plan's key."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any, Callable


def cached(path: Path, digest: str, module_file: str, key: str, compute: Callable[[], dict[str, Any]],
           say: Callable[[str], None] = print) -> dict[str, Any]:
    digest = hashlib.sha256((digest + Path(module_file).read_text()).encode()).hexdigest()
    if path.exists():
        try:
            old = json.loads(path.read_text())
        except ValueError:
            old = {}
        if old.get("digest") == digest and old.get("plan") == key:
            say(f"{path.name} is current (its inputs are unchanged); reused")
            return old
    doc = compute() | {"digest": digest, "plan": key}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc, indent=1, default=float) + "\n")
    return doc
