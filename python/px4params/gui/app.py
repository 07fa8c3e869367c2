"""The page's server: Starlette on loopback, the page and its script as static files shipped in
the package (nothing fetched from the internet), a JSON API over the vehicle, and a WebSocket
that pushes values and status messages as they arrive.

    GET  /                      the page
    GET  /api/state             mode, source, metadata, values, messages, health, limits
    POST /api/write             {"changes": [{"name", "value"}]} -> one result per change, in order
                                (an instance mask's change may carry "was", the mask it was
                                made from: only the bits it changes are written)
    POST /api/review            {"filename", "text"} -> the changes the file would make
    GET  /api/export?format=params|airframe   the configuration as a file
    GET|POST /api/manifest      the picker, and the devices a set of values configures
                                (:mod:`px4params.gui.manifest`)
    WS   /ws                    {"kind": "value"|"values"|"status", ...}

Every request passes :class:`~px4params.gui.admission.Admission` first (Host, Origin, the run's
token, the body's size).
"""

from __future__ import annotations

import asyncio
import json
import math
import os
import re
from collections.abc import Iterable
from typing import Any

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from px4params.errors import Px4ParamsError
from px4params.gui import files, manifest
from px4params.gui.admission import MAX_BODY, MAX_CHANGES, Admission
from px4params.vehicle.drivers import load_drivers

__all__ = ["make_app"]

STATIC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "static")


def make_app(vehicle: Any, *, token: str, hosts: Iterable[str], cookie: str) -> Admission:
    """The application over ``vehicle`` (a :class:`~px4params.gui.vehicle.MavlinkVehicle` or
    :class:`~px4params.gui.vehicle.StoreVehicle`), admitting requests with ``token`` to
    ``hosts`` (see :class:`~px4params.gui.admission.Admission`)."""

    async def page(request: Request) -> Response:
        return FileResponse(os.path.join(STATIC, "index.html"))

    async def state(request: Request) -> Response:
        body = vehicle.state()
        body["metadata"] = vehicle.metadata
        body["limits"] = {"changes": MAX_CHANGES, "body": MAX_BODY}  # the page writes in parts
        return JSONResponse(body)

    floats = {e["name"] for e in vehicle.metadata.get("parameters", ()) if e.get("type") == "Float"}

    async def write(request: Request) -> Response:
        refused = _foreign(request)
        if refused is not None:
            return refused
        try:
            body = _json(await request.body())
            changes = body.get("changes") if isinstance(body, dict) else None
            if isinstance(changes, list) and len(changes) > MAX_CHANGES:
                return _too_many(len(changes))
            writes = _writes(changes, floats)
        except (ValueError, RecursionError) as e:  # (nesting too deep)
            return JSONResponse(
                {"error": f"expected {{'changes': [{{'name', 'value'}}]}}: {e}"}, 400
            )
        results = []
        for name, value, was in writes:
            result = await asyncio.to_thread(vehicle.write, name, value, was)
            results.append(result.as_dict())
        return JSONResponse({"results": results, "values": vehicle.state()["values"]})

    async def review(request: Request) -> Response:
        refused = _foreign(request)
        if refused is not None:
            return refused
        try:
            body = _json(await request.body())
            filename, text = (_text_field(body, key) for key in ("filename", "text"))
        except (ValueError, RecursionError) as e:  # (nesting too deep)
            return JSONResponse({"error": f"expected {{'filename', 'text'}}: {e}"}, 400)
        store = getattr(vehicle, "store", None)
        try:
            found = await asyncio.to_thread(
                files.review_file, filename, text, dict(vehicle.values), vehicle.metadata, store
            )
        except Px4ParamsError as e:
            return JSONResponse({"error": str(e)}, 400)
        return JSONResponse(found)

    async def export(request: Request) -> Response:
        kind = request.query_params.get("format", "params")
        store = getattr(vehicle, "store", None)
        values = dict(vehicle.values)
        if kind == "params":
            text = await asyncio.to_thread(files.export_params, values, vehicle.metadata, store)
            name = "vehicle.params"
        elif kind == "airframe":
            text = await asyncio.to_thread(files.export_airframe, values, vehicle.metadata, store)
            name = "vehicle.airframe"
        else:
            return JSONResponse({"error": f"format {kind!r}: expected params or airframe"}, 400)
        headers = {"Content-Disposition": f'attachment; filename="{name}"'}
        return Response(text, media_type="text/plain; charset=utf-8", headers=headers)

    async def socket(ws: WebSocket) -> None:
        await ws.accept()
        loop = asyncio.get_running_loop()
        queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
        stop = vehicle.listen(lambda event: loop.call_soon_threadsafe(queue.put_nowait, event))
        # Waits for the client as well as for events: a client that left (or the server's
        # shutdown, which closes every socket) ends the handler at once, not at the next event.
        gone = asyncio.ensure_future(_until_closed(ws))
        try:
            while not gone.done():
                event = asyncio.ensure_future(queue.get())
                await asyncio.wait([event, gone], return_when=asyncio.FIRST_COMPLETED)
                if not event.done():
                    event.cancel()
                    break
                await ws.send_text(json.dumps(event.result()))
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            gone.cancel()
            if gone.done() and not gone.cancelled():
                gone.exception()  # a receive that failed ended the socket: nothing to report
            stop()

    routes = [
        Route("/", page),
        Route("/api/state", state),
        Route("/api/write", write, methods=["POST"]),
        Route("/api/review", review, methods=["POST"]),
        Route("/api/export", export),
        *manifest.routes(vehicle, load_drivers()),  # the device cards and the picker
        WebSocketRoute("/ws", socket),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]
    return Admission(Starlette(routes=routes), token=token, hosts=hosts, cookie=cookie)


async def _until_closed(ws: WebSocket) -> None:
    """Returns when the client closes the socket (the page sends nothing)."""
    while (await ws.receive())["type"] != "websocket.disconnect":
        pass


def _too_many(count: int) -> Response:
    return JSONResponse(
        {
            "error": f"{count} changes refused: at most {MAX_CHANGES} per request "
            "(write them in parts)"
        },
        413,
    )


def _foreign(request: Request) -> Response | None:
    """Refuses a write another site's page could send from the user's browser without a
    preflight: only JSON (a cross-site JSON request needs the browser's preflight, which this
    server never grants). Other origins are refused before (``admission``)."""
    media_type = request.headers.get("content-type", "").partition(";")[0].strip().lower()
    if media_type != "application/json":  # (not "application/jsonx")
        return JSONResponse({"error": "expected a JSON body (content-type application/json)"}, 415)
    return None


# A request's body, read whole and checked piece by piece: each refusal names the piece and
# what it should be, never Python's words for what went wrong inside.

#: Digits a number in a request may have: more than any parameter's range needs.
_MAX_DIGITS = 40
_INTEGER = re.compile(r"[+-]?(?:0[xX][0-9A-Fa-f]+|[0-9]+)")
# (NaN and the infinities are numbers here: the store refuses them, naming the parameter.)
_REAL = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|nan|inf(?:inity)?)", re.I
)


def _json(raw: bytes) -> Any:
    def whole(text: str) -> int:
        digits = len(text.lstrip("-"))
        if digits > _MAX_DIGITS:
            raise ValueError(f"a number of {digits} digits (no parameter holds one)")
        return int(text)

    def real(text: str) -> float:
        number = float(text)
        if math.isinf(number):
            raise ValueError(f"{text[:20]}...: beyond the range of a float")
        return number

    try:
        return json.loads(raw, parse_int=whole, parse_float=real)
    except json.JSONDecodeError as e:
        raise ValueError(f"not JSON: {e}") from None
    except UnicodeDecodeError:
        raise ValueError("not JSON: not UTF-8") from None


def _text_field(body: Any, key: str) -> str:
    if not isinstance(body, dict) or key not in body:
        raise ValueError(f"the body has no {key!r}")
    value = body[key]
    if not isinstance(value, str):
        raise ValueError(f"{key!r} is {_kind(value)}, not text")
    return value


def _writes(changes: Any, floats: set[str]) -> list[tuple[str, int | float, int | None]]:
    """The ``(name, value, was)`` of each change of a write's body."""
    if changes is None:
        raise ValueError("the body has no 'changes'")
    if not isinstance(changes, list):
        raise ValueError(f"'changes' is {_kind(changes)}, not a list")
    writes = []
    for n, change in enumerate(changes):
        if not isinstance(change, dict):
            raise ValueError(f"change {n} is {_kind(change)}, not an object")
        for key in ("name", "value"):
            if key not in change:
                raise ValueError(f"change {n} has no {key!r}")
        name = change["name"]
        if not isinstance(name, str):
            raise ValueError(f"change {n}: the name is {_kind(name)}, not text")
        was = int(_number(change["was"], False)) if change.get("was") is not None else None
        writes.append((name, _number(change["value"], name in floats), was))
    return writes


def _kind(value: Any) -> str:
    """A JSON value's kind, as the page's author would name it."""
    names = {bool: "a boolean", str: "text", list: "a list", dict: "an object"}
    return "null" if value is None else names.get(type(value), "a number")


def _number(value: Any, is_float: bool) -> int | float:
    """A value from the page as the parameter's type carries it (Float or Int32): a JSON
    number, or text spelling one (an integer in decimal or 0x hexadecimal)."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ValueError(f"{value!r} is not a number")
    if isinstance(value, str):
        pattern = _REAL if is_float else _INTEGER
        if len(value) > _MAX_DIGITS or not pattern.fullmatch(value):
            what = "a number" if is_float else "an integer (decimal, or hexadecimal with 0x)"
            raise ValueError(f"{value[:_MAX_DIGITS]!r} is not {what}")
        return float(value) if is_float else int(value, 0)
    if is_float:
        return float(value)
    if isinstance(value, float):
        if not value.is_integer():
            raise ValueError(f"{value!r} is not an integer")
        return int(value)
    return value
