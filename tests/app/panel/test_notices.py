"""How long a notice stays (issue 56, item 1): long enough to read it, by hand-counted words."""

from __future__ import annotations

import pytest

from sandbox.app.panel.common import LONGEST, reading_seconds


def test_a_notice_stays_as_long_as_its_words_take_to_read():
    assert reading_seconds("Goal changed", "Using circle.") == 5.0  # 4 words: the shortest stay
    assert reading_seconds("Shape not used", "too few points.") == 5.0
    assert reading_seconds("Shape not used", "too few points.", 10.0) == 10.0  # a refusal: 10 s at least
    # 35 words: 35 / 3.5 = 10 s; 70 words: 20 s
    assert reading_seconds("t", " ".join(["word"] * 34)) == pytest.approx(10.0)
    assert reading_seconds("t", " ".join(["word"] * 69)) == pytest.approx(20.0)
    assert reading_seconds("t", " ".join(["word"] * 500)) == LONGEST == 30.0  # a pointer over it holds it longer
