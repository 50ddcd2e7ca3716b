"""The documentation stays in step with the code and with itself: the parameter
table in docs/cli.md is the declaration's, and every relative link in README.md,
MODEL.md and docs/ (and the design log and reports under static/) reaches a
file, and a heading where it names one."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from sandbox.model.config import markdown_table

ROOT = Path(__file__).resolve().parent.parent
CLI = ROOT / "docs" / "cli.md"
PAGES = sorted({ROOT / "README.md", ROOT / "MODEL.md", *(ROOT / "docs").glob("*.md"), *(ROOT / "static").rglob("*.md")})
#: Pages linked to before they exist, each written on another branch: remove an entry once its page is merged.
WRITTEN_ELSEWHERE: set[str] = set()

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def test_parameter_table_matches_the_declaration():
    text = CLI.read_text(encoding="utf-8")
    table = text.split("<!-- params:begin -->")[1].split("<!-- params:end -->")[0].strip()
    assert table == markdown_table(), (
        "regenerate with: python -c 'from sandbox.model.config import markdown_table; print(markdown_table())'")


def prose(text: str) -> str:
    """``text`` without fenced code blocks and inline code, where brackets are not links."""
    text = re.sub(r"^\s*```.*?^\s*```", "", text, flags=re.S | re.M)
    return re.sub(r"`[^`\n]*`", "", text)


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[`*_]|<[^>]+>", "", heading).strip().lower()
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link's text
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    found, counts = set(), {}
    text = re.sub(r"^\s*```.*?^\s*```", "", page.read_text(encoding="utf-8"), flags=re.S | re.M)
    for heading in re.findall(r"^#{1,6}\s+(.+?)\s*#*\s*$", text, flags=re.M):
        base = slug(heading)
        n = counts.get(base, 0)
        counts[base] = n + 1
        found.add(base if n == 0 else f"{base}-{n}")
    return found


def relative_links(page: Path) -> list[str]:
    return [t for t in LINK.findall(prose(page.read_text(encoding="utf-8")))
            if not re.match(r"^[a-z][a-z0-9+.-]*:", t, flags=re.I)]  # http:, https:, mailto: ...


def test_the_link_checker_sees_links_and_headings():
    assert slug("`phototaxis sweep` and `phototaxis report`") == "phototaxis-sweep-and-phototaxis-report"
    assert slug("The paper's evaluation in one command") == "the-papers-evaluation-in-one-command"
    assert slug("Results of the default profile (`authors-code`)") == "results-of-the-default-profile-authors-code"
    readme = relative_links(ROOT / "README.md")
    assert "static/sandbox.png" in readme and "docs/cli.md" in readme


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_every_relative_link_resolves(page):
    broken = []
    for target in relative_links(page):
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        name = file.relative_to(ROOT).as_posix() if file.is_relative_to(ROOT) else str(file)
        if name in WRITTEN_ELSEWHERE and not file.exists():
            continue
        if not file.exists():
            broken.append(f"{target}: no such file")
        elif anchor and file.suffix == ".md" and anchor not in anchors(file):
            broken.append(f"{target}: no heading #{anchor} in {name}")
    assert not broken, f"{page.relative_to(ROOT)}: " + "; ".join(broken)
