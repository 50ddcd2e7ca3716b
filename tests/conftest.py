import numpy as np
import pytest

from sandbox.model.config import Config


@pytest.fixture
def small_config() -> Config:
    """A quick world: few bodies, same arena and lights as the paper."""
    return Config(robots=30, boxes=60)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)


@pytest.fixture(autouse=True)
def serve_keeps_the_fork_server(monkeypatch) -> None:
    """The worker's fork server belongs to its tests: ``serve`` run in a test's process (its flags, its
    refusals, the App stood in for) neither starts nor stops it. serve stops it on its way out whatever
    ended it, a refused flag included: each such test cost the worker its warm fork server, and its next
    simulation process waited 1-3 s for a new one (five times in a run of the fast loop).
    ``tests/commands/test_serve_stop.py`` and ``tests/test_readme.py`` check serve's own start and stop, in
    processes of their own."""
    from sandbox.commands import serve as server

    monkeypatch.setattr(server, "start_fork_server", lambda: None)
    monkeypatch.setattr(server, "stop_fork_server", lambda: None)


def pytest_xdist_auto_num_workers(config) -> int:
    """``-n auto``: one worker per core, at most 4. More workers only add start-up (each imports
    the model and starts its own servers and browsers) and the tests are CPU-bound."""
    import os

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(4, cores))


def pytest_configure(config) -> None:
    """Compile the package's bytecode once, before any test starts a process. Where
    PYTHONDONTWRITEBYTECODE is set (as on our CI machines), nothing else writes it, and every
    process the tests start (simulation processes, ``phototaxis`` commands, servers) compiled all
    of ``sandbox`` again: a fifth of a server's start. Python reads bytecode whatever that variable
    says. Only the first process compiles (xdist's workers start after it); an up-to-date file is
    left alone.

    The test modules themselves are compiled by pytest, which rewrites their asserts first and keeps
    the result only where Python may write bytecode: with that variable set, every worker rewrote
    every test module at every run (2.5 s of each worker's 3.8 s collection). So this process lets
    pytest keep them; the processes the tests start still inherit the variable."""
    import compileall
    import os
    import sys
    from pathlib import Path

    sys.dont_write_bytecode = False
    if os.environ.get("PYTEST_XDIST_WORKER") is None:
        root = Path(__file__).resolve().parent.parent
        for folder in ("sandbox", "tests", "examples"):
            compileall.compile_dir(root / folder, quiet=1)


def names_slow(expression: str) -> bool:
    """Whether a ``-m`` expression names the ``slow`` marker (as a word: ``slow``, ``not slow``)."""
    import re

    return re.search(r"\bslow\b", expression) is not None


def leave_out_slow(config, items) -> None:
    """The fast loop: a ``-m`` expression that does not name ``slow`` leaves the slow tests out, so
    ``-m "not browser"`` runs what a change needs in a minute; with no ``-m`` (the full suite, CI)
    or one that names them (``-m slow``, ``-m "slow or not browser"``) they run."""
    expression = config.getoption("markexpr", "") or ""
    if not expression or names_slow(expression):
        return
    slow = [item for item in items if item.get_closest_marker("slow") is not None]
    if slow:
        config.hook.pytest_deselected(items=slow)
        items[:] = [item for item in items if item.get_closest_marker("slow") is None]


def pytest_collection_modifyitems(config, items) -> None:
    """Slow tests leave a run whose ``-m`` does not name them (``leave_out_slow``). The longest modules
    go first, the browser modules (tests/browser/test_browser_app.py is a third of the full suite) and then
    those with slow tests, so that the run does not end with one worker busy on a long module while the
    others wait. Each module runs whole in one worker, in order (--dist loadfile, pyproject.toml): a
    browser module's tests share one page and build on what the earlier ones left, and any module's
    server is started once. xdist keeps this order of modules (--no-loadscope-reorder): by default it
    hands them out by their number of tests, and the drawing module's 170 s started last."""
    leave_out_slow(config, items)

    def module(item) -> str:
        return item.nodeid.split("::", 1)[0]

    def having(marker: str) -> set[str]:
        return {module(item) for item in items if item.get_closest_marker(marker) is not None}

    browser, slow = having("browser"), having("slow")
    items.sort(key=lambda item: (module(item) not in browser, module(item) not in slow))  # stable: in order


@pytest.fixture(scope="module")
def browser(request):
    """One headless Chromium for a browser test module (see tests/browsing.py)."""
    from tests.browsing import CHROMIUM, TEST_CHROMIUM_ARGS, PatientBrowser, playwright_api

    with playwright_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=TEST_CHROMIUM_ARGS)
        yield PatientBrowser(browser, in_full=getattr(request.module, "DRAWN_IN_FULL", False))
        browser.close()
