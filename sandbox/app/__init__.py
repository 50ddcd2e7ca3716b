"""The browser sandbox (``phototaxis serve``, :mod:`sandbox.commands.serve`): a viser app on top of the
engine, in four rooms. Imports run downhill: ``world`` and ``web`` know nothing of the rest, ``view``
draws what ``world`` snapshots, ``panel`` uses all three, and the ``serve`` command puts them together.
Each room's modules say which thread runs them; docs/code.md's Threads table has them all.

- :mod:`.world`  the simulation behind the app: what the app may ask of it, the runner (a thread, or a
  process of its own), snapshots, and the lockstep of two worlds in compare mode. No viser.
- :mod:`.web`    the server's transport and who may talk to it: the gate, access, every page message
  checked and budgeted, the event queue, the one seam onto viser's private code, pacing, and the
  scripts the page runs.
- :mod:`.view`   what is drawn on the floor: the scene from snapshots, hexagons, the legend, colours,
  the shape being drawn, the compared world, and Pillow frames for recordings.
- :mod:`.panel`  the control panel: one module per folder (run, goal shape and drawing, strategies,
  metrics, result, compare, challenge, Learn, ...).

Every module's docstring says what it owns and which thread runs it; docs/code.md has the map.
"""
