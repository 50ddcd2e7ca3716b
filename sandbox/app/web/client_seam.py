"""The page scripts' seam onto viser's client (any thread: a script is read once, then filled in; the check
runs in the tests): each script as it is sent, the rows of its table, and their check against the client
the installed viser serves.

The scripts (``sandbox/app/web/page/*.js``, package data) do what viser's page lacks, inside it: they
find its Mantine markup, listen where it listens, wrap what it calls, wait as long as it animates. None of
that is an API, and viser builds its client anew in each release. So each script has a table beside it,
in the module that sends it (``CLIENT`` in :mod:`.page_keys`, :mod:`.page_layout`, :mod:`.page_sends`,
:mod:`.page_touch`, :mod:`.pacing`): one :class:`Relies` per thing it relies on, what the script writes,
why, and what in viser's client bundle shows that it is still there. :func:`missing` reads the bundle
(viser ships its client built: ``viser/client/build/index.html``, the scripts and styles compressed in
it) and names each row it does not find; ``tests/app/web/test_client_seam.py`` fails on any, so a new viser fails
a test, not a classroom. The check is the tests', not the start's: a row missing costs one thing on the
page (a notice that stays, a drawer that starts open), not the server, and every start would pay for
reading the bundle.

What a script takes from viser's client is either markup, found wherever the script writes it
(:func:`relied_on`: Mantine's classes, attribute and class selectors, what it asks the DOM for, the
prototypes and globals it wraps), or a value in the script's one ``VISER = {...}`` object (a text, a
key, a breakpoint, a time). The tests require each of them to be a row, and each row to be one of them.
"""

from __future__ import annotations

import functools
import json
import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import viser

# How missing() finds a row in the bundle.
TEXT = "text"        # each of ``found`` (default: what the script writes) is in the bundle, as written
PATTERN = "pattern"  # each of ``found`` (a regular expression; a ` in it stands for any quote) matches it
MANTINE = "mantine"  # the Mantine class the script writes (.mantine-<Component>-<part>) is one viser's
#                      Mantine makes: the component is in the bundle, its classes have the part, and its
#                      class names carry the prefix "mantine" (Mantine's default, static classes on);
#                      and each of ``found`` matches, as for PATTERN

#: Where a script's settings go: ``$name``, filled in with the setting's JSON.
SETTING = re.compile(r"\$([A-Za-z_]\w*)")


@dataclass(frozen=True)
class Relies:
    """One thing a page script relies on in viser's client: ``uses``, as the script writes it (a selector,
    a name, a text, a number), why, and how :func:`missing` finds it in viser's client (``found``: texts
    or patterns; ``values``: the numbers a PATTERN's first group captures, across all its matches, must
    be exactly these)."""

    uses: str
    why: str
    how: str = PATTERN
    found: tuple[str, ...] = ()
    values: tuple[int, ...] = ()


#: What every script relies on: how a page runs the scripts the server sends it.
RUNS_SCRIPTS = Relies(
    "RunJavascriptMessage", "the server sends each script as viser's RunJavascriptMessage, which the page runs "
    "with Function(source)(): in its global scope (window), at once, every time it comes",
    found=(r"case`RunJavascriptMessage`:Function\([\w$]+\.source\)\(\)",))


# ---------------------------------------------------------------- scripts
def script(name: str, **settings: object) -> str:
    """The page script ``page/<name>`` as a page is sent it: each ``$setting`` replaced by its JSON (every
    one given, and no other)."""
    source = _source(name)
    wanted = set(SETTING.findall(source))
    if wanted != set(settings):
        raise ValueError(f"page/{name} takes the settings {sorted(wanted)}, not {sorted(settings)}")
    return SETTING.sub(lambda m: json.dumps(settings[m.group(1)]), source)


@functools.cache
def _source(name: str) -> str:
    return resources.files("sandbox.app.web").joinpath("page", name).read_text(encoding="utf-8")


# ----------------------------------------------------- what a script uses
#: A string literal (its quote in group 1), or a comment: what the rest of a script's text is made of.
_LITERAL_OR_COMMENT = re.compile(r"""//[^\n]*|/\*.*?\*/|(["'`])((?:\\.|(?!\1)[^\\])*)\1""", re.S)
_MANTINE_CLASS = re.compile(r"(?<![\w-])\.?mantine-[A-Za-z]+-[A-Za-z]+")
_ATTRIBUTE = re.compile(r"""\[\s*[\w-]+\s*(?:[~|^$*]?=\s*(?:"[^"]*"|'[^']*'|[^\]\s]+)\s*)?\]""")
_CLASS_SELECTOR = re.compile(r"(?<![\w.-])\.[A-Za-z_][\w-]*")
_DATA_NAME = re.compile(r"(?<![\w-])data-[a-z][\w-]*")
_MESSAGE = re.compile(r"\b[A-Z]\w*Message\b")
_DOM_QUERY = re.compile(r"""\.(?:querySelector|querySelectorAll|closest|matches)\(\s*"""
                        r"""(["'`])((?:\\.|(?!\1)[^\\])*)\1\s*\)""")
_PROTOTYPE = re.compile(r"\b[A-Z]\w*\.prototype\b")
_WRAPPED_GLOBAL = re.compile(r"\bwindow\.(?!__phototaxis)\w+(?=\s*=[^=])")
_NUMBER = re.compile(r"(?<![\w.$])-?\d+(?:\.\d+)?(?![\w.])")


def relied_on(source: str) -> set[str]:
    """What ``source`` (a script as sent) takes from viser's client, each as a row of its table writes
    it: the markup in its strings (Mantine's classes, attribute and class selectors, ``data-`` names,
    message names), each selector it asks the DOM for whole, the prototypes and the globals it wraps, and
    each text or number in its ``VISER = {...}`` (a text that holds markup counts as its markup)."""
    found: set[str] = set()
    for text in _literals(source):
        found |= _markup(text)
    found |= {_quoted(m.group(2)) for m in _DOM_QUERY.finditer(source)}
    code = _code(source)
    found |= set(_PROTOTYPE.findall(code)) | set(_WRAPPED_GLOBAL.findall(code))
    return found | _visers_values(source)


def uncovered(source: str, rows: tuple[Relies, ...]) -> list[str]:
    """What ``source`` takes from viser's client that no row of ``rows`` writes (a row covers what it
    writes and the markup in it: ``div[style*="x"]`` covers ``[style*="x"]``)."""
    covered = {part for row in rows for part in {row.uses, *_markup(row.uses)}}
    return sorted(relied_on(source) - covered)


def stale(source: str, rows: tuple[Relies, ...]) -> list[str]:
    """The rows of ``rows`` for nothing ``source`` takes from viser's client."""
    uses = relied_on(source)
    return [row.uses for row in rows if row.uses not in uses]


def _literals(source: str) -> list[str]:
    return [_unescaped(m.group(2)) for m in _LITERAL_OR_COMMENT.finditer(source) if m.group(1)]


def _code(source: str) -> str:
    """``source`` with its comments and the insides of its strings blanked (each character a space, so
    that a place in it is the same place in ``source``)."""
    return _LITERAL_OR_COMMENT.sub(lambda m: _blank(m.group(0), keep_ends=bool(m.group(1))), source)


def _blank(text: str, keep_ends: bool) -> str:
    return text[0] + " " * (len(text) - 2) + text[-1] if keep_ends else " " * len(text)


def _unescaped(text: str) -> str:
    return re.sub(r"\\(.)", r"\1", text)


def _quoted(selector: str) -> str:
    """A selector as rows write it: double quotes in attribute selectors."""
    return _unescaped(selector).replace("'", '"')


def _markup(text: str) -> set[str]:
    attributes = {_quoted(a) for a in _ATTRIBUTE.findall(text)}
    rest = _ATTRIBUTE.sub(" ", text)
    classes = {c if c.startswith(".") else "." + c for c in _MANTINE_CLASS.findall(rest)}
    classes |= set(_CLASS_SELECTOR.findall(rest))
    return attributes | classes | set(_DATA_NAME.findall(rest)) | set(_MESSAGE.findall(rest))


def _visers_values(source: str) -> set[str]:
    """Each text and number in the script's ``const VISER = {...}`` (none if it has none)."""
    start = source.find("const VISER = {")
    if start < 0:
        return set()
    block = _balanced(source, source.index("{", start))
    values = set()
    for text in _literals(block):
        values |= _markup(text) or {text}
    values |= set(_NUMBER.findall(_code(block)))
    return values


def _balanced(source: str, opening: int) -> str:
    """The braces' text from ``source[opening]`` ("{") to its match, strings skipped."""
    depth, position = 0, opening
    code = _code(source)
    for position in range(opening, len(code)):
        depth += {"{": 1, "}": -1}.get(code[position], 0)
        if depth == 0:
            break
    return source[opening:position + 1]


# ------------------------------------------------------- viser's client
#: Where viser keeps its built client: one page, its scripts and styles compressed into an attribute.
CLIENT_PAGE = Path(viser.__file__).resolve().parent / "client" / "build" / "index.html"
#: The bundle's payload: base-88 text of one zstd frame (styles, then scripts), and their sizes in bytes.
_PAYLOAD = re.compile(r'<script data-p="([^"]*)" data-ss="(\d+)" data-cs="(\d+)">')
#: viser's base-88 alphabet (its vite-plugin-compress-html.mts): printable ASCII but " & < > ' `.
_BASE88 = "".join(chr(c) for c in range(0x21, 0x7F) if chr(c) not in "\"&<>'`")


@functools.cache
def bundle(page: Path = CLIENT_PAGE) -> str:
    """The scripts and styles of viser's client, as its page unpacks them (the page's own text if it
    carries them unpacked)."""
    html = page.read_text(encoding="utf-8")
    payload = _PAYLOAD.search(html)
    if payload is None:
        return html
    import zstandard  # (viser's own dependency: its server sends zstd too)

    packed = _from_base88(payload.group(1))
    size = int(payload.group(2)) + int(payload.group(3))
    return zstandard.ZstdDecompressor().decompress(packed, max_output_size=size).decode("utf-8")


def _from_base88(text: str) -> bytes:
    """viser's base-88: 5 characters for 4 bytes (a last group of k characters: k - 1 bytes)."""
    import numpy as np

    digit = np.full(128, 255, np.uint64)
    digit[[ord(c) for c in _BASE88]] = np.arange(88, dtype=np.uint64)
    codes = digit[np.frombuffer(text.encode("ascii"), np.uint8)]
    whole, rest = divmod(len(codes), 5)
    groups = codes[:whole * 5].reshape(whole, 5)
    values = np.zeros(whole, np.uint64)
    for column in range(5):
        values = values * np.uint64(88) + groups[:, column]
    out = values.astype(">u4").tobytes()
    if rest:
        value = 0
        for code in codes[whole * 5:]:
            value = value * 88 + int(code)
        out += value.to_bytes(rest - 1, "big")
    return out


# ------------------------------------------------------------------ check
def missing(rows: tuple[Relies, ...], client: str | None = None) -> list[str]:
    """The rows of ``rows`` that viser's client (``client``: its bundle's text; the installed viser's by
    default) does not show, each as ``what the script writes: what is not there``."""
    client = bundle() if client is None else client
    return [f"{row.uses}: {absent}" for row in rows for absent in _absent(row, client)]


def _absent(row: Relies, client: str) -> list[str]:
    if row.how == TEXT:
        return [f"no {text!r}" for text in row.found or (row.uses,) if text not in client]
    absent = _absent_mantine(row.uses, client) if row.how == MANTINE else []
    absent += [f"nothing matches {pattern!r}" for pattern in row.found if not _search(pattern, client)]
    if row.values and not absent:
        seen = {int(m.group(1)) for pattern in row.found for m in re.finditer(regex(pattern), client)}
        if seen != set(row.values):
            absent.append(f"the numbers are {sorted(seen)}, not {sorted(row.values)}")
    return absent


def regex(pattern: str) -> str:
    """A row's pattern as a regular expression: each ` in it stands for any of JavaScript's quotes."""
    return pattern.replace("`", "[`\"']")


def _search(pattern: str, client: str) -> bool:
    return re.search(regex(pattern), client) is not None


def _absent_mantine(uses: str, client: str) -> list[str]:
    absent = [f"no Mantine default {setting}" for setting, pattern in
              (("classNamesPrefix mantine", r"classNamesPrefix:[\w$]+=`mantine`"),
               ("withStaticClasses", r"withStaticClasses:[\w$]+=!0")) if not _search(pattern, client)]
    for name in _MANTINE_CLASS.findall(uses):
        component, part = name.lstrip(".").split("-")[1:]
        parts = _mantine_parts(component, client)
        if parts is None:
            absent.append(f"no Mantine component {component}")
        elif part not in parts:
            absent.append(f"{component}'s classes have no {part}")
    return absent


def _mantine_parts(component: str, client: str) -> set[str] | None:
    """The parts (root, closeButton, ...) of the classes of Mantine's ``component`` in the bundle, or None
    if it is not there: ``X.displayName="@mantine/core/<component>"``, then ``X.classes=`` an object of
    them, the name of one, or several spread."""
    named = re.search(r"\.displayName=[`\"']@mantine/core/" + component + r"[`\"']", client)
    if named is None:
        return None
    return _class_parts(_name_before(client, named.start()), client, depth=0)


def _class_parts(holder: str, client: str, depth: int) -> set[str]:
    value = _assigned(client, holder + ".classes=", r"\{[^{}]*\}|[\w$]+")
    if value is None or depth > 3:
        return set()
    if not value.startswith("{"):
        value = _assigned(client, value + "=", r"\{[^{}]*\}") or "{}"
    parts = set(re.findall(r"[{,]([A-Za-z]\w*):", value))
    for spread in re.findall(r"\.\.\.([\w$]+)\.classes", value):
        parts |= _class_parts(spread, client, depth + 1)
    return parts


def _assigned(client: str, target: str, value: str) -> str | None:
    """What the bundle assigns to ``target`` (``name=`` or ``name.field=``, not a longer name's), if it
    matches ``value`` (a pattern). (Found by its text first: a pattern that starts with a name's
    characters would try every place in two megabytes.)"""
    for found in re.finditer(re.escape(target), client):
        if found.start() == 0 or not re.match(r"[\w$.]", client[found.start() - 1]):
            match = re.compile(value).match(client, found.end())
            if match:
                return match.group(0)
    return None


def _name_before(client: str, end: int) -> str:
    """The name (a minified one) that ends at ``end``."""
    return re.search(r"[\w$]+$", client[max(0, end - 64):end]).group(0)
