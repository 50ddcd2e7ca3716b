"""What every browser test module shares: ``pytestmark = BROWSER_MARKS`` marks it ``browser`` and
skips it without Debian's chromium or without Playwright. Its ``browser`` fixture (one headless
Chromium per module) is in tests/conftest.py."""

from __future__ import annotations

import pytest

from sandbox.app.live_bench import chromium_path

CHROMIUM = chromium_path()
BROWSER_MARKS = [pytest.mark.browser,
                 pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (apt-get install chromium)")]
playwright_api = pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install -e '.[test]')")
