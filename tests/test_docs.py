"""The documentation stays in step with the code and with itself: the parameter
table in docs/cli.md is the declaration's, MODEL.md's table of where the
profiles differ holds exactly the parameters whose two profile values differ,
with those values, and every relative link in README.md, MODEL.md and docs/
(and the reports under static/, and the design notes in docs/) reaches a file, and a heading
where it names one."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from sandbox.model.config import PAPER_TEXT, AUTHORS_CODE, markdown_table, params

ROOT = Path(__file__).resolve().parent.parent
CLI = ROOT / "docs" / "cli.md"
MODEL = ROOT / "MODEL.md"
PAGES = sorted({ROOT / "README.md", ROOT / "MODEL.md", *(ROOT / "docs").glob("*.md"), *(ROOT / "static").rglob("*.md")})
#: Pages linked to before they exist, each written on another branch: remove an entry once its page is merged.
WRITTEN_ELSEWHERE: set[str] = set()

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def test_parameter_table_matches_the_declaration():
    text = CLI.read_text(encoding="utf-8")
    table = text.split("<!-- params:begin -->")[1].split("<!-- params:end -->")[0].strip()
    assert table == markdown_table(), (
        "regenerate with: python -c 'from sandbox.model.config import markdown_table; print(markdown_table())'")


def section_table(text: str, heading: str) -> list[dict[str, str]]:
    """The first Markdown table under ``heading``, one {column header: cell} per row."""
    section = re.split(rf"^{re.escape(heading)}[ \t]*$", text, maxsplit=1, flags=re.M)
    assert len(section) == 2, f"no heading {heading!r}"
    lines = [line.strip() for line in section[1].splitlines()]
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    table = []
    for line in lines[start:]:
        if not line.startswith("|"):
            break
        table.append([cell.strip() for cell in line.strip("|").split("|")])
    header, rows = table[0], table[2:]  # table[1] is the | --- | rule
    return [dict(zip(header, row)) for row in rows]


def shown(value: object, unit: str) -> str:
    """A profile's value as MODEL.md's table writes it: in code type, then its unit."""
    text = f"`{value:g}`" if isinstance(value, float) else f"`{value}`"
    return f"{text} {unit}" if unit else text


def profile_differences() -> dict[str, tuple[str, str]]:
    """parameter -> its (paper-text, authors-code) values as shown, for every parameter they differ in."""
    return {p.name: (shown(p.value_in(PAPER_TEXT), p.unit), shown(p.value_in(AUTHORS_CODE), p.unit))
            for p in params() if p.value_in(PAPER_TEXT) != p.value_in(AUTHORS_CODE)}


def documented_differences() -> tuple[dict[str, tuple[str, str]], list[str]]:
    """parameter -> (paper-text, authors-code) cells of MODEL.md's 'Where the profiles differ' table,
    and the rows that do not name one parameter (or name one twice)."""
    rows = section_table(MODEL.read_text(encoding="utf-8"), "## Where the profiles differ")
    found, malformed = {}, []
    for row in rows:
        row = {header.split()[0]: cell for header, cell in row.items()}  # "`authors-code` (the program)"
        name = re.fullmatch(r"`(\w+)`", row["parameter"])
        if not name or name[1] in found:
            malformed.append(row["parameter"])
        else:
            found[name[1]] = (row["`paper-text`"], row["`authors-code`"])
    return found, malformed


def test_model_md_lists_every_profile_difference_with_the_codes_values():
    (documented, malformed), declared = documented_differences(), profile_differences()
    problems = [f"rows that are not one parameter in code type, once: {malformed}"] if malformed else []
    if missing := sorted(set(declared) - set(documented)):
        problems.append(f"parameters the profiles set differently, missing: {missing}")
    if extra := sorted(set(documented) - set(declared)):
        problems.append(f"parameters both profiles set alike, or no parameter: {extra}")
    problems += [f"{name} is {documented[name]} in the table, {declared[name]} in the code"
                 for name in sorted(set(declared) & set(documented)) if documented[name] != declared[name]]
    assert not problems, "MODEL.md's table of where the profiles differ is not sandbox/model/config.py's:\n" + \
        "\n".join(problems)


def test_the_profile_check_sees_a_difference_and_its_values():
    assert profile_differences()["sleep_time"] == ("`0` s", "`0.5` s")
    assert profile_differences()["light_angle"] == ("`elevation`", "`squared-offsets`")
    assert "iterations" not in profile_differences() and "robots" not in profile_differences()
    rows = section_table("## T\n\ntext\n\n| a | b |\n| --- | --- |\n| `x` | 1 m |\n\nafter\n| c |", "## T")
    assert rows == [{"a": "`x`", "b": "1 m"}]


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
