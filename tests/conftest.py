import numpy as np
import pytest

from sandbox.model.config import Config


@pytest.fixture
def small_config() -> Config:
    """A quick world: few bodies, same arena and lights as the paper."""
    return Config(robots=30, boxes=60)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)
