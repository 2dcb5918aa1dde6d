"""The SPDX line every generated source file starts with (LICENSE: MIT), and
the one banner that says where a generated file comes from."""

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


#: comment syntax of the banner per file type (Markdown: an HTML comment)
_BANNER = {**_COMMENT, ".md": "<!-- {} -->"}


def banner(path: str | PurePosixPath, source: str, writer: str = "torqueloop.flow.generate") -> str:
    """The first line after the SPDX line of every generated file:
    ``Generated from SOURCE by WRITER - do not edit.`` in the comment syntax
    of ``path`` (a file name, or its suffix such as ``.h``)."""
    p = str(path)
    fmt = _BANNER[p if p.startswith(".") else PurePosixPath(p).suffix]
    return fmt.format(f"Generated from {source} by {writer} - do not edit.")
