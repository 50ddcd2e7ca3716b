"""Chase: the closed loop (interim)."""

from sandbox.model.chase.controller import ChaseController

__all__ = ["ChaseController"]
