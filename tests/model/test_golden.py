"""The default model's exact state after short seeded runs (see tests/golden/runs.py).

A change that moves one of these digests changes the science: update them
knowingly (``python -m tests.golden.runs --update``) in the same commit, and
say why in its message."""

import pytest

from tests.golden.runs import LONG, QUICK, key, run_digest, stored


@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.slow) if name in LONG else name
                                  for name in QUICK])
def test_state_digest_is_unchanged(name):
    steps = QUICK[name]
    assert run_digest(name, steps) == stored()[key(name, steps)], f"{name} moved: see tests/golden/runs.py"
