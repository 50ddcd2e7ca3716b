"""phototaxis-sandbox: open-loop collective assembly by a phototaxic swarm.

The package's folders follow the design:

- :mod:`sandbox.model`        the simulation (headless)
- :mod:`sandbox.shapes`       goal polygons from files
- :mod:`sandbox.experiments`  sweeps, statistics, reports
- :mod:`sandbox.app`          the browser sandbox and recordings
- :mod:`sandbox.commands`     the ``phototaxis`` command (with :mod:`sandbox.cli`, its flags)

For scripts::

    from sandbox import Config, Simulation
    sim = Simulation(Config(shape="star", switch=0.25), seed=1)
"""

__version__ = "0.1.0"
__all__ = ["CASES", "Config", "Simulation", "case_config"]


def __getattr__(name: str):
    # Loaded on first use, so that importing any sandbox module (the command
    # line, a sweep's parent process) does not load pymunk and numba.
    if name == "Simulation":
        from sandbox.model.simulation import Simulation

        return Simulation
    if name in ("CASES", "Config", "case_config"):
        from sandbox.model import config

        return getattr(config, name)
    raise AttributeError(f"module 'sandbox' has no attribute {name!r}")
