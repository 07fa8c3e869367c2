"""``px4params gui`` against attacks from a real browser (Debian's Chromium, headless, driven by
Playwright), in a browser that has opened the real page and so holds its cookie:

- a page served from another origin (a second server on 127.0.0.1, another port: same site,
  so even a SameSite=Strict cookie goes along) can neither read ``/api/state``, nor write, nor
  open the WebSocket;
- a page reached through a rebound name (``evil.example``, which Chromium resolves to
  127.0.0.1 by ``--host-resolver-rules``: DNS rebinding), whose requests to the page's port are
  same-origin for the browser, cannot either;
- the real page, opened with its token, works, and the token leaves the address bar.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest
from browser import TIMEOUT, chromium
from gui_server import Gui, gui_on_store, load_store, make_store

#: What an attacker's script tries against ``target`` (the page's server, from wherever the
#: script runs): read the state, write INA238_INST = 0 (removes every INA238) as JSON and as a
#: "simple" text/plain request, and open the WebSocket. Each outcome as text.
ATTACK = """async (target) => {
  const out = {};
  const body = JSON.stringify({ changes: [{ name: "INA238_INST", value: 0 }] });
  try {
    const r = await fetch(target + "api/state", { credentials: "include" });
    out.state = `${r.status} ${(await r.text()).slice(0, 300)}`;
  } catch (e) { out.state = `failed: ${e.name}`; }
  try {
    const r = await fetch(target + "api/write", {
      method: "POST", credentials: "include",
      headers: { "content-type": "application/json" }, body,
    });
    out.write = `${r.status}`;
  } catch (e) { out.write = `failed: ${e.name}`; }
  try {
    await fetch(target + "api/write", {
      method: "POST", mode: "no-cors", credentials: "include",
      headers: { "content-type": "text/plain" }, body,
    });
    out.plain = "sent";
  } catch (e) { out.plain = `failed: ${e.name}`; }
  out.socket = await new Promise((resolve) => {
    const ws = new WebSocket(target.replace("http", "ws") + "ws");
    ws.onopen = () => { ws.close(); resolve("open"); };
    ws.onerror = () => resolve("error");
    setTimeout(() => resolve("no answer"), 10000);
  });
  return out;
}"""


@pytest.fixture
def store_file(tmp_path: Path) -> Path:
    return make_store(tmp_path)


@pytest.fixture
def gui(store_file: Path) -> Iterator[Gui]:
    served = gui_on_store(store_file)
    yield served
    served.stop()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with chromium("--host-resolver-rules=MAP evil.example 127.0.0.1") as launched:
        yield launched


@pytest.fixture
def context(browser: Any) -> Iterator[Any]:
    context = browser.new_context()
    context.set_default_timeout(TIMEOUT)
    yield context
    context.close()


class _AttackerPage(BaseHTTPRequestHandler):
    def do_GET(self) -> None:
        body = b"<!doctype html><title>cute cats</title><p>nothing to see"
        self.send_response(200)
        self.send_header("content-type", "text/html")
        self.send_header("content-length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args: Any) -> None:
        pass


@contextlib.contextmanager
def _attacker_server() -> Iterator[int]:
    """Another web server on 127.0.0.1 (another port: another origin, the same site); its
    port while it runs."""
    server = ThreadingHTTPServer(("127.0.0.1", 0), _AttackerPage)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield int(server.server_address[1])
    finally:
        server.shutdown()
        server.server_close()


@pytest.fixture
def attacker() -> Iterator[str]:
    with _attacker_server() as port:
        yield f"http://127.0.0.1:{port}/"


def _instances(store_file: Path) -> list[str]:
    return load_store(store_file).instances("INA238")


def _open_real_page(context: Any, gui: Gui) -> Any:
    page = context.new_page()
    page.goto(gui.url)
    page.wait_for_selector("body[data-ready=true]")
    return page


def test_the_real_page_works_with_its_token(context: Any, gui: Gui, store_file: Path) -> None:
    errors: list[str] = []
    page = context.new_page()
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto(gui.url)
    page.wait_for_selector("body[data-ready=true]")
    assert page.url == gui.base  # the token left the address bar (and the history)
    assert page.evaluate("document.cookie") == ""  # HttpOnly: no script reads it
    cookies = {c["name"]: c for c in context.cookies()}
    cookie = cookies[f"px4params-gui-{gui.port}"]
    assert (cookie["value"], cookie["httpOnly"], cookie["sameSite"]) == (gui.token, True, "Strict")
    page.click(".instance[data-instance='INA238#1'] button.remove")
    page.click("#review-open")
    page.click("#review-write")
    page.wait_for_function("document.querySelector('#review-table .result').textContent !== ''")
    assert page.locator("#review-table .result").inner_text() == "acknowledged: 1"
    assert _instances(store_file) == ["INA238#0"]
    opened = page.evaluate(
        """() => new Promise((resolve) => {
          const ws = new WebSocket(`ws://${location.host}/ws`);
          ws.onopen = () => { ws.close(); resolve("open"); };
          ws.onerror = () => resolve("error");
        })"""
    )
    assert opened == "open"
    assert errors == []


def test_a_page_without_the_token_is_refused(context: Any, gui: Gui) -> None:
    page = context.new_page()
    response = page.goto(gui.base)
    assert response.status == 403
    assert "no token: open the URL px4params gui printed at start" in page.content()


def test_another_origin_can_neither_read_write_nor_watch(
    context: Any, gui: Gui, attacker: str, store_file: Path
) -> None:
    _open_real_page(context, gui)  # the user's browser holds the page's cookie
    evil = context.new_page()
    evil.goto(attacker)
    out = evil.evaluate(ATTACK, gui.base)
    assert out["state"] == "failed: TypeError"  # no CORS: the browser hides the answer
    assert out["write"] == "failed: TypeError"  # the preflight is refused
    assert out["plain"] == "sent"  # no-cors sends blindly; the server refuses it (below)
    assert out["socket"] == "error"
    assert _instances(store_file) == ["INA238#0", "INA238#1"]


def test_a_rebound_name_can_neither_read_write_nor_watch(context: Any, store_file: Path) -> None:
    """DNS rebinding: the user opens http://evil.example:PORT/, served by the attacker's
    server; then the name points at 127.0.0.1, where the page's server listens on the same
    port (here: the attacker's server stops and the page's starts on its port, Chromium
    resolving evil.example to 127.0.0.1 throughout). For the browser, the attacker's script
    now talks to its own origin, and carries no cookie (another site)."""
    real = context.new_page()
    with _attacker_server() as port:
        evil_origin = f"http://evil.example:{port}/"
        evil = context.new_page()
        evil.goto(evil_origin)
        assert evil.title() == "cute cats"
    gui = gui_on_store(store_file, port)
    try:
        real.goto(gui.url)  # the user's own page is open too, with its cookie
        real.wait_for_selector("body[data-ready=true]")
        out = evil.evaluate(ATTACK, evil_origin)
        assert out["state"].startswith(
            f'403 {{"error": "Host \'evil.example:{port}\' is not one this server answers to'
        )
        assert out["write"] == "403"
        assert out["socket"] == "error"
        assert _instances(store_file) == ["INA238#0", "INA238#1"]
        real.close()
    finally:
        gui.stop()


def test_another_page_cannot_frame_the_page(context: Any, gui: Gui, attacker: str) -> None:
    """Clickjacking: a page of another port (the same site, so the cookie would go along)
    puts the real page in a frame to trick clicks on 'Write selected': the browser refuses."""
    _open_real_page(context, gui)
    evil = context.new_page()
    evil.goto(attacker)
    evil.evaluate(
        """(url) => new Promise((resolve) => {
          const frame = document.createElement("iframe");
          frame.src = url;
          frame.onload = () => resolve();
          document.body.append(frame);
          setTimeout(resolve, 5000);
        })""",
        gui.base,
    )
    (framed,) = [f for f in evil.frames if f != evil.main_frame]
    assert "Device manifest" not in framed.content()
    assert framed.query_selector("#review-write") is None


def test_the_page_explains_a_413(context: Any, gui: Gui, tmp_path: Path) -> None:
    page = _open_real_page(context, gui)
    big = tmp_path / "huge.params"
    big.write_text("# " + "x" * (1 << 20) + "\n")
    page.set_input_files("#load", str(big))
    page.wait_for_selector("dialog#review[open]")
    assert page.inner_text("#review-notes").startswith("request body of ")
    assert page.inner_text("#review-notes").endswith(
        "bytes refused: at most 1048576 bytes per request"
    )
