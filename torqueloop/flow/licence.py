"""The SPDX line every generated source file starts with (LICENSE: MIT)."""

from __future__ import annotations

from pathlib import PurePosixPath

SPDX = "SPDX-License-Identifier: MIT"
#: comment syntax per generated file type (Markdown carries none)
_COMMENT = {".v": "// {}", ".vh": "// {}", ".vhd": "-- {}", ".h": "/* {} */", ".ld": "/* {} */",
            ".qsf": "# {}", ".sdc": "# {}"}


def with_licence(path: str | PurePosixPath, text: str) -> str:
    """A generated file's text with the SPDX line first (unchanged if it has one or is prose)."""
    fmt = _COMMENT.get(PurePosixPath(str(path)).suffix)
    if fmt is None or SPDX in text[:400]:
        return text
    return fmt.format(SPDX) + "\n" + text
