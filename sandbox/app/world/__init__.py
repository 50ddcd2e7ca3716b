"""The simulation behind the app: the commands the app may send it, the runner that owns the
:class:`~sandbox.model.simulation.Simulation` (a thread, or a child process), the immutable snapshots it
publishes, and the lockstep that holds two worlds on the same step; and many worlds sharing one
process (a class's). Knows nothing of viser.

- :mod:`.orders`    what the app can ask of a simulation: one dataclass per command, with what it does
- :mod:`.contract`  the runner interface, written once over ``submit(command) -> Future``
- :mod:`.runner`    the simulation loop on a thread of its own: the only code that touches the simulation
- :mod:`.child`     the same loop in a child process, for the live app, answering in typed messages;
                    restarts a crashed one
- :mod:`.host`      a world host: one child process holding many worlds, stepped in turn by its thread
- :mod:`.baton`     the host's scheduler and builder threads taking turns (a long build in slices)
- :mod:`.pool`      the app's side of the hosts: up to one per core, each world on the least loaded
- :mod:`.hosted`    one world in a host behind the runner contract (a class's student world)
- :mod:`.standing`  which settings a crashed child is started again from
- :mod:`.faults`    faults the tests put into a child (a slow or failing build), read from the environment
- :mod:`.snapshot`  what a picture of the simulation needs, copied out of the loop
- :mod:`.lockstep`  compare mode's second world held on the running world's step (event thread)
"""
