"""The simulation behind the app: the commands the app may send it, the runner that owns the
:class:`~sandbox.model.simulation.Simulation` (a thread, or a child process), the immutable snapshots it
publishes, and the lockstep that holds two worlds on the same step. Knows nothing of viser.

- :mod:`.orders`    what the app can ask of a simulation: one dataclass per command, with what it does
- :mod:`.contract`  the runner interface, written once over ``submit(command) -> Future``
- :mod:`.runner`    the simulation loop on a thread of its own: the only code that touches the simulation
- :mod:`.child`     the same loop in a child process, for the live app, answering in typed messages;
                    restarts a crashed one
- :mod:`.standing`  which settings a crashed child is started again from
- :mod:`.faults`    faults the tests put into a child (a slow or failing build), read from the environment
- :mod:`.snapshot`  what a picture of the simulation needs, copied out of the loop
- :mod:`.lockstep`  compare mode's second world held on the running world's step (event thread)
"""
