"""The page's server (``px4params.gui.app``) over a store file, spoken to in-process over ASGI
(https://asgi.readthedocs.io/en/latest/specs/www.html) with the helpers of
``tests/test_admission.py``: the routes of the module's docstring, their status codes (HTTP
semantics: 400 for a body that is not what the route takes, 413 for too many changes, 415 for
a body that is not JSON), the JSON bodies the page reads, and the WebSocket that pushes the
vehicle's events. ``tests/test_gui.py`` runs the same app behind uvicorn with a browser."""

from __future__ import annotations

import asyncio
import gc
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import px4params
import pytest
from px4params.gui.admission import MAX_BODY, MAX_CHANGES, Admission
from px4params.gui.app import STATIC, make_app
from px4params.gui.vehicle import StoreVehicle
from px4params.store.classic import BUNDLED_CLASSIC
from test_admission import (
    COOKIE,
    HOST,
    TOKEN,
    authorized,
    call,
    error_of,
    headers_of,
    status_of,
)

JSON = ("Content-Type", "application/json")


@pytest.fixture
def served(store_file: Path) -> Iterator[tuple[Admission, StoreVehicle]]:
    vehicle = StoreVehicle(str(store_file), None, [], poll_interval=3600)
    yield make_app(vehicle, token=TOKEN, hosts=[HOST], cookie=COOKIE), vehicle
    vehicle.close()


def body_of(sent: list[dict[str, Any]]) -> bytes:
    status_of(sent)
    return b"".join(m.get("body", b"") for m in sent[1:])


def ask(
    app: Admission,
    path: str,
    *,
    query: str = "",
    method: str = "GET",
    headers: list[tuple[str, str]] | None = None,
    body: bytes = b"",
) -> list[dict[str, Any]]:
    """One HTTP request as a server hands it over: the body, then nothing until the answer is
    sent (a client that stays; Starlette's responses stop early on ``http.disconnect``)."""
    scope = {
        "type": "http",
        "method": method,
        "path": path,
        "root_path": "",
        "query_string": query.encode(),
        "headers": [(k.lower().encode(), v.encode()) for k, v in headers or authorized()],
    }
    incoming = [{"type": "http.request", "body": body, "more_body": False}]
    sent: list[dict[str, Any]] = []

    async def receive() -> dict[str, Any]:
        if incoming:
            return incoming.pop(0)
        await asyncio.Event().wait()  # the client waits for the answer
        raise AssertionError("unreachable")

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)

    asyncio.run(app(scope, receive, send))
    return sent


def post(app: Admission, path: str, payload: Any, *, content_type: str = "application/json"):
    data = payload if isinstance(payload, bytes) else json.dumps(payload).encode()
    headers = authorized(("Content-Type", content_type), ("Content-Length", str(len(data))))
    return ask(app, path, method="POST", headers=headers, body=data)


def get(app: Admission, path: str, query: str = "") -> list[dict[str, Any]]:
    return ask(app, path, query=query)


# -- reading -----------------------------------------------------------------------------------


def test_the_page_is_the_packaged_index_html(served: tuple[Admission, StoreVehicle]) -> None:
    app, _ = served
    sent = get(app, "/")
    assert status_of(sent) == 200
    assert headers_of(sent)["content-type"].startswith("text/html")
    assert body_of(sent) == (Path(STATIC) / "index.html").read_bytes()
    script = get(app, "/static/app.js")
    assert status_of(script) == 200 and body_of(script) == (Path(STATIC) / "app.js").read_bytes()


def test_state_is_the_vehicle_s_with_its_metadata_and_the_write_limits(
    served: tuple[Admission, StoreVehicle], store_file: Path
) -> None:
    app, vehicle = served
    sent = get(app, "/api/state")
    assert status_of(sent) == 200 and headers_of(sent)["content-type"] == "application/json"
    state = json.loads(body_of(sent))
    assert state["mode"] == "store" and state["source"] == str(store_file)
    assert state["values"]["INA238_1C"] == 0x45
    assert state["metadata"] == vehicle.metadata
    assert {"name": "INA238_1C"}.items() <= next(
        e for e in state["metadata"]["parameters"] if e["name"] == "INA238_1C"
    ).items()
    assert state["limits"] == {"changes": 256, "body": 1 << 20}
    assert (MAX_CHANGES, MAX_BODY) == (256, 1 << 20)
    assert state["messages"] == [] and state["health"] == []


def test_nothing_without_the_token(served: tuple[Admission, StoreVehicle]) -> None:
    app, _ = served
    sent = ask(app, "/api/state", headers=[("Host", HOST)])
    assert status_of(sent) == 403 and error_of(sent).startswith("no token")


# -- writing -----------------------------------------------------------------------------------


def test_a_write_answers_one_result_per_change_in_order_and_the_values(
    served: tuple[Admission, StoreVehicle], store_file: Path, schema: px4params.Schema
) -> None:
    app, _ = served
    changes = [
        {"name": "INA238_1C", "value": 70},
        {"name": "INA238_1C", "value": 200},  # out of range: refused, value kept
        {"name": "INA238_1P", "value": "0x140"},  # text in any base Python reads
        {"name": "BAT1_CAPACITY", "value": "5000.5"},  # a Float parameter from text
        {"name": "SYS_AUTOSTART", "value": 4001.0},  # an integral float for an Int32
    ]
    sent = post(app, "/api/write", {"changes": changes})
    assert status_of(sent) == 200
    answer = json.loads(body_of(sent))
    assert [(r["name"], r["ok"], r["value"]) for r in answer["results"]] == [
        ("INA238_1C", True, 70),
        ("INA238_1C", False, 70),
        ("INA238_1P", True, 320),
        ("BAT1_CAPACITY", True, 5000.5),
        ("SYS_AUTOSTART", True, 4001),
    ]
    assert answer["results"][0]["reason"] == ""
    assert answer["results"][1]["reason"].startswith("INA238_1C: ")
    assert "out of range" in answer["results"][1]["reason"]
    assert answer["values"]["INA238_1C"] == 70 and answer["values"]["SYS_AUTOSTART"] == 4001
    saved = px4params.Store.load(store_file, schema, classic=BUNDLED_CLASSIC)
    assert saved.get("INA238#1.bus.i2c.address") == 70 and saved.get("SYS_AUTOSTART") == 4001
    assert saved.get("BAT1_CAPACITY") == 5000.5


@pytest.mark.parametrize(
    ("payload", "why"),
    [
        ({"changes": [{"name": "INA238_1C", "value": 70.5}]}, "70.5 is not an integer"),
        ({"changes": [{"name": "INA238_1C", "value": True}]}, "True is not a number"),
        ({"changes": [{"name": "INA238_1C", "value": None}]}, "None is not a number"),
        ({"changes": [{"name": "INA238_1C", "value": [1]}]}, "[1] is not a number"),
        ({"changes": [{"name": "INA238_1C", "value": "seventy"}]}, "'seventy' is not an integer"),
        ({"changes": [{"name": "INA238_1C"}]}, "change 0 has no 'value'"),
        ({"change": []}, "the body has no 'changes'"),
        (b"{not json", "not JSON: Expecting property name"),
    ],
)
def test_a_write_the_route_cannot_read_is_400_and_writes_nothing(
    served: tuple[Admission, StoreVehicle], payload: Any, why: str
) -> None:
    app, vehicle = served
    sent = post(app, "/api/write", payload)
    assert status_of(sent) == 400
    error = error_of(sent)
    assert error.startswith("expected {'changes': [{'name', 'value'}]}: ")
    assert why in error
    assert vehicle.values["INA238_1C"] == 0x45


def test_a_write_of_more_than_256_changes_is_413_before_any_is_read(
    served: tuple[Admission, StoreVehicle],
) -> None:
    app, _ = served
    bad = {"name": "INA238_1C", "value": 0.5}  # each unreadable: a 400 once counted
    sent = post(app, "/api/write", {"changes": [bad] * 257})
    assert status_of(sent) == 413
    assert error_of(sent) == "257 changes refused: at most 256 per request (write them in parts)"
    assert status_of(post(app, "/api/write", {"changes": [bad] * 256})) == 400


@pytest.mark.parametrize("route", ["/api/write", "/api/review"])
def test_a_post_that_is_not_json_is_415(served: tuple[Admission, StoreVehicle], route: str) -> None:
    """A form or text/plain POST needs no CORS preflight: another site's page could send it."""
    app, vehicle = served
    for content_type in ("text/plain", "application/x-www-form-urlencoded", ""):
        payload = {"changes": [{"name": "INA238_1C", "value": 70}]}
        sent = post(app, route, payload, content_type=content_type)
        assert status_of(sent) == 415
        assert error_of(sent) == "expected a JSON body (content-type application/json)"
    assert vehicle.values["INA238_1C"] == 0x45
    sent = post(app, "/api/write", payload, content_type="application/json; charset=utf-8")
    assert status_of(sent) == 200 and vehicle.values["INA238_1C"] == 70


# -- files -------------------------------------------------------------------------------------


def test_a_review_lists_what_a_params_file_would_change(
    served: tuple[Admission, StoreVehicle],
) -> None:
    app, vehicle = served
    text = "1\t1\tINA238_1C\t70\t6\n"  # QGC's .params: vehicle, component, name, value, type
    sent = post(app, "/api/review", {"filename": "qgc.params", "text": text})
    assert status_of(sent) == 200
    assert json.loads(body_of(sent)) == {
        "changes": [{"name": "INA238_1C", "current": 0x45, "new": 70}],
        "notes": [],
    }
    assert vehicle.values["INA238_1C"] == 0x45  # a review writes nothing


@pytest.mark.parametrize(
    ("payload", "why"),
    [({"filename": "x.params"}, "'text'"), ({"text": ""}, "'filename'"), (b"[", "Expecting")],
)
def test_a_review_the_route_cannot_read_is_400(
    served: tuple[Admission, StoreVehicle], payload: Any, why: str
) -> None:
    app, _ = served
    sent = post(app, "/api/review", payload)
    assert status_of(sent) == 400
    error = error_of(sent)
    assert error.startswith("expected {'filename', 'text'}: ") and why in error


def test_a_review_of_a_file_that_cannot_be_read_is_400_with_its_error(
    served: tuple[Admission, StoreVehicle],
) -> None:
    app, _ = served
    sent = post(app, "/api/review", {"filename": "bad.params", "text": "1\t1\tNOPE\n"})
    assert status_of(sent) == 400
    assert "bad.params" in error_of(sent)


@pytest.mark.parametrize(
    ("query", "name"),
    [
        ("", "vehicle.params"),
        ("format=params", "vehicle.params"),
        ("format=airframe", "vehicle.airframe"),
    ],
)
def test_an_export_is_a_text_attachment_named_by_its_format(
    served: tuple[Admission, StoreVehicle], query: str, name: str
) -> None:
    app, _ = served
    sent = get(app, "/api/export", query)
    assert status_of(sent) == 200
    headers = headers_of(sent)
    assert headers["content-type"] == "text/plain; charset=utf-8"
    assert headers["content-disposition"] == f'attachment; filename="{name}"'
    text = body_of(sent).decode()
    if name.endswith(".params"):
        assert "\tINA238_1C\t69\t6" in text  # QGC's columns, INT32 type 6
    else:
        assert "param add INA238#1\n" in text  # the shell's commands, by leaf index
        assert "param set-default INA238#1[4] 69\n" in text


def test_an_export_in_another_format_is_400(served: tuple[Admission, StoreVehicle]) -> None:
    app, _ = served
    sent = get(app, "/api/export", "format=xml")
    assert status_of(sent) == 400
    assert error_of(sent) == "format 'xml': expected params or airframe"


# -- the WebSocket -----------------------------------------------------------------------------


async def _socket_session(app: Admission, vehicle: StoreVehicle) -> list[dict[str, Any]]:
    """Opens /ws, has the vehicle write (an event from another thread, as the store's watcher
    sends them), then leaves: what the server sent."""
    incoming: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
    sent: list[dict[str, Any]] = []
    got_one = asyncio.Event()

    async def receive() -> dict[str, Any]:
        return await incoming.get()

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)
        if message["type"] == "websocket.send":
            got_one.set()

    scope = {
        "type": "websocket",
        "path": "/ws",
        "root_path": "",
        "query_string": b"",
        "headers": [(k.lower().encode(), v.encode()) for k, v in authorized()],
        "subprotocols": [],
    }
    incoming.put_nowait({"type": "websocket.connect"})
    served = asyncio.ensure_future(app(scope, receive, send))
    while not sent:
        await asyncio.sleep(0.01)
    assert sent[0]["type"] == "websocket.accept"
    incoming.put_nowait({"type": "websocket.receive", "text": "hello"})  # the page says nothing
    result = await asyncio.to_thread(vehicle.write, "INA238_1C", 71)
    assert result.ok
    await asyncio.wait_for(got_one.wait(), 10)
    incoming.put_nowait({"type": "websocket.disconnect", "code": 1001})
    await asyncio.wait_for(served, 10)  # the client left: the handler ends at once
    return sent


def test_the_socket_pushes_the_vehicle_s_events_and_stops_listening_when_closed(
    served: tuple[Admission, StoreVehicle],
) -> None:
    app, vehicle = served
    sent = asyncio.run(_socket_session(app, vehicle))
    pushed = [json.loads(m["text"]) for m in sent if m["type"] == "websocket.send"]
    assert pushed[0]["kind"] == "values" and pushed[0]["values"]["INA238_1C"] == 71
    assert vehicle._listeners == []  # the page's listener is gone with its socket


def test_a_socket_from_another_origin_is_closed_before_it_opens(
    served: tuple[Admission, StoreVehicle],
) -> None:
    app, vehicle = served
    headers = authorized(("Origin", "http://evil.example"))
    sent = call(app, kind="websocket", path="/ws", headers=headers)
    assert sent == [
        {
            "type": "websocket.close",
            "code": 1008,
            "reason": "requests from http://evil.example are not accepted",
        }
    ]
    assert vehicle._listeners == []


def test_the_files_of_a_store_with_its_own_types_carry_their_parameters(tmp_path: Path) -> None:
    """A store over a DSDL folder of its own: review and export go through that store's
    types (the bundled ones know no PROBE)."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Probe.1.0.dsdl").write_text(
        "# A level probe\n# @max_instances 2\n\nuint8 level\n@sealed\n"
    )
    schema = px4params.load_schema([str(root)], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema)
    store.add("PROBE#1")
    store.set("PROBE#1.level", 7)
    store.save(tmp_path / "probe.store")
    vehicle = StoreVehicle(str(tmp_path / "probe.store"), None, [str(root)], poll_interval=3600)
    try:
        app = make_app(vehicle, token=TOKEN, hosts=[HOST], cookie=COOKIE)
        sent = post(
            app, "/api/review", {"filename": "a.airframe", "text": "param set PROBE_1A 9\n"}
        )
        assert json.loads(body_of(sent)) == {
            "changes": [{"name": "PROBE_1A", "current": 7, "new": 9}],
            "notes": [],
        }
        assert body_of(get(app, "/api/export")).decode().endswith("\n1\t1\tPROBE_1A\t7\t6\n")
        airframe = body_of(get(app, "/api/export", "format=airframe")).decode()
        assert airframe.endswith("\nparam add PROBE#1\nparam set-default PROBE#1[0] 7\n")
    finally:
        vehicle.close()


def test_mask_writes_made_from_one_mask_keep_each_others_instances(
    served: tuple[Admission, StoreVehicle], store_file: Path, schema: px4params.Schema
) -> None:
    # Two pages (or a page and a shell) read INA238_INST = 0b10 and each added one instance:
    # the second write's absolute mask removed the first one's instance, and no one was told.
    app, _ = served

    def write(value: int, was: int | None) -> dict[str, Any]:
        change = {
            "name": "INA238_INST",
            "value": value,
            **({"was": was} if was is not None else {}),
        }
        (result,) = json.loads(body_of(post(app, "/api/write", {"changes": [change]})))["results"]
        return result

    def instances() -> list[str]:
        saved = px4params.Store.load(store_file, schema, classic=BUNDLED_CLASSIC)
        return saved.instances("INA238")

    assert write(0b011, was=0b010) == {
        "name": "INA238_INST",
        "ok": True,
        "value": 0b011,
        "reason": "",
    }
    assert write(0b110, was=0b010)["value"] == 0b111  # #0 stays
    assert instances() == ["INA238#0", "INA238#1", "INA238#2"]
    # A shell adds INA238#3 to the file; a page that saw 0b111 removes #0: #3 stays.
    shell = px4params.Store.load(store_file, schema, classic=BUNDLED_CLASSIC)
    shell.add("INA238#3")
    shell.save(store_file)
    assert write(0b110, was=0b111)["value"] == 0b1110
    assert instances() == ["INA238#1", "INA238#2", "INA238#3"]
    # Without the mask it was made from, a mask is written as given, as a ground station's is.
    assert write(0b010, was=None)["value"] == 0b010
    assert instances() == ["INA238#1"]


@pytest.mark.parametrize(
    ("body", "why"),
    [
        # Each said what Python found wrong inside (helper-111): "None: unknown parameter
        # 'None'", "list indices must be integers or slices, not str", "use
        # sys.set_int_max_str_digits()", and a finite number called "inf".
        (b'{"changes": [{"name": null, "value": 1}]}', "change 0: the name is null, not text"),
        (b'{"changes": [{"name": {"a": 1}, "value": 1}]}',
         "change 0: the name is an object, not text"),
        (b'{"changes": {"name": "INA238_1C", "value": 70}}', "'changes' is an object, not a list"),
        (b'{"changes": [5]}', "change 0 is a number, not an object"),
        (b"[]", "the body has no 'changes'"),
        (b"null", "the body has no 'changes'"),
        (b'{"changes": [{"name": "INA238_1C", "value": 1' + b"0" * 4999 + b"}]}",
         "a number of 5000 digits (no parameter holds one)"),
        (b'{"changes": [{"name": "INA238_1Q", "value": 9' + b"9" * 4999 + b".5}]}",
         "99999999999999999999...: beyond the range of a float"),
        (b'{"changes": [{"name": "INA238_1C", "value": 70}]}\xff', "not JSON: not UTF-8"),
    ],
)  # fmt: skip
def test_a_write_body_of_the_wrong_shape_is_named_piece_by_piece(
    served: tuple[Admission, StoreVehicle], body: bytes, why: str
) -> None:
    app, vehicle = served
    sent = post(app, "/api/write", body)
    assert status_of(sent) == 400
    assert error_of(sent) == f"expected {{'changes': [{{'name', 'value'}}]}}: {why}"
    assert vehicle.values["INA238_1C"] == 0x45


def test_a_write_whose_changes_are_not_a_list_is_400_whatever_their_length(
    served: tuple[Admission, StoreVehicle],
) -> None:
    app, _ = served
    for changes in ("x" * 300, {"name": "INA238_1C", "value": 70}, 5):
        sent = post(app, "/api/write", {"changes": changes})
        assert status_of(sent) == 400, changes
        assert error_of(sent).startswith("expected {'changes': [{'name', 'value'}]}: ")


# -- the WebSocket when the connection fails (issue 40) ----------------------------------------


async def _failing_socket(
    app: Admission, vehicle: StoreVehicle, *, receive_fails: bool
) -> list[dict[str, Any]]:
    """Opens /ws over a connection that fails: the client's receive raises (a reset), or the
    server's send of the first event does (a client gone: the server's ``ClientDisconnected``
    is an OSError). Returns what the loop reported to its exception handler."""
    loop = asyncio.get_running_loop()
    reported: list[dict[str, Any]] = []
    loop.set_exception_handler(lambda _loop, context: reported.append(context))
    accepted = asyncio.Event()
    incoming: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
    incoming.put_nowait({"type": "websocket.connect"})

    async def receive() -> dict[str, Any]:
        message = await incoming.get()
        if message["type"] == "reset":
            raise ConnectionResetError("connection reset by peer")
        return message

    async def send(message: dict[str, Any]) -> None:
        if message["type"] == "websocket.accept":
            accepted.set()
        elif message["type"] == "websocket.send":
            raise ConnectionResetError("the client is gone")

    scope = {
        "type": "websocket",
        "path": "/ws",
        "root_path": "",
        "query_string": b"",
        "headers": [(k.lower().encode(), v.encode()) for k, v in authorized()],
        "subprotocols": [],
    }
    served = asyncio.ensure_future(app(scope, receive, send))
    await asyncio.wait_for(accepted.wait(), 10)
    if receive_fails:
        incoming.put_nowait({"type": "reset"})
    else:
        assert (await asyncio.to_thread(vehicle.write, "INA238_1C", 71)).ok
    await asyncio.wait_for(served, 10)  # ends, and without an error
    del served
    gc.collect()  # a task whose error nobody read says so when it is collected
    await asyncio.sleep(0)
    return reported


@pytest.mark.issue40
@pytest.mark.parametrize("receive_fails", [True, False], ids=["reset", "client_gone"])
def test_a_socket_whose_connection_fails_ends_quietly_and_stops_listening(
    served: tuple[Admission, StoreVehicle], receive_fails: bool
) -> None:
    app, vehicle = served
    reported = asyncio.run(_failing_socket(app, vehicle, receive_fails=receive_fails))
    assert reported == []  # no "Task exception was never retrieved", no error of the handler
    assert vehicle._listeners == []


@pytest.mark.issue40
def test_the_module_exports_make_app() -> None:
    namespace: dict[str, Any] = {}
    exec("from px4params.gui.app import *", namespace)
    assert namespace["make_app"] is make_app


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("value", "why"),
    [
        (True, "True is not a number"),  # JSON's true is no number, though Python's bool is an int
        (None, "None is not a number"),
        ({"v": 1}, "{'v': 1} is not a number"),
        (70.5, "70.5 is not an integer"),  # INA238_1C is an Int32
        ("70.5", "'70.5' is not an integer (decimal, or hexadecimal with 0x)"),
        ("7_0", "'7_0' is not an integer (decimal, or hexadecimal with 0x)"),  # int() took it
        (" 70 ", "' 70 ' is not an integer (decimal, or hexadecimal with 0x)"),
    ],
)
def test_a_value_that_is_no_number_of_its_parameter_s_type_is_named_whole(
    served: tuple[Admission, StoreVehicle], value: Any, why: str
) -> None:
    app, vehicle = served
    sent = post(app, "/api/write", {"changes": [{"name": "INA238_1C", "value": value}]})
    assert status_of(sent) == 400
    assert error_of(sent) == f"expected {{'changes': [{{'name', 'value'}}]}}: {why}"
    assert vehicle.values["INA238_1C"] == 0x45
