"""The one error a polygon file can cause, and the helpers that word it."""

from __future__ import annotations

import json
import math


class ShapeError(ValueError):
    """A polygon could not be used; the message is one line a user can act on."""


def fail(source: str, what: str, where: str | None = None) -> ShapeError:
    """A :class:`ShapeError` naming the source and, where it helps, the line or vertex."""
    prefix = f"{source}, {where}" if where else source
    return ShapeError(" ".join(f"{prefix}: {what}".split()))


def to_float(token, source: str, where: str) -> float:
    """A finite float from a file's token, or a :class:`ShapeError` saying why not."""
    if isinstance(token, bool) or not isinstance(token, (int, float, str)):
        raise fail(source, f"{json.dumps(token)[:40]} is not a number", where)
    try:
        value = float(token)
    except OverflowError:
        value = math.inf
    except ValueError:
        raise fail(source, f"{str(token)[:40]!r} is not a number", where) from None
    if not math.isfinite(value):
        raise fail(source, f"{str(token)[:40]!r} is not a finite number", where)
    return value
