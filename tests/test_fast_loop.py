"""The fast loop's rule (tests/conftest.py, docs/testing.md): a ``-m`` expression that does not name
``slow`` leaves the slow tests out, so ``-m "not browser"`` is the minute's loop; the full suite (no
``-m``) and an expression that names them run them."""

from __future__ import annotations

from types import SimpleNamespace

from tests.conftest import leave_out_slow, names_slow


def test_an_expression_names_slow_as_a_word():
    assert names_slow("slow") and names_slow("not slow") and names_slow("slow or not browser")
    assert names_slow("(slow)and browser")
    assert not names_slow("not browser") and not names_slow("") and not names_slow("slowly or browser")


class Item(SimpleNamespace):
    def get_closest_marker(self, name: str):
        return name if name in self.marks else None


def kept(expression: str | None) -> list[str]:
    """The tests left after the rule, for ``-m expression`` (None: no ``-m``)."""
    items = [Item(name="unit", marks=()), Item(name="end-to-end", marks=("slow",)),
             Item(name="page", marks=("browser",))]
    deselected: list = []
    config = SimpleNamespace(getoption=lambda name, default=None: expression,
                             hook=SimpleNamespace(pytest_deselected=lambda items: deselected.extend(items)))
    leave_out_slow(config, items)
    assert {item.name for item in deselected} | {item.name for item in items} == {"unit", "end-to-end", "page"}
    return [item.name for item in items]


def test_the_fast_loop_leaves_the_slow_tests_out_and_the_full_suite_runs_them():
    assert kept(None) == kept("") == ["unit", "end-to-end", "page"]  # pytest -q: everything
    assert kept("not browser") == ["unit", "page"]  # the browser tests go by -m itself, after this
    assert kept("slow") == kept("slow or not browser") == ["unit", "end-to-end", "page"]  # (-m selects after)
