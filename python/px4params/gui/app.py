"""The page's server: Starlette on loopback, the page and its script as static files shipped in
the package (nothing fetched from the internet), a JSON API over the vehicle, and a WebSocket
that pushes values and status messages as they arrive.

    GET  /                      the page
    GET  /api/state             mode, source, metadata, values, messages, health
    POST /api/write             {"changes": [{"name", "value"}]} -> one result per change, in order
    POST /api/review            {"filename", "text"} -> the changes the file would make
    GET  /api/export?format=params|airframe   the configuration as a file
    WS   /ws                    {"kind": "value"|"values"|"status", ...}
"""

from __future__ import annotations

import asyncio
import json
import os
from typing import Any

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from px4params.errors import Px4ParamsError
from px4params.gui import files

__all__ = ["make_app"]

STATIC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "static")


def make_app(vehicle: Any) -> Starlette:
    """The application over ``vehicle`` (a :class:`~px4params.gui.vehicle.MavlinkVehicle` or
    :class:`~px4params.gui.vehicle.StoreVehicle`)."""

    async def page(request: Request) -> Response:
        return FileResponse(os.path.join(STATIC, "index.html"))

    async def state(request: Request) -> Response:
        body = vehicle.state()
        body["metadata"] = vehicle.metadata
        return JSONResponse(body)

    floats = {e["name"] for e in vehicle.metadata.get("parameters", ()) if e.get("type") == "Float"}

    async def write(request: Request) -> Response:
        refused = _foreign(request)
        if refused is not None:
            return refused
        try:
            changes = (await request.json())["changes"]
            pairs = [
                (str(c["name"]), _number(c["value"], str(c["name"]) in floats)) for c in changes
            ]
        except (ValueError, KeyError, TypeError) as e:
            return JSONResponse(
                {"error": f"expected {{'changes': [{{'name', 'value'}}]}}: {e}"}, 400
            )
        results = []
        for name, value in pairs:
            result = await asyncio.to_thread(vehicle.write, name, value)
            results.append(result.as_dict())
        return JSONResponse({"results": results, "values": vehicle.state()["values"]})

    async def review(request: Request) -> Response:
        refused = _foreign(request)
        if refused is not None:
            return refused
        try:
            body = await request.json()
            filename, text = str(body["filename"]), str(body["text"])
        except (ValueError, KeyError, TypeError) as e:
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
        origin = ws.headers.get("origin")
        if origin is not None and origin != f"http://{ws.headers.get('host')}":
            await ws.close(code=1008)  # another site's page may not watch the vehicle
            return
        await ws.accept()
        loop = asyncio.get_running_loop()
        queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
        stop = vehicle.listen(lambda event: loop.call_soon_threadsafe(queue.put_nowait, event))
        try:
            while True:
                event = await queue.get()
                await ws.send_text(json.dumps(event))
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            stop()

    routes = [
        Route("/", page),
        Route("/api/state", state),
        Route("/api/write", write, methods=["POST"]),
        Route("/api/review", review, methods=["POST"]),
        Route("/api/export", export),
        WebSocketRoute("/ws", socket),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]
    return Starlette(routes=routes)


def _foreign(request: Request) -> Response | None:
    """Refuses a write another site's page could send from the user's browser: only JSON (a
    cross-site JSON request needs the browser's preflight, which this server never grants)
    and, when the browser names the origin, this page's own."""
    if not request.headers.get("content-type", "").startswith("application/json"):
        return JSONResponse({"error": "expected a JSON body (content-type application/json)"}, 415)
    origin = request.headers.get("origin")
    if origin is not None and origin != f"http://{request.headers.get('host')}":
        return JSONResponse({"error": f"requests from {origin} are not accepted"}, 403)
    return None


def _number(value: Any, is_float: bool) -> int | float:
    """A value from the page as the parameter's type carries it (Float or Int32)."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise TypeError(f"{value!r} is not a number")
    number = float(value) if is_float else int(value, 0) if isinstance(value, str) else value
    if not is_float and isinstance(number, float):
        if not number.is_integer():
            raise TypeError(f"{value!r} is not an integer")
        number = int(number)
    return number
