"""Who may use ``px4params gui``'s server (issue 36): the run's token, the Host allow-list
(DNS rebinding), foreign origins, the size of requests, a non-loopback bind, and stopping with
an open WebSocket. Spoken to with plain HTTP (``http.client``) and a real WebSocket client
(``websockets``), as an attacker's script or curl would; the browser's view is in
``tests/test_gui_browser_security.py``."""

from __future__ import annotations

import asyncio
import http.client
import json
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import websockets
from gui_server import CLI, Gui, env_for, gui_on_store, load_store, make_store
from px4params.cli.commands.gui import _is_loopback
from px4params.gui.admission import allowed_hosts

WRITE = json.dumps({"changes": [{"name": "INA238_INST", "value": 0}]})  # removes both INA238s


@pytest.fixture
def store_file(tmp_path: Path) -> Path:
    return make_store(tmp_path)


@pytest.fixture
def gui(store_file: Path) -> Iterator[Gui]:
    served = gui_on_store(store_file)
    yield served
    served.stop()


def _instances(store_file: Path) -> list[str]:
    return load_store(store_file).instances("INA238")


def request(
    gui: Gui,
    method: str,
    path: str,
    body: bytes | str | None = None,
    headers: dict[str, str] | None = None,
    *,
    chunked: bool = False,
    upgrade: bool = False,
) -> tuple[int, dict[str, str], bytes]:
    """One request to the page's server: status, headers (lower-case names) and body."""
    conn = http.client.HTTPConnection("127.0.0.1", gui.port, timeout=20)
    try:
        sent = {"Host": gui.host, **(headers or {})}
        data = body.encode() if isinstance(body, str) else body
        if chunked:
            conn.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
            for key, value in sent.items():
                conn.putheader(key, value)
            conn.putheader("Transfer-Encoding", "chunked")
            conn.endheaders()
            assert data is not None
            try:
                for i in range(0, len(data), 65536):
                    part = data[i : i + 65536]
                    conn.send(f"{len(part):x}\r\n".encode() + part + b"\r\n")
                conn.send(b"0\r\n\r\n")
            except (BrokenPipeError, ConnectionResetError):
                pass  # refused before the end: the answer is waiting
        else:
            conn.request(method, path, body=data, headers=sent)
        response = conn.getresponse()
        answer = {k.lower(): v for k, v in response.getheaders()}
        if upgrade and response.status == 101:
            return response.status, answer, b""  # the socket is open: close it unread
        return response.status, answer, response.read()
    finally:
        conn.close()


def authorized(gui: Gui, **extra: str) -> dict[str, str]:
    return {"Authorization": f"token {gui.token}", **extra}


def json_headers(gui: Gui, **extra: str) -> dict[str, str]:
    return authorized(gui, **{"Content-Type": "application/json", **extra})


def open_socket(gui: Gui, headers: dict[str, str]) -> str:
    """The WebSocket handshake of the page's ``/ws`` with ``headers`` (written by hand, so
    that Host can be any): "open" (101 Switching Protocols), or the refusal's status."""
    handshake = {
        "Upgrade": "websocket",
        "Connection": "Upgrade",
        "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==",
        "Sec-WebSocket-Version": "13",
        **headers,
    }
    status, answer, _ = request(gui, "GET", "/ws", headers=handshake, upgrade=True)
    if status == 101:
        # RFC 6455's example key and its accept value
        assert answer["sec-websocket-accept"] == "s3pPLMBiTxaQ9kYGzzhZRbK+xOo="
        return "open"
    return f"HTTP {status}"


# -- the token -------------------------------------------------------------------------------


@pytest.mark.parametrize("path", ["/", "/api/state", "/api/export", "/static/app.js"])
def test_nothing_without_the_token(gui: Gui, path: str) -> None:
    status, _, body = request(gui, "GET", path)
    assert status == 403
    assert json.loads(body)["error"] == (
        "no token: open the URL px4params gui printed at start (it ends in ?token=...), "
        "or send the header 'Authorization: token ...'"
    )


def test_no_write_and_no_socket_without_the_token(gui: Gui, store_file: Path) -> None:
    headers = {"Content-Type": "application/json", "Origin": f"http://{gui.host}"}
    status, _, _ = request(gui, "POST", "/api/write", WRITE, headers)
    assert status == 403
    assert open_socket(gui, {"Origin": f"http://{gui.host}"}) == "HTTP 403"
    wrong = {"Authorization": "token " + "0" * 48}
    assert request(gui, "GET", "/api/state", headers=wrong)[0] == 403
    assert open_socket(gui, wrong) == "HTTP 403"
    assert _instances(store_file) == ["INA238#0", "INA238#1"]


def test_the_token_url_sets_a_strict_cookie_and_leaves_the_address_bar(gui: Gui) -> None:
    status, headers, _ = request(gui, "GET", f"/?token={gui.token}")
    assert status == 303 and headers["location"] == "/"
    name, _, rest = headers["set-cookie"].partition("=")
    assert name == f"px4params-gui-{gui.port}"
    value, *attributes = [a.strip() for a in rest.split(";")]
    assert value == gui.token
    assert {"HttpOnly", "SameSite=Strict", "Path=/"} <= set(attributes)
    # the cookie alone lets the page in
    cookie = {"Cookie": f"{name}={value}"}
    assert request(gui, "GET", "/", headers=cookie)[0] == 200
    assert request(gui, "GET", "/api/state", headers=cookie)[0] == 200
    assert open_socket(gui, cookie) == "open"
    # another query is kept, a wrong token refused
    status, headers, _ = request(gui, "GET", f"/api/export?format=params&token={gui.token}")
    assert status == 303 and headers["location"] == "/api/export?format=params"
    status, _, body = request(gui, "GET", "/?token=" + "1" * 48)
    assert status == 403
    assert json.loads(body)["error"] == "wrong token: open the URL px4params gui printed at start"


def test_scripts_use_the_authorization_header(gui: Gui) -> None:
    status, _, body = request(gui, "GET", "/api/state", headers=authorized(gui))
    assert status == 200 and json.loads(body)["mode"] == "store"
    assert open_socket(gui, authorized(gui)) == "open"


# -- DNS rebinding: the Host header --------------------------------------------------------


def test_a_rebound_name_is_refused_everywhere(gui: Gui, store_file: Path) -> None:
    """A page on evil.example whose name now resolves to 127.0.0.1 sends its own Host and
    Origin; with or without the token (it has none, but a proxy might add it), nothing."""
    evil = f"evil.example:{gui.port}"
    rebound = {"Host": evil, "Origin": f"http://{evil}"}
    expected = (
        f"Host '{evil}' is not one this server answers to (expected "
        f"127.0.0.1:{gui.port}, [::1]:{gui.port}, localhost:{gui.port}; "
        "px4params gui --allow-host NAME adds one)"
    )
    for headers in (rebound, {**rebound, **authorized(gui)}):
        status, _, body = request(gui, "GET", "/api/state", headers=headers)
        assert (status, json.loads(body)["error"]) == (403, expected)
        status, _, _ = request(
            gui, "POST", "/api/write", WRITE, {**headers, "Content-Type": "application/json"}
        )
        assert status == 403
        assert request(gui, "GET", "/", headers=headers)[0] == 403
        assert request(gui, "GET", f"/?token={gui.token}", headers=headers)[0] == 403
        assert open_socket(gui, headers) == "HTTP 403"
    assert _instances(store_file) == ["INA238#0", "INA238#1"]


def test_loopback_names_and_allowed_hosts_are_answered(store_file: Path) -> None:
    served = Gui(
        ["--store", str(store_file), "--allow-host", "Laptop.Local"],
        env_for(store_file.parent),
        store_file.parent,
    )
    try:
        for host in ("localhost", "127.0.0.1", "[::1]", "laptop.local", "LAPTOP.local"):
            headers = authorized(served, Host=f"{host}:{served.port}")
            assert request(served, "GET", "/api/state", headers=headers)[0] == 200, host
        # a name without the port, or with another one, is not the same host
        for host in ("localhost", f"localhost:{served.port + 1}", "laptop.local"):
            assert (
                request(served, "GET", "/api/state", headers=authorized(served, Host=host))[0]
                == 403
            )
    finally:
        served.stop()


# -- what held and must keep holding -------------------------------------------------------


def test_foreign_origins_and_plain_text_are_refused_with_the_token(
    gui: Gui, store_file: Path
) -> None:
    for origin in ("http://evil.example", "null", f"http://127.0.0.1:{gui.port + 1}"):
        status, _, body = request(
            gui, "POST", "/api/write", WRITE, json_headers(gui, Origin=origin)
        )
        assert (status, json.loads(body)["error"]) == (
            403,
            f"requests from {origin} are not accepted",
        )
        assert request(gui, "GET", "/api/state", headers=authorized(gui, Origin=origin))[0] == 403
        assert open_socket(gui, authorized(gui, Origin=origin)) == "HTTP 403"
    for media_type in ("text/plain", "application/jsonx", "application/json-seq"):
        headers = authorized(gui, **{"Content-Type": media_type})
        assert request(gui, "POST", "/api/write", WRITE, headers)[0] == 415, media_type
    assert _instances(store_file) == ["INA238#0", "INA238#1"]
    for path in ("/static/../app.py", "/static/%2e%2e/app.py", "/static/..%2fapp.py"):
        assert request(gui, "GET", path, headers=authorized(gui))[0] == 404, path


# -- the size of requests ------------------------------------------------------------------


def test_json_nested_too_deep_is_a_400_not_a_traceback(gui: Gui, store_file: Path) -> None:
    # 100,000 nested arrays made json raise RecursionError: HTTP 500 and a traceback on the
    # server's stderr.
    deep = "[" * 100_000
    for path, shape in (("/api/write", "{'changes'"), ("/api/review", "{'filename'")):
        status, _, body = request(gui, "POST", path, deep, json_headers(gui))
        error = json.loads(body)["error"]
        assert (status, error.startswith(f"expected {shape}")) == (400, True), error
    assert _instances(store_file) == ["INA238#0", "INA238#1"]
    gui.stop()
    assert gui.proc.stderr is not None and "Traceback" not in gui.proc.stderr.read()


def test_a_review_of_an_odd_file_name_is_a_400_not_a_traceback(gui: Gui, store_file: Path) -> None:
    # A NUL or 300 characters in the name, '..', a lone surrogate in the text: HTTP 500.
    for body in (
        {"filename": "a\u0000b.json", "text": "{}"},
        {"filename": "a" * 300, "text": "{}"},
        {"filename": "..", "text": "param set X 1"},
        {"filename": "v.json", "text": "\ud800"},
    ):
        status, _, answer = request(gui, "POST", "/api/review", json.dumps(body), json_headers(gui))
        assert status == 400 and json.loads(answer)["error"], (body, status, answer)
    gui.stop()
    assert gui.proc.stderr is not None and "Traceback" not in gui.proc.stderr.read()


def test_oversize_bodies_are_refused_with_413(gui: Gui, store_file: Path) -> None:
    big = json.dumps({"changes": [{"name": "INA238_INST", "value": 0}], "pad": "x" * (2 << 20)})
    expected = f"request body of {len(big)} bytes refused: at most 1048576 bytes per request"
    status, _, body = request(gui, "POST", "/api/write", big, json_headers(gui))
    assert (status, json.loads(body)["error"]) == (413, expected)
    # without a declared length: counted as it arrives
    status, _, body = request(gui, "POST", "/api/write", big, json_headers(gui), chunked=True)
    assert (status, json.loads(body)["error"]) == (
        413,
        "request body refused: at most 1048576 bytes per request",
    )
    review = json.dumps({"filename": "big.params", "text": "#" * (2 << 20)})
    assert request(gui, "POST", "/api/review", review, json_headers(gui))[0] == 413
    assert _instances(store_file) == ["INA238#0", "INA238#1"]
    # the server still answers
    assert request(gui, "GET", "/api/state", headers=authorized(gui))[0] == 200


def test_too_many_changes_are_refused_with_413(gui: Gui, store_file: Path) -> None:
    changes = [{"name": "INA238_INST", "value": 0}] + [{"name": "INA238_1C", "value": 70}] * 256
    status, _, body = request(
        gui, "POST", "/api/write", json.dumps({"changes": changes}), json_headers(gui)
    )
    assert (status, json.loads(body)["error"]) == (
        413,
        "257 changes refused: at most 256 per request (write them in parts)",
    )
    assert _instances(store_file) == ["INA238#0", "INA238#1"]
    status, _, body = request(
        gui, "POST", "/api/write", json.dumps({"changes": changes[1:]}), json_headers(gui)
    )
    assert status == 200 and len(json.loads(body)["results"]) == 256
    _, _, state = request(gui, "GET", "/api/state", headers=authorized(gui))
    assert json.loads(state)["limits"] == {"changes": 256, "body": 1048576}


# -- stopping ------------------------------------------------------------------------------


def _stops_within(gui: Gui, sig: int, seconds: float) -> float:
    start = time.monotonic()
    gui.proc.send_signal(sig)
    try:
        gui.proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        gui.proc.kill()
        gui.proc.wait()
        raise AssertionError(f"signal {sig}: still running after 10 s") from None
    took = time.monotonic() - start
    assert took < seconds, f"signal {sig}: stopped after {took:.1f} s"
    return took


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_stops_the_page_with_a_socket_open(gui: Gui, sig: int) -> None:
    async def hold() -> Any:
        ws = await websockets.connect(
            f"ws://127.0.0.1:{gui.port}/ws", additional_headers=authorized(gui), open_timeout=10
        )
        await asyncio.sleep(0.3)
        return ws

    async def run() -> Any:
        ws = await hold()
        took = await asyncio.to_thread(_stops_within, gui, sig, 2.0)
        with pytest.raises(websockets.ConnectionClosed):
            await asyncio.wait_for(ws.recv(), 5)
        return took

    asyncio.run(run())


def test_sigterm_stops_the_page_after_a_socket_left(gui: Gui) -> None:
    assert open_socket(gui, authorized(gui)) == "open"  # opened and closed by the client
    _stops_within(gui, signal.SIGTERM, 2.0)


# -- listening -----------------------------------------------------------------------------


@pytest.mark.parametrize("where", ["0.0.0.0:0", "192.0.2.7:8080"])
def test_a_non_loopback_bind_needs_allow_remote(store_file: Path, where: str) -> None:
    result = subprocess.run(
        [*CLI, "gui", "--store", str(store_file), "--http", where],
        capture_output=True,
        text=True,
        env=env_for(store_file.parent),
        timeout=60,
    )
    assert result.returncode != 0 and result.stdout == ""
    assert result.stderr == (
        f"px4params: error: --http {where} is not a loopback address: other machines could "
        "change the vehicle's parameters; add --allow-remote to mean it (docs/security.md)\n"
    )


def test_allow_remote_lets_a_non_loopback_bind_through(store_file: Path) -> None:
    """With --allow-remote the address is tried (192.0.2.7 is a documentation address that no
    machine here has, so the bind itself fails: tests listen on loopback only)."""
    result = subprocess.run(
        [*CLI, "gui", "--store", str(store_file), "--http", "192.0.2.7:0", "--allow-remote"],
        capture_output=True,
        text=True,
        env=env_for(store_file.parent),
        timeout=60,
    )
    assert result.returncode != 0 and result.stdout == ""
    assert result.stderr.startswith("px4params: error: cannot listen on http 192.0.2.7:0: ")
    assert len(result.stderr.splitlines()) == 1


def test_the_hosts_answered() -> None:
    loopback = {"localhost:8080", "127.0.0.1:8080", "[::1]:8080"}
    assert allowed_hosts(8080, "127.0.0.1") == loopback
    assert allowed_hosts(8080, "0.0.0.0") == loopback  # a wildcard is no name
    assert allowed_hosts(8080, "192.168.1.5", ["Laptop", "proxy:9000", "[fe80::1]"]) == loopback | {
        "192.168.1.5:8080",
        "laptop:8080",
        "proxy:9000",
        "[fe80::1]:8080",
    }
    assert "localhost" in allowed_hosts(80, "127.0.0.1")  # browsers leave port 80 out


def test_a_signing_key_needs_a_vehicle(store_file: Path) -> None:
    result = subprocess.run(
        [*CLI, "gui", "--store", str(store_file), "--signing-key", "link.key"],
        capture_output=True,
        text=True,
        env=env_for(store_file.parent),
        timeout=60,
    )
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.splitlines()[-1] == (
        "px4params gui: error: --signing-key signs a vehicle's link: it needs --udp"
    )


@pytest.mark.parametrize(
    "host, loopback",
    [
        ("127.0.0.1", True),
        ("127.0.0.2", True),  # all of 127.0.0.0/8 is loopback
        ("localhost", True),
        ("0.0.0.0", False),
        ("192.0.2.7", False),
        ("10.0.0.1", False),
        ("no-such-host.invalid", False),
    ],
)
def test_which_addresses_are_loopback(host: str, loopback: bool) -> None:
    assert _is_loopback(host) is loopback


def test_no_framing_no_sniffing_no_referrer(gui: Gui) -> None:
    for path, headers in (("/", authorized(gui)), ("/api/state", {}), (f"/?token={gui.token}", {})):
        _, answer, _ = request(gui, "GET", path, headers=headers)
        assert answer["content-security-policy"] == "frame-ancestors 'none'", path
        assert answer["x-frame-options"] == "DENY"
        assert answer["x-content-type-options"] == "nosniff"
        assert answer["referrer-policy"] == "no-referrer"


def test_a_large_websocket_message_closes_the_socket(gui: Gui) -> None:
    async def flood() -> int | None:
        async with websockets.connect(
            f"ws://127.0.0.1:{gui.port}/ws", additional_headers=authorized(gui), open_timeout=10
        ) as ws:
            await ws.send("x" * 100_000)
            with pytest.raises(websockets.ConnectionClosed):
                await asyncio.wait_for(ws.recv(), 10)
            return ws.close_code

    assert asyncio.run(flood()) == 1009  # "message too big"
    assert request(gui, "GET", "/api/state", headers=authorized(gui))[0] == 200


# -- connections that send no request ------------------------------------------------------


def test_a_connection_without_a_whole_request_head_is_closed(gui: Gui) -> None:
    # uvicorn kept a connection that never sent a request, or sent its head a byte at a time,
    # open for as long as the peer liked: 300 such held 300 descriptors for minutes.
    import socket

    from px4params.gui.connections import REQUEST_SECONDS

    silent = socket.create_connection(("127.0.0.1", gui.port), timeout=5)
    partial = socket.create_connection(("127.0.0.1", gui.port), timeout=5)
    partial.sendall(b"GET /api/state HTTP/1.1\r\nHost: 127.0.0.1\r\n")  # no blank line: not whole
    started = time.monotonic()

    async def socket_meanwhile() -> str:
        # A WebSocket opened meanwhile outlives the deadline: its upgrade was a whole request.
        async with websockets.connect(
            f"ws://127.0.0.1:{gui.port}/ws", additional_headers=authorized(gui), open_timeout=10
        ) as ws:
            await asyncio.sleep(REQUEST_SECONDS + 2)
            await ws.ping()
            return "open"

    assert asyncio.run(socket_meanwhile()) == "open"
    for conn in (silent, partial):
        conn.settimeout(max(1.0, REQUEST_SECONDS + 5 - (time.monotonic() - started)))
        assert conn.recv(1024) == b""  # closed by the server, nothing answered
        conn.close()
    assert time.monotonic() - started < REQUEST_SECONDS + 5
    # A request made whole in time is answered.
    assert request(gui, "GET", "/api/state", headers=authorized(gui))[0] == 200


def _closed_while_trickling(sock: Any, data: bytes) -> bool:
    """Sends ``data`` a byte every 2 s (bounded: 2 s a byte); whether the server closed the
    connection meanwhile, answering nothing."""
    for byte in data:
        try:
            sock.sendall(bytes([byte]))
        except OSError:  # reset by the server
            return True
        sock.settimeout(2.0)
        try:
            if sock.recv(1024) == b"":
                return True
        except TimeoutError:
            continue
    return False


def test_a_request_trickling_its_body_is_closed(gui: Gui) -> None:
    # A whole head with the token and Content-Length 100000, then a body byte every 2 s: the
    # connection stayed open as long as the peer liked (helper-111).
    import socket

    from px4params.gui.connections import REQUEST_SECONDS

    sock = socket.create_connection(("127.0.0.1", gui.port), timeout=5)
    token = "".join(f"{k}: {v}\r\n" for k, v in authorized(gui).items())
    head = (
        f"POST /api/write HTTP/1.1\r\nHost: {gui.host}\r\n{token}"
        "Content-Type: application/json\r\nContent-Length: 100000\r\n\r\n"
    )
    started = time.monotonic()
    sock.sendall(head.encode())
    assert _closed_while_trickling(sock, b" " * int(REQUEST_SECONDS))
    assert time.monotonic() - started < REQUEST_SECONDS + 5
    sock.close()
    # A whole request in time is answered.
    assert request(gui, "GET", "/api/state", headers=authorized(gui))[0] == 200


def test_a_kept_alive_connection_trickling_its_next_head_is_closed(gui: Gui) -> None:
    # Each byte restarted uvicorn's 5 s idle timer: a byte every 2 s held the connection after
    # its first request for as long as the peer liked.
    import http.client

    from px4params.gui.connections import REQUEST_SECONDS

    conn = http.client.HTTPConnection("127.0.0.1", gui.port, timeout=10)
    conn.request("GET", "/api/state", headers={"Host": gui.host, **authorized(gui)})
    assert conn.getresponse().read()
    conn.request("GET", "/api/state", headers={"Host": gui.host, **authorized(gui)})
    second = conn.getresponse()  # kept alive: a second request in time is answered
    assert second.status == 200 and second.read()
    answered = time.monotonic()
    sock = conn.sock
    assert sock is not None
    head = b"GET /api/state HTTP/1.1\r\nHost: 127.0.0.1\r\n"
    assert _closed_while_trickling(sock, head[: int(REQUEST_SECONDS)])
    assert time.monotonic() - answered < REQUEST_SECONDS + 5
    conn.close()
