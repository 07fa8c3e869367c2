"""Who may use the page's server: an ASGI layer in front of every route (the page, its static
files, the API and the WebSocket) that admits a request only when

1. its ``Host`` header is one this server answers to (the loopback names and the bound address
   with the port, and the names given with ``--allow-host``): a page whose domain an attacker
   rebinds to 127.0.0.1 (DNS rebinding) sends its own name and is refused;
2. it names no other origin (``Origin``, which browsers send on cross-origin fetches, on
   POSTs and on every WebSocket; ``Origin: null`` included);
3. it carries the run's secret token, as Jupyter does: the URL printed at start has
   ``?token=...``; the first request with it gets an ``HttpOnly``, ``SameSite=Strict`` cookie
   and a redirect to the same URL without the token; later requests carry the cookie, scripts
   may send ``Authorization: token ...`` instead;
4. its body is at most :data:`MAX_BODY` bytes (413 otherwise, before the route reads it).

Refusals are JSON ``{"error": ...}`` (a WebSocket is closed before it opens: HTTP 403). Every
response also says that no other page may frame this one (clickjacking: a page of another port
is the same site and would get the cookie), that the browser must not guess content types,
and that the address (with a token, on the first visit) is never sent on as a referrer.
"""

from __future__ import annotations

import hmac
import json
import secrets
from collections.abc import Awaitable, Callable, Iterable, MutableMapping
from typing import Any
from urllib.parse import parse_qsl, urlencode

__all__ = [
    "LOOPBACK_NAMES",
    "MAX_BODY",
    "MAX_CHANGES",
    "Admission",
    "allowed_hosts",
    "new_token",
]

#: Request bodies accepted, in bytes: a parameter file or a review of every parameter of a
#: vehicle is far smaller (PX4's 1909 parameters as a QGC .params file: under 100 kB).
MAX_BODY = 1 << 20
#: Changes one write request may carry; the page sends a longer review in parts. Each change is
#: a round trip to the vehicle, and writes wait on each other.
MAX_CHANGES = 256
#: Names a browser on this machine uses for the loopback address.
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "[::1]")
#: Headers of every response: no framing by other pages, no type sniffing, no referrer.
SECURITY_HEADERS = (
    (b"content-security-policy", b"frame-ancestors 'none'"),
    (b"x-frame-options", b"DENY"),
    (b"x-content-type-options", b"nosniff"),
    (b"referrer-policy", b"no-referrer"),
)

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
App = Callable[[Scope, Receive, Send], Awaitable[None]]


def new_token() -> str:
    """A run's secret: 48 hex digits (192 bits), as Jupyter's."""
    return secrets.token_hex(24)


def allowed_hosts(port: int, bound: str, extra: Iterable[str] = ()) -> frozenset[str]:
    """``Host`` header values this server answers to: the loopback names and ``bound`` (unless
    a wildcard) with ``port``, and each of ``extra`` (``NAME`` gets ``port``; ``NAME:PORT`` is
    taken as given). Lower case, as compared."""
    names = list(LOOPBACK_NAMES)
    if bound not in ("0.0.0.0", "", "::"):
        names.append(f"[{bound}]" if ":" in bound else bound)
    hosts = {f"{name.lower()}:{port}" for name in names}
    for name in extra:
        name = name.strip().lower()
        has_port = name.rpartition(":")[2].isdigit() and (not name.startswith("[") or "]:" in name)
        hosts.add(name if has_port else f"{name}:{port}")
    if port == 80:  # a browser leaves the default port out
        hosts |= {h.rsplit(":", 1)[0] for h in list(hosts)}
    return frozenset(hosts)


class Admission:
    """Wraps ``app``: requests that pass the checks above reach it, others get 403 or 413.
    ``cookie``: the cookie's name; cookies are shared by every port of a host, so it should
    name the port (two pages on one machine keep their own)."""

    def __init__(
        self,
        app: App,
        *,
        token: str,
        hosts: Iterable[str],
        cookie: str,
        max_body: int = MAX_BODY,
    ) -> None:
        if not token:
            raise ValueError("the page never runs without a token")
        self.app = app
        self.token = token
        self.hosts = frozenset(h.lower() for h in hosts)
        self.cookie = cookie
        self.max_body = max_body

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        send = _with_security_headers(send)
        headers = _headers(scope)
        query = parse_qsl(scope.get("query_string", b"").decode("latin-1"), keep_blank_values=True)
        given = [v for k, v in query if k == "token"]
        refusal = self._refusal(headers, given)
        if refusal is not None:
            await _refuse(scope, receive, send, 403, refusal)
            return
        if given and scope["type"] == "http" and scope["method"] in ("GET", "HEAD"):
            # The token URL: the cookie from now on, and the address bar without the secret.
            rest = urlencode([(k, v) for k, v in query if k != "token"])
            location = scope.get("root_path", "") + scope["path"] + (f"?{rest}" if rest else "")
            cookie = f"{self.cookie}={self.token}; Path=/; HttpOnly; SameSite=Strict"
            await _respond(send, 303, b"", [(b"location", location.encode()), _cookie(cookie)])
            return
        if scope["type"] == "http":
            body = await self._body(scope, headers, receive, send)
            if body is None:
                return
            receive = _replay(body, receive)
        await self.app(scope, receive, send)

    def _refusal(self, headers: dict[str, str], given: list[str]) -> str | None:
        host = headers.get("host", "").lower()
        if host not in self.hosts:
            expected = ", ".join(sorted(self.hosts))
            return (
                f"Host {host or '(none)'!r} is not one this server answers to (expected "
                f"{expected}; px4params gui --allow-host NAME adds one)"
            )
        origin = headers.get("origin")
        if origin is not None and origin.lower() != f"http://{host}":
            return f"requests from {origin} are not accepted"
        if given:
            if len(given) == 1 and self._matches(given[0]):
                return None
            return "wrong token: open the URL px4params gui printed at start"
        if self._matches(_cookies(headers.get("cookie", "")).get(self.cookie, "")):
            return None
        scheme, _, value = headers.get("authorization", "").partition(" ")
        if scheme.lower() == "token" and self._matches(value.strip()):
            return None
        return (
            "no token: open the URL px4params gui printed at start (it ends in ?token=...), "
            "or send the header 'Authorization: token ...'"
        )

    def _matches(self, candidate: str) -> bool:
        return hmac.compare_digest(candidate.encode(), self.token.encode())

    async def _body(
        self, scope: Scope, headers: dict[str, str], receive: Receive, send: Send
    ) -> bytes | None:
        """The whole body, or None once a 413 is sent (by its declared length, else by what
        arrived)."""
        declared = headers.get("content-length", "")
        if declared.isdigit() and int(declared) > self.max_body:
            await _refuse(scope, receive, send, 413, self._too_large(int(declared)))
            return None
        chunks: list[bytes] = []
        size = 0
        while True:
            message = await receive()
            if message["type"] != "http.request":
                break  # the client left; the route sees an empty body
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > self.max_body:
                await _refuse(scope, receive, send, 413, self._too_large(None))
                return None
            chunks.append(chunk)
            if not message.get("more_body", False):
                break
        return b"".join(chunks)

    def _too_large(self, size: int | None) -> str:
        what = f"of {size} bytes " if size is not None else ""
        return f"request body {what}refused: at most {self.max_body} bytes per request"


def _headers(scope: Scope) -> dict[str, str]:
    """Request headers by lower-case name (the first of repeated ones)."""
    out: dict[str, str] = {}
    for key, value in scope.get("headers", ()):
        out.setdefault(key.decode("latin-1").lower(), value.decode("latin-1"))
    return out


def _with_security_headers(send: Send) -> Send:
    async def sending(message: Message) -> None:
        if message["type"] == "http.response.start":
            message = {**message, "headers": [*message.get("headers", ()), *SECURITY_HEADERS]}
        await send(message)

    return sending


def _cookies(text: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for part in text.split(";"):
        name, sep, value = part.strip().partition("=")
        if sep:
            out.setdefault(name, value)
    return out


def _cookie(text: str) -> tuple[bytes, bytes]:
    return b"set-cookie", text.encode()


def _replay(body: bytes, receive: Receive) -> Receive:
    """A ``receive`` that hands the route the body already read, then waits as before (for
    the client's disconnect)."""
    sent = False

    async def replayed() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await receive()

    return replayed


async def _respond(
    send: Send, status: int, body: bytes, headers: list[tuple[bytes, bytes]]
) -> None:
    headers = [*headers, (b"content-length", str(len(body)).encode())]
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})


async def _refuse(scope: Scope, receive: Receive, send: Send, status: int, why: str) -> None:
    if scope["type"] == "websocket":
        await receive()  # websocket.connect
        await send({"type": "websocket.close", "code": 1008, "reason": why[:120]})
        return
    body = json.dumps({"error": why}).encode()
    await _respond(send, status, body, [(b"content-type", b"application/json")])
