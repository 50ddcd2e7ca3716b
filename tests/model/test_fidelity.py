"""The model, run, against the authors' program: a change to the model that moves what the robots do
to the boxes fails here, not only in the golden digests (which fail on any change, meant or not).

The circle case's first contraction (6,000 steps, one seed) is compared with the program's measured
series: the fraction of boxes in the goal before the band reaches them (the boxes' start, the goal's
size), halfway through the sweep (how fast the band and the robots on it move the boxes) and once it
has swept them in. Measured with the default profile, seed 2 is within 0.012 of the program's means;
the paper's light falloff (0.068), its photocells (0.051), its motor (0.17), no box skin (0.036),
a slower or faster contraction (0.975 -> 0.98 or 0.97: 0.26, 0.20) or boxes twice as dense (0.047)
each put it further than the tolerance.
"""

from __future__ import annotations

import pytest

from sandbox.experiments import reference
from sandbox.model.config import case_config
from sandbox.model.simulation import Simulation

SEED = 2


@pytest.mark.slow
def test_the_circles_first_contraction_follows_the_authors_program():
    steps = max(reference.PROGRAM_CIRCLE_FIRST_CONTRACTION)
    sim = Simulation(case_config("circle"), seed=SEED)
    sim.step(steps)
    ours = {sample.step: sample.fraction_in_goal for sample in sim.history}
    apart = {step: round(ours[step] - program, 4)
             for step, program in reference.PROGRAM_CIRCLE_FIRST_CONTRACTION.items()}
    assert all(abs(gap) <= reference.FRACTION_TOLERANCE for gap in apart.values()), (
        f"the circle's fraction in goal minus the program's, by step: {apart} "
        f"(at most {reference.FRACTION_TOLERANCE} allowed)")
