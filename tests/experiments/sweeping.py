"""What the tests of generated draws share: a ``sweep`` command line parsed as the CLI parses it, and the
model's refusal replaced by one that refuses the shapes a test names (the real check builds the outlines,
a second and more on a cold process)."""

from __future__ import annotations

from typing import Callable

import numpy as np

from sandbox.experiments import draws
from sandbox.experiments.sweep import add_parser
from sandbox.shapes import generator


def parsed(*argv: str):
    """``phototaxis sweep ARGV`` as the command line parses it."""
    import argparse

    parser = argparse.ArgumentParser()
    add_parser(parser.add_subparsers())
    return parser.parse_args(["sweep", *argv])


def replace_refusal(monkeypatch, applies: Callable = lambda config: True) -> set[str]:
    """The model's refusal, replaced: it refuses the shapes named in the returned set, under the settings
    ``applies`` accepts."""
    names: set[str] = set()

    def refusal(config, vertices):
        for name in names:
            if applies(config) and np.array_equal(vertices, generator.generated_vertices(name)):
                return f"{name}: too large, say"
        return ""

    monkeypatch.setattr(draws, "refusal", refusal)
    return names
