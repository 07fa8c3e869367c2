"""``px4params gui`` rules that a wrong product would break without the rest of the suite
noticing (issue 40: bugs planted one at a time stayed green):

* the page's promise (docs/ground-stations.md: "An invalid entry is marked next to its field
  ... and never staged"), so a field whose last entry is invalid has nothing in the review,
  even when a valid value was typed before;
* a WebSocket opened by a page of another site (its ``Origin`` is not this server's) is
  refused, as the HTTP routes refuse such requests: another site may not watch the vehicle.

Real peers: Debian's Chromium driven by Playwright, and the ``websockets`` client, which sends
the ``Origin`` header a browser would.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest
from gui_server import env_for
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

REPO = Path(__file__).resolve().parents[1]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"
CLI = [sys.executable, "-m", "px4params"]
TIMEOUT = 15_000  # ms, for anything the page waits on


_env = env_for  # the environment of a test's own px4params (tests/gui_server.py)


@pytest.fixture
def offline_gui(tmp_path: Path) -> Iterator[str]:
    """``px4params gui --store`` on the example airframe's store: the URL it announces."""
    env = _env(tmp_path)
    subprocess.run(
        [*CLI, "run", str(AIRFRAME)],
        env=env,
        cwd=tmp_path,
        check=True,
        capture_output=True,
        timeout=120,
    )
    store = tmp_path / "vehicle.store"
    proc = subprocess.Popen(
        [*CLI, "gui", "--store", str(store), "--http", "127.0.0.1:0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=tmp_path,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        match = re.search(r"on (http://127\.0\.0\.1:\d+/\S*)", line)
        assert match, f"no URL announced: {line!r}"
        yield match[1]
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _socket_url(page_url: str) -> str:
    """The page's WebSocket (``/ws``), with whatever query the announced URL carries."""
    parts = urlsplit(page_url)
    return f"ws://{parts.netloc}/ws" + (f"?{parts.query}" if parts.query else "")


def test_a_websocket_from_a_foreign_origin_is_refused(offline_gui: str) -> None:
    url = _socket_url(offline_gui)
    own = f"http://{urlsplit(offline_gui).netloc}"
    # The page's own origin is let in (so what follows is refused for its Origin alone).
    with connect(url, origin=own, open_timeout=10) as ws:  # type: ignore[arg-type]
        assert ws.response is not None and ws.response.status_code == 101
    # Another site's: refused at the handshake (403), or closed at once with 1008 (policy
    # violation), never served.
    try:
        with connect(url, origin="http://evil.example", open_timeout=10) as ws:  # type: ignore[arg-type]
            try:
                ws.recv(timeout=5)
            except ConnectionClosed as closed:
                assert closed.rcvd is not None and closed.rcvd.code == 1008
            except TimeoutError:
                pytest.fail("a WebSocket from http://evil.example was accepted")
            else:
                pytest.fail("a WebSocket from http://evil.example was sent an event")
    except InvalidStatus as refused:
        assert refused.response.status_code == 403


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture
def page() -> Iterator[Any]:
    if CHROMIUM is None:
        pytest.skip("no Chromium: scripts/setup.sh installs Debian's chromium with apt")
    from playwright import sync_api

    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
        context = browser.new_context(viewport={"width": 1400, "height": 1000})
        page = context.new_page()
        page.set_default_timeout(TIMEOUT)
        errors: list[str] = []
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        yield page
        page.goto("about:blank")  # leave before the server stops (no reconnecting socket)
        context.close()
        browser.close()
        assert errors == [], f"console errors: {errors}"


def test_a_valid_then_invalid_entry_leaves_nothing_in_the_review(
    offline_gui: str, page: Any
) -> None:
    page.goto(offline_gui)
    page.wait_for_selector("body[data-ready=true]")
    # INA238#1's I2C address (uint7, 0..127; the airframe's 0x45): 70 is a change ...
    address = page.locator("input[data-name='INA238_1C']")
    address.fill("70")
    assert page.inner_text("#pending") == "1"
    # ... then 300 in the same field: invalid, so the 70 typed before must not be written.
    address.fill("300")
    error = page.locator(".instance[data-instance='INA238#1'] .error")
    assert error.inner_text() == "300: above the maximum 0x7F"  # the address, shown in hex
    assert page.inner_text("#pending") == "0"
    assert page.locator("#review-open").is_disabled()
    # A valid change elsewhere opens the review: only that one is in it.
    page.locator("input[data-name='INA238_0C']").fill("70")
    assert page.inner_text("#pending") == "1"
    page.click("#review-open")
    page.wait_for_selector("dialog#review[open]")
    names = page.locator("#review-table tbody tr").evaluate_all(
        "rows => rows.map(r => r.dataset.name)"
    )
    assert names == ["INA238_0C"]
