"""Text from outside shown as text: the one place a name, a file's content or an error quoting
either is made safe to write into the panel's markdown (issue 54, item 1). Pure functions; any thread.

How viser 1.1.1's page shows what the server sends it (read from its client, ``viser/client/src``):

- **Markdown** (``gui.add_markdown``, a handle's ``.content``): parsed as GitHub markdown, and raw
  HTML in it is rendered **unsanitised** (``Markdown.tsx``, ``rehypeRawDom.ts``). A name written
  there as it is runs script in every page (``<iframe srcdoc=...>``), restyles the page
  (``<style>``), or loads a remote picture (``![](https://...)``). Everything from outside goes
  through :func:`plain` before it is written there.
- **Text** (React strings): notification titles and bodies, control labels, hints, dropdown
  options, text fields' values, folder and tab labels, button labels, a modal's title, chart
  titles and series labels (uPlot sets ``textContent``), and the 3-D labels (``scene.add_label``:
  glyphs rasterised onto the canvas). Markup there is shown as its characters: nothing to escape,
  and escaping would show the backslashes.
- **HTML** (``gui.add_html``, icons): never given anything from outside (the sandbox uses neither
  for text).

``tests/app/panel/test_plain_text.py`` checks that every markdown writer under ``sandbox/app`` puts text from
outside through :func:`plain`; ``tests/browser/test_browser_names.py``, that hostile names arrive as text in
a real browser.
"""

from __future__ import annotations

import functools
import re
import string

#: Every ASCII punctuation character: CommonMark lets each be escaped with a backslash, which then
#: stands for the character itself. Escaping them all leaves no markdown or HTML construct a name
#: could start: no tag or comment (``<``), entity (``&``), link or image (``[``, ``!``, ``(``),
#: code (backtick), emphasis (``*``, ``_``, ``~``), heading, list, quote or rule at a line's start
#: (``#``, ``-``, ``+``, ``.``, ``>``), table cell (``|``).
_PUNCTUATION = re.compile("([" + re.escape(string.punctuation) + "])")
#: GitHub's autolinks are found in the text once escapes are undone (remark-gfm links
#: ``https://evil.example`` written ``https\:\/\/evil\.example``): an invisible word joiner after
#: each ``:`` and ``@`` and between ``www`` and its ``.`` breaks the patterns it looks for
#: (``https?://``, ``www.``, ``name@domain``). The page shows the same characters.
_AUTOLINK = re.compile(r"([:@]|(?i:www)(?=\.))")
WORD_JOINER = "\u2060"
#: Line breaks, tabs and other control characters (C0, DEL, C1, the Unicode line and paragraph
#: separators): a name is one line. A new line in it could start a block of its own (a table row
#: ends at one); runs of spaces become one (markdown shows one, and four start code).
_BREAKS = re.compile(r"[\s\x00-\x1f\x7f-\x9f\u2028\u2029]+")


def plain(text: object) -> str:
    """``text`` (a name, a file's words, an error message) to write into markdown, so that the page
    shows exactly its characters: every ASCII punctuation character backslash-escaped, line breaks
    and runs of white space as one space, a word joiner where an autolink would start. Use it on
    each piece from outside, never on markdown we wrote (its ``**`` would show), and never inside a
    code span (escapes are literal there)."""
    return _plain(str(text))


@functools.lru_cache(maxsize=1024)
def _plain(text: str) -> str:
    """:func:`plain` of a string, remembered: a panel writes the same names every frame (a class's
    desks, 30 pages at 10 frames a second)."""
    one_line = _BREAKS.sub(" ", text)
    return _PUNCTUATION.sub(r"\\\1", _AUTOLINK.sub(r"\1" + WORD_JOINER, one_line))
