"""A light program in 20 lines: a ring of light that shrinks onto the goal, again and again.

    phototaxis run --controller examples/shrinking_ring.py:ShrinkingRing --steps 20000
"""
import numpy as np

from sandbox.model.programs import LightProgram


class ShrinkingRing(LightProgram):
    every = 100  # world steps between two updates

    def reset(self, config, goal):
        self.centre, self.smallest, self.band = goal.centre, goal.radius + 0.5, config.band
        self.radius = 24.0

    def update(self, observation):
        self.radius *= 0.975  # contract by 2.5 % per update ...
        if self.radius < self.smallest:
            self.radius = 24.0  # ... and start again from the outside
        distance = np.linalg.norm(observation.light_centres - self.centre, axis=-1)
        return (np.abs(distance - self.radius) <= self.band).astype(float)
