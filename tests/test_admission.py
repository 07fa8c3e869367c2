"""The page server's admission layer (``px4params.gui.admission``), spoken to in-process over
the ASGI protocol (https://asgi.readthedocs.io/en/latest/specs/www.html): each request is a
scope, the body arrives as ``http.request`` messages, a WebSocket's first message is
``websocket.connect``. The rules are those of docs/security.md and the module's docstring: the
Host allow-list (DNS rebinding), no foreign Origin, the run's token (query once, then the
cookie, or ``Authorization: token``), the body's size, and the headers every answer carries.
``tests/test_gui_security.py`` checks the same through the real server with plain HTTP."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest
from px4params.gui.admission import (
    MAX_BODY,
    MAX_CHANGES,
    SECURITY_HEADERS,
    Admission,
    allowed_hosts,
    new_token,
)

TOKEN = "a1" * 24  # 48 hex digits, as new_token()'s
HOST = "localhost:8765"
COOKIE = "px4params-gui-8765"


class Route:
    """The wrapped application: records what reached it (the scope and the whole body it
    read) and answers 200 with a header of its own."""

    def __init__(self) -> None:
        self.calls: list[tuple[dict[str, Any], bytes]] = []
        self.after_body: list[dict[str, Any]] = []

    async def __call__(self, scope: dict[str, Any], receive: Any, send: Any) -> None:
        body = b""
        if scope["type"] == "http":
            while True:  # as Starlette's Request.stream reads it
                message = await receive()
                if message["type"] == "http.disconnect":
                    break
                assert message["type"] == "http.request", message
                body += message.get("body", b"")
                if not message.get("more_body", False):
                    break
            if scope.get("wait_for_disconnect"):
                self.after_body.append(await receive())
        self.calls.append((scope, body))
        if scope["type"] == "lifespan":
            return
        if scope["type"] == "websocket":
            await receive()
            await send({"type": "websocket.accept"})
            return
        await send(
            {"type": "http.response.start", "status": 200, "headers": [(b"x-route", b"yes")]}
        )
        await send({"type": "http.response.body", "body": b"ok"})


def admission(route: Route, **kwargs: Any) -> Admission:
    return Admission(
        route,
        token=kwargs.pop("token", TOKEN),
        hosts=kwargs.pop("hosts", [HOST]),
        cookie=COOKIE,
        **kwargs,
    )


def call(
    app: Admission,
    *,
    path: str = "/api/state",
    query: str = "",
    method: str = "GET",
    headers: list[tuple[str, str]] | None = None,
    body: list[bytes] | None = None,
    kind: str = "http",
    root_path: str = "",
    disconnect: bool = False,
    wait_for_disconnect: bool = False,
) -> list[dict[str, Any]]:
    """One request through ``app``: the messages it sent back. ``headers`` default to the Host
    this server answers to; ``body`` is the chunks the client sends (each its own message);
    ``disconnect``: the client leaves after them."""
    scope: dict[str, Any] = {
        "type": kind,
        "path": path,
        "root_path": root_path,
        "query_string": query.encode("latin-1"),
        "headers": [
            (k.lower().encode("latin-1"), v.encode("latin-1"))
            for k, v in (headers if headers is not None else [("Host", HOST)])
        ],
    }
    if kind == "http":
        scope["method"] = method
    if wait_for_disconnect:
        scope["wait_for_disconnect"] = True
    incoming: list[dict[str, Any]] = []
    if kind == "websocket":
        incoming.append({"type": "websocket.connect"})
    else:
        chunks = body if body is not None else [b""]
        for i, chunk in enumerate(chunks):
            incoming.append(
                {"type": "http.request", "body": chunk, "more_body": i < len(chunks) - 1}
            )
        if disconnect:
            incoming.clear()  # gone before sending a body: only the disconnect follows
    incoming.append({"type": "http.disconnect"})
    sent: list[dict[str, Any]] = []

    async def receive() -> dict[str, Any]:
        assert incoming, "read past the client's last message"
        return incoming.pop(0)

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)

    asyncio.run(app(scope, receive, send))
    return sent


def status_of(sent: list[dict[str, Any]]) -> int:
    """The status of an HTTP answer: ``http.response.start``, then the body's messages."""
    assert sent[0]["type"] == "http.response.start"
    assert all(m["type"] == "http.response.body" for m in sent[1:]) and len(sent) > 1
    return sent[0]["status"]


def headers_of(sent: list[dict[str, Any]]) -> dict[str, str]:
    return {k.decode(): v.decode() for k, v in sent[0]["headers"]}


def error_of(sent: list[dict[str, Any]]) -> str:
    status_of(sent)
    assert headers_of(sent)["content-type"] == "application/json"
    body = sent[1]["body"]
    assert headers_of(sent)["content-length"] == str(len(body))
    return json.loads(body)["error"]


def authorized(*extra: tuple[str, str]) -> list[tuple[str, str]]:
    return [("Host", HOST), ("Authorization", f"token {TOKEN}"), *extra]


NO_TOKEN = (
    "no token: open the URL px4params gui printed at start (it ends in ?token=...), "
    "or send the header 'Authorization: token ...'"
)
WRONG_TOKEN = "wrong token: open the URL px4params gui printed at start"


# -- the Host allow-list -------------------------------------------------------------------


def test_the_hosts_of_an_address_bound_by_name_or_ipv6() -> None:
    loopback = {"localhost:8080", "127.0.0.1:8080", "[::1]:8080"}
    # an IPv6 address is written in brackets in a Host header (RFC 3986 IP-literal)
    assert allowed_hosts(8080, "fe80::7") == loopback | {"[fe80::7]:8080"}
    assert allowed_hosts(8080, "Pilot-PC") == loopback | {"pilot-pc:8080"}
    # the wildcards of both families, and none given, name no host
    for wildcard in ("0.0.0.0", "::", ""):
        assert allowed_hosts(8080, wildcard) == loopback, wildcard


def test_allow_host_names_with_and_without_a_port() -> None:
    hosts = allowed_hosts(8080, "127.0.0.1", [" Proxy.Example:443 ", "[fe80::1]:9000", "[fe80::2]"])
    assert {"proxy.example:443", "[fe80::1]:9000", "[fe80::2]:8080"} <= hosts
    # an IPv6 literal's colons are not a port
    assert "[fe80::2]" not in hosts and "[fe80::1]:9000:8080" not in hosts
    assert "proxy.example:443:8080" not in hosts


def test_port_80_is_also_answered_without_the_port() -> None:
    assert allowed_hosts(80, "127.0.0.1", ["laptop"]) == {
        "localhost:80",
        "127.0.0.1:80",
        "[::1]:80",
        "laptop:80",
        "localhost",
        "127.0.0.1",
        "[::1]",
        "laptop",
    }
    assert "localhost" not in allowed_hosts(8080, "127.0.0.1")


def test_a_host_not_answered_is_refused_with_the_list() -> None:
    route = Route()
    app = admission(route, hosts=["LocalHost:8765", "127.0.0.1:8765"])
    assert status_of(call(app, headers=authorized())) == 200  # names compared in lower case
    for host, shown in (("evil.example:8765", "'evil.example:8765'"), ("", "'(none)'")):
        sent = call(app, headers=[("Host", host), ("Authorization", f"token {TOKEN}")])
        assert status_of(sent) == 403
        assert error_of(sent) == (
            f"Host {shown} is not one this server answers to (expected 127.0.0.1:8765, "
            "localhost:8765; px4params gui --allow-host NAME adds one)"
        )
    sent = call(app, headers=[("Authorization", f"token {TOKEN}")])  # no Host header at all
    assert error_of(sent).startswith("Host '(none)' is not one")
    assert len(route.calls) == 1


def test_the_first_host_header_counts() -> None:
    route = Route()
    app = admission(route)
    sent = call(app, headers=[("Host", "evil.example"), *authorized()])
    assert status_of(sent) == 403 and error_of(sent).startswith("Host 'evil.example'")
    assert status_of(call(app, headers=[*authorized(), ("Host", "evil.example")])) == 200


# -- Origin --------------------------------------------------------------------------------


def test_the_page_s_own_origin_is_accepted_in_any_case() -> None:
    route = Route()
    app = admission(route)
    for origin in (f"http://{HOST}", f"HTTP://LOCALHOST:{HOST.split(':')[1]}"):
        assert status_of(call(app, headers=authorized(("Origin", origin)))) == 200, origin
    for origin in ("null", f"https://{HOST}", "http://localhost:8766", "http://evil.example"):
        sent = call(app, headers=authorized(("Origin", origin)))
        assert (status_of(sent), error_of(sent)) == (
            403,
            f"requests from {origin} are not accepted",
        )
    assert len(route.calls) == 2


def test_a_websocket_from_another_origin_is_closed_before_it_opens() -> None:
    route = Route()
    app = admission(route)
    sent = call(app, kind="websocket", path="/ws", headers=authorized(("Origin", "null")))
    # closing before accepting: the server answers the handshake with 403
    assert sent == [
        {"type": "websocket.close", "code": 1008, "reason": "requests from null are not accepted"}
    ]
    sent = call(app, kind="websocket", path="/ws", headers=authorized())
    assert sent == [{"type": "websocket.accept"}]
    assert [scope["type"] for scope, _ in route.calls] == ["websocket"]


def test_a_websocket_refusal_s_reason_fits_a_close_frame() -> None:
    """RFC 6455 5.5: a control frame's payload is at most 125 bytes, 2 of them the code."""
    long_host = "x" * 200 + ".example"
    sent = call(admission(Route()), kind="websocket", headers=[("Host", long_host)])
    (close,) = sent
    assert close["code"] == 1008
    assert close["reason"] == f"Host '{long_host}' is not one this server answers to"[:120]
    assert len(close["reason"].encode()) == 120


# -- the token -----------------------------------------------------------------------------


def test_no_admission_without_a_token() -> None:
    with pytest.raises(ValueError, match=r"^the page never runs without a token$"):
        Admission(Route(), token="", hosts=[HOST], cookie=COOKIE)


def test_new_tokens_are_48_hex_digits_and_differ() -> None:
    tokens = {new_token() for _ in range(8)}
    assert len(tokens) == 8
    for token in tokens:
        assert len(token) == 48 and int(token, 16) >= 0 and token == token.lower()


def test_without_a_token_nothing_reaches_the_route() -> None:
    route = Route()
    app = admission(route)
    for headers in (
        [("Host", HOST)],
        [("Host", HOST), ("Authorization", f"Bearer {TOKEN}")],
        [("Host", HOST), ("Authorization", TOKEN)],
        [("Host", HOST), ("Authorization", f"token {TOKEN[:-1]}")],
        [("Host", HOST), ("Cookie", f"other={TOKEN}")],
        [("Host", HOST), ("Cookie", f"{COOKIE}={TOKEN}x")],
    ):
        sent = call(app, headers=headers)
        assert (status_of(sent), error_of(sent)) == (403, NO_TOKEN), headers
    sent = call(app, kind="websocket", headers=[("Host", HOST)])
    assert sent[0]["type"] == "websocket.close" and sent[0]["reason"] == NO_TOKEN[:120]
    assert route.calls == []


def test_the_authorization_scheme_is_case_insensitive() -> None:
    route = Route()
    app = admission(route)
    for value in (f"Token {TOKEN}", f"TOKEN {TOKEN}", f"token  {TOKEN} "):
        assert status_of(call(app, headers=[("Host", HOST), ("Authorization", value)])) == 200
    assert len(route.calls) == 3


def test_the_cookie_is_found_among_others() -> None:
    route = Route()
    app = admission(route)
    for cookie in (
        f"{COOKIE}={TOKEN}",
        f"theme=dark; {COOKIE}={TOKEN}",
        f"flag;{COOKIE}={TOKEN};x=1",
        f"{COOKIE}={TOKEN}; {COOKIE}=stale",  # the first of a repeated name (RFC 6265 5.4)
    ):
        assert status_of(call(app, headers=[("Host", HOST), ("Cookie", cookie)])) == 200, cookie
    sent = call(app, headers=[("Host", HOST), ("Cookie", f"{COOKIE}=stale; {COOKIE}={TOKEN}")])
    assert status_of(sent) == 403
    # another port's page has its own cookie name: its token does not open this one
    sent = call(app, headers=[("Host", HOST), ("Cookie", f"px4params-gui-8766={TOKEN}")])
    assert status_of(sent) == 403


def test_the_token_url_sets_the_cookie_and_redirects_without_the_secret() -> None:
    route = Route()
    app = admission(route)
    for method in ("GET", "HEAD"):
        sent = call(app, path="/", query=f"token={TOKEN}", method=method, headers=[("Host", HOST)])
        assert status_of(sent) == 303
        headers = headers_of(sent)
        assert headers["location"] == "/"
        assert headers["set-cookie"] == f"{COOKIE}={TOKEN}; Path=/; HttpOnly; SameSite=Strict"
        assert headers["content-length"] == "0" and sent[1]["body"] == b""
    # the rest of the query is kept, an empty value too; a mount's prefix is part of the path
    sent = call(
        app,
        path="/api/export",
        root_path="/gui",
        query=f"format=params&token={TOKEN}&empty=",
        headers=[("Host", HOST)],
    )
    assert headers_of(sent)["location"] == "/gui/api/export?format=params&empty="
    assert route.calls == []


def test_a_token_in_a_post_s_query_is_admitted_without_a_redirect() -> None:
    route = Route()
    app = admission(route)
    sent = call(app, method="POST", query=f"token={TOKEN}", body=[b"{}"], headers=[("Host", HOST)])
    assert status_of(sent) == 200 and route.calls[0][1] == b"{}"


def test_a_wrong_or_repeated_token_in_the_query_is_refused() -> None:
    route = Route()
    app = admission(route)
    for query in ("token=" + "0" * 48, "token=", f"token={TOKEN}&token={TOKEN}"):
        # a good cookie alongside does not rescue a wrong token in the address
        sent = call(app, path="/", query=query, headers=authorized(("Cookie", f"{COOKIE}={TOKEN}")))
        assert (status_of(sent), error_of(sent)) == (403, WRONG_TOKEN), query
    assert route.calls == []


# -- the body ------------------------------------------------------------------------------


def test_a_body_at_the_limit_is_admitted_and_one_byte_more_refused() -> None:
    route = Route()
    app = admission(route, max_body=10)
    sent = call(
        app, method="POST", headers=authorized(("Content-Length", "10")), body=[b"0123456789"]
    )
    assert status_of(sent) == 200 and route.calls[-1][1] == b"0123456789"
    sent = call(app, method="POST", headers=authorized(("Content-Length", "11")), body=[b"x" * 11])
    assert (status_of(sent), error_of(sent)) == (
        413,
        "request body of 11 bytes refused: at most 10 bytes per request",
    )
    assert len(route.calls) == 1


def test_a_body_without_a_length_is_counted_as_it_arrives() -> None:
    route = Route()
    app = admission(route, max_body=10)
    sent = call(app, method="POST", headers=authorized(), body=[b"0123", b"", b"456789"])
    assert status_of(sent) == 200 and route.calls[-1][1] == b"0123456789"
    # a declared length that is no number is not believed: the bytes are counted
    for declared in ("", "abc", "-5"):
        sent = call(
            app,
            method="POST",
            headers=authorized(("Content-Length", declared)),
            body=[b"01234", b"56789", b"X"],
        )
        assert (status_of(sent), error_of(sent)) == (
            413,
            "request body refused: at most 10 bytes per request",
        ), declared
    assert len(route.calls) == 1


def test_the_default_limit_is_one_mebibyte() -> None:
    route = Route()
    app = admission(route)
    assert MAX_BODY == 1 << 20
    sent = call(app, method="POST", headers=authorized(), body=[b"x" * MAX_BODY])
    assert status_of(sent) == 200 and len(route.calls[-1][1]) == MAX_BODY
    sent = call(app, method="POST", headers=authorized(), body=[b"x" * MAX_BODY, b"y"])
    assert error_of(sent) == "request body refused: at most 1048576 bytes per request"


def test_a_client_that_leaves_gives_the_route_an_empty_body() -> None:
    route = Route()
    sent = call(admission(route), method="POST", headers=authorized(), disconnect=True)
    assert status_of(sent) == 200 and route.calls[-1][1] == b""


def test_the_route_reads_the_body_once_then_waits_for_the_client() -> None:
    route = Route()
    call(
        admission(route),
        method="POST",
        headers=authorized(),
        body=[b"ab", b"cd"],
        wait_for_disconnect=True,
    )
    assert route.calls[-1][1] == b"abcd"
    assert route.after_body == [{"type": "http.disconnect"}]


# -- what every answer says ----------------------------------------------------------------


def test_every_answer_forbids_framing_sniffing_and_referrers() -> None:
    expected = {k.decode(): v.decode() for k, v in SECURITY_HEADERS}
    assert expected == {
        "content-security-policy": "frame-ancestors 'none'",
        "x-frame-options": "DENY",
        "x-content-type-options": "nosniff",
        "referrer-policy": "no-referrer",
    }
    route = Route()
    app = admission(route)
    admitted = call(app, headers=authorized())
    assert headers_of(admitted) == {"x-route": "yes", **expected}  # the route's own kept
    assert admitted[1] == {"type": "http.response.body", "body": b"ok"}
    for refused in (call(app), call(app, path="/", query=f"token={TOKEN}")):
        assert expected.items() <= headers_of(refused).items()


def test_other_scopes_pass_through_untouched() -> None:
    """ASGI's lifespan scope (startup, shutdown) is the server's, not a request."""
    route = Route()
    app = admission(route)
    scope = {"type": "lifespan"}

    async def receive() -> dict[str, Any]:
        raise AssertionError("not read")

    async def send(message: dict[str, Any]) -> None:
        raise AssertionError("not sent")

    asyncio.run(app(scope, receive, send))
    assert route.calls == [(scope, b"")]


def test_asgi_s_optional_keys_take_their_defaults() -> None:
    """ASGI: an ``http.request`` message may leave out ``body`` (default empty) and
    ``more_body`` (default False); a scope may leave out ``root_path`` (default empty)."""
    route = Route()
    app = admission(route)
    scope: dict[str, Any] = {
        "type": "http",
        "method": "POST",
        "path": "/api/write",
        "query_string": b"",
        "headers": [(b"host", HOST.encode()), (b"authorization", f"token {TOKEN}".encode())],
    }
    messages = [
        {"type": "http.request", "body": b"{}", "more_body": True},
        {"type": "http.request"},
    ]
    sent: list[dict[str, Any]] = []

    async def receive() -> dict[str, Any]:
        assert messages, "read past the body's last message"
        return messages.pop(0)

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)

    asyncio.run(app(scope, receive, send))
    assert status_of(sent) == 200 and route.calls[-1][1] == b"{}"
    # the token URL of a scope without root_path redirects to the path alone
    scope = {**scope, "method": "GET", "path": "/", "query_string": f"token={TOKEN}".encode()}
    scope["headers"] = [(b"host", HOST.encode())]
    sent.clear()
    asyncio.run(app(scope, receive, send))
    assert headers_of(sent)["location"] == "/"


def test_the_documented_limits() -> None:
    """docs/security.md: requests of at most 1 MiB, and at most 256 changes per write (the
    page writes a longer review in parts of 256)."""
    assert (MAX_BODY, MAX_CHANGES) == (1048576, 256)
