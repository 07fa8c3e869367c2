"""Flight logs: ``autostart run --ulog`` writes a ULog that pyulog (the library of PX4's log
tools and Flight Review) reads, and ``px4params health`` tells it back.

The expected values are worked out here from the ULog specification (PX4 dev guide, "ULog File
Format") and from the bench file, not taken from the writer.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from px4params.cli.main import main
from px4params.errors import Px4ParamsError, ULogError
from px4params.formats.ulog import ULogWriter
from pyulog import ULog
from shared_data import shared_file

REPO = Path(__file__).resolve().parents[1]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"
FAULTS = REPO / "examples" / "two_batteries_faults.bench.toml"


# -- the writer, byte by byte -------------------------------------------------------------------


def test_header_and_flag_bits() -> None:
    data = ULogWriter(start_us=0x0102030405060708).getvalue()
    # "ULog", 0x01 0x12 0x35, version 1, the start time (uint64, little-endian).
    assert data[:16] == b"\x55\x4c\x6f\x67\x01\x12\x35\x01" + bytes.fromhex("0807060504030201")
    # Flag bits: size 40, type 'B', 8 compat + 8 incompat flag bytes, 3 appended offsets.
    assert data[16:19] == b"\x28\x00B" and data[19:] == bytes(40)


def test_definitions_and_data_bytes() -> None:
    log = ULogWriter()
    log.define("t", [("uint64_t", "timestamp"), ("int16_t", "x"), ("char[3]", "s")])
    log.info("sys_name", "ab")
    log.parameter("P_INT", 7)
    log.parameter("P_FLT", 0.5)
    msg_id = log.subscribe("t")
    log.data(msg_id, 5, -2, "hi")
    log.log("error", 6, "lost")
    body = log.getvalue()[16 + 3 + 40 :]
    fmt = b"t:uint64_t timestamp;int16_t x;char[3] s;"
    key = b"char[2] sys_name"
    expected = b"".join(
        [
            struct.pack("<HB", len(fmt), ord("F")) + fmt,
            struct.pack("<HB", 1 + len(key) + 2, ord("I")) + bytes([len(key)]) + key + b"ab",
            struct.pack("<HB", 1 + 13 + 4, ord("P")) + b"\x0dint32_t P_INT" + b"\x07\x00\x00\x00",
            struct.pack("<HB", 1 + 11 + 4, ord("P")) + b"\x0bfloat P_FLT" + b"\x00\x00\x00\x3f",
            struct.pack("<HB", 3 + 1, ord("A")) + b"\x00\x00\x00t",  # multi ID 0, msg ID 0
            struct.pack("<HB", 2 + 8 + 2 + 3, ord("D")) + b"\x00\x00" + (5).to_bytes(8, "little")
            + b"\xfe\xff" + b"hi\x00",
            struct.pack("<HB", 1 + 8 + 4, ord("L")) + b"3" + (6).to_bytes(8, "little") + b"lost",
        ]
    )  # fmt: skip
    assert body == expected


def test_multi_ids_count_per_message() -> None:
    log = ULogWriter()
    log.define("a", [("uint64_t", "timestamp")])
    log.define("b", [("uint64_t", "timestamp")])
    ids = [log.subscribe(name) for name in ("a", "b", "a", "a")]
    assert ids == [0, 1, 2, 3]
    subscriptions = [m for m in _messages(log.getvalue()) if m[0] == "A"]
    assert [(p[0], p[3:].decode()) for _, p in subscriptions] == [(0, "a"), (0, "b"), (1, "a"),
                                                                   (2, "a")]  # fmt: skip


@pytest.mark.parametrize(
    ("act", "message"),
    [
        (lambda w: w.define("x", [("uint32_t", "time")]), "format x: the first field must be"),
        (lambda w: w.define("x", [("uint64_t", "timestamp"), ("int", "y")]), "x.y: unknown ULog"),
        (lambda w: w.define("x", [("uint64_t", "timestamp"), ("char[", "y")]), "bad array type"),
        (lambda w: w.subscribe("nothing"), "no format nothing defined"),
        (lambda w: (w.log("info", 1, "a"), w.info("k", "v")), "information k after the first"),
        (lambda w: (w.log("info", 9, "a"), w.log("info", 8, "b")), "timestamp 8 us is before"),
        (lambda w: w.info("k", "v" * 70000), "'I' of 70014 bytes \\(at most 65535\\)"),
    ],
)
def test_writer_errors(act, message) -> None:
    with pytest.raises(ULogError, match=message) as info:
        act(ULogWriter())
    assert isinstance(info.value, Px4ParamsError) and "\n" not in str(info.value)


def _messages(data: bytes) -> list[tuple[str, bytes]]:
    """The messages of a ULog file, by an independent reading of the framing."""
    assert data[:7] == b"ULog\x01\x12\x35"
    pos, out = 16, []
    while pos < len(data):
        size, kind = struct.unpack_from("<HB", data, pos)
        out.append((chr(kind), data[pos + 3 : pos + 3 + size]))
        pos += 3 + size
    assert pos == len(data)
    return out


# -- a faulty bench run, read with pyulog ---------------------------------------------------------


def _run(tmp_path: Path, capsys, *args: str) -> tuple[int, Path, str]:
    log = tmp_path / "run.ulg"
    status = main(
        ["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(FAULTS), "--ulog",
         str(log), *args]
    )  # fmt: skip
    out = capsys.readouterr()
    assert out.err == ""
    return status, log, out.out


def _name(data, n: int) -> str:
    """A char[] field as pyulog gives it (one int8 column per character)."""
    chars = [int(data[f"instance[{i}]"][n]) for i in range(24)]
    return bytes(c for c in chars if c).decode()


def test_faulty_bench_log_read_with_pyulog(tmp_path, capsys) -> None:
    status, path, out = _run(tmp_path, capsys)
    assert status == 1 and f"to {path}" in out
    ulog = ULog(str(path))
    info = ulog.msg_info_dict
    assert info["sys_name"] == "px4params" and info["px4params_mode"] == "manifest"
    assert info["px4params_duration_us"] == "10000000"
    assert ulog.msg_info_multiple_dict["manifest_instance"] == [
        ["INA238#0 ina238 on I2C bus 1 address 0x45"],
        ["INA238#1 ina238 on I2C bus 2 address 0x45"],
        ["AK09916#0 ak09916 on I2C bus 1 address 0x0C"],
    ]
    # Parameters: classic ones and the destructured names a ground station sees.
    params = ulog.initial_parameters
    assert params["SENS_EXT_I2C_PRB"] == 1
    assert params["INA238_1C"] == 0x45  # INA238#1's I2C address (letter C: bus.i2c.address)
    assert params["INA238_INST"] == 0b11  # the instance mask: INA238#0 and #1

    topics = {(d.name, d.multi_id): d.data for d in ulog.data_list}
    assert {name for name, _ in topics} == {"driver_health", "driver_perf", "arming_check"}
    # Multi IDs: one per instance, in the manifest's order.
    for multi_id, name in enumerate(["INA238#0", "INA238#1", "AK09916#0"]):
        for topic in ("driver_health", "driver_perf"):
            data = topics[(topic, multi_id)]
            assert {_name(data, n) for n in range(len(data["timestamp"]))} == {name}
    # Published device IDs, from the bench's buses and addresses and drv_sensor.h's devtypes.
    ina1 = topics[("driver_health", 1)]
    assert int(ina1["device_id"][-1]) == (0xD4 << 16) | (0x45 << 8) | (2 << 3) | 1
    assert int(topics[("driver_health", 2)]["device_id"][-1]) == 0x090C09
    # Timestamps never go back, in every topic and in the logged messages.
    for data in topics.values():
        stamps = [int(t) for t in data["timestamp"]]
        assert stamps == sorted(stamps) and stamps[-1] <= 10_000_000
    logged = [int(m.timestamp) for m in ulog.logged_messages]
    assert logged == sorted(logged)
    # INA238#1 dies at 6 s: healthy before, critical at the end, one reset (timeout) counted.
    health = list(zip(ina1["timestamp"], ina1["health"], strict=True))
    assert all(h == 0 for t, h in health if 100_000 <= t < 6_000_000)
    assert health[-1][1] == 2
    assert int(topics[("driver_perf", 1)]["timeouts"][-1]) == 1
    # Logged messages with PX4's levels.
    said = [(m.log_level_str(), m.message) for m in ulog.logged_messages]
    assert ("ERROR", "ina238 INA238#1: device lost on I2C bus 2 address 0x45: 10 bad transfers in "
            "a row") in said  # fmt: skip
    assert ("WARNING", "commander: arming refused: AK09916#0, INA238#0") in said
    assert any(level == "INFO" and text.startswith("ak09916 AK09916#0: started") for level, text
               in said)  # fmt: skip


def test_perf_counters_continuous_across_arming(tmp_path, capsys) -> None:
    # --legacy, seed 3: the commander says "may arm" at 0.1 s and "refused" at 6.5 s.
    status, path, _ = _run(tmp_path, capsys, "--legacy", "--seed", "3")
    assert status == 1
    ulog = ULog(str(path))
    arming = next(d.data for d in ulog.data_list if d.name == "arming_check")
    changes = [
        (int(t), bool(ok))
        for n, (t, ok) in enumerate(zip(arming["timestamp"], arming["may_arm"], strict=True))
        if n == 0 or bool(ok) != bool(arming["may_arm"][n - 1])
    ]
    assert changes == [(100_000, True), (6_500_000, False)]
    perf = next(d.data for d in ulog.data_list if d.name == "driver_perf")
    stamps = [int(t) for t in perf["timestamp"]]
    assert stamps == [n * 1_000_000 for n in range(1, 11)]  # every second, armed or not
    transfers = [int(x) for x in perf["transfers"]]
    assert transfers == sorted(transfers) and transfers[0] > 0
    assert ulog.msg_info_multiple_dict["silently_missing"] == [
        ["ina238 INA238#0 on I2C bus 1 address 0x45: never started, nobody was told"],
        ["ak09916 AK09916#0 on I2C bus 1 address 0x0C: never started, nobody was told"],
    ]


@pytest.mark.skipif(shutil.which("ulog_info") is None, reason="pyulog's ulog_info is not on PATH")
def test_pyulog_command_line_tools_read_it(tmp_path, capsys) -> None:
    _, path, _ = _run(tmp_path, capsys)
    info = subprocess.run(
        ["ulog_info", str(path)], capture_output=True, text=True, check=True, timeout=60
    ).stdout
    assert "driver_health" in info and "sys_name: px4params" in info
    messages = subprocess.run(
        ["ulog_messages", str(path)], capture_output=True, text=True, check=True, timeout=60
    ).stdout
    assert "device lost on I2C bus 2 address 0x45" in messages
    subprocess.run(["ulog2csv", "-o", str(tmp_path), str(path)], check=True, timeout=60)
    rows = (tmp_path / "run_driver_perf_1.csv").read_text().splitlines()
    assert rows[0].startswith("timestamp,transfers,errors,timeouts,probe_attempts,elapsed_us")
    assert len(rows) == 1 + 10


# -- px4params health -----------------------------------------------------------------------------


def test_health_tells_the_story(tmp_path, capsys) -> None:
    direct = tmp_path / "direct.svg"
    _, path, _ = _run(tmp_path, capsys, "--timeline", str(direct))
    picture = tmp_path / "from_log.svg"
    assert main(["health", str(path), "--timeline", str(picture)]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[1] == "first failure: INA238#1 (ina238) at 6.50 s: no data for 0.6 s"
    assert out[2] == "commander: refused at 0.10 s"
    at = out.index("INA238#1 (ina238 on I2C bus 2 address 0x45, device ID 0xD44511)")
    assert "     6.90 s  lost (driver reset)" in out[at:]
    assert any(line.startswith("  at the end: critical; ") and "1 timeout," in line
               for line in out[at:])  # fmt: skip
    # The picture drawn from the log is the picture drawn from the run.
    assert picture.read_text() == direct.read_text()


def test_health_json(tmp_path, capsys) -> None:
    _, path, _ = _run(tmp_path, capsys)
    assert main(["health", str(path), "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    by = {i["instance"]: i for i in doc["instances"]}
    assert by["INA238#1"]["perf"]["resets"] == 1 and by["INA238#1"]["health"] == "critical"
    assert by["AK09916#0"]["marks"][0][1] == "start"


def test_health_errors(tmp_path, capsys) -> None:
    missing = tmp_path / "nothing.ulg"
    assert main(["health", str(missing)]) == 1
    expected = f"px4params: error: {missing}: cannot read: No such file or directory\n"
    assert capsys.readouterr().err == expected
    garbage = tmp_path / "garbage.ulg"
    garbage.write_bytes(b"not a log at all")
    assert main(["health", str(garbage)]) == 1
    err = capsys.readouterr().err
    assert (
        err.startswith(f"px4params: error: {garbage}: not a ULog file (") and err.count("\n") == 1
    )


def test_health_refuses_a_px4_flight_log(capsys) -> None:
    real = shared_file("sample_log_small.ulg")  # skips with the reason when ../shared is absent
    assert main(["health", str(real)]) == 1
    assert capsys.readouterr().err == (
        f"px4params: error: {real}: not a log of 'px4params autostart run --ulog' (no "
        "px4params_mode information)\n"
    )


def test_health_runs_as_a_command(tmp_path) -> None:
    """No traceback on the way out, through the installed entry point's module."""
    result = subprocess.run(
        [sys.executable, "-m", "px4params", "health", str(tmp_path / "x.ulg")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 1 and "Traceback" not in result.stderr


def test_a_lost_device_that_answers_again_is_logged_as_recovered(tmp_path, capsys) -> None:
    # A 60% noisy bus: with seed 3 the monitor is lost (10 bad transfers in a row) and found
    # again (the simulation is deterministic for a seed).
    bench = tmp_path / "noisy.bench.toml"
    bench.write_text(
        '[[bus]]\nkind = "i2c"\nbus_id = 1\nerror_rate = 0.6\n\n'
        '[[device]]\nchip = "INA238"\nbus = "i2c"\nbus_id = 1\naddress = 0x45\n'
    )
    airframe = tmp_path / "one.airframe"
    airframe.write_text("param add INA238#0\nparam set-default INA238#0.bus.i2c.bus_id 1\n")
    log, direct, picture = tmp_path / "noisy.ulg", tmp_path / "d.svg", tmp_path / "p.svg"
    main(["autostart", "run", "--airframe", str(airframe), "--bench", str(bench), "--seed", "3",
          "--ulog", str(log), "--timeline", str(direct)])  # fmt: skip
    capsys.readouterr()
    said = [(m.log_level_str(), m.message) for m in ULog(str(log)).logged_messages]
    lost = next(n for n, (level, text) in enumerate(said) if "device lost" in text)
    assert said[lost][0] == "ERROR"
    level, text = next((lv, t) for lv, t in said[lost:] if "recovered" in t)
    assert level == "NOTICE"
    assert text.startswith("ina238 INA238#0: recovered: started again on I2C bus 1 address 0x45")
    # health reads both starts as starts, and the reset between them.
    assert main(["health", str(log), "--json"]) in (0, 1)
    marks = json.loads(capsys.readouterr().out)["instances"][0]["marks"]
    assert [what for _, what in marks[:3]] == ["start", "reset", "start"]
    assert marks[1][0] == pytest.approx(6.06)  # when it was lost, not when the slice ended
    main(["health", str(log), "--timeline", str(picture)])
    assert picture.read_text() == direct.read_text()


# -- a run written by hand, read back sample by sample (issue 40) ---------------------------------
# The mutation run found what the bench runs above leave open. Here the events are written by
# hand, so every sample and logged message the log must hold is known from docs/autostart.md
# ("The flight log") and the ULog specification, and pyulog reads them back.

INA = {"instance": "INA238#0", "driver": "ina238", "bus": "i2c", "bus_id": 1, "address": 0x45}
AK = {"instance": "AK09916#0", "driver": "ak09916", "bus": "i2c", "bus_id": 1, "address": 0x0C}
#: The device IDs the drivers publish: devtype, address, bus 1 << 3 | I2C (PX4's layout).
INA_ID, AK_ID = 0xD44509, 0x090C09


def _perf(where: dict, t: float, transfers: int, errors: int, resets: int, probes: int) -> dict:
    return {"t": t, "event": "perf", **where, "transfers": transfers, "bad_transfers": errors,
            "resets": resets, "probe_attempts": probes}  # fmt: skip


HAND_EVENTS = [
    {"t": 0.0, "event": "register", **INA},
    {"t": 0.0, "event": "register", **AK},
    {
        "t": 0.05,
        "event": "started",
        **INA,
        "device_id": INA_ID,
        "device_id_hex": "0xD44509",
        "attempts": 1,
    },
    {"t": 0.1, "event": "health", **INA, "health": "nominal", "reason": None},
    {"t": 0.1, "event": "health", **AK, "health": "warning", "reason": "no answer yet"},
    {"t": 0.1, "event": "arming", "may_arm": False},
    _perf(INA, 1.0, 10, 1, 0, 1),
    _perf(AK, 1.0, 0, 0, 0, 3),
    {"t": 1.5, "event": "reset", **INA, "at": 1.45, "reason": "10 bad transfers in a row"},
    {"t": 1.5, "event": "health", **INA, "health": "critical", "reason": "lost"},
    _perf(INA, 2.0, 12, 11, 1, 1),
    {
        "t": 2.2,
        "event": "started",
        **INA,
        "device_id": INA_ID,
        "device_id_hex": "0xD44509",
        "attempts": 2,
    },
    {"t": 2.3, "event": "health", **INA, "health": "nominal", "reason": None},
    {"t": 2.3, "event": "health", **AK, "health": "nominal", "reason": None},
    {"t": 2.3, "event": "arming", "may_arm": True},
    _perf(INA, 3.0, 20, 11, 1, 2),
]


def _hand_run(events: list[dict], duration: float = 3.0, mode: str = "manifest"):
    from px4params.vehicle.simbench import InstanceResult, RunResult

    instances = [
        InstanceResult("INA238#0", "ina238", "INA238", "i2c", 1, 0x45),
        InstanceResult("AK09916#0", "ak09916", "AK09916", "i2c", 1, 0x0C),
    ]
    return RunResult(mode=mode, seed=7, duration=duration, bench="hand.bench.toml",
                     instances=instances, may_arm=True, failures=[], events=events)  # fmt: skip


def _samples(ulog: ULog, topic: str, multi_id: int, *fields: str) -> list[tuple]:
    data = next(d.data for d in ulog.data_list if (d.name, d.multi_id) == (topic, multi_id))
    return [tuple(int(data[f][n]) for f in fields) for n in range(len(data["timestamp"]))]


@pytest.mark.issue40
def test_a_hand_written_run_sample_by_sample(tmp_path: Path) -> None:
    from px4params import __version__
    from px4params.vehicle.flight_log import run_ulog

    path = tmp_path / "hand.ulg"
    path.write_bytes(run_ulog(_hand_run(HAND_EVENTS), {"SYS_AUTOSTART": 4001}, version="9.9"))
    ulog = ULog(str(path))
    info = ulog.msg_info_dict
    assert (info["sys_name"], info["ver_sw"], info["px4params_seed"]) == ("px4params", "9.9", 7)
    assert (info["px4params_mode"], info["px4params_bench"]) == ("manifest", "hand.bench.toml")
    assert info["px4params_duration_us"] == "3000000" and "ver_hw" in info
    assert __version__ != "9.9"
    assert ulog.msg_info_multiple_dict["driver_instance"] == [
        ["INA238#0 ina238 i2c 1 69"], ["AK09916#0 ak09916 i2c 1 12"],
    ]  # fmt: skip
    assert ulog.initial_parameters == {"SYS_AUTOSTART": 4001}
    health = ("timestamp", "device_id", "health", "registered")
    # Critical from registering (what the commander assumes until the first answer), the device
    # ID once started, then every change and a sample with each second's perf counters.
    assert _samples(ulog, "driver_health", 0, *health) == [
        (0, 0, 2, 1),
        (100_000, INA_ID, 0, 1),
        (1_000_000, INA_ID, 0, 1),
        (1_500_000, INA_ID, 2, 1),
        (2_000_000, INA_ID, 2, 1),
        (2_300_000, INA_ID, 0, 1),
        (3_000_000, INA_ID, 0, 1),
    ]
    assert _samples(ulog, "driver_health", 1, *health) == [
        (0, 0, 2, 1), (100_000, 0, 1, 1), (1_000_000, 0, 1, 1), (2_300_000, 0, 0, 1),
    ]  # fmt: skip
    perf = ("timestamp", "transfers", "errors", "timeouts", "probe_attempts", "elapsed_us")
    # elapsed_us: the time since the driver last started (0 while it is lost or never started).
    assert _samples(ulog, "driver_perf", 0, *perf) == [
        (1_000_000, 10, 1, 0, 1, 950_000),
        (2_000_000, 12, 11, 1, 1, 0),
        (3_000_000, 20, 11, 1, 2, 800_000),
    ]
    assert _samples(ulog, "driver_perf", 1, *perf) == [(1_000_000, 0, 0, 0, 3, 0)]
    # The commander's answer on every change and once a second, with how many devices block it.
    assert _samples(ulog, "arming_check", 0, "timestamp", "may_arm", "blocking") == [
        (100_000, 0, 1),
        (1_000_000, 0, 1),
        (2_000_000, 0, 2),  # INA238#0 lost, AK09916#0 warning
        (2_300_000, 1, 0),
        (3_000_000, 1, 0),
    ]
    said = [(int(m.timestamp), m.log_level_str(), m.message) for m in ulog.logged_messages]
    where = "on I2C bus 1 address 0x45"
    assert said == [
        (0, "DEBUG", f"ina238 INA238#0 {where}: critical: starting"),
        (0, "DEBUG", "ak09916 AK09916#0 on I2C bus 1 address 0x0C: critical: starting"),
        (50_000, "INFO", f"ina238 INA238#0: started {where} (device ID 0xD44509, after 1 probe "
                         "attempts)"),
        (100_000, "NOTICE", f"ina238 INA238#0 {where}: nominal"),
        (100_000, "WARNING", "ak09916 AK09916#0 on I2C bus 1 address 0x0C: warning: no answer yet"),
        (100_000, "WARNING", "commander: arming refused: AK09916#0"),
        (1_450_000, "ERROR", f"ina238 INA238#0: device lost {where}: 10 bad transfers in a row"),
        (1_500_000, "ERROR", f"ina238 INA238#0 {where}: critical: lost"),
        (2_200_000, "NOTICE", f"ina238 INA238#0: recovered: started again {where} (device ID "
                              "0xD44509, after 2 probe attempts)"),
        (2_300_000, "NOTICE", f"ina238 INA238#0 {where}: nominal"),
        (2_300_000, "NOTICE", "ak09916 AK09916#0 on I2C bus 1 address 0x0C: nominal"),
        (2_300_000, "INFO", "commander: may arm: every manifest device is nominal"),
        (3_000_000, "INFO", "px4params: end of the run"),  # docs/autostart.md's words
    ]  # fmt: skip


@pytest.mark.issue40
def test_a_hand_written_run_read_back(tmp_path: Path) -> None:
    """px4params health's reading of the same log: each device's story as the events tell it."""
    from px4params.vehicle.flight_log import read_run_ulog, run_ulog

    path = tmp_path / "hand.ulg"
    data = run_ulog(_hand_run(HAND_EVENTS), {}, version="9.9")
    path.write_bytes(data)
    run = read_run_ulog(str(path))
    assert (run.mode, run.seed, run.duration, run.bench) == ("manifest", 7, 3.0, "hand.bench.toml")
    assert (run.may_arm, run.failures, run.arming) == (True, [], [(0.1, False), (2.3, True)])
    assert run.log_cut_at is None and run.silently_missing == []
    ina, ak = run.instances
    assert (ina.name, ina.driver, ina.kind, ina.bus_id, ina.address) == (
        "INA238#0", "ina238", "i2c", 1, 0x45,
    )  # fmt: skip
    assert ina.timeline == [
        (0.0, "critical", "starting"), (0.1, "nominal", ""), (1.5, "critical", "lost"),
        (2.3, "nominal", ""),
    ]  # fmt: skip
    assert ina.marks == [(0.05, "start"), (1.45, "reset"), (2.2, "start")]
    assert (ina.started_at, ina.device_id, ina.health, ina.reason, ina.registered) == (
        0.05, INA_ID, "nominal", "", True,
    )  # fmt: skip
    assert (ina.transfers, ina.bad_transfers, ina.resets, ina.probe_attempts) == (20, 11, 1, 2)
    assert ak.timeline == [
        (0.0, "critical", "starting"), (0.1, "warning", "no answer yet"), (2.3, "nominal", ""),
    ]  # fmt: skip
    assert (ak.marks, ak.started_at, ak.device_id) == ([], None, None)  # never started
    assert (ak.transfers, ak.probe_attempts) == (0, 3)

    # The same log cut short just before its last message (the clean end): what it tells is
    # known up to its last moment, 3 s (the last perf samples), and no further.
    end = struct.pack("<HB", 1 + 8 + 25, ord("L")) + b"6" + (3_000_000).to_bytes(8, "little")
    assert data.endswith(end + b"px4params: end of the run")
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[: -len(end) - 25])
    assert read_run_ulog(str(cut)).log_cut_at == 3.0


@pytest.mark.issue40
def test_before_the_commanders_first_answer_arming_is_refused(tmp_path: Path) -> None:
    """A perf second before the commander has answered: the log says it may not arm, and an
    instance nobody has reported on yet is critical (docs/autostart.md: critical until the
    first answer). A device ID the driver did not give is 0, PX4's "no device"."""
    from px4params.vehicle.flight_log import run_ulog

    events = [
        _perf(INA, 1.0, 5, 0, 0, 1),
        {
            "t": 1.2,
            "event": "started",
            **INA,
            "device_id": None,
            "device_id_hex": "-",
            "attempts": 1,
        },
        {"t": 1.5, "event": "health", **INA, "health": "nominal", "reason": None},
    ]
    path = tmp_path / "early.ulg"
    path.write_bytes(run_ulog(_hand_run(events, duration=2.0), {}))
    ulog = ULog(str(path))
    assert ulog.msg_info_dict["ver_sw"] == "unknown"  # no version given
    assert _samples(ulog, "arming_check", 0, "timestamp", "may_arm", "blocking") == [
        (1_000_000, 0, 0),
    ]
    assert _samples(ulog, "driver_health", 0, "timestamp", "device_id", "health") == [
        (1_000_000, 0, 2), (1_500_000, 0, 0),
    ]  # fmt: skip
    perf = _samples(ulog, "driver_perf", 0, "timestamp", "elapsed_us")
    assert perf == [(1_000_000, 0)]
    assert ulog.logged_messages[-1].message == "px4params: end of the run"
    assert int(ulog.logged_messages[-1].timestamp) == 2_000_000
    # Read back: AK09916#0 has no perf sample at all, so no counters.
    from px4params.vehicle.flight_log import read_run_ulog

    run = read_run_ulog(str(path))
    ina, ak = run.instances
    assert (ina.transfers, ina.probe_attempts, ina.device_id) == (5, 1, None)
    # Its first sample came with no logged message: no reason to tell.
    assert ina.timeline == [(1.0, "critical", ""), (1.5, "nominal", "")]
    # No answer from the commander logged, only the refusal sampled at 1 s: AK09916#0 (never
    # heard of, so critical: starting) blocks arming and the nominal INA238#0 does not.
    assert (run.may_arm, run.arming) == (False, [(1.0, False)])
    assert run.failures == ["ak09916 AK09916#0 on I2C bus 1 address 0x0C: critical: starting"]
    assert (ak.transfers, ak.bad_transfers, ak.resets, ak.probe_attempts) == (0, 0, 0, 0)


@pytest.mark.issue40
def test_blocking_devices_are_counted_up_to_255(tmp_path: Path) -> None:
    """arming_check.blocking is a uint8_t: 256 devices still starting (a ULog multi ID is a
    uint8_t: at most 256 instances of a topic) count as 255."""
    from px4params.vehicle.flight_log import run_ulog
    from px4params.vehicle.simbench import InstanceResult, RunResult

    names = [f"INA238#{n}" for n in range(256)]
    instances = [InstanceResult(n, "ina238", None, "i2c", 1, 0x40) for n in names]
    events = [{"t": 0.0, "event": "register", **INA, "instance": n} for n in names]
    events.append({"t": 0.1, "event": "arming", "may_arm": False})
    run = RunResult("manifest", 0, 1.0, "b", instances, False, [], events=events)
    path = tmp_path / "many.ulg"
    path.write_bytes(run_ulog(run, {}))
    assert _samples(ULog(str(path)), "arming_check", 0, "timestamp", "blocking") == [(100_000, 255)]


@pytest.mark.issue40
def test_the_topics_formats(tmp_path: Path) -> None:
    """docs/autostart.md's topics, as pyulog reads their formats: PX4's field types, the device
    ID a uint32_t as in sensor topics, instance names in 24 characters."""
    from px4params.vehicle.flight_log import run_ulog

    path = tmp_path / "hand.ulg"
    path.write_bytes(run_ulog(_hand_run(HAND_EVENTS), {}))
    formats = {name: f.fields for name, f in ULog(str(path)).message_formats.items()}
    assert formats == {
        "driver_health": [
            ("uint64_t", 0, "timestamp"), ("uint32_t", 0, "device_id"), ("uint8_t", 0, "health"),
            ("bool", 0, "registered"), ("char", 24, "instance"),
        ],
        "driver_perf": [
            ("uint64_t", 0, "timestamp"), ("uint32_t", 0, "transfers"), ("uint32_t", 0, "errors"),
            ("uint32_t", 0, "timeouts"), ("uint32_t", 0, "probe_attempts"),
            ("uint64_t", 0, "elapsed_us"), ("char", 24, "instance"),
        ],
        "arming_check": [
            ("uint64_t", 0, "timestamp"), ("bool", 0, "may_arm"), ("uint8_t", 0, "blocking"),
        ],
    }  # fmt: skip


@pytest.mark.issue40
def test_a_manifest_instance_without_a_driver_and_a_run_without_events(tmp_path: Path) -> None:
    from px4params.vehicle.autostart import Configured
    from px4params.vehicle.flight_log import run_ulog

    gadget = Configured("GADGET#0", "GADGET", None, "i2c", 1, 0x20, {})
    path = tmp_path / "gadget.ulg"
    path.write_bytes(run_ulog(_hand_run(HAND_EVENTS), {}, [gadget]))
    assert ULog(str(path)).msg_info_multiple_dict["manifest_instance"] == [
        ["GADGET#0 - on I2C bus 1 address 0x20"]
    ]
    with pytest.raises(ValueError) as e:
        run_ulog(_hand_run(None), {})  # type: ignore[arg-type]
    assert str(e.value) == "the run's events were not recorded (run(..., record_events=True))"


@pytest.mark.issue40
def test_health_messages_word_for_word(tmp_path: Path) -> None:
    """The logged health changes: 'nominal' alone (whatever reason came with it), a level with
    its reason, a level without one; a quiet start that found nothing (DEBUG); the commander
    refusing before any device has answered."""
    from px4params.vehicle.flight_log import run_ulog

    events = [
        {"t": 0.1, "event": "arming", "may_arm": False},  # before any device has answered
        {"t": 0.5, "event": "start_failed", **AK, "quiet": True, "reason": "no ACK"},
        {"t": 0.6, "event": "health", **AK, "health": "critical", "reason": None},
        {"t": 0.7, "event": "health", **AK, "health": "warning", "reason": "checksum error in AUX"},
        {"t": 0.8, "event": "health", **INA, "health": "nominal", "reason": "answers again"},
    ]
    path = tmp_path / "texts.ulg"
    path.write_bytes(run_ulog(_hand_run(events, duration=1.0), {}))
    said = [(m.log_level_str(), m.message) for m in ULog(str(path)).logged_messages]
    ak = "ak09916 AK09916#0 on I2C bus 1 address 0x0C"
    assert said[:-1] == [
        ("WARNING", "commander: arming refused: devices still starting"),
        ("DEBUG", "ak09916 on I2C bus 1 address 0x0C: quiet start found nothing (no ACK)"),
        ("ERROR", f"{ak}: critical"),
        ("WARNING", f"{ak}: warning: checksum error in AUX"),
        ("NOTICE", "ina238 INA238#0 on I2C bus 1 address 0x45: nominal"),
    ]
    from px4params.vehicle.flight_log import read_run_ulog

    ina, ak = read_run_ulog(str(path)).instances
    assert (ina.timeline, ina.registered) == ([(0.8, "nominal", "")], True)  # one sample
    assert ak.timeline == [(0.6, "critical", ""), (0.7, "warning", "checksum error in AUX")]


def test_samples_are_the_instance_they_name_when_a_driver_instance_line_is_lost(
    tmp_path: Path,
) -> None:
    # INA238#0's driver_instance line damaged (its key no longer "driver_instance"): AK09916#0's
    # line came first, and the reader gave it INA238#0's samples (multi ID 0), device ID too.
    # (Found and fixed by a helper, helper-108, on a branch of its own; carried over here.)
    from px4params.vehicle.flight_log import read_run_ulog, run_ulog

    data = run_ulog(_hand_run(HAND_EVENTS), {})
    whole = tmp_path / "whole.ulg"
    whole.write_bytes(data)
    _, told = read_run_ulog(str(whole)).instances
    line = b"char[24] driver_instanceINA238#0 "
    assert data.count(line) == 1
    path = tmp_path / "damaged.ulg"
    path.write_bytes(data.replace(line, b"char[24] driver_instancXINA238#0 "))
    (ak,) = read_run_ulog(str(path)).instances
    assert ak.name == "AK09916#0"
    assert ak.timeline == told.timeline == [
        (0.0, "critical", "starting"), (0.1, "warning", "no answer yet"), (2.3, "nominal", ""),
    ]  # fmt: skip
    assert (ak.device_id, ak.transfers, ak.probe_attempts) == (None, 0, 3)


def _crafted(path: Path, mode: str | None, lines: list[str] | None) -> str:
    """A ULog with the information px4params health looks for, or not."""
    log = ULogWriter()
    if mode is not None:
        log.info("px4params_mode", mode)
    for line in lines or ():
        log.info("driver_instance", line, multi=True)
    path.write_bytes(log.getvalue())
    return str(path)


@pytest.mark.issue40
def test_health_refuses_logs_it_did_not_write_word_for_word(tmp_path: Path) -> None:
    from px4params.vehicle.flight_log import read_run_ulog

    refusal = "not a log of 'px4params autostart run --ulog' (no px4params_mode information)"
    path = _crafted(tmp_path / "instances_only.ulg", None, ["INA238#0 ina238 i2c 1 69"])
    with pytest.raises(ULogError) as e:
        read_run_ulog(path)
    assert str(e.value) == f"{path}: {refusal}"
    # The mode alone: a run of no devices (an empty manifest's), which never armed.
    empty = read_run_ulog(_crafted(tmp_path / "mode_only.ulg", "manifest", None))
    assert (empty.instances, empty.may_arm, empty.arming) == ([], False, [])
    # A driver_instance line is "instance driver bus bus_id address", numbers in decimal.
    for n, line in enumerate(
        ["INA238#0 ina238 i2c one 69", "INA238#0 ina238 i2c 1 0x45", "INA238#0 ina238 i2c 1"]
    ):
        path = _crafted(tmp_path / f"bad{n}.ulg", "manifest", ["AK09916#0 ak09916 i2c 1 12", line])
        with pytest.raises(ULogError) as e:
            read_run_ulog(path)
        assert str(e.value) == f"{path}: driver_instance 1: cannot read {line!r}"


@pytest.mark.parametrize(
    ("field", "topic"),
    [
        (b"timeouts", "driver_perf 0"),
        (b"probe_attempts", "driver_perf 0"),
        (b"may_arm", "arming_check 0"),
        (b"registered", "driver_health 0"),
    ],
)
def test_a_log_whose_topic_lacks_a_field_is_refused_in_one_line(
    tmp_path: Path, field: bytes, topic: str
) -> None:
    # A field renamed in the format definition (same length, so the log still parses): the
    # topic is there without it. It raised KeyError through `px4params health`.
    from px4params.vehicle.flight_log import _FIELDS, read_run_ulog, run_ulog

    data = run_ulog(_hand_run(HAND_EVENTS), {}, version="9.9")
    renamed = field[:1].upper() + field[1:]
    assert data.count(b" " + field + b";") == 1
    path = tmp_path / "renamed.ulg"
    path.write_bytes(data.replace(b" " + field + b";", b" " + renamed + b";"))
    with pytest.raises(ULogError) as e:
        read_run_ulog(str(path))
    name = topic.split()[0]
    assert str(e.value) == (
        f"{path}: {topic} has no field {field.decode()!r} (a log of 'autostart run --ulog' has "
        f"{', '.join(_FIELDS[name])})"
    )


def test_a_driver_instance_line_that_is_not_text_is_refused_in_one_line(tmp_path: Path) -> None:
    # pyulog gives an info value whose type is not char[N] as bytes; joining it raised TypeError
    from px4params.vehicle.flight_log import read_run_ulog

    path = _crafted(tmp_path / "ok.ulg", "manifest", ["INA238#0 ina238 i2c 1 69"])
    data = Path(path).read_bytes()
    assert data.count(b"char[24] driver_instance") == 1
    bad = tmp_path / "bad.ulg"
    bad.write_bytes(data.replace(b"char[24] driver_instance", b"chzr[24] driver_instance"))
    with pytest.raises(ULogError) as e:
        read_run_ulog(str(bad))
    assert str(e.value) == (
        f"{bad}: driver_instance 0 is \"[b'INA238#0 ina238 i2c 1 69']\", not text (a damaged log?)"
    )


@pytest.mark.parametrize(
    ("key", "value", "shown"),
    [
        ("px4params_mode", "manual", "px4params_mode is 'manual', not 'manifest' or 'legacy'"),
        ("px4params_mode", 7, "px4params_mode is '7', not text"),
        ("px4params_bench", 3, "px4params_bench is '3', not text"),
        ("silently_missing", 3, "silently_missing 0 is '[3]', not text"),
    ],
)
def test_a_run_information_that_is_no_text_or_no_mode_is_refused_in_one_line(
    tmp_path: Path, capsys, key: str, value: object, shown: str
) -> None:
    # A mode it does not know was read as a legacy boot's and skipped the manifest's check; a
    # number where the writer writes text gave a TypeError traceback (helper-108 found both).
    log = ULogWriter()
    if key != "px4params_mode":
        log.info("px4params_mode", "legacy")
    log.info(key, value, multi=key == "silently_missing")
    path = tmp_path / "damaged.ulg"
    path.write_bytes(log.getvalue())
    assert main(["health", str(path)]) == 1
    assert capsys.readouterr().err == f"px4params: error: {path}: {shown} (a damaged log?)\n"


@pytest.mark.issue40
def test_a_run_with_nothing_but_its_end_and_a_log_without_the_run_figures(tmp_path: Path) -> None:
    """A run with no events still ends cleanly (its end is its only message); a log with no
    seed, duration or bench information reads as seed 0, 0 s, no bench."""
    from px4params.vehicle.flight_log import read_run_ulog, run_ulog

    path = tmp_path / "quiet.ulg"
    path.write_bytes(run_ulog(_hand_run([], duration=1.0), {}))
    assert [m.message for m in ULog(str(path)).logged_messages] == ["px4params: end of the run"]
    assert read_run_ulog(str(path)).log_cut_at is None
    bare = read_run_ulog(_crafted(tmp_path / "bare.ulg", "legacy", ["INA238#0 ina238 i2c 1 69"]))
    assert (bare.mode, bare.seed, bare.duration, bare.bench) == ("legacy", 0, 0.0, "")


@pytest.mark.issue40
def test_a_corrupt_log_is_no_clean_end_even_with_its_end_message(tmp_path: Path) -> None:
    """A data message of a subscription the log never made (msg ID 99), just before the end:
    pyulog reads the rest but calls the file corrupt, and what the log tells is uncertain from
    its last moment on, although its last message is the run's end."""
    from px4params.vehicle.flight_log import read_run_ulog, run_ulog

    data = run_ulog(_hand_run(HAND_EVENTS), {})
    end = 3 + 1 + 8 + len("px4params: end of the run")  # the last message, 'L'
    stray = struct.pack("<HB", 3, ord("D")) + struct.pack("<H", 99) + b"\x00"
    path = tmp_path / "corrupt.ulg"
    path.write_bytes(data[:-end] + stray + data[-end:])
    assert ULog(str(path)).logged_messages[-1].message == "px4params: end of the run"
    assert read_run_ulog(str(path)).log_cut_at == 3.0


@pytest.mark.issue40
def test_a_log_cut_after_a_message_with_no_sample_and_the_silently_missing(tmp_path: Path) -> None:
    """A log whose only record is a logged message (a driver started at 0.5 s: no sample yet),
    cut before its end: its last moment is the message's. And a legacy boot's silently missing
    instances come back as the run listed them."""
    from px4params.vehicle.flight_log import read_run_ulog, run_ulog

    started = {"t": 0.5, "event": "started", **INA, "device_id": INA_ID,
               "device_id_hex": "0xD44509", "attempts": 1}  # fmt: skip
    run = _hand_run([started], duration=2.0, mode="legacy")
    run.silently_missing = ["ak09916 AK09916#0 on I2C bus 1 address 0x0C: never started"]
    data = run_ulog(run, {})
    path = tmp_path / "whole.ulg"
    path.write_bytes(data)
    assert read_run_ulog(str(path)).silently_missing == run.silently_missing
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[: -(3 + 1 + 8 + len("px4params: end of the run"))])
    assert read_run_ulog(str(cut)).log_cut_at == 0.5


@pytest.mark.issue40
def test_a_health_code_px4params_does_not_know_reads_as_critical(tmp_path: Path, capsys) -> None:
    """driver_health.health is 0 nominal, 1 warning, 2 critical (docs/autostart.md); a code
    beyond them (a newer writer's, or damage) is read as the worst known, critical, saying so;
    and a device that ends critical keeps the vehicle from arming, whatever the log's
    commander said (it said "may arm" beside an empty reason)."""
    from px4params.vehicle.flight_log import read_run_ulog

    log = ULogWriter()
    log.info("px4params_mode", "manifest")
    log.info("driver_instance", "INA238#0 ina238 i2c 1 69", multi=True)
    log.define("driver_health", [("uint64_t", "timestamp"), ("uint32_t", "device_id"),
                                 ("uint8_t", "health"), ("bool", "registered"),
                                 ("char[24]", "instance")])  # fmt: skip
    log.define("arming_check", [("uint64_t", "timestamp"), ("bool", "may_arm"),
                                ("uint8_t", "blocking")])  # fmt: skip
    msg_id = log.subscribe("driver_health")
    arming_id = log.subscribe("arming_check")
    log.data(msg_id, 1_000_000, INA_ID, 0, True, "INA238#0")
    log.data(arming_id, 1_000_000, True, 0)
    log.data(msg_id, 2_000_000, INA_ID, 7, True, "INA238#0")
    log.data(msg_id, 2_500_000, INA_ID, 7, True, "INA238#0")
    log.data(msg_id, 3_000_000, INA_ID, 8, True, "INA238#0")
    path = tmp_path / "newer.ulg"
    path.write_bytes(log.getvalue())
    result = read_run_ulog(str(path))
    (ina,) = result.instances
    # 8 after 7 is news (its reason said 7), 7 after 7 is not
    unknown = "health code {}, unknown here: taken as critical"
    assert ina.timeline == [
        (1.0, "nominal", ""), (2.0, "critical", unknown.format(7)),
        (3.0, "critical", unknown.format(8)),
    ]  # fmt: skip
    assert (ina.health, ina.device_id) == ("critical", INA_ID)
    assert (result.arming, result.may_arm) == ([(1.0, True)], False)
    failure = f"ina238 INA238#0 on I2C bus 1 address 0x45: critical: {unknown.format(8)}"
    assert result.failures == [failure]
    # The story says why the commander's last word is overruled.
    assert main(["health", str(path)]) == 1
    lines = capsys.readouterr().out.splitlines()
    at = lines.index("commander: may arm at 1.00 s")
    assert lines[at + 1 : at + 3] == [
        "warning: the commander's last answer is 'may arm', but at 3.00 s, where the log ends "
        "these devices block arming:",
        f"  {failure}",
    ]


def test_a_benchs_name_is_kept_in_the_log_and_said_by_health(tmp_path: Path, capsys) -> None:
    from px4params.vehicle.flight_log import read_run_ulog, run_ulog

    named = dataclasses.replace(_hand_run(HAND_EVENTS), bench_name="quad, two packs")
    path = tmp_path / "named.ulg"
    path.write_bytes(run_ulog(named, {}, version="9.9"))
    assert ULog(str(path)).msg_info_dict["px4params_bench_name"] == "quad, two packs"
    assert read_run_ulog(str(path)).bench_name == "quad, two packs"
    main(["health", str(path)])
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith(f"{path}: manifest boot of quad, two packs (hand.bench.toml), 3 s")
    # a bench without a name writes none, and reads back as none
    plain = tmp_path / "plain.ulg"
    plain.write_bytes(run_ulog(_hand_run(HAND_EVENTS), {}, version="9.9"))
    assert "px4params_bench_name" not in ULog(str(plain)).msg_info_dict
    assert read_run_ulog(str(plain)).bench_name == ""
    assert _hand_run(HAND_EVENTS).as_dict()["bench_name"] == ""  # a run made without one


def test_a_manifest_instance_the_log_tells_nothing_of_is_refused(tmp_path: Path) -> None:
    # A byte changed in AK09916#0's driver_instance key: the story had the two INA238s only,
    # "may arm", exit 0, while the log's manifest lists AK09916#0. A run gives every configured
    # instance a driver story, started or not.
    from px4params.vehicle.autostart import Configured
    from px4params.vehicle.flight_log import read_run_ulog, run_ulog

    gadget = Configured("GADGET#0", "GADGET", None, "i2c", 1, 0x20, {})
    path = tmp_path / "untold.ulg"
    path.write_bytes(run_ulog(_hand_run(HAND_EVENTS), {}, [gadget]))
    with pytest.raises(ULogError) as e:
        read_run_ulog(str(path))
    assert str(e.value) == (
        f"{path}: manifest instance GADGET#0 has no driver story (driver_instance): a damaged log?"
    )


@pytest.mark.parametrize(
    ("key", "value"), [("px4params_duration_us", "G0000000"), ("px4params_seed", "-1")]
)
def test_a_run_information_that_is_no_whole_number_is_refused_in_one_line(
    tmp_path: Path, capsys, key: str, value: str
) -> None:
    # It raised ValueError through `px4params health`, with a traceback.
    log = ULogWriter()
    log.info("px4params_mode", "manifest")
    log.info(key, value)
    path = tmp_path / "damaged.ulg"
    path.write_bytes(log.getvalue())
    assert main(["health", str(path)]) == 1
    assert capsys.readouterr().err == (
        f"px4params: error: {path}: {key} is {value!r}, not a whole number (a damaged log?)\n"
    )


@pytest.mark.parametrize(("mode", "may_arm"), [("legacy", True), ("manifest", False)])
def test_the_verdict_is_the_devices_as_the_mode_judges_them(
    tmp_path: Path, mode: str, may_arm: bool
) -> None:
    # A legacy run that may arm with a device at warning was read back as refused: the
    # manifest's rule was applied to both (helper-108 found it). The rule is the run's own,
    # simbench.blocks_arming: with the manifest, every instance not nominal, one no driver
    # registered too; today, a registered device that is critical.
    from px4params.vehicle.flight_log import read_run_ulog

    log = ULogWriter()
    log.info("px4params_mode", mode)
    log.info("driver_instance", "INA238#0 ina238 i2c 1 69", multi=True)
    log.info("driver_instance", "AK09916#0 ak09916 i2c 1 12", multi=True)
    log.define("driver_health", [("uint64_t", "timestamp"), ("uint32_t", "device_id"),
                                 ("uint8_t", "health"), ("bool", "registered"),
                                 ("char[24]", "instance")])  # fmt: skip
    log.define("arming_check", [("uint64_t", "timestamp"), ("bool", "may_arm"),
                                ("uint8_t", "blocking")])  # fmt: skip
    ina, ak, arming = (log.subscribe(t) for t in ("driver_health", "driver_health", "arming_check"))
    log.data(ina, 1_000_000, INA_ID, 1, True, "INA238#0")  # warning, registered
    log.data(ak, 1_000_000, 0, 2, False, "AK09916#0")  # critical, never registered
    log.data(arming, 1_000_000, True, 0)
    path = tmp_path / f"{mode}.ulg"
    path.write_bytes(log.getvalue())
    run = read_run_ulog(str(path))
    assert (run.may_arm, run.verdict) == (may_arm, "may arm" if may_arm else "arming refused")
    # (a level logged without a reason ends the line: it ended in ": ")
    assert run.failures == ([] if may_arm else [
        "ina238 INA238#0 on I2C bus 1 address 0x45: warning",
        "ak09916 AK09916#0 on I2C bus 1 address 0x0C: critical",
    ])  # fmt: skip
