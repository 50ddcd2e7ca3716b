"""The model: the arena, the light field, the robots, the controller and
how success is measured. Headless: nothing here imports the web app.

- :mod:`.config`      every parameter, declared once, and the two profiles
- :mod:`.lights`      the light grid and the luminosity field it casts
- :mod:`.robots`      photocells, control law, energy (numpy reference)
- :mod:`.kernels`     the robots' per-step work, compiled with numba
- :mod:`.world`       the pymunk world: walls, bodies, bulk state
- :mod:`.undamped`    robots the space's damping leaves alone
- :mod:`.controller`  the goal and the contract / hold / dilate controller
- :mod:`.outlines`    the lit outline (flare) and its smallest / largest sizes
- :mod:`.geometry`    pure polygon geometry
- :mod:`.metrics`     the success metrics and their samples
- :mod:`.simulation`  ``Simulation``: reset, step, read-only state
"""
