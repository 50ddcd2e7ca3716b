"""phototaxis-sandbox: open-loop collective assembly by a phototaxic swarm."""

__version__ = "0.1.0"
