"""The browser sandbox (``phototaxis serve``): a viser app on top of the engine.

Modules, one idea each:

- :mod:`.commands` what the app can ask of a simulation: one dataclass per command
- :mod:`.contract` the runner interface, written once over ``submit(command) -> Future``
- :mod:`.runner`   the simulation loop (a thread), its command queue and snapshots
- :mod:`.process`  the same loop in a process of its own, for the live app
- :mod:`.scene`    the top-down scene drawn from snapshots
- :mod:`.panel`    the control panel (run, shape, strategies, metrics, ...)
- :mod:`.learn`    the Learn text and its illustrations
- :mod:`.palette`  colours and pictures shared with recordings
- :mod:`.frames`   Pillow frames for GIF / MP4
- :mod:`.server`   the app and the ``serve`` subcommand
- :mod:`.record`   the ``record`` subcommand: HTML replays, GIF and MP4
- :mod:`.live_bench`  speed with a real browser connected
"""
