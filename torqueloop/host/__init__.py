# SPDX-License-Identifier: MIT
"""The host tool behind the ``torqueloop`` command (torqueloop/cli.py).

- :mod:`.transport`: open a link by URL (serial port, RN-XV ``socket://``).
- :mod:`.client`: the protocol client (retries, timeouts, seq, counters),
  built on the generated :mod:`torqueloop.spec.protocol`.
- :mod:`.units`: positions in rad / mm / counts, gains in physical units.
- :mod:`.config`: ``config save`` / ``config load`` (JSON, validated).
- :mod:`.analysis`: step-test figures, CSV and plots from telemetry records.
- :mod:`.simboard`, :mod:`.server`: the simulated board on a local TCP port.
- :mod:`.upload`: firmware images for ``upload``.
- :mod:`.serve`, :mod:`.remote`: ``torqueloop serve`` (one link and session
  for many local clients) and its client.
- :mod:`.shell`, :mod:`.termplot`: ``torqueloop shell`` and its live text plot.
"""
