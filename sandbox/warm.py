"""Imported once by the fork server of :mod:`sandbox.processes`, before it forks a simulation
process: the model, the live app's simulation process module and the world host's (no web server), numba's compiled
kernels loaded from its cache and the robots' compiled velocity function. Every process forked
afterwards has them already. Nothing else imports it: it sets the process's Ctrl+C aside.

Ctrl+C in a terminal reaches every process of the group. It is for the program that started the fork
server, which stops it and its forks; here it would end the loading with a KeyboardInterrupt traceback
(multiprocessing makes the fork server ignore it only once its preloading is done). Every process it
forks inherits this too, from its first instruction: the app's simulation processes and the sweep and
advice workers ignore Ctrl+C anyway."""

import signal

signal.signal(signal.SIGINT, signal.SIG_IGN)

from sandbox.app.world import child, host  # noqa: E402,F401  (the child's and the world host's entry points)
from sandbox.model import kernels, simulation, undamped  # noqa: E402,F401

kernels.warm_up()
if undamped.VECT_AS_TWO_DOUBLES:
    undamped._compiled_velocity_function()  # same address in every fork: Chipmunk is loaded here
