"""Imported once by the fork server of :mod:`sandbox.processes`, before it forks a simulation
process: the model, the live app's simulation process module (no web server), numba's compiled
kernels loaded from its cache and the robots' compiled velocity function. Every process forked
afterwards has them already. Importing this module elsewhere only costs that time once."""

from sandbox.app import process  # noqa: F401  (the child's entry point, and the runner)
from sandbox.model import kernels, simulation, undamped  # noqa: F401

kernels.warm_up()
if undamped.VECT_AS_TWO_DOUBLES:
    undamped._compiled_velocity_function()  # same address in every fork: Chipmunk is loaded here
