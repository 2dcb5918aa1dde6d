# SPDX-License-Identifier: MIT
"""The browser dashboard of ``torqueloop serve --http``: live plots and
controls of both axes over the session server (docs/host.md, "Dashboard").

- :mod:`.hub`: the telemetry's fan-out to pages - a history ring, one
  bounded queue per page (drop-oldest for that page only, counted);
- :mod:`.access`: who may do what - tokens for watching and for commanding;
- :mod:`.actions`: what a page may ask, in physical units, carried out
  through the session server's one authenticated session with the board;
- :mod:`.plots`: the Bokeh figures (BokehJS, shipped in the bokeh wheel,
  draws them in the page);
- :mod:`.web`: the Tornado application (HTTP and the WebSocket);
- :mod:`.listen`: a WebSocket client without a browser (scripts, the bench).

Only :mod:`.plots`, :mod:`.web` and :mod:`.listen` need the ``dash`` extra (bokeh, tornado);
``static/`` holds the page and its glue script.
"""
