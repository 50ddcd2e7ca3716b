"""The model: the arena, the light field, the robots, the controller and
how success is measured. Headless: nothing here imports the web app.

- :mod:`.config`      every parameter, declared once, and the two profiles
- :mod:`.config_error` ``ConfigError``, below config and the budget that both raise it
- :mod:`.lights`      the light grid and the luminosity field it casts
- :mod:`.robots`      photocells, control law, energy (numpy reference)
- :mod:`.kernels`     the robots' per-step work, compiled with numba
- :mod:`.world`       the pymunk world: walls, bodies, bulk state
- :mod:`.undamped`    robots the space's damping leaves alone
- :mod:`.pymunk_seam` every use of pymunk's private code: its table, its check
- :mod:`.goal`        the goal region, fitted to the centre and the boxes' area
- :mod:`.controller`  the paper's contract / hold / dilate controller (Algorithm 1)
- :mod:`.schedule`    where the controller is in its cycle (a state a copy can run ahead)
- :mod:`.phases`      the controller's three phase names
- :mod:`.outlines`    the outline family: the lit outline (flare) and its sizes
- :mod:`.band`        which lights a band along an outline turns on; no corners
- :mod:`.notes`       what is said before a run: a goal that does not fit, a strategy that does nothing
- :mod:`.preview`     a goal before it is used: fitted, with its smallest and largest outlines
- :mod:`.chase`       chase, a closed loop of ours: the controller seeing the boxes
- :mod:`.programs`    the light-program interface: observations, pattern checks, loading
- :mod:`.env`         a Gymnasium-style environment: the light pattern is the action
- :mod:`.design`      a goal and the light program that built it, in one file: record, replay, save, load
- :mod:`.metrics`     the success metrics and their samples
- :mod:`.simulation`  ``Simulation``: reset, step, read-only state
"""
