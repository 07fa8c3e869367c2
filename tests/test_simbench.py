"""The simulated bench: bench files, booting the manifest with faults, health, the commander's
arming check, --legacy, the event log and the timeline picture.

The scenarios of issue 6 run through the command line (exit code and the lines a user sees);
the simulation's properties (determinism for a seed, published device IDs, the commander's
consistency) are checked with hypothesis through the Python API.
"""

from __future__ import annotations

import dataclasses
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from px4params import Store
from px4params.cli.main import main
from px4params.store.spec import parameter_specs
from px4params.vehicle import devid
from px4params.vehicle.autostart import Configured, configured, load_manifest
from px4params.vehicle.drivers import DEFAULT_DRIVERS, Drivers, load_drivers
from px4params.vehicle.simbench import (
    Bench,
    BenchBus,
    BenchDevice,
    BenchFileError,
    RunResult,
    healthy_bench,
    load_bench,
    parse_bench,
    run,
)
from px4params.vehicle.timeline import render_svg
from shared_data import current_devtypes
from strategies import budget

REPO = Path(__file__).resolve().parents[1]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"
BENCH = REPO / "examples" / "two_batteries.bench.toml"

DEVICES = """
[[device]]
chip = "INA238"
bus = "i2c"
bus_id = 1
address = 0x45

[[device]]
chip = "INA238"
bus = "i2c"
bus_id = 2
address = 0x45
{second}

[[device]]
chip = "AK09916"
bus = "i2c"
bus_id = 1
address = 0x0C
{mag}
"""


def bench_text(second: str = "", mag: str = "", extra: str = "") -> str:
    return extra + DEVICES.format(second=second, mag=mag)


@pytest.fixture(scope="module")
def drivers(schema):
    return load_drivers(DEFAULT_DRIVERS, parameter_specs(schema))


@pytest.fixture(scope="module")
def manifest(drivers):
    return configured(load_manifest(None, AIRFRAME), drivers)


def boot(tmp_path: Path, capsys, text: str, *args: str) -> tuple[int, str]:
    path = tmp_path / "bench.toml"
    path.write_text(text)
    status = main(["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(path), *args])
    captured = capsys.readouterr()
    assert captured.err == ""
    return status, captured.out


def refused_lines(out: str) -> list[str]:
    lines = out.splitlines()
    start = next(n for n, line in enumerate(lines) if line.startswith("commander: arming refused"))
    return [line.strip() for line in lines[start + 1 :] if line.startswith("  ")]


# -- the scenarios ------------------------------------------------------------------------------


def test_everything_present_may_arm(capsys):
    status = main(["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(BENCH)])
    out = capsys.readouterr().out
    assert status == 0
    assert "commander: may arm (all 3 configured devices nominal)" in out
    assert "device id 0xD44509" in out and "device id 0x090C09" in out


def test_ina238_1_absent_is_refused_with_one_clear_line(tmp_path, capsys):
    status, out = boot(tmp_path, capsys, bench_text(second="absent = true"))
    assert status == 1
    assert "commander: arming refused (1 of 3 devices not nominal):" in out
    (line,) = refused_lines(out)
    assert re.fullmatch(
        r"ina238 INA238#1 on I2C bus 2 address 0x45: critical: not found: no ACK "
        r"\(\d+ probe attempts, still retrying\)",
        line,
    ), line


def test_missing_from_the_bench_is_the_same_as_absent(tmp_path, capsys, drivers, manifest):
    text = bench_text().replace("bus_id = 2\naddress = 0x45", "bus_id = 3\naddress = 0x45")
    status, out = boot(tmp_path, capsys, text)
    assert status == 1
    assert refused_lines(out)[0].startswith("ina238 INA238#1 on I2C bus 2 address 0x45: critical")


def test_bus_at_30_percent_errors_starts_after_retries_with_warning(tmp_path, capsys):
    noisy = '[[bus]]\nkind = "i2c"\nbus_id = 1\nerror_rate = 0.3\n'
    status, out = boot(tmp_path, capsys, bench_text(extra=noisy), "--json")
    result = json.loads(out)
    assert status == 1 and result["may_arm"] is False
    by = {i["instance"]: i for i in result["instances"]}
    for name in ("INA238#0", "AK09916#0"):  # both on bus 1
        inst = by[name]
        assert inst["started_at"] is not None, name
        assert inst["health"] == "warning", name
        assert inst["perf"]["bad_transfers"] > 0
        assert re.fullmatch(r"\d+% bad transfers in the last 2 s \(\d+ of \d+\)", inst["reason"])
    assert by["INA238#0"]["perf"]["probe_attempts"] > 1  # it took retries to start
    assert by["INA238#0"]["started_at"] > 0
    assert by["INA238#1"]["health"] == "nominal"  # bus 2 is clean
    assert result["failures"] == [
        f"ina238 INA238#0 on I2C bus 1 address 0x45: warning: {by['INA238#0']['reason']}",
        f"ak09916 AK09916#0 on I2C bus 1 address 0x0C: warning: {by['AK09916#0']['reason']}",
    ]


def test_noisy_bus_always_starts_eventually(drivers, manifest):
    # Keep running: whatever the seed, 30% errors never keep a driver from starting.
    bench = parse_bench(
        bench_text(extra='[[bus]]\nkind = "i2c"\nbus_id = 1\nerror_rate = 0.3\n'), "b", drivers
    )
    retried = 0
    for seed in range(20):
        result = run(bench, drivers, manifest, duration=5, seed=seed)
        assert all(i.started_at is not None for i in result.instances), seed
        ina = next(i for i in result.instances if i.name == "INA238#0")
        retried += ina.probe_attempts > 1
        assert ina.health == "warning"
    assert retried >= 10  # a probe is three transfers: at 30% errors most first attempts fail


def test_absent_with_legacy_boots_with_the_device_silently_missing(tmp_path, capsys):
    status, out = boot(tmp_path, capsys, bench_text(second="absent = true"), "--legacy")
    assert status == 0
    assert "commander: may arm (it knows only the 2 drivers that started)" in out
    assert "silently missing (configured in the manifest, never started, no message):" in out
    assert "  ina238 INA238#1 on I2C bus 2 address 0x45: never started, nobody was told" in out
    assert "ina238@i2c1" in out and "ak09916@i2c1" in out
    assert "arming refused" not in out


def test_legacy_misses_a_slow_device_the_manifest_waits_for(tmp_path, capsys):
    slow = bench_text(mag="power_up = 2.5")
    status, out = boot(tmp_path, capsys, slow, "--json")
    assert status == 0
    mag = next(i for i in json.loads(out)["instances"] if i["instance"] == "AK09916#0")
    assert mag["started_at"] >= 2.5 and mag["health"] == "nominal"
    status, out = boot(tmp_path, capsys, slow, "--legacy")
    assert status == 0
    assert "ak09916 AK09916#0 on I2C bus 1 address 0x0C: never started, nobody was told" in out
    assert "'ak09916 -X -q start' on I2C bus 1 at 0x0C: no ACK after 3 probes" in out


def test_device_that_dies_is_lost_and_reset(tmp_path, capsys):
    status, out = boot(tmp_path, capsys, bench_text(second="dies_after = 4"), "--json")
    result = json.loads(out)
    assert status == 1
    inst = next(i for i in result["instances"] if i["instance"] == "INA238#1")
    assert inst["started_at"] == 0.0
    assert inst["perf"]["resets"] == 1
    assert inst["health"] == "critical"
    assert inst["reason"].startswith("lost: reset at 4.90 s after 10 bad transfers in a row;")
    levels = [level for _, level, _ in inst["timeline"]]
    assert levels[:2] == ["critical", "nominal"] and levels[-1] == "critical"
    assert [what for _, what in inst["marks"]] == ["start", "reset"]


def test_wrong_chip_id(tmp_path, capsys):
    status, out = boot(tmp_path, capsys, bench_text(mag="chip_id = 0x0A"))
    assert status == 1
    (line,) = refused_lines(out)
    assert line.startswith(
        "ak09916 AK09916#0 on I2C bus 1 address 0x0C: critical: not found: wrong chip id 0xA "
        "in register 0x01 (expected 0x9) ("
    )


def probe_times(result, instance: str) -> list[float]:
    return [e["t"] for e in result.events if e["event"] == "probe" and e["instance"] == instance]


def test_probes_back_off_from_20_ms_doubling_up_to_1_s(drivers, manifest):
    # Retried after 20 ms, then with the delay doubling up to 1 s (docs/autostart.md).
    bench = parse_bench(bench_text(mag="absent = true"), "b", drivers)
    result = run(bench, drivers, manifest, duration=5, record_events=True)
    delays = [0.02, 0.04, 0.08, 0.16, 0.32, 0.64, 1.0, 1.0, 1.0]
    expected = [round(sum(delays[:n]), 6) for n in range(len(delays) + 1)]
    assert expected[-1] == 4.26
    assert probe_times(result, "AK09916#0") == expected


def test_a_wrong_chip_id_fails_the_probe_before_the_configuration_write(drivers, manifest):
    # A probe is a soft reset, the chip id read, the configuration write: a wrong id read by
    # the second transfer fails the attempt, so each attempt makes two good transfers. In 3 s
    # the attempts are at 0, 0.02, 0.06, 0.14, 0.30, 0.62, 1.26 and 2.26 s.
    bench = parse_bench(bench_text(mag="chip_id = 0x0A"), "b", drivers)
    result = run(bench, drivers, manifest, duration=3)
    mag = next(i for i in result.instances if i.name == "AK09916#0")
    assert (mag.probe_attempts, mag.transfers, mag.bad_transfers) == (8, 16, 0)


def test_a_bus_error_is_told_apart_from_no_ack(tmp_path, capsys):
    # Every transfer fails on the bus: the chip is there but never answers cleanly. 15 probe
    # attempts in 10 s, as for the missing compass of docs/autostart.md.
    status, out = boot(tmp_path, capsys, bench_text(mag="error_rate = 1.0"))
    assert status == 1
    assert refused_lines(out) == [
        "ak09916 AK09916#0 on I2C bus 1 address 0x0C: critical: not found: bus error "
        "(15 probe attempts, still retrying)"
    ]


def test_a_device_that_stops_answering_is_critical_after_the_data_timeout(drivers, manifest):
    # Powered up at 0.03 s, the INA238 (10 Hz) is found by the probe at 0.06 s (after retries
    # at 0 and 0.02 s) and transfers at 0.16, 0.26, ... s; dying at 4.1 s, its last good
    # transfer is at 4.06 s. No good transfer for more than 0.5 s is critical: first seen at
    # the 100 ms tick after 4.56 s. (Ten bad transfers in a row, at 5.06 s, make it reset.)
    bench = parse_bench(bench_text(second="power_up = 0.03\ndies_after = 4.1"), "b", drivers)
    result = run(bench, drivers, manifest, duration=6)
    ina = next(i for i in result.instances if i.name == "INA238#1")
    assert ina.started_at == 0.06
    critical = [(t, why) for t, level, why in ina.timeline if level == "critical" and t > 0]
    assert critical[0] == (4.6, "no data for 0.5 s")
    assert critical[1][1].startswith("lost: reset at 5.06 s after 10 bad transfers in a row;")


@pytest.mark.parametrize("dies_after", [1.0, 2.0, 3.0, 4.0, 5.0, 7.0])
def test_the_data_timeout_is_the_same_whenever_a_device_dies(dies_after, drivers, manifest):
    # The INA238 (10 Hz, found at 0 s) dying at a whole second has its last good transfer
    # 0.1 s before; more than 0.5 s without one is first seen at the tick 0.6 s after it.
    bench = parse_bench(bench_text(second=f"dies_after = {dies_after}"), "b", drivers)
    result = run(bench, drivers, manifest, duration=dies_after + 1)
    ina = next(i for i in result.instances if i.name == "INA238#1")
    no_data = [(t, why) for t, level, why in ina.timeline if why.startswith("no data")]
    assert no_data == [(dies_after + 0.5, "no data for 0.6 s")]


def test_legacy_probes_back_to_back_and_misses_a_device_10_ms_late(drivers, manifest):
    # Today's -q start probes three times at once at boot; the manifest's driver retries after
    # 20 ms and finds the compass that powered up at 10 ms.
    bench = parse_bench(bench_text(mag="power_up = 0.01"), "b", drivers)
    result = run(bench, drivers, manifest, duration=1)
    assert next(i for i in result.instances if i.name == "AK09916#0").started_at == 0.02
    result = run(bench, drivers, manifest, duration=1, legacy=True)
    mag = [q["line"] for q in result.quiet if q["device"] == "AK09916"]
    assert [line for line in mag if line.startswith("'ak09916 ")] == [
        "'ak09916 -X -q start' on I2C bus 1 at 0x0C: no ACK after 3 probes; not started, no message"
    ]


def test_a_declared_bus_without_an_error_rate_is_clean(drivers, manifest):
    # BenchBus's error rate defaults to none, as a [[bus]] table's does.
    parsed = parse_bench(bench_text(), "b", drivers)
    bench = Bench("b", "b", {("i2c", 1): BenchBus("i2c", 1)}, parsed.devices)
    result = run(bench, drivers, manifest, duration=3)
    assert result.may_arm
    assert [i.bad_transfers for i in result.instances] == [0, 0, 0]


def test_a_healthy_boot_counts_the_documented_transfers(capsys):
    # docs/autostart.md: three probe transfers, then one per period up to the end (10 s at
    # 10 Hz and 50 Hz: 100 and 500), none bad.
    status = main(["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(BENCH)])
    lines = capsys.readouterr().out.splitlines()
    assert status == 0
    assert lines[1:] == [
        "  INA238#0  ina238  I2C bus 1 address 0x45   nominal  started 0.000 s, device id "
        "0xD44509; 103 transfers, 0 bad, 0 resets",
        "  INA238#1  ina238  I2C bus 2 address 0x45   nominal  started 0.000 s, device id "
        "0xD44511; 103 transfers, 0 bad, 0 resets",
        "  AK09916#0 ak09916 I2C bus 1 address 0x0C   nominal  started 0.000 s, device id "
        "0x090C09; 503 transfers, 0 bad, 0 resets",
        "commander: may arm (all 3 configured devices nominal)",
    ]


def test_a_missing_compass_counts_the_documented_probes(tmp_path, capsys):
    # docs/autostart.md's missing compass: 15 probe attempts in 10 s, each a bad transfer.
    status, out = boot(tmp_path, capsys, bench_text(mag="absent = true"))
    assert status == 1
    assert (
        "  AK09916#0 ak09916 I2C bus 1 address 0x0C   critical not started; 15 transfers, 15 "
        "bad, 0 resets (not found: no ACK (15 probe attempts, still retrying))"
    ) in out.splitlines()


def test_a_late_start_counts_its_transfers_from_the_probe_that_found_it(drivers, manifest):
    # Powered up at 0.03 s, both are found by the third probe, at 0.06 s (after one-transfer
    # failures at 0 and 0.02 s: 2 bad + 3 good probe transfers). In 2.55 s the INA238
    # (10 Hz) then transfers at 0.16 .. 2.46 s (24), the AK09916 (50 Hz) at 0.08 .. 2.54 s
    # (124).
    late = "power_up = 0.03"
    bench = parse_bench(bench_text(second=late, mag=late), "b", drivers)
    result = run(bench, drivers, manifest, duration=2.55)
    by = {i.name: i for i in result.instances}
    counts = {
        n: (i.started_at, i.probe_attempts, i.transfers, i.bad_transfers) for n, i in by.items()
    }
    assert counts == {
        "INA238#0": (0.0, 1, 3 + 25, 0),
        "INA238#1": (0.06, 3, 5 + 24, 2),
        "AK09916#0": (0.06, 3, 5 + 124, 2),
    }


@pytest.mark.parametrize("noise", ["", "\nerror_rate = 0.001"])
def test_the_first_window_counts_the_probe_transfers(noise, drivers, manifest):
    # At the first tick (0.1 s) the last 2 s hold the probes' transfers: for both, 2 failed
    # and 3 good; the AK09916 (50 Hz) has also transferred at 0.08 and 0.10 s, the INA238
    # (10 Hz) not yet. More than 5% bad is a warning. (The same with a trace of noise, whose
    # transfers are counted one by one.)
    late = "power_up = 0.03" + noise
    bench = parse_bench(bench_text(second=late, mag=late), "b", drivers)
    result = run(bench, drivers, manifest, duration=0.1)
    by = {i.name: i.timeline for i in result.instances}
    assert by["INA238#1"] == [
        (0.0, "critical", "starting"),
        (0.1, "warning", "40% bad transfers in the last 2 s (2 of 5)"),
    ]
    assert by["AK09916#0"] == [
        (0.0, "critical", "starting"),
        (0.1, "warning", "29% bad transfers in the last 2 s (2 of 7)"),
    ]
    assert by["INA238#0"] == [(0.0, "critical", "starting"), (0.1, "nominal", "")]


def test_a_lost_device_is_reset_and_probed_again_with_backoff(drivers, manifest):
    # Dying at 4 s (last good transfer 3.9 s), the 10 Hz INA238 is critical at 4.5 s, resets
    # after ten bad transfers in a row (4.0 .. 4.9 s) and probes again 20 ms later with the
    # backoff started afresh: at 4.92, 4.94, 4.98, 5.06, 5.22 and 5.54 s (the next, 6.18 s, is
    # after the run).
    bench = parse_bench(bench_text(second="dies_after = 4"), "b", drivers)
    result = run(bench, drivers, manifest, duration=6, record_events=True)
    ina = next(i for i in result.instances if i.name == "INA238#1")
    lost = "lost: reset at 4.90 s after 10 bad transfers in a row; "
    assert ina.timeline[-3:] == [
        (4.5, "critical", "no data for 0.6 s"),
        (4.9, "critical", lost + "0 probe attempts since, last: reset"),
        (5.0, "critical", lost + "3 probe attempts since, last: no ACK"),
    ]
    assert ina.reason == lost + "6 probe attempts since, last: no ACK"
    assert (ina.probe_attempts, ina.resets, ina.marks) == (7, 1, [(0.0, "start"), (4.9, "reset")])
    assert probe_times(result, "INA238#1") == [0.0, 4.92, 4.94, 4.98, 5.06, 5.22, 5.54]


def test_an_absent_device_is_probed_once_a_second_through_a_long_run(drivers, manifest):
    # The backoff's 2 ** attempts overflowed a float after 1,024 attempts: a run of 1,020 s
    # with an absent device ended in a traceback (OverflowError).
    bench = parse_bench(bench_text(mag="absent = true"), "b", drivers)
    result = run(bench, drivers, manifest, duration=1100)
    # Probes at 0, 0.02, 0.06, 0.14, 0.30, 0.62 (20 ms doubling), 1.26 s, then every 1 s up to
    # 1,099.26 s: 6 + 1,099.
    mag = next(i for i in result.instances if i.name == "AK09916#0")
    assert mag.started_at is None and mag.probe_attempts == 1105


def test_a_device_dying_at_once_is_reset_after_ten_bad_transfers(drivers, manifest):
    # Found by the probe at 0 s, dead at 0.05 s: its first ten transfers (0.1 .. 1.0 s) fail.
    bench = parse_bench(bench_text(second="dies_after = 0.05"), "b", drivers)
    result = run(bench, drivers, manifest, duration=1.5)
    ina = next(i for i in result.instances if i.name == "INA238#1")
    assert ina.marks == [(0.0, "start"), (1.0, "reset")]


def test_a_device_dead_from_the_start_is_never_found(drivers, manifest):
    # dies_after = 0: it stops answering at once, before the first probe's transfer.
    bench = parse_bench(bench_text(second="dies_after = 0"), "b", drivers)
    result = run(bench, drivers, manifest, duration=1)
    ina = next(i for i in result.instances if i.name == "INA238#1")
    assert ina.started_at is None
    assert ina.reason.startswith("not found: no ACK (")


def test_the_event_log_of_probes(drivers, manifest):
    # A failed probe says why; one that finds the chip has no reason. Today's start probes
    # three times at once, 1 ms apart, and then gives up quietly.
    bench = parse_bench(bench_text(mag="absent = true"), "b", drivers)
    result = run(bench, drivers, manifest, duration=0.1, record_events=True)
    probes = {e["instance"]: (e["ok"], e["reason"]) for e in result.events if e["event"] == "probe"}
    assert probes == {
        "INA238#0": (True, None),
        "INA238#1": (True, None),
        "AK09916#0": (False, "no ACK"),
    }
    result = run(bench, drivers, manifest, duration=0.1, legacy=True, record_events=True)
    mine = [
        (e["t"], e["event"], e.get("reason"), e.get("quiet"))
        for e in result.events
        if e.get("instance") == "ak09916@i2c1"
    ]
    assert mine == [
        (0.0, "probe", "no ACK", None),
        (0.001, "probe", "no ACK", None),
        (0.002, "probe", "no ACK", None),
        (0.002, "start_failed", "no ACK", True),
    ]


def test_a_flaky_device_fails_its_share_of_transfers(drivers, manifest):
    # 60 s at 50 Hz: about 3000 transfers, 30% failing (a standard deviation of 25, 0.8%).
    bench = parse_bench(bench_text(mag="error_rate = 0.3"), "b", drivers)
    result = run(bench, drivers, manifest, duration=60, seed=3)
    mag = next(i for i in result.instances if i.name == "AK09916#0")
    assert 2990 <= mag.transfers <= 3010 + 3 * mag.probe_attempts
    assert 0.27 < mag.bad_transfers / mag.transfers < 0.33


def test_every_reset_is_counted(drivers, manifest):
    # 60% of the transfers failing: ten in a row now and then, each a reset and a mark.
    bench = parse_bench(bench_text(mag="error_rate = 0.6"), "b", drivers)
    result = run(bench, drivers, manifest, duration=60, seed=0, record_events=True)
    mag = next(i for i in result.instances if i.name == "AK09916#0")
    resets = [e["at"] for e in result.events if e["event"] == "reset" and e["instance"] == mag.name]
    assert mag.resets >= 2
    assert mag.resets == len(resets) == len([m for m in mag.marks if m[1] == "reset"])


def test_a_trace_of_noise_does_not_change_when_a_dead_device_resets(drivers, manifest):
    # As without noise: the good transfer at 3.9 s ends any run of bad ones, ten more (4.0 ..
    # 4.9 s) make it reset.
    bench = parse_bench(bench_text(second="dies_after = 4\nerror_rate = 0.001"), "b", drivers)
    result = run(bench, drivers, manifest, duration=5)
    ina = next(i for i in result.instances if i.name == "INA238#1")
    assert ina.marks == [(0.0, "start"), (4.9, "reset")]


def ina238_at_3_hz(tmp_path, schema):
    """The bundled drivers with INA238's rate 3 Hz: its transfers every 1/3 s, off the
    microsecond grid."""
    text = DEFAULT_DRIVERS.read_text()
    assert text.count("order = 30\n") == 1 and "rate_hz = 10\n" in text
    head, tail = text.split("order = 30\n")
    custom = tmp_path / "d.toml"
    custom.write_text(head + "order = 30\n" + tail.replace("rate_hz = 10\n", "rate_hz = 3\n", 1))
    slow = load_drivers(custom, parameter_specs(schema))
    assert slow["ina238"].rate_hz == 3
    return slow, configured(load_manifest(None, AIRFRAME), slow)


def test_times_are_kept_to_the_microsecond(tmp_path, schema):
    # A driver declared at 3 Hz transfers every 1/3 s: found at 0 s and dead at 4.2 s, its
    # last good transfer is the 12th (4 s), the 13th .. 22nd fail: it resets at 22/3 s.
    slow, manifest = ina238_at_3_hz(tmp_path, schema)
    bench = parse_bench(bench_text(second="dies_after = 4.2"), "b", slow)
    result = run(bench, slow, manifest, duration=8, record_events=True)
    ina = next(i for i in result.instances if i.name == "INA238#1")
    assert ina.marks == [(0.0, "start"), (7.333333, "reset")]
    (reset,) = [e for e in result.events if e["event"] == "reset" and e["instance"] == ina.name]
    assert reset["at"] == 7.333333


def test_a_start_after_a_reset_is_kept_to_the_microsecond(tmp_path, schema):
    # ULog and the timeline keep whole microseconds. A 3 Hz driver resets 10/3 s after a bad
    # run starts, off the grid, and its first good probe comes a backoff after that: with this
    # seed, found at 0.62 s, reset at 0.62 + 98/3 s, found again four probes later (+0.16 s).
    slow, manifest = ina238_at_3_hz(tmp_path, schema)
    bench = parse_bench(bench_text(second="error_rate = 0.55"), "b", slow)
    result = run(bench, slow, manifest, duration=40, seed=2)
    ina = next(i for i in result.instances if i.name == "INA238#1")
    assert [what for _, what in ina.marks] == ["start", "reset", "start"]
    reset, again = ina.marks[1][0], ina.marks[2][0]
    assert reset == pytest.approx(0.62 + 98 / 3, abs=1e-6)
    assert again == pytest.approx(reset + 0.16, abs=1e-6)
    assert all(at == round(at, 6) for at, _ in ina.marks), ina.marks


def test_flaky_device(drivers, manifest):
    bench = parse_bench(bench_text(mag="error_rate = 0.5"), "b", drivers)
    result = run(bench, drivers, manifest, duration=5, seed=1)
    mag = next(i for i in result.instances if i.name == "AK09916#0")
    assert mag.health in ("warning", "critical")
    assert 0.3 < mag.bad_transfers / mag.transfers < 0.7
    assert result.may_arm is False


def test_unstartable_instance_is_refused(tmp_path, capsys, schema, drivers):
    s = load_manifest(None, AIRFRAME)
    s.set("INA238#1.bus.i2c.bus_id", 0)
    path = tmp_path / "v.store"
    s.save(path)
    status = main(["autostart", "run", "--store", str(path), "--bench", str(BENCH)])
    out = capsys.readouterr().out
    assert status == 1
    assert refused_lines(out) == [
        "ina238 INA238#1 on I2C bus 0 address 0x45: critical: not started: i2c bus_id is 0 "
        "(unset; buses are numbered from 1)"
    ]


def test_instance_without_a_driver_is_refused(tmp_path, drivers, schema):
    s = Store(schema)
    s.add("INA238#0")
    s.set("INA238#0.bus.i2c.bus_id", 1)
    only_mags = load_drivers(DEFAULT_DRIVERS)
    text = DEFAULT_DRIVERS.read_text().replace(
        "autostart = true\norder = 30", "autostart = false\norder = 30"
    )
    custom = tmp_path / "d.toml"
    custom.write_text(text)
    mine = load_drivers(custom, parameter_specs(schema))
    assert not mine["ina238"].autostart and only_mags["ina238"].autostart
    result = run(load_bench(BENCH, mine), mine, configured(s, mine), duration=1)
    assert result.failures == [
        "ina238 INA238#0 on I2C bus 1 address 0x45: critical: not started: driver ina238 "
        "does not autostart"
    ]


def test_legacy_without_a_manifest(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    status = main(["autostart", "run", "--bench", str(BENCH), "--legacy"])
    out = capsys.readouterr().out
    assert status == 0
    assert "(no manifest to compare with: give --store or --airframe)" in out
    # Without --legacy there is nothing to boot.
    assert main(["autostart", "run", "--bench", str(BENCH)]) == 1
    assert "no store file px4params.store" in capsys.readouterr().err


# -- seeing it: events, perf counters, the timeline --------------------------------------------


def test_event_log_with_perf_counters(tmp_path, capsys):
    events = tmp_path / "run.jsonl"
    status, out = boot(
        tmp_path,
        capsys,
        bench_text(second="dies_after = 3"),
        "--events",
        str(events),
        "--duration",
        "6",
    )
    assert status == 1
    assert "wrote " in out and str(events) in out
    records = [json.loads(line) for line in events.read_text().splitlines()]
    times = [r["t"] for r in records]
    assert times == sorted(times)
    assert records[0]["event"] == "boot" and records[-1]["event"] == "verdict"
    kinds = {r["event"] for r in records}
    assert {"auto", "register", "probe", "started", "health", "perf", "reset", "arming"} <= kinds
    perf = [r for r in records if r["event"] == "perf"]
    assert len(perf) == 3 * 6  # each instance, every second
    assert {"transfers", "bad_transfers", "resets"} <= set(perf[0])
    last = {r["instance"]: r for r in perf}
    assert last["INA238#1"]["resets"] == 1 and last["INA238#0"]["bad_transfers"] == 0
    # Counters only grow.
    for name in last:
        seq = [r["transfers"] for r in perf if r["instance"] == name]
        assert seq == sorted(seq)
    started = next(r for r in records if r["event"] == "started" and r["instance"] == "INA238#0")
    assert started["device_id"] == 0xD44509 and started["device_id_hex"] == "0xD44509"


def test_timeline_svg(tmp_path, capsys):
    picture = tmp_path / "run.svg"
    status, out = boot(
        tmp_path, capsys, bench_text(second="absent = true"), "--timeline", str(picture)
    )
    assert status == 1 and f"wrote health timeline to {picture}" in out
    root = ET.fromstring(picture.read_text())
    ns = "{http://www.w3.org/2000/svg}"
    assert root.tag == f"{ns}svg"
    texts = " ".join("".join(t.itertext()) for t in root.iter(f"{ns}text"))
    assert "arming refused" in texts and "INA238#1" in texts and "simulated time (s)" in texts
    tips = ["".join(t.itertext()) for t in root.iter(f"{ns}title")]
    assert any("critical: not found: no ACK" in tip for tip in tips)


def test_timeline_of_a_legacy_run_shows_the_missing(drivers, manifest):
    bench = parse_bench(bench_text(second="absent = true"), "b", drivers)
    result = run(bench, drivers, manifest, duration=3, legacy=True)
    svg = render_svg(result)
    ET.fromstring(svg)
    assert "INA238#1 (ina238)" in svg and "stroke-dasharray" in svg
    assert "may arm" in svg


def test_json_result(tmp_path, capsys):
    status, out = boot(tmp_path, capsys, bench_text(), "--json", "--seed", "7")
    result = json.loads(out)
    assert status == 0
    assert result["mode"] == "manifest" and result["seed"] == 7 and result["may_arm"] is True
    assert [i["instance"] for i in result["instances"]] == ["INA238#0", "INA238#1", "AK09916#0"]
    assert result["instances"][0]["device_id_hex"] == "0xD44509"


def test_json_result_fields(tmp_path, capsys):
    status, out = boot(tmp_path, capsys, bench_text(), "--json", "--duration", "1")
    result = json.loads(out)
    assert status == 0
    first = result.pop("instances")[0]
    assert result == {
        "mode": "manifest",
        "seed": 0,
        "duration": 1.0,
        "bench": str(tmp_path / "bench.toml"),
        "bench_name": "",
        "may_arm": True,
        "failures": [],
        "quiet": [],
        "silently_missing": [],
        "arming": [[0.1, True]],  # the first health check, every device nominal
        "log_cut_at": None,
    }
    assert first == {
        "instance": "INA238#0",
        "driver": "ina238",
        "parameter": "INA238",
        "bus": "i2c",
        "bus_id": 1,
        "address": 0x45,
        "location": "I2C bus 1 address 0x45",
        "registered": True,
        "health": "nominal",
        "reason": "",
        "started_at": 0.0,
        "device_id": 0xD44509,
        "device_id_hex": "0xD44509",
        "perf": {"transfers": 13, "bad_transfers": 0, "resets": 0, "probe_attempts": 1},
        "timeline": [[0.0, "critical", "starting"], [0.1, "nominal", ""]],
        "marks": [[0.0, "start"]],
    }


@pytest.mark.parametrize("duration", ["0", "-1", "nan", "inf", "100000", "x"])
def test_bad_duration(duration, capsys):
    # Refused as the command line is read (a usage error), as every duration option is.
    args = ["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(BENCH)]
    with pytest.raises(SystemExit) as e:
        main([*args, "--duration", duration])
    assert e.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        "px4params autostart run: error: argument --duration: expected seconds more than 0 and "
        f"at most 86400, not '{duration}'"
    )


def test_without_bench_the_manifest_boots_healthy(capsys):
    # (--bench was required; a healthy bench is now the default: see "autostart run without
    # --bench" below)
    assert main(["autostart", "run", "--airframe", str(AIRFRAME)]) == 0
    assert capsys.readouterr().out.startswith("manifest boot of a healthy bench")


# -- bench files: every error, by message -----------------------------------------------------


def bench_error(text: str, drivers) -> str:
    with pytest.raises(BenchFileError) as e:
        parse_bench(text, "bench.toml", drivers)
    message = str(e.value)
    assert "\n" not in message and message.startswith("bench.toml: ")
    return message


AT = "bench.toml: device #1 (INA238 on I2C bus 1 address 0x45): "
ONE = '[[device]]\nchip = "INA238"\nbus = "i2c"\nbus_id = 1\naddress = 0x45\n'


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[[device]\n", "bench.toml: not TOML: "),
        ("[hardware]\nx = 1\n", "bench.toml: unknown top-level key 'hardware' (expected: bench,"),
        ("[[devices]]\nchip = 1\n", "bench.toml: unknown top-level key 'devices' (did you mean"),
        ('[bench]\nnme = "x"\n', "bench.toml: [bench]: unknown key 'nme' (did you mean 'name'?)"),
        ("[bench]\nname = 3\n", "bench.toml: [bench]: name must be a string, not 3"),
        ("bench = 3\n", "bench.toml: [bench] must be a table"),
        ("device = 3\n", "bench.toml: 'device' must be [[device]] tables"),
        (
            ONE.replace("address = 0x45", "address = 0x45\nadress = 1"),
            "bench.toml: device #1 (INA238): unknown key 'adress' (did you mean 'address'?)",
        ),
        (
            ONE.replace("0x45", "200"),
            "bench.toml: device #1 (INA238): I2C address 200 (0xC8) is out of range 0..127 "
            "(0x00..0x7F)",
        ),
        (
            ONE.replace("i2c", "spi").replace("0x45", "32"),
            "bench.toml: device #1 (INA238): SPI chip select 32 (0x20) is out of range 0..31",
        ),
        (
            ONE.replace("0x45", '"0x45"'),
            "bench.toml: device #1 (INA238): address must be an integer (e.g. 0x45), not '0x45'",
        ),
        (
            ONE.replace('"INA238"', '"INA239"'),
            "bench.toml: device #1 (INA239): unknown chip 'INA239' (no declared driver drives "
            "it; did you mean INA238?)",
        ),
        (
            ONE.replace('"INA238"', '"XYZ"'),
            "bench.toml: device #1 (XYZ): unknown chip 'XYZ' (no declared driver drives it; "
            "known: AK09916, ASP5033, AUAV, BATMON_SMBUS,",
        ),
        (ONE.replace("bus_id = 1\n", ""), "bench.toml: device #1 (INA238): missing key 'bus_id'"),
        (
            ONE.replace('chip = "INA238"\n', ""),
            "bench.toml: device #1: missing key 'chip'",
        ),
        (
            ONE.replace('bus = "i2c"', 'bus = "can"'),
            "bench.toml: device #1 (INA238): bus 'can' is not a simulated bus kind (expected i2c "
            "or spi)",
        ),
        (
            ONE.replace('bus = "i2c"', 'bus = "serial"'),
            "bench.toml: device #1 (INA238): bus 'serial' is not a simulated bus kind (not "
            "simulated) (expected i2c or spi)",
        ),
        (
            ONE.replace("bus_id = 1", "bus_id = 16"),
            "bench.toml: device #1 (INA238): bus_id must be an integer 1..15, not 16",
        ),
        (
            ONE + "error_rate = 1.5\n",
            AT + "error_rate must be a number from 0 to 1",
        ),
        (
            ONE + "dies_after = -2\n",
            AT + "dies_after must be a number of seconds >= 0, not -2",
        ),
        (
            ONE + "power_up = inf\n",
            AT + "power_up must be a number of seconds >= 0, not inf",
        ),
        (
            ONE + "chip_id = -1\n",
            AT + "chip_id must be an integer 0..0xFFFF, not -1",
        ),
        (
            ONE + 'absent = "yes"\n',
            AT + "absent must be true or",
        ),
        (
            ONE + ONE.replace("INA238", "INA228"),
            "bench.toml: device #2 (INA228): I2C bus 1 address 0x45 already has a INA238",
        ),
        ('[[bus]]\nkind = "i2c"\n', "bench.toml: bus #1: missing key 'bus_id'"),
        ("[[bus]]\nbus_id = 1\n", "bench.toml: bus #1: missing key 'kind'"),
        (
            '[[bus]]\nkind = "i2c"\nbus_id = 1\nnoise = 0.1\n',
            "bench.toml: bus #1: unknown key 'noise' (expected: kind, bus_id, error_rate)",
        ),
        (
            '[[bus]]\nkind = "i2c"\nbus_id = 1\nerror_rate = "30%"\n',
            "bench.toml: bus #1: error_rate must be a number from 0 to 1",
        ),
        (
            '[[bus]]\nkind = "i2c"\nbus_id = 1\n[[bus]]\nkind = "i2c"\nbus_id = 1\n',
            "bench.toml: bus #2: i2c bus 1 is declared twice",
        ),
    ],
)
def test_bench_file_errors(text, message, drivers):
    assert bench_error(text, drivers).startswith(message)


def device_text(
    bus: str = "i2c", bus_id: object = 1, address: object = 0x45, extra: str = ""
) -> str:
    return (
        f'[[device]]\nchip = "INA238"\nbus = "{bus}"\nbus_id = {bus_id}\naddress = {address}\n'
        + extra
    )


@pytest.mark.parametrize(
    ("bus", "address", "location"),
    [
        ("i2c", "0", "I2C bus 1 address 0x00"),
        ("i2c", "127", "I2C bus 1 address 0x7F"),
        ("spi", "0", "SPI bus 1 chip select 0"),
        ("spi", "31", "SPI bus 1 chip select 31"),
    ],
)
def test_addresses_at_both_ends_of_their_range_are_accepted(bus, address, location, drivers):
    # The bench file's ranges: an I2C address 0..127, an SPI chip select 0..31.
    (device,) = parse_bench(device_text(bus, address=address), "b", drivers).devices.values()
    assert (device.address, device.location) == (int(address), location)


@pytest.mark.parametrize(
    ("bus", "address", "message"),
    [
        ("i2c", "128", "I2C address 128 (0x80) is out of range 0..127 (0x00..0x7F)"),
        ("i2c", "-1", "I2C address -1 is out of range 0..127 (0x00..0x7F)"),
        ("spi", "32", "SPI chip select 32 (0x20) is out of range 0..31 (0x00..0x1F)"),
        ("spi", "-1", "SPI chip select -1 is out of range 0..31 (0x00..0x1F)"),
        ("i2c", "true", "address must be an integer (e.g. 0x45), not True"),
    ],
)
def test_addresses_outside_their_range_are_refused(bus, address, message, drivers):
    text = device_text(bus, address=address)
    assert bench_error(text, drivers) == f"bench.toml: device #1 (INA238): {message}"


@pytest.mark.parametrize("bus_id", [1, 15])
def test_bus_ids_at_both_ends_of_their_range_are_accepted(bus_id, drivers):
    bus = f'[[bus]]\nkind = "i2c"\nbus_id = {bus_id}\n'
    bench = parse_bench(bus + device_text(bus_id=bus_id), "b", drivers)
    assert list(bench.buses) == [("i2c", bus_id)]
    assert list(bench.devices) == [("i2c", bus_id, 0x45)]


@pytest.mark.parametrize("bus_id", ["0", "16", "true", '"1"'])
@pytest.mark.parametrize("table", ["bus", "device"])
def test_bus_ids_outside_1_to_15_are_refused(table, bus_id, drivers):
    if table == "bus":
        text, where = f'[[bus]]\nkind = "i2c"\nbus_id = {bus_id}\n', "bus #1"
    else:
        text, where = device_text(bus_id=bus_id), "device #1 (INA238)"
    shown = {"true": "True", '"1"': "'1'"}.get(bus_id, bus_id)
    assert bench_error(text, drivers) == (
        f"bench.toml: {where}: bus_id must be an integer 1..15, not {shown}"
    )


@pytest.mark.parametrize("chip_id", [0, 0xFFFF])
def test_chip_ids_at_both_ends_of_their_range_are_accepted(chip_id, drivers):
    (device,) = parse_bench(
        device_text(extra=f"chip_id = {chip_id}\n"), "b", drivers
    ).devices.values()
    assert device.chip_id == chip_id


@pytest.mark.parametrize(
    ("chip_id", "shown"),
    [
        ("0x10000", "65536"),
        ("-1", "-1"),
        ("true", "True"),
        ('"0x2260"', "'0x2260'"),
        ("1.0", "1.0"),
    ],
)
def test_chip_ids_outside_16_bits_are_refused(chip_id, shown, drivers):
    text = device_text(extra=f"chip_id = {chip_id}\n")
    assert bench_error(text, drivers) == f"{AT}chip_id must be an integer 0..0xFFFF, not {shown}"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("bus = [1]\n", "bench.toml: bus #1: is not a table"),
        ("device = [1]\n", "bench.toml: device #1: is not a table"),
        (
            '[[device]]\nchip = 5\nbus = "i2c"\nbus_id = 1\naddress = 1\n',
            "bench.toml: device #1: chip must be a string, not 5",
        ),
        (
            "[bench]\ncolour = 1\n",
            "bench.toml: [bench]: unknown key 'colour' (expected: name, description)",
        ),
    ],
)
def test_bench_file_errors_whole_message(text, message, drivers):
    assert bench_error(text, drivers) == message


@pytest.mark.parametrize("key", ["power_up", "dies_after"])
@pytest.mark.parametrize(("value", "shown"), [("true", "True"), ('"2 s"', "'2 s'"), ("-1", "-1")])
def test_seconds_must_be_numbers_from_0(key, value, shown, drivers):
    text = device_text(extra=f"{key} = {value}\n")
    assert bench_error(text, drivers) == f"{AT}{key} must be a number of seconds >= 0, not {shown}"


def test_a_result_built_without_the_optional_fields_has_them_empty():
    # As a result read back from a flight log is: nothing quiet, missing or recorded.
    result = RunResult("manifest", 0, 1.0, "b", [], True, [])
    assert (result.quiet, result.silently_missing, result.arming, result.events) == (
        [],
        [],
        [],
        None,
    )
    assert result.as_dict()["log_cut_at"] is None


@pytest.mark.parametrize(
    ("may_arm", "arming", "cut_at", "verdict"),
    [
        (True, [(0.1, True)], None, "may arm"),
        (False, [(0.1, False)], None, "arming refused"),
        (False, [], None, "arming refused"),  # a whole run: the commander's silence refuses
        (False, [(0.1, False)], 2.0, "arming refused"),
        (True, [(0.1, True)], 2.0, "may arm"),
        (False, [], 0.0, "no arming answer logged"),  # cut before the commander answered
    ],
)
def test_the_verdict_of_a_log_cut_before_any_answer_is_no_answer(
    may_arm: bool, arming: list[tuple[float, bool]], cut_at: float | None, verdict: str
) -> None:
    result = RunResult("manifest", 0, 1.0, "b", [], may_arm, [], arming=arming, log_cut_at=cut_at)
    assert result.verdict == verdict


def test_bench_table_may_describe_the_bench(drivers):
    text = '[bench]\nname = "quad"\ndescription = "the frame on the desk"\n' + ONE
    assert parse_bench(text, "b", drivers).name == "quad"


@pytest.mark.parametrize(
    ("content", "reason"),
    [
        (None, "cannot read: is a folder, not a file"),
        (b"[[device]]\n\xff", "not a text file: byte 0xFF at offset 11 is not UTF-8"),
    ],
)
def test_unreadable_bench_file(tmp_path, content, reason, drivers):
    path = tmp_path / "b.toml"
    if content is None:
        path.mkdir()
    else:
        path.write_bytes(content)
    with pytest.raises(BenchFileError) as e:
        load_bench(path, drivers)
    assert str(e.value) == f"{path}: {reason}"


def test_bench_file_not_found(tmp_path, capsys, drivers):
    with pytest.raises(BenchFileError, match=r"nope\.toml: no such bench file$"):
        load_bench(tmp_path / "nope.toml", drivers)
    status = main(
        ["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(tmp_path / "n.toml")]
    )
    assert status == 1
    assert (
        capsys.readouterr().err == f"px4params: error: {tmp_path / 'n.toml'}: no such bench file\n"
    )


def test_bench_error_through_the_cli(tmp_path, capsys):
    path = tmp_path / "b.toml"
    path.write_text(ONE.replace("0x45", "200"))
    args = ["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(path)]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"px4params: error: {path}: device #1 (INA238): I2C address 200")
    assert err.count("\n") == 1 and "Traceback" not in err


def test_the_example_benches_load(drivers):
    for path in sorted((REPO / "examples").glob("*.bench.toml")):
        bench = load_bench(path, drivers)
        assert bench.devices, path


# -- properties -----------------------------------------------------------------------------------

_LOCATIONS = [("INA238", "i2c", 1, 0x45), ("INA238", "i2c", 2, 0x45), ("AK09916", "i2c", 1, 0x0C)]

faults = st.fixed_dictionaries(
    {
        "absent": st.booleans(),
        "chip_id": st.one_of(st.none(), st.sampled_from([0x09, 0x0A, 0x238, 0x2260])),
        "error_rate": st.sampled_from([0.0, 0.0, 0.02, 0.3, 0.9]),
        "dies_after": st.one_of(st.none(), st.floats(0, 4, allow_nan=False)),
        "power_up": st.one_of(st.just(0.0), st.floats(0, 4, allow_nan=False)),
    }
)
benches = st.builds(
    lambda present, fault_list, bus_rates: Bench(
        "generated",
        "generated",
        {("i2c", b): BenchBus("i2c", b, r) for b, r in zip((1, 2), bus_rates, strict=True)},
        {
            (kind, bus, address): BenchDevice(chip, kind, bus, address, **f)
            for (chip, kind, bus, address), here, f in zip(
                _LOCATIONS, present, fault_list, strict=True
            )
            if here
        },
    ),
    st.lists(st.booleans(), min_size=3, max_size=3),
    st.lists(faults, min_size=3, max_size=3),
    st.lists(st.sampled_from([0.0, 0.1, 0.3]), min_size=2, max_size=2),
)


@settings(
    max_examples=budget(40),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(bench=benches, seed=st.integers(0, 2**32), legacy=st.booleans())
def test_a_run_is_determined_by_its_seed(bench, seed, legacy, drivers, manifest):
    one = run(bench, drivers, manifest, duration=3, seed=seed, legacy=legacy, record_events=True)
    two = run(bench, drivers, manifest, duration=3, seed=seed, legacy=legacy, record_events=True)
    assert one.as_dict() == two.as_dict()
    assert one.events == two.events


@settings(
    max_examples=budget(40),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(bench=benches, seed=st.integers(0, 1000))
def test_the_commander_refuses_exactly_the_devices_not_nominal(bench, seed, drivers, manifest):
    result = run(bench, drivers, manifest, duration=3, seed=seed)
    bad = [i for i in result.instances if i.health != "nominal"]
    assert result.may_arm == (not bad)
    assert result.failures == [i.failure_line() for i in bad]
    for i, line in zip(bad, result.failures, strict=True):
        assert line.startswith(
            f"{i.driver} {i.name} on I2C bus {i.bus_id} address 0x{i.address:02X}: "
        )
        assert line.endswith(f": {i.health}: {i.reason}") and i.reason
    # An absent device, or one answering the wrong chip id, never starts.
    for i in result.instances:
        device = bench.devices.get((i.kind, i.bus_id, i.address))
        if (
            device is None
            or device.absent
            or device.chip_id not in (None, drivers[i.driver].chip_id)
        ):
            assert i.started_at is None and i.health == "critical"
        # Health is a function of what happened: transfers add up.
        assert 0 <= i.bad_transfers <= i.transfers


@settings(
    max_examples=budget(30),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    places=st.lists(
        st.tuples(
            st.sampled_from(["INA238", "AK09916", "BMM350", "RM3100"]),
            st.integers(1, 15),
            st.integers(0x03, 0x77),
        ),
        min_size=1,
        max_size=4,
        unique_by=lambda p: p[1:],
    )
)
def test_published_device_ids_round_trip(places, schema, drivers):
    s = Store(schema)
    devices = {}
    for chip, bus_id, address in places:
        name = s.add(chip)
        s.set(f"{name}.bus.i2c.bus_id", bus_id)
        s.set(f"{name}.bus.i2c.address", address)
        devices[("i2c", bus_id, address)] = BenchDevice(chip, "i2c", bus_id, address)
    manifest = configured(s, drivers)
    result = run(Bench("b", "b", {}, devices), drivers, manifest, duration=0.5)
    assert result.may_arm
    table = current_devtypes()
    for inst, c in zip(result.instances, manifest, strict=True):
        assert inst.device_id == c.device_id
        decoded = devid.decode(inst.device_id, table)
        assert (decoded.bus_type_name, decoded.bus, decoded.address) == ("I2C", c.bus_id, c.address)
        assert decoded.devtype == drivers[inst.driver].devtype
        assert decoded.devtype_name == c.driver.chip


def test_spi_device(schema, drivers):
    s = Store(schema)
    s.add("LIS3MDL#0")
    value = s.get("LIS3MDL#0")
    value["bus"] = {"spi": {"bus_id": 1, "chip_select": 3, "max_frequency": 0, "mode": 3}}
    s.set("LIS3MDL#0", value)
    text = '[[device]]\nchip = "LIS3MDL"\nbus = "spi"\nbus_id = 1\naddress = 3\n'
    result = run(parse_bench(text, "b", drivers), drivers, configured(s, drivers), duration=1)
    (inst,) = result.instances
    assert result.may_arm and inst.location == "SPI bus 1 chip select 3"
    assert devid.decode(inst.device_id, current_devtypes()).describe() == (
        "LIS3MDL (MAG), SPI bus 1, device 3"
    )


# -- autostart run without --bench: a healthy bench from the manifest --------------------------


HEALTHY_BENCH_FILE = REPO / "examples" / "two_batteries.bench.toml"


def _boot(capsys: pytest.CaptureFixture[str], *words: str) -> tuple[int, list[str], str]:
    status = main(["autostart", "run", "--airframe", str(AIRFRAME), "--duration", "5", *words])
    out, err = capsys.readouterr()
    return status, out.splitlines(), err


def test_run_without_bench_boots_every_configured_device_healthy(
    capsys: pytest.CaptureFixture[str],
) -> None:
    status, lines, err = _boot(capsys)
    assert (status, err) == (0, "")
    assert lines[0] == (
        "manifest boot of a healthy bench (every configured device present, no faults): "
        "3 configured instances, 5 s simulated, seed 0"
    )
    assert lines[-1] == "commander: may arm (all 3 configured devices nominal)"
    # The same boot as on the hand-written bench of the same vehicle, device for device.
    status, by_hand, err = _boot(capsys, "--bench", str(HEALTHY_BENCH_FILE))
    assert (status, err) == (0, "")
    assert lines[1:] == by_hand[1:]
    assert [line.split()[0] for line in lines[1:4]] == ["INA238#0", "INA238#1", "AK09916#0"]


def test_run_without_bench_leaves_out_what_cannot_start(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Bus 0 is no bus: the instance cannot start, so no device is put there and arming is
    # refused for it, as on any bench.
    airframe = tmp_path / "bus0.airframe"
    airframe.write_text(
        "param add INA238#0\nparam set-default INA238#0.bus.i2c.bus_id 0\n"
        "param add AK09916#0\nparam set-default AK09916#0.bus.i2c.bus_id 1\n"
        "param set-default AK09916#0.bus.i2c.address 0x0C\n"
    )
    status = main(["autostart", "run", "--airframe", str(airframe), "--duration", "3"])
    out = capsys.readouterr().out
    assert status == 1
    assert "AK09916#0 ak09916 I2C bus 1 address 0x0C   nominal" in out
    assert "commander: arming refused (1 of 2 devices not nominal):" in out
    # Nor does today's boot of that bench find a bus 0 to probe.
    assert main(["autostart", "run", "--airframe", str(airframe), "--legacy"]) == 0
    assert capsys.readouterr().out.startswith(
        "legacy boot of a healthy bench (every configured device present, no faults): every "
        "probed driver '-X -q start' on I2C buses 1 at its default address"
    )


def test_healthy_bench_is_the_hand_written_one(drivers, manifest):
    # The example bench is the two-battery airframe with every device present and no faults:
    # the bench `autostart run` boots without --bench is the same, device for device.
    assert healthy_bench(manifest).devices == load_bench(HEALTHY_BENCH_FILE, drivers).devices


def test_legacy_boots_every_i2c_bus_of_the_bench(tmp_path, capsys):
    # A [[bus]] entry puts a bus on the bench even without a device on it; an SPI bus is not
    # one the legacy '-X' start probes.
    buses = '[[bus]]\nkind = "i2c"\nbus_id = 3\n[[bus]]\nkind = "spi"\nbus_id = 4\n'
    status, out = boot(tmp_path, capsys, bench_text(extra=buses), "--legacy")
    assert status == 0
    assert out.splitlines()[0].startswith(
        "legacy boot of " + str(tmp_path / "bench.toml") + ": every probed driver '-X -q start' "
        "on I2C buses 1, 2, 3 at its default address, 3 probes"
    )


def test_legacy_without_manifest_needs_a_bench(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    assert main(["autostart", "run", "--legacy"]) == 1
    assert capsys.readouterr() == (
        "",
        "px4params: error: --legacy without a manifest (--store or --airframe) needs --bench "
        "FILE\n",
    )


def test_run_defaults_to_ten_seconds_seed_0_and_no_event_log(drivers, manifest):
    result = run(healthy_bench(manifest), drivers, manifest)
    assert (result.duration, result.seed, result.events) == (10.0, 0, None)
    assert result.arming == [(0.1, True)]


@pytest.mark.parametrize("duration", [0, 0.0, -1, float("nan"), float("inf"), float("-inf")])
def test_run_refuses_a_duration_that_is_not_a_positive_number(duration, drivers, manifest):
    with pytest.raises(BenchFileError) as caught:
        run(healthy_bench(manifest), drivers, manifest, duration=duration)
    assert str(caught.value) == f"duration must be a positive number of seconds, not {duration}"


def test_a_manifest_run_needs_the_configured_instances(drivers, manifest):
    with pytest.raises(BenchFileError) as caught:
        run(healthy_bench(manifest), drivers, None)
    assert str(caught.value) == "a manifest run needs the configured instances"


@pytest.mark.parametrize(
    ("duration", "seconds"), [(0.9, []), (1.0, [1.0]), (1.9, [1.0]), (2.0, [1.0, 2.0])]
)
def test_perf_counters_are_recorded_at_each_whole_second_of_the_run(
    duration, seconds, drivers, manifest
):
    result = run(healthy_bench(manifest), drivers, manifest, duration=duration, record_events=True)
    perf = [r["t"] for r in result.events if r["event"] == "perf"]
    assert perf == [t for t in seconds for _ in range(3)]  # the three instances, every second


def test_a_run_shorter_than_a_tick_ends_on_its_own_last_slice_in_microseconds(drivers, manifest):
    # One slice, ending at the run's end (0.0123456789 s, kept as 0.012346 s): every device is
    # found at 0 s and is nominal there, so the commander may arm from then on.
    result = run(
        healthy_bench(manifest), drivers, manifest, duration=0.0123456789, record_events=True
    )
    assert result.arming == [(0.012346, True)]
    for i in result.instances:
        assert i.timeline[-1] == (0.012346, "nominal", "")
    ticked = [r for r in result.events if r["event"] in ("health", "arming", "verdict")]
    assert len(ticked) == 3 + 1 + 1 and {r["t"] for r in ticked} == {0.012346}


def test_an_instance_nothing_starts_is_known_to_the_commander_with_all_its_problems(
    drivers, manifest
):
    problems = (
        "no driver declared for parameter INA238",
        "i2c bus_id is 0 (unset; buses are numbered from 1)",
    )
    orphan = Configured("INA238#5", "INA238", None, "i2c", 0, 0x45, {}, problems)
    result = run(
        healthy_bench(manifest), drivers, [*manifest, orphan], duration=1, record_events=True
    )
    reason = "not started: no driver declared for parameter INA238; i2c bus_id is 0 (unset; " + (
        "buses are numbered from 1)"
    )
    assert result.failures == [f"- INA238#5 on I2C bus 0 address 0x45: critical: {reason}"]
    (out,) = [i for i in result.instances if i.name == "INA238#5"]
    # Critical with its reason from the start, and never anything else.
    assert out.timeline == [(0.0, "critical", reason)]
    assert out.as_dict()["registered"] is False and out.as_dict()["driver"] == "-"
    # Not registered by a driver: the commander knows it, but no driver keeps perf counters.
    perf = {r["instance"] for r in result.events if r["event"] == "perf"}
    assert perf == {c.instance for c in manifest}


def test_legacy_starts_only_the_i2c_drivers_with_a_default_address_not_started_by_a_switch(
    drivers, manifest
):
    # Started first (lowest order): an SPI-only driver, an I2C driver without a default
    # address and one a SENS_EN_* switch starts; today's boot starts none of them and goes on.
    changed = {
        "ina226": {"buses": ("spi",), "order": -3},
        "ina228": {"default_address": None, "order": -2},
        "ina238": {"started_by": "parameter", "enabled_by": "SENS_EN_INA238", "order": -1},
    }
    mine = Drivers(
        [dataclasses.replace(d, **changed.get(d.name, {})) for d in drivers], "mine.toml"
    )
    bench = parse_bench(bench_text(), "b", mine)
    orphan = Configured("INA238#5", "INA238", None, "i2c", 1, 0x40, {}, ("no driver",))
    result = run(bench, mine, [*manifest, orphan], duration=1, legacy=True, record_events=True)
    started = [r["driver"] for r in result.events if r["event"] == "legacy_start"]
    assert not set(changed) & set(started) and {"ak09916", "ist8310"} <= set(started)
    names = {i.name for i in result.instances}
    # The compass on bus 1 answers; on bus 2 nothing does: left out, quiet.
    assert "ak09916@i2c1" in names and "ak09916@i2c2" not in names
    # The commander hears the health of what started, and only of that.
    health = [(r["t"], r["instance"], r["health"]) for r in result.events if r["event"] == "health"]
    assert (0.1, "ak09916@i2c1", "nominal") in health
    assert not [h for h in health if h[1] == "ak09916@i2c2"]
    quiet = [q for q in result.quiet if q["line"].startswith("'ak09916 ")]
    assert quiet == [
        {
            "line": "'ak09916 -X -q start' on I2C bus 2 at 0x0C: no ACK after 3 probes; "
            "not started, no message",
            "device": None,
        }
    ]
    assert "- INA238#5 on I2C bus 1 address 0x40: never started, nobody was told" in (
        result.silently_missing
    )


def test_an_instance_on_a_bus_the_bench_does_not_simulate_is_not_started(drivers, manifest):
    on_can = Configured("INA238#4", "INA238", drivers["ina238"], "dronecan", 1, 7, {}, ())
    result = run(healthy_bench(manifest), drivers, [*manifest, on_can], duration=1)
    assert result.failures == [
        "ina238 INA238#4 on DroneCAN interface 1 node 7: critical: not started: bus kind "
        "dronecan is not simulated by the bench"
    ]


@pytest.mark.parametrize(
    ("power_up", "rate_hz", "nominal_at"),
    [
        # Probes at 0 s (no ACK: 1 bad transfer) and 0.02 s (found: 3 good), then 16 transfers
        # at 8.5 Hz up to 1.9 s: at 2 s the window holds 1 bad of 20, exactly 5%: not more.
        (0.01, 8.5, 2.0),
        # Probes at 0 and 0.02 s fail, 0.06 s finds it, then 19 transfers at 10 Hz: at 2 s the
        # window holds 2 bad of 24; at 2.1 s the first slice, with both, has left it.
        (0.03, 10.0, 2.1),
    ],
)
def test_a_warning_needs_more_than_5_percent_bad_transfers_in_the_last_2_s(
    power_up, rate_hz, nominal_at, drivers, manifest
):
    mine = Drivers(
        [dataclasses.replace(d, rate_hz=rate_hz) if d.name == "ina238" else d for d in drivers],
        "mine.toml",
    )
    bench = parse_bench(bench_text(second=f"power_up = {power_up}"), "b", mine)
    result = run(bench, mine, manifest, duration=3)
    (ina,) = [i for i in result.instances if i.name == "INA238#1"]
    assert [(t, level) for t, level, _ in ina.timeline[1:]] == [
        (0.1, "warning"),
        (nominal_at, "nominal"),
    ]


@pytest.mark.parametrize(
    ("chip", "declared_id"),
    [
        ("INA226", 0x2260),  # its id register is 0xFF: register 0x3F reads 0
        ("INA228", 0),  # the same register 0x3F, declared (here) to hold 0
    ],
)
def test_a_chip_read_outside_its_id_register_or_without_an_id_answers_0(
    chip, declared_id, drivers, manifest
):
    mine = Drivers(
        [dataclasses.replace(d, chip_id=declared_id) if d.chip == chip else d for d in drivers],
        "mine.toml",
    )
    text = bench_text().replace('chip = "INA238"', f'chip = "{chip}"', 1)
    result = run(parse_bench(text, "b", mine), mine, manifest, duration=1)
    (ina,) = [i for i in result.instances if i.name == "INA238#0"]
    # Probes at 0, 0.02, 0.06, 0.14, 0.3 and 0.62 s (the next at 1.26 s).
    assert ina.reason == (
        "not found: wrong chip id 0x0 in register 0x3F (expected 0x238) "
        "(6 probe attempts, still retrying)"
    )


def test_a_legacy_start_still_probing_when_the_run_ends_is_not_found_yet(drivers, manifest):
    # Today's probes are 1 ms apart (0, 1 and 2 ms): a run of 1.5 ms ends between the second
    # and the third, nothing answering on bus 2.
    result = run(
        parse_bench(bench_text(), "b", drivers), drivers, manifest, duration=0.0015, legacy=True
    )
    (ak,) = [i for i in result.instances if i.name == "ak09916@i2c2"]
    assert (ak.health, ak.reason) == (
        "critical",
        "not found: no ACK (2 probe attempts, still retrying)",
    )


def test_a_benchs_name_is_said_with_its_file_and_kept_in_its_flight_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    named = '[bench]\nname = "quad, two packs"\n\n' + bench_text()
    status, out = boot(tmp_path, capsys, named)
    path = tmp_path / "bench.toml"
    assert status == 0
    assert out.splitlines()[0].startswith(f"manifest boot of quad, two packs ({path}): ")
    status, out = boot(tmp_path, capsys, named, "--legacy")
    assert out.splitlines()[0].startswith(f"legacy boot of quad, two packs ({path}): ")
    status, out = boot(tmp_path, capsys, named, "--json")
    assert json.loads(out)["bench_name"] == "quad, two packs"
    # without a name, the file alone
    status, out = boot(tmp_path, capsys, bench_text())
    assert out.splitlines()[0].startswith(f"manifest boot of {path}: ")


@pytest.mark.parametrize(("name", "code"), [("quad\x1b[2J", "001B"), ("two\nlines", "000A")])
def test_a_bench_name_with_a_control_character_is_refused(drivers, name, code):
    # It was printed raw: an escape sequence cleared the terminal of whoever ran the bench.
    text = f"[bench]\nname = {json.dumps(name)}\n" + ONE
    with pytest.raises(BenchFileError) as e:
        parse_bench(text, "b.toml", drivers)
    assert str(e.value) == (
        f"b.toml: [bench]: name holds the control character U+{code} (a name is one line of "
        "printable text)"
    )
