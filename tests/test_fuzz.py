"""Fuzzing what reads untrusted bytes: the decoders of every bundled type, the store file loader,
CAN frame reassembly, the SLCAN adapter and the DroneCAN node, the MAVLink server's packet
handler, and DSDL loading of random and hostile type trees. Each must answer with a value or
its own error (a :class:`Px4ParamsError`), never anything else, and a refused store file
changes nothing.

CI runs a small budget; ``scripts/fuzz.sh`` runs the same tests with a large one
(``PX4PARAMS_HYPOTHESIS_SCALE``) and prints the counts.
"""

from __future__ import annotations

import contextlib
import random
import zlib
from pathlib import Path
from typing import Any

import px4params
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from px4params import _native
from px4params.errors import DsdlError, Px4ParamsError, StoreFileError
from px4params.links.can_transfer import Frame, TransferReceiver
from px4params.links.slcan import SlcanAdapter
from px4params.store.classic import BUNDLED_CLASSIC
from px4params.store.file import encode_file
from strategies import LONG_RUN, budget

SCHEMA = px4params.load_schema(use_env=False)
KEYS = sorted(SCHEMA.keys())


def fuzz(examples: int) -> settings:
    """The budget; in the long run also a deadline, so that an input that takes a reader
    minutes (a denial of service) is reported with the input, like a crash."""
    deadline = 20_000 if LONG_RUN else None
    return settings(
        max_examples=budget(examples), deadline=deadline, suppress_health_check=list(HealthCheck)
    )


@fuzz(300)
@given(key=st.sampled_from(KEYS), data=st.binary(max_size=300), tao=st.booleans())
def test_decoders_answer_or_refuse(key: str, data: bytes, tao: bool) -> None:
    t = SCHEMA[key]
    try:
        value = t.decode(data, tao=tao, allow_trailing=True)
    except Px4ParamsError:
        return
    # What decodes is a value of the type: it encodes (p_version is the encoder's to set, and
    # a decoded one may be any number), and that decodes to the same value.
    again = t.encode(_without_version(value), tao=tao)
    assert t.encode(t.decode(again, tao=tao), tao=tao) == again


def _without_version(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _without_version(v) for k, v in value.items() if k != "p_version"}
    if isinstance(value, list):
        return [_without_version(v) for v in value]
    return value


def _store_bytes() -> tuple[px4params.Store, bytes]:
    store = px4params.Store(SCHEMA, classic=BUNDLED_CLASSIC)
    store.add("INA238#0")
    store.add("INA238#2")
    store.set("INA238#2.current", 150)
    store.set_default("SYS_AUTOSTART", 4001)
    store.add("AK09916#1")
    return store, encode_file(store)


STORE, GOOD = _store_bytes()


@fuzz(300)
@given(data=st.data())
def test_mutated_store_files_load_whole_or_not_at_all(
    data: st.DataObject, tmp_path_factory
) -> None:
    raw = bytearray(GOOD)
    for _ in range(data.draw(st.integers(1, 8))):
        kind = data.draw(st.sampled_from(["flip", "set", "cut", "insert"]))
        at = data.draw(st.integers(0, max(0, len(raw) - 1)))
        if kind == "flip" and raw:
            raw[at] ^= 1 << data.draw(st.integers(0, 7))
        elif kind == "set" and raw:
            raw[at] = data.draw(st.integers(0, 255))
        elif kind == "cut":
            del raw[at:]
        else:
            raw[at:at] = data.draw(st.binary(min_size=1, max_size=8))
    path = tmp_path_factory.mktemp("mutated") / "m.store"
    path.write_bytes(bytes(raw))
    store = px4params.Store(SCHEMA, classic=BUNDLED_CLASSIC)
    store.set("SYS_AUTOSTART", 7)
    before = encode_file(store)
    try:
        store.load_from(path)
    except StoreFileError:
        assert encode_file(store) == before  # refused: nothing applied
        return
    # Accepted: only a file whose CRC-32 trailer holds (checked here with zlib, not by the
    # loader), and what was loaded saves back to a file that loads to the same store.
    assert len(raw) >= 14 and zlib.crc32(raw[:-4]) == int.from_bytes(raw[-4:], "little")
    saved = encode_file(store)
    again = px4params.Store(SCHEMA, classic=BUNDLED_CLASSIC)
    path.write_bytes(saved)
    again.load_from(path)
    assert encode_file(again) == saved


@fuzz(300)
@given(
    frames=st.lists(st.tuples(st.integers(0, (1 << 29) - 1), st.binary(max_size=8)), max_size=40)
)
def test_frame_reassembly_never_breaks(frames: list[tuple[int, bytes]]) -> None:
    receiver = TransferReceiver()
    for can_id, data in frames:
        done = receiver.feed(Frame(can_id, data))
        if done is not None:
            with contextlib.suppress(Px4ParamsError):
                _native.reassemble(done.datas, signature=0x1234)
    with contextlib.suppress(Px4ParamsError):
        _native.reassemble([d for _, d in frames], signature=0)


@fuzz(200)
@given(data=st.binary(max_size=400))
def test_slcan_adapter_takes_any_bytes(data: bytes) -> None:
    adapter = SlcanAdapter()
    replies, frames = adapter.feed(b"O\r" + data)
    assert all(len(f.data) <= 8 for f in frames)
    assert set(replies) <= set(b"\r\x07Zz" + b"V1013vpx4paramsNPX4PF00")


class _NullPort:
    def fileno(self) -> int:
        return -1

    def read(self, size: int) -> bytes:
        return b""

    def write(self, data: bytes) -> int:
        return len(data)


NODE_STORE = px4params.Store(SCHEMA, classic=BUNDLED_CLASSIC)
NODE_STORE.add("INA238#1")


@fuzz(200)
@given(
    frames=st.lists(
        st.tuples(
            st.integers(0, 31),  # priority
            st.sampled_from([1, 5, 10, 11, 99]),  # GetNodeInfo, RestartNode, ExecuteOpcode, GetSet
            st.integers(1, 127),  # source
            st.binary(min_size=1, max_size=8),
        ),
        max_size=30,
    )
)
def test_dronecan_node_answers_or_ignores(frames: list[tuple[int, int, int, bytes]]) -> None:
    from px4params.links.dronecan_node import DronecanParamNode

    node = DronecanParamNode(NODE_STORE, _NullPort(), schema=SCHEMA)
    before = encode_file(NODE_STORE)
    for priority, dtid, source, data in frames:
        can_id = priority << 24 | dtid << 16 | 1 << 15 | 1 << 8 | 1 << 7 | source
        node.on_frame(Frame(can_id, data))
    # Random frames carry no valid write (CRC-16 per multi-frame transfer, exact shapes).
    assert encode_file(NODE_STORE) == before or node.stats["accepted"]


@fuzz(200)
@given(datagram=st.binary(max_size=300), fields=st.lists(st.integers(0, 2**32 - 1), max_size=12))
def test_mavlink_server_survives_any_datagram(datagram: bytes, fields: list[int]) -> None:
    from pymavlink.dialects.v20 import common as mavlink

    server = _MAVLINK_SERVER
    peer = ("127.0.0.1", 9)
    for msg in server._parse(peer, datagram):
        server._handle(peer, msg)
    # A well-formed message with random fields.
    rng = random.Random(sum(fields) + len(datagram))
    mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    name = rng.choice(["PARAM_SET", "PARAM_REQUEST_READ", "COMMAND_LONG", "FILE_TRANSFER_PROTOCOL"])
    cls = getattr(mavlink, f"MAVLink_{name.lower()}_message")
    args: list[Any] = []
    for field_type in cls.fieldtypes:
        if field_type == "char":
            args.append(bytes(rng.choice(b"AB_#") for _ in range(rng.randint(0, 16))))
        elif field_type == "float":
            args.append(rng.choice([0.0, 1.5, float("nan"), 1e30, -1.0]))
        elif "[" in field_type or field_type.startswith("uint8_t["):
            args.append([rng.randint(0, 255) for _ in range(251)])
        else:
            args.append(fields.pop() % 256 if fields else rng.randint(0, 255))
    try:
        message = cls(*args)
        packed = message.pack(mav)
    except Exception:  # pymavlink refuses some random field combinations itself
        assume(False)
        return
    for msg in server._parse(peer, packed):
        server._handle(peer, msg)


@pytest.fixture(scope="module", autouse=True)
def _mavlink_server() -> Any:
    from px4params.links.mavlink import MavlinkParamServer

    global _MAVLINK_SERVER
    store = px4params.Store(SCHEMA, classic=BUNDLED_CLASSIC)
    store.add("INA238#0")
    server = MavlinkParamServer(store, "127.0.0.1", 0)
    server._send = lambda *a, **k: None  # type: ignore[method-assign]  # no peer to answer
    _MAVLINK_SERVER = server
    yield server
    server._sock.close()


_MAVLINK_SERVER: Any = None


# -- hostile DSDL trees ------------------------------------------------------------------------


@st.composite
def type_trees(draw: st.DrawFn) -> dict[str, str]:
    """A few types referring to each other: deep nesting, huge arrays, wide unions."""
    count = draw(st.integers(1, 6))
    files: dict[str, str] = {}
    for i in range(count):
        lines = []
        union = draw(st.booleans()) and i > 0
        width = draw(st.integers(2, 300)) if union else draw(st.integers(1, 4))
        for n in range(width):
            if i > 0 and draw(st.booleans()):
                elem = f"T{draw(st.integers(0, i - 1))}.1.0"
            else:
                elem = draw(st.sampled_from(["uint8", "int3", "float16", "bool", "uint64"]))
            shape = draw(st.sampled_from(["", "[{}]", "[<={}]"]))
            size = draw(st.sampled_from([1, 2, 7, 255, 65535, 100_000_000]))
            lines.append(f"{elem}{shape.format(size)} f{n}")
        files[f"T{i}.1.0.dsdl"] = ("@union\n" if union else "") + "\n".join(lines) + "\n@sealed\n"
    return files


@fuzz(15)
@given(files=type_trees())
def test_hostile_type_trees_load_or_are_refused(files: dict[str, str], tmp_path_factory) -> None:
    root = tmp_path_factory.mktemp("trees") / "fz"
    root.mkdir()
    for name, text in files.items():
        (root / name).write_text(text)
    try:
        schema = px4params.load_schema(
            [root], include_dronecan=False, use_env=False, cache_dir=root.parent / "cache"
        )
    except DsdlError:
        return
    for key in schema.keys():  # noqa: SIM118 - a Schema, not a dict
        if key.startswith("fz."):
            t = schema[key]
            assert t.max_bits <= 65535 * 8
            t.default()


def test_the_long_run_is_documented() -> None:
    script = Path(__file__).resolve().parents[1] / "scripts" / "fuzz.sh"
    assert "PX4PARAMS_HYPOTHESIS_SCALE" in script.read_text()
