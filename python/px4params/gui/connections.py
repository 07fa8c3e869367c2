"""The page's HTTP connections: uvicorn's HTTP/1.1 protocol with a deadline for each request
(its head and its body).

uvicorn closes a kept-alive connection that goes idle after a response, but not one that never
sends a request, or sends its head a byte at a time (each byte restarts the idle timer): each
held a connection (and a file descriptor) for as long as its peer liked, and so did a body sent
a byte at a time. Here a connection whose request, head and body, is not complete within
:data:`REQUEST_SECONDS` of connecting, or of the response before it, is closed. A WebSocket's
upgrade request is a request like any other: once it is in, the deadline is gone.
"""

from __future__ import annotations

import asyncio
from typing import Any

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

#: Seconds a new connection has to send its first request whole (uvicorn's keep-alive timeout
#: is 5 s; a browser's preconnected socket that sends nothing is closed, which it expects).
REQUEST_SECONDS = 10.0

#: h11's states of a peer whose request is not yet all in.
_UNFINISHED = (h11.IDLE, h11.SEND_BODY)


class RequestDeadline(H11Protocol):
    """:class:`H11Protocol` that closes a connection whose next request is late."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._deadline = self.loop.call_later(REQUEST_SECONDS, self._late)

    def on_response_complete(self) -> None:
        super().on_response_complete()
        # Kept alive: the next request has as long as the first one had.
        if not self.transport.is_closing() and self.conn.their_state is h11.IDLE:
            self._cancel()
            self._deadline = self.loop.call_later(REQUEST_SECONDS, self._late)

    def handle_events(self) -> None:
        super().handle_events()
        # A request is in once h11 has left IDLE (a whole head) and SEND_BODY (the whole body).
        if self._deadline is not None and self.conn.their_state not in _UNFINISHED:
            self._cancel()

    def handle_websocket_upgrade(self, event: h11.Request) -> None:
        # The upgrade request is whole (h11 waits in SEND_BODY for an end that never comes: the
        # connection is the WebSocket's from here).
        self._cancel()
        super().handle_websocket_upgrade(event)

    def connection_lost(self, exc: Exception | None) -> None:
        self._cancel()
        super().connection_lost(exc)

    def _cancel(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None

    def _late(self) -> None:
        self._deadline = None
        if self.conn.their_state in _UNFINISHED and not self.transport.is_closing():
            self.transport.close()
