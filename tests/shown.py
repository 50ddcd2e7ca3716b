"""What a markdown panel shows of its text: the backslash escapes that
:func:`sandbox.app.panel.plain.plain` puts before punctuation undone and its invisible word joiners
left out, so that a test can look for the words a page reads (``1-2``) in the markdown sent
(``1\\-2``)."""

from __future__ import annotations

import re

from sandbox.app.panel.plain import WORD_JOINER

_ESCAPE = re.compile(r"\\([!-/:-@\[-`{-~])")


def shown(markdown: str) -> str:
    return _ESCAPE.sub(r"\1", markdown).replace(WORD_JOINER, "")
