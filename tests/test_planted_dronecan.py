"""DroneCAN rules that a wrong product would break without the rest of the suite noticing
(issue 40: bugs planted one at a time stayed green). Each expected answer comes from the
rule, not from our code:

* ``uavcan.protocol.param.Value`` (DroneCAN DSDL, as pydronecan ships it) carries
  ``boolean_value`` as a ``uint8`` "for alignment reasons": only 0 and 1 are booleans. A GetSet
  request whose value is not one is refused, and the response carries the value the node
  still holds (GetSet.uavcan: the response is the parameter's state after the request).
* UAVCAN v0 specification, "Transfer reception": a transfer with the same transfer ID from
  the same source is a duplicate (a redundant interface) only within the transfer timeout,
  2 s; after it, the same transfer ID starts a new transfer (the 5-bit ID wraps every 32
  transfers, so a node sending once a second reuses an ID every 32 s).
"""

from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Any

import dronecan
import px4params
import pytest
from dronecan import transport
from dronecan_bus import PX4PARAMS, served
from px4params.errors import EncodeError, Px4ParamsError
from px4params.links.can_transfer import (
    DEFAULT_PRIORITY,
    CanId,
    Frame,
    TransferReceiver,
    can_id,
    frames,
    parse_can_id,
    reassemble,
)
from px4params.links.dronecan_params import DronecanParams
from px4params.store.classic import BUNDLED_CLASSIC

GETSET = dronecan.uavcan.protocol.param.GetSet
OPCODE = dronecan.uavcan.protocol.param.ExecuteOpcode
NODE = 1
#: An IST8310 magnetometer: its ``internal`` field is a DSDL ``bool`` (dsdl/px/Ist8310.1.0.dsdl)
#: with ``@default false``; DroneCAN's long name of instance 0's is IST8310_0_INTERNAL.
AIRFRAME = "param add IST8310#0\nparam set-default IST8310#0.bus.i2c.bus_id 1\n"
BOOLEAN = "IST8310_0_INTERNAL"


@pytest.fixture
def ist8310_store(tmp_path: Path) -> Path:
    airframe = tmp_path / "ist8310.airframe"
    airframe.write_text(AIRFRAME)
    store = tmp_path / "vehicle.store"
    subprocess.run(
        [*PX4PARAMS, "run", str(airframe), "--store", str(store)],
        check=True,
        capture_output=True,
        timeout=120,
    )
    return store


def _load(path: Path) -> px4params.Store:
    return px4params.Store.load(path, classic=BUNDLED_CLASSIC)


@pytest.mark.parametrize("number", [2, 255])
def test_getset_boolean_outside_0_1_is_refused_and_the_value_unchanged(
    ist8310_store: Path, number: int
) -> None:
    store = _load(ist8310_store)
    params = DronecanParams(store)
    entry = params.entry(BOOLEAN)
    assert entry is not None and entry.value == {"boolean_value": 0}  # @default false
    before = {n: store.encoded(n) for n in store.names()}
    with pytest.raises(Px4ParamsError) as refused:
        params.set(BOOLEAN, {"boolean_value": number})
    assert str(refused.value) == f"{BOOLEAN}: value {number} is not a boolean (0 or 1)"
    assert {n: store.encoded(n) for n in store.names()} == before
    assert store.get("IST8310#0.internal") is False
    # 1 and 0 are booleans: taken.
    params.set(BOOLEAN, {"boolean_value": 1})
    assert store.get("IST8310#0.internal") is True
    params.set(BOOLEAN, {"boolean_value": 0})
    assert store.get("IST8310#0.internal") is False
    # GetSet's bounds are a NumericValue (no boolean variant): integers 0 and 1.
    entry = params.entry(BOOLEAN)
    assert entry is not None
    assert (entry.default, entry.min, entry.max) == (
        {"boolean_value": 0},
        {"integer_value": 0},
        {"integer_value": 1},
    )


def _active(value: Any) -> tuple[str, Any]:
    kind = dronecan.get_active_union_field(value)
    return kind, getattr(value, kind) if kind != "empty" else None


def test_pydronecan_getset_of_boolean_2_answers_the_unchanged_value(ist8310_store: Path) -> None:
    """The same rule end to end: pydronecan (its own SLCAN driver) asks ``dronecan serve``."""
    with served(ist8310_store) as path:
        node = dronecan.make_node(path, node_id=100, bitrate=1_000_000)
        try:

            def call(request: Any) -> Any:
                got: list[Any] = []
                node.request(request, NODE, got.append, timeout=3.0)
                for _ in range(400):  # at most about 4 s
                    if got:
                        break
                    node.spin(0.01)
                assert got and got[0] is not None, f"no response to {type(request).__name__}"
                return got[0].response

            def getset(**value: Any) -> Any:
                request = GETSET.Request(name=BOOLEAN.encode())
                if value:
                    request.value = dronecan.uavcan.protocol.param.Value(**value)
                return call(request)

            assert _active(getset().value) == ("boolean_value", 0)
            assert _active(getset(boolean_value=2).value) == ("boolean_value", 0)
            assert _active(getset().value) == ("boolean_value", 0)
            assert call(OPCODE.Request(opcode=OPCODE.Request().OPCODE_SAVE)).ok
        finally:
            node.close()
    assert _load(ist8310_store).get("IST8310#0.internal") is False
    assert f"refused: {BOOLEAN}: value 2 is not a boolean (0 or 1)" in served.output  # type: ignore[attr-defined]


# -- the transfer timeout ------------------------------------------------------------------------


class Clock:
    """A clock the test moves by hand (no sleeping, no timing in assertions)."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def _frames(tid: int, *, long: bool) -> list[Frame]:
    """pydronecan's frames of one transfer from node 10: a NodeStatus message (one frame), or
    a GetSet response to node 20 (several)."""
    if long:
        payload = GETSET.Response(
            name=b"INA238_1_CURRENT", value=dronecan.uavcan.protocol.param.Value(integer_value=7)
        )
        dest, service = 20, True
    else:
        payload = dronecan.uavcan.protocol.NodeStatus(uptime_sec=42)
        dest, service = None, False
    t = transport.Transfer(
        payload=payload,
        source_node_id=10,
        dest_node_id=dest,
        transfer_id=tid,
        service_not_message=service,
        request_not_response=False,
    )
    return [Frame(f.message_id, bytes(f.bytes)) for f in t.to_frames()]


def _delivered(receiver: TransferReceiver, frames: list[Frame]) -> int:
    return sum(receiver.feed(f) is not None for f in frames)


@pytest.mark.parametrize("long", [False, True], ids=["single-frame", "multi-frame"])
def test_same_transfer_id_after_the_2s_timeout_is_a_new_transfer(long: bool) -> None:
    frames = _frames(5, long=long)
    assert (len(frames) > 1) == long
    clock = Clock()
    receiver = TransferReceiver(clock=clock)
    assert _delivered(receiver, frames) == 1
    clock.now += 1.0  # within the timeout: the same transfer again (a redundant interface)
    assert _delivered(receiver, frames) == 0
    clock.now += 1.5  # 2.5 s after the first: transfer ID 5 again is a new transfer
    assert _delivered(receiver, frames) == 1
    clock.now += 30.0  # and so after any longer silence
    assert _delivered(receiver, frames) == 1
    # Another transfer ID from the same source is new at once.
    assert _delivered(receiver, _frames(6, long=long)) == 1


# -- CAN IDs (issue 40's mutation run: what survived in can_transfer.py) -------------------------


def _pydronecan_can_id(payload: Any, *, source: int, dest: int | None, request: bool) -> int:
    t = transport.Transfer(
        payload=payload,
        source_node_id=source,
        dest_node_id=dest,
        transfer_id=0,
        transfer_priority=DEFAULT_PRIORITY,
        service_not_message=dest is not None,
        request_not_response=request,
    )
    return int(t.to_frames()[0].message_id)


def test_can_ids_are_pydronecans_and_a_service_frame_is_a_response_unless_told() -> None:
    status = dronecan.uavcan.protocol.NodeStatus()
    assert can_id(341, source_node=10) == _pydronecan_can_id(
        status, source=10, dest=None, request=False
    )
    response = GETSET.Response()
    request = GETSET.Request()
    # Without request=True a service frame is a response: bit 15 clear.
    assert can_id(11, source_node=10, dest_node=20) == _pydronecan_can_id(
        response, source=10, dest=20, request=False
    )
    assert can_id(11, source_node=10, dest_node=20, request=True) == _pydronecan_can_id(
        request, source=10, dest=20, request=True
    )
    # The ends of every range are valid (UAVCAN v0: message type IDs 0..65535, service type
    # IDs 0..255, node IDs 1..127, priorities 0..31).
    assert can_id(0, source_node=1, priority=0) == 1
    assert can_id(0xFFFF, source_node=127, priority=31) == 31 << 24 | 0xFFFF << 8 | 127
    assert can_id(0, source_node=1, dest_node=1, priority=0) == 1 << 8 | 1 << 7 | 1
    assert can_id(0xFF, source_node=127, dest_node=127) == (
        31 << 24 | 0xFF << 16 | 127 << 8 | 1 << 7 | 127
    )


#: can_id's arguments, then the number refused: its name, range and value as the message gives
#: them ("priority must be an integer in 0..31, got 32").
OUT_OF_RANGE: list[tuple[dict[str, Any], str, str, str]] = [
    ({"dtid": 341, "source_node": 10, "priority": 32}, "priority", "0..31", "32"),
    ({"dtid": 341, "source_node": 10, "priority": -1}, "priority", "0..31", "-1"),
    ({"dtid": 341, "source_node": 0}, "source node ID", "1..127", "0"),
    ({"dtid": 341, "source_node": 128}, "source node ID", "1..127", "128"),
    ({"dtid": 341, "source_node": True}, "source node ID", "1..127", "True"),
    ({"dtid": 341, "source_node": 1.0}, "source node ID", "1..127", "1.0"),
    ({"dtid": 65536, "source_node": 10}, "message data type ID", "0..65535", "65536"),
    ({"dtid": -1, "source_node": 10}, "message data type ID", "0..65535", "-1"),
    ({"dtid": 256, "source_node": 10, "dest_node": 20}, "service data type ID", "0..255", "256"),
    ({"dtid": -1, "source_node": 10, "dest_node": 20}, "service data type ID", "0..255", "-1"),
    ({"dtid": 11, "source_node": 10, "dest_node": 0}, "destination node ID", "1..127", "0"),
    ({"dtid": 11, "source_node": 10, "dest_node": 128}, "destination node ID", "1..127", "128"),
]


@pytest.mark.parametrize(("arguments", "what", "limits", "given"), OUT_OF_RANGE)
def test_can_id_refuses_numbers_out_of_range_by_name(
    arguments: dict[str, Any], what: str, limits: str, given: str
) -> None:
    with pytest.raises(ValueError) as refused:
        can_id(**arguments)
    assert str(refused.value) == f"{what} must be an integer in {limits}, got {given}"


# -- GetSet entries (issue 40's mutation run: what survived in dronecan_params.py) ---------------

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "two_batteries.airframe"
INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1
#: IEEE 754 single precision's largest finite value, (2 - 2**-23) * 2**127.
FLT_MAX = (2 - 2**-23) * 2.0**127


@pytest.fixture
def example_params(tmp_path: Path) -> tuple[px4params.Store, DronecanParams]:
    store_path = tmp_path / "vehicle.store"
    subprocess.run(
        [*PX4PARAMS, "run", str(EXAMPLE), "--store", str(store_path)],
        check=True,
        capture_output=True,
        timeout=120,
    )
    store = _load(store_path)
    return store, DronecanParams(store)


def _integers(*numbers: int) -> tuple[dict[str, int], ...]:
    return tuple({"integer_value": n} for n in numbers)


def test_getset_entries_of_classic_parameters_and_masks(
    example_params: tuple[px4params.Store, DronecanParams],
) -> None:
    """Bounds and defaults as PX4's parameter metadata gives them (BAT1_CAPACITY: Float,
    default -1 "when unknown", -1..100000 mAh); an Int32 without bounds spans int32, what
    MAVLink and the store can hold; an instance mask of INA238 (@max_instances 4) is 0..15,
    no instance by default."""
    store, params = example_params
    capacity = params.entry("BAT1_CAPACITY")
    assert capacity is not None
    assert (capacity.value, capacity.default, capacity.min, capacity.max) == (
        {"real_value": -1.0},
        {"real_value": -1.0},
        {"real_value": -1.0},
        {"real_value": 100000.0},
    )
    mag = params.entry("CAL_MAG0_ID")
    assert mag is not None
    assert (mag.value, mag.default, mag.min, mag.max) == _integers(0, 0, INT32_MIN, INT32_MAX)
    mask = params.entry("INA238_INST")
    assert mask is not None
    assert (mask.value, mask.default, mask.min, mask.max) == _integers(0b11, 0, 0, 15)
    # Writes say what changed.
    assert params.set("SYS_AUTOSTART", {"integer_value": 4001}) == "SYS_AUTOSTART = 4001"
    assert store.get("SYS_AUTOSTART") == 4001
    assert params.set("INA238_INST", {"integer_value": 0b11}) == "INA238_INST: no change"


def test_getset_entries_of_leaves_keep_their_default_apart(
    example_params: tuple[px4params.Store, DronecanParams],
) -> None:
    _, params = example_params
    params.set("INA238_1_I2C_ADDRESS", {"integer_value": 0x44})
    address = params.entry("INA238_1_I2C_ADDRESS")
    assert address is not None
    assert (address.value, address.default) == _integers(0x44, 0x45)  # the airframe's default
    # On SPI the default (an I2C value) has no such leaf: GetSet's "empty" variant.
    params.set("INA238_1_BUS_TYPE", {"integer_value": 1})
    names = [params.name_at(i) or "" for i in range(len(params))]
    spi = [params.entry(n) for n in names if n.startswith("INA238_1_SPI_")]
    assert len(spi) >= 3  # bus_id, chip_select, mode, ...
    assert all(e is not None and e.default == {"empty": {}} for e in spi)
    # A write without a value is refused by its variant's name.
    with pytest.raises(Px4ParamsError) as refused:
        params.set("INA238_1_SPI_BUS_ID", {})
    assert str(refused.value) == (
        "INA238_1_SPI_BUS_ID: empty refused: the parameter takes integer_value"
    )


def test_getset_bounds_of_float_leaves_are_their_types(tmp_path: Path) -> None:
    """A float32 leaf spans IEEE 754 single precision (its largest finite value is a valid
    bound, sent as real_value), a float16 one +-65504."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Floats.1.0.dsdl").write_text(
        "# Floats\n# @max_instances 1\n\nfloat32 single\n# a\n\nfloat16 half\n# b\n\n@sealed\n"
    )
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("FLOATS#0")
    params = DronecanParams(store)
    single, half = params.entry("FLOATS_0_SINGLE"), params.entry("FLOATS_0_HALF")
    assert single is not None and half is not None
    assert (single.min, single.max) == ({"real_value": -FLT_MAX}, {"real_value": FLT_MAX})
    assert (half.min, half.max) == ({"real_value": -65504.0}, {"real_value": 65504.0})


def test_getset_default_of_an_element_the_default_array_lacks_is_empty(tmp_path: Path) -> None:
    """A dynamic array's default is empty: the elements a value has have no default, which
    GetSet says with its "empty" variant; the length's default is 0, its bounds 0..capacity."""
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Things.1.0.dsdl").write_text(
        "# Things\n# @max_instances 1\n\nuint8[<=3] items\n# x\n\n@sealed\n"
    )
    schema = px4params.load_schema([root], use_env=False, cache_dir=tmp_path / "cache")
    store = px4params.Store(schema, classic=BUNDLED_CLASSIC)
    store.add("THINGS#0")
    store.set("THINGS#0", {"items": [7, 8]})
    params = DronecanParams(store)
    for name, value in (("THINGS_0_ITEMS_0", 7), ("THINGS_0_ITEMS_1", 8)):
        entry = params.entry(name)
        assert entry is not None
        assert (entry.value, entry.default) == ({"integer_value": value}, {"empty": {}})
        assert (entry.min, entry.max) == _integers(0, 255)  # uint8
    length = params.entry("THINGS_0_ITEMS_LEN")
    assert length is not None
    assert (length.value, length.default, length.min, length.max) == _integers(2, 0, 0, 3)


# -- frames, CAN IDs read back, the receiver's limits (what survived in can_transfer.py) --------


@pytest.mark.parametrize(
    "fields",
    [
        CanId(31, 0xFFFF, 127),
        CanId(0, 0, 1),
        CanId(17, 341, 10),
        CanId(31, 0xFF, 127, 127, True),
        CanId(0, 0, 1, 1, False),
        CanId(30, 11, 10, 20, True),
    ],
)
def test_parse_can_id_reads_back_every_field(fields: CanId) -> None:
    identifier = can_id(
        fields.dtid,
        source_node=fields.source_node,
        priority=fields.priority,
        dest_node=fields.dest_node,
        request=fields.request,
    )
    parsed = parse_can_id(identifier)
    assert parsed == fields
    assert parsed.service == (fields.dest_node is not None)
    if fields.dest_node is None:  # a message: no destination, not a request
        assert (parsed.dest_node, parsed.request) == (None, False)


def test_frames_defaults_and_refusals(schema: px4params.Schema) -> None:
    status = schema.get("uavcan.protocol.NodeStatus")
    getset = schema.get("uavcan.protocol.param.GetSet.Request")
    value = {"uptime_sec": 1, "health": 0, "mode": 0, "sub_mode": 0,
             "vendor_specific_status_code": 0}  # fmt: skip
    (frame,) = frames(status, value, source_node=10)
    assert frame.data[-1] == 0xC0  # start and end of transfer, toggle 0, transfer ID 0
    assert frame.can_id == can_id(341, source_node=10)
    with pytest.raises(EncodeError):  # uint2 health: 4 does not fit, no saturation unless asked
        frames(status, {**value, "health": 4}, source_node=10)
    saturated = frames(status, {**value, "health": 4}, source_node=10, saturate=True)
    assert reassemble(status, [f.data for f in saturated])[0]["health"] == 3
    refusals = [
        ({"dest_node": 20}, "uavcan.protocol.NodeStatus is a message; a destination node is "
         "for services"),
        ({}, "uavcan.protocol.param.GetSet.Request is a service request; it needs a "
         "destination node"),
        ({"transfer_id": 32}, "transfer ID must be an integer in 0..31, got 32"),
    ]  # fmt: skip
    for arguments, message in refusals:
        data_type = status if "dest_node" in arguments or "transfer_id" in arguments else getset
        with pytest.raises(ValueError) as refused:
            frames(data_type, value if data_type is status else {}, source_node=10, **arguments)
        assert str(refused.value).startswith(message), str(refused.value)
    response = schema.get("uavcan.protocol.param.GetSet.Response")
    (first, *_) = frames(response, _getset_response("X"), source_node=10, dest_node=20)
    assert parse_can_id(first.can_id).request is False  # a response
    with pytest.raises(ValueError) as refused:
        frames(response, _getset_response("X"), source_node=10)
    assert str(refused.value) == (
        "uavcan.protocol.param.GetSet.Response is a service response; it needs a destination node"
    )
    with pytest.raises(ValueError) as refused:  # a px type has no DroneCAN data type ID
        frames(schema.get("px.Tmp102"), {}, source_node=10)
    assert str(refused.value) == "px.Tmp102.1.0 has no default data type ID; give one"


def _getset_response(name: str) -> dict[str, Any]:
    empty = {"empty": {}}
    return {"value": {"integer_value": -5}, "default_value": empty, "max_value": empty,
            "min_value": empty, "name": name}  # fmt: skip


def test_reassemble_reads_classic_can_by_default(schema: px4params.Schema) -> None:
    response = schema.get("uavcan.protocol.param.GetSet.Response")
    sent = frames(response, _getset_response("INA238_1_SOME_LONG_NAME"), source_node=10,
                  dest_node=20, transfer_id=9)  # fmt: skip
    assert len(sent) > 2  # multi-frame, the name's length left out (tail array optimization)
    got, transfer_id = reassemble(response, [f.data for f in sent])
    assert transfer_id == 9
    assert bytes(got["name"]) == b"INA238_1_SOME_LONG_NAME"
    assert got["value"] == {"integer_value": -5}


def _hand_made_frames(count: int, tid: int = 3) -> list[Frame]:
    """``count`` frames of one transfer from node 10, tail bytes by the rule (start bit on the
    first, end bit on the last, toggle alternating from 0), payload bytes arbitrary."""
    identifier = can_id(341, source_node=10)
    out = []
    for n in range(count):
        tail = (0x80 if n == 0 else 0) | (0x40 if n == count - 1 else 0) | (n & 1) << 5 | tid
        out.append(Frame(identifier, bytes(7) + bytes([tail])))
    return out


def test_receiver_takes_256_frames_and_drops_a_longer_transfer() -> None:
    receiver = TransferReceiver()
    done = [receiver.feed(f) for f in _hand_made_frames(256)]
    assert done[-1] is not None and len(done[-1].datas) == 256
    receiver = TransferReceiver()
    assert all(receiver.feed(f) is None for f in _hand_made_frames(257))
    assert receiver.ignored == 1  # the 257th frame drops the session


def test_receiver_counts_what_it_ignores_and_skips_what_it_does_not_accept() -> None:
    sent = _hand_made_frames(3)
    receiver = TransferReceiver()
    assert receiver.ignored == 0
    # Joined half-way: two frames without a session, each counted once.
    assert [receiver.feed(f) for f in sent[1:]] == [None, None]
    assert receiver.ignored == 2
    # Only services addressed to node 1 accepted: a message is skipped, not counted.
    picky = TransferReceiver(lambda ident: ident.dest_node == 1)
    assert [picky.feed(f) for f in sent] == [None, None, None]
    assert picky.ignored == 0
    everyone = TransferReceiver(lambda ident: True)
    assert [everyone.feed(f) is not None for f in sent] == [False, False, True]


def test_receiver_counts_each_kind_of_ignored_frame() -> None:
    clock = Clock()
    one = _hand_made_frames(1)  # a single-frame transfer, transfer ID 3
    cases: list[tuple[str, list[Frame]]] = [
        ("empty frames", [Frame(one[0].can_id, b""), Frame(one[0].can_id, b"")]),
        ("anonymous frames", [Frame(one[0].can_id & ~0x7F, one[0].data)] * 2),
        ("start frames with the toggle set",
         [Frame(one[0].can_id, bytes([0xA3])), Frame(one[0].can_id, bytes([0xA4]))]),
        ("the same transfer twice again", one * 3),
        ("frames of another transfer ID in a session",
         _hand_made_frames(3)[:1] + _hand_made_frames(3, tid=4)[1:2]
         + _hand_made_frames(3, tid=5)[:1] + _hand_made_frames(3, tid=6)[1:2]),
        ("two transfers of 257 frames", _hand_made_frames(257) + _hand_made_frames(257, tid=4)),
    ]  # fmt: skip
    for what, sent in cases:
        receiver = TransferReceiver(clock=clock)
        for frame in sent:
            receiver.feed(frame)
        assert receiver.ignored == 2, what


def test_receiver_remembers_4096_finished_transfers() -> None:
    """Duplicates are told apart by the last transfer of each session; the oldest record goes
    once more than 4096 sessions finished (many peers over a long time)."""

    def single(dtid: int) -> Frame:
        return Frame(can_id(dtid, source_node=10), bytes([0xC0 | 3]))

    receiver = TransferReceiver()
    assert [receiver.feed(single(d)) is not None for d in range(4096)] == [True] * 4096
    assert receiver.feed(single(0)) is None  # all 4096 remembered: a duplicate
    assert receiver.feed(single(4096)) is not None  # the 4097th: the oldest is forgotten
    assert receiver.feed(single(0)) is not None  # so this is a new transfer
