"""The headless Chromium that tests open ``px4params gui``'s page in: Debian's package, driven
by Playwright, and every page watched for console errors. Importing this module skips the test
module that imports it where there is no Chromium."""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from playwright import sync_api

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None:
    pytest.skip(
        "no Chromium: scripts/setup.sh installs Debian's chromium with apt where it can",
        allow_module_level=True,
    )
TIMEOUT = 15_000  # ms, for anything the page waits on


@contextlib.contextmanager
def chromium(*args: str) -> Iterator[Any]:
    """Chromium, headless, with ``args`` on its command line besides ``--no-sandbox``."""
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=CHROMIUM, headless=True, args=["--no-sandbox", *args]
        )
        yield browser
        browser.close()


def open_page(browser: Any, width: int = 1400, height: int = 1000) -> tuple[Any, Any, list[str]]:
    """A new context and page of ``width`` x ``height``, and the list that collects the page's
    console errors and uncaught exceptions."""
    context = browser.new_context(viewport={"width": width, "height": height})
    page = context.new_page()
    page.set_default_timeout(TIMEOUT)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    return context, page, errors


@contextlib.contextmanager
def watched_page(browser: Any, width: int = 1400, height: int = 1000) -> Iterator[Any]:
    """:func:`open_page`'s page; when the block ends, its context is closed and any console
    error fails the test."""
    context, page, errors = open_page(browser, width, height)
    yield page
    context.close()
    assert errors == [], f"console errors: {errors}"


def shot(page: Any, name: str, tmp_path: Path, element: Any = None) -> None:
    """A screenshot of ``page`` (or ``element``) as ``name``: in ``$PX4PARAMS_SCREENSHOTS``
    when set (docs/images has them), else in ``tmp_path``."""
    folder = Path(os.environ.get("PX4PARAMS_SCREENSHOTS") or tmp_path)
    folder.mkdir(parents=True, exist_ok=True)
    (element or page).screenshot(path=str(folder / name))
