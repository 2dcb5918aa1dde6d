# SPDX-License-Identifier: MIT
"""Reference models of the RTL cores: the oracles the test benches compare
against, written from the specification (docs/), not from the RTL.  Host-side
tools use them too, to predict what the hardware will do with a setting."""
