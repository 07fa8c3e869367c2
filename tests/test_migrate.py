"""Migration of today's configuration (QGC .params, ULog) into a device manifest."""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import px4params
import pytest
import shared_data
from px4params import migrate
from px4params.cli.main import build_parser
from px4params.store.classic import BUNDLED_CLASSIC
from px4params.vehicle import devid
from shared_data import shared_file

# A small devtype table of our own, so that the .params tests need no shared data.
DEVTYPES = (
    "code\tname\n0x01\tDRV_MAG_DEVTYPE_HMC5883\n0x09\tDRV_MAG_DEVTYPE_AK09916\n"
    "0x0A\tDRV_MAG_DEVTYPE_LIS2MDL\n0x0B\tDRV_MAG_DEVTYPE_TST5883\n"
)
AK09916_I2C1 = devid.encode("i2c", 1, 0x0C, 0x09)  # 592905, as in the sample log
HMC5883_I2C1 = devid.encode("i2c", 1, 0x1E, 0x01)  # 73225, the driver guide's example
TST5883_I2C1 = devid.encode("i2c", 1, 0x1E, 0x0B)  # a chip of this test's own type
UAVCAN_BARO = devid.encode("uavcan", 0, 125, 0x40)
SIM_MAG = devid.encode("simulation", 0, 1, 0x09)
UNKNOWN_I2C = devid.encode("i2c", 2, 0x30, 0x77)


def params_file(path: Path, rows: list[tuple[str, object, int]], extra: str = "") -> Path:
    lines = ["# Onboard parameters for Vehicle 1", "#", "# Vehicle-Id Component-Id Name Value Type"]
    for name, value, kind in rows:
        text = f"{value:.18f}" if kind == 9 else str(value)
        lines.append(f"1\t1\t{name}\t{text}\t{kind}")
    path.write_text("\n".join(lines) + "\n" + extra)
    return path


ROWS: list[tuple[str, object, int]] = [
    ("SENS_EN_INA238", 1, 6),
    ("INA238_CURRENT", 327.68, 9),  # the driver's default: the type holds whole amperes
    ("INA238_SHUNT", 0.0003, 9),  # float16 holds 0.000299931
    ("INA238_CONFIG", 3, 6),  # no field for it
    ("SENS_EN_INA226", 0, 6),
    ("SENS_EN_LL40LS", 1, 6),  # 1 is the PWM driver; the I2C one (bundled) is 2
    ("SENS_EXT_I2C_PRB", 1, 6),
    ("CAL_MAG0_ID", AK09916_I2C1, 6),
    ("CAL_MAG0_ROT", 2, 6),
    ("CAL_MAG0_EN", 1, 6),
    ("CAL_MAG1_ID", HMC5883_I2C1, 6),
    ("CAL_MAG2_ID", 1 << 25, 6),
    ("CAL_BARO0_ID", UAVCAN_BARO, 6),
    ("CAL_MAG3_ID", SIM_MAG, 6),
    ("CAL_ACC1_ID", UNKNOWN_I2C, 6),
    ("CAL_MAG_PRIME", AK09916_I2C1, 6),
    ("MC_ROLL_P", 6.5, 9),
]


@pytest.fixture
def devtypes(tmp_path: Path) -> devid.DevtypeTable:
    path = tmp_path / "devtypes.tsv"
    path.write_text(DEVTYPES)
    return devid.load_table("current", path)


def run_airframe(airframe: Path, store: Path, tmp_path: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PX4PARAMS_STORE",)}
    env.setdefault("PX4PARAMS_CACHE_DIR", str(tmp_path / "cache"))
    return subprocess.run(
        [sys.executable, "-m", "px4params", "run", str(airframe), "--store", str(store)],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )


def load_store(store: Path, monkeypatch: pytest.MonkeyPatch):
    from px4params.store.session import open_session

    return open_session(str(store), os.environ.get("PX4PARAMS_PARAMETERS_JSON")).store


def apply_airframe(text: str, store) -> None:
    """The airframe through the Store API (used when `px4params run` is not there)."""
    for line in text.splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        words = line.split()
        assert words[:2] in (["param", "add"], ["param", "set-default"]), line
        if words[1] == "add":
            store.add(words[2])
        else:
            value = words[3]
            number = float(value) if "." in value or "e" in value else int(value, 0)
            store.set_default(words[2], number)


def boards_available() -> bool:
    try:
        import px4params.vehicle.boards  # noqa: F401
    except ImportError:
        return False
    return True


def has_run_command() -> bool:
    return "run" in build_parser()._subparsers._group_actions[0].choices  # type: ignore[union-attr]


# -- the sample log ---------------------------------------------------------------------------


@pytest.fixture
def sample_log() -> Path:
    return shared_file(shared_data.SAMPLE_LOG)


def test_sample_log(sample_log: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The external AK09916 on I2C bus 1 at 0x0C is the board's (its boot console: "equal to
    '-b 2'", which PX4 1.11 counts as the second external bus: rc.board_sensors:17's `ak09916 -X
    -b 2 -R 6 start`, see tests/test_boards.py); the log's
    differential_pressure topic (0x472811: devtype 0x47, MS4525 in PX4 1.11's drv_sensor.h)
    and its boot console show the MS4525DO airspeed sensor rc.sensors started on I2C bus 2 at
    0x28 (issue 34, defect 8: not bus 1); the airframe is accepted by `px4params run`."""
    if not boards_available():
        pytest.skip("the board table's CubeOrange 1.11 line 17 makes the AK09916 the board's")
    config = migrate.read_config(sample_log)
    assert config.kind == "ULog" and len(config.params) == 980
    assert "ver_hw CUBEPILOT_CUBEORANGE" in config.details
    proposal = migrate.migrate(config)
    assert proposal.table == "px4-v1.11"  # the log's release, v1.11.2
    assert [i.name for i in proposal.instances] == ["MS4525DO#0"]
    (ms,) = proposal.instances
    assert ms.values == {"bus.i2c.bus_id": 2, "bus.i2c.address": 0x28}
    assert ms.origin == (
        "differential_pressure 0 = 4663313: MS4525 (DIFF_PRESS), I2C bus 2, address 0x28; boot "
        "console line 27: 'ms4525_airspeed #0 on I2C bus 2 (external, equal to '-b 1')'"
    )
    # The topic's device ID gives the address the 1.11 console line does not print.
    assert not [a for a in proposal.assumptions if "names no address" in a]
    assert proposal.airframe().startswith(
        "# Device manifest migrated by px4params from sample_log_small.ulg (ULog)\n"
        "# Review before use: see the migration report.\n"
        "\n"
        "# MS4525DO#0: differential_pressure 0 = 4663313: MS4525 (DIFF_PRESS), I2C bus 2, "
        "address 0x28; boot console line 27: 'ms4525_airspeed #0 on I2C bus 2 (external, equal "
        "to '-b 1')'\n"
        "param add MS4525DO#0\n"
    )
    report = proposal.report()
    internal = ": internal SPI sensor: started by the board's startup script, not by the manifest"
    assert proposal.not_in_manifest == [
        "CAL_ACC0_ID, CAL_GYRO0_ID = 2424842: ICM20649 (IMU), SPI bus 1, device 0" + internal,
        "CAL_ACC1_ID, CAL_GYRO1_ID = 3670050: ICM20602 (IMU), SPI bus 4, device 0" + internal,
        "CAL_ACC2_ID, CAL_GYRO2_ID = 2621474: ICM20948 (IMU), SPI bus 4, device 0" + internal,
        "CAL_MAG0_ID = 589858: AK09916 (MAG), SPI bus 4, device 0 (disabled: CAL_MAG0_EN = 0)"
        + internal,
        "CAL_MAG1_ID = 592905: AK09916 (MAG), I2C bus 1, address 0x0C: started by the board's "
        "script (PX4/PX4-Autopilot boards/cubepilot/cubeorange/init/rc.board_sensors:17 at "
        "v1.11.0 (tag v1.11.0, 71db0903a9, 2020-09-07))",
        "sensor_baro 0 = 3997706: MS5611 (BARO), SPI bus 1, device 0" + internal,
        "sensor_baro 1 = 3997730: MS5611 (BARO), SPI bus 4, device 0" + internal,
    ]
    assert proposal.replaced[0].startswith("SENS_EXT_I2C_PRB = 1: external I2C devices were found")
    assert "SENS_EN_PX4FLOW" in proposal.disabled
    # PX4's metadata: SENS_EN_THERMAL is thermal control (-1 unavailable, 0 off, 1 on), not a
    # driver that the manifest replaces.
    assert "SENS_EN_THERMAL" not in proposal.disabled
    assert proposal.not_carried == [
        "SENS_EN_THERMAL = 0 (thermal control off): not a driver switch; it stays a classic "
        "parameter",
        "boot console line 18: 'rgbled #0 on I2C bus 1 (external, equal to '-b 2')': no bundled "
        "parameter type for rgbled; it stays started as today",
    ]
    assert f"Unchanged: {proposal.unchanged} other parameters stay classic" in report
    assert proposal.unchanged == 980 - len(proposal.used) and proposal.unchanged > 900

    airframe = tmp_path / "vehicle.airframe"
    airframe.write_text(proposal.airframe())
    if has_run_command():
        store_file = tmp_path / "vehicle.store"
        result = run_airframe(airframe, store_file, tmp_path)
        assert result.returncode == 0, result.stderr
        store = load_store(store_file, monkeypatch)
    else:  # pragma: no cover - `px4params run` not there yet
        import px4params

        store = px4params.Store()
        apply_airframe(proposal.airframe(), store)
    assert store.instances("AK09916") == []
    assert store.get("MS4525DO#0.bus.i2c.bus_id") == 2
    assert store.get("MS4525DO#0", default=True) == store.get("MS4525DO#0")  # set as defaults


def test_sample_log_cli(sample_log: Path, tmp_path: Path) -> None:
    if not boards_available():
        pytest.skip("the board table's CubeOrange 1.11 line 17 makes the AK09916 the board's")
    out = tmp_path / "v.airframe"
    r = cli("migrate", str(sample_log), "-o", str(out))
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(f"Migration of {sample_log} (ULog, 980 parameters)\n")
    assert r.stdout.endswith(f"\nwrote {out}: 1 instance\n")
    assert "param add MS4525DO#0\n" in out.read_text()
    assert "param add AK09916#0\n" not in out.read_text()  # the board's (test_sample_log)


# -- a .params file ---------------------------------------------------------------------------


def test_params_file(
    tmp_path: Path, devtypes: devid.DevtypeTable, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = params_file(tmp_path / "vehicle.params", ROWS, "1\t100\tGMB_MODE\t2\t6\n")
    config = migrate.read_config(path)
    assert config.kind == "QGC .params" and config.params["INA238_SHUNT"] == pytest.approx(0.0003)
    assert config.skipped == ["component 100: 1 parameters (not the autopilot's)"]
    proposal = migrate.migrate(config, table=devtypes)
    ina, ak, hmc = proposal.instances
    assert (ina.name, ak.name, hmc.name) == ("INA238#0", "AK09916#0", "HMC5883#0")
    assert ina.origin == (
        "SENS_EN_INA238 = 1: ina238 started on I2C bus 1 at the driver's default address 0x45"
    )
    assert hmc.values == {"bus.i2c.bus_id": 1, "bus.i2c.address": 0x1E, "rotation": 0}
    assert ina.values["current"] == 327 and ina.values["shunt"] == pytest.approx(0.0003, rel=1e-3)
    assert ina.notes == [
        "INA238_CURRENT = 327.68 A becomes current = 327 A (uint10, 1..327)",
        "INA238_SHUNT = 0.0003 Ohm becomes shunt = 0.000299930573 Ohm (float16, 1e-05..0.1)",
        "today's start line also sets a battery index (-t), which nothing here names (without "
        "-t the driver uses 1): INA238 has no field for it",
    ]
    # Issue 34, defect 3: CAL_MAG0_ROT is calibration's; the driver runs without -R.
    assert ak.values == {"bus.i2c.bus_id": 1, "bus.i2c.address": 0x0C, "rotation": 0}
    assert ak.notes == [
        "CAL_MAG0_ROT = 2 stays a classic parameter: calibration applies it; the driver's "
        "rotation is 0 (rc.sensors starts it without -R)"
    ]
    assert "CAL_MAG0_ROT" not in proposal.used
    assert proposal.not_carried == [
        "INA238_CONFIG = 3: INA238 has no field for it",
        "SENS_EN_LL40LS = 1: starts no I2C driver of the manifest (its ll40ls starts on "
        "SENS_EN_LL40LS == 2); it stays a classic parameter",
        "CAL_MAG2_ID = 33554432: not a device ID",
        f"CAL_ACC1_ID = {UNKNOWN_I2C}: devtype 0x77 (not in the current table), I2C bus 2, "
        "address 0x30: no bundled parameter type for devtype 0x77; today it is found by probing, "
        "in the manifest it needs a type",
    ]
    assert proposal.not_in_manifest == [
        f"CAL_BARO0_ID = {UAVCAN_BARO}: devtype 0x40 (not in the current table), UAVCAN bus 0, "
        "node 125: DroneCAN sensor: found on the CAN bus, not by the manifest",
        f"CAL_MAG3_ID = {SIM_MAG}: AK09916 (MAG), simulation bus 0, address 0x01: simulated "
        "sensor: not part of the manifest",
    ]
    assert proposal.disabled == ["SENS_EN_INA226"]
    assert proposal.unchanged == 2  # MC_ROLL_P, and CAL_MAG0_ROT: calibration's, not the driver's
    report = proposal.report()
    assert "  component 100: 1 parameters (not the autopilot's)\n" in report
    assert "Unchanged: 2 other parameters stay classic parameters" in report
    assert "  not enabled, nothing to carry over: SENS_EN_INA226\n" in report
    data = proposal.as_dict()
    assert json.loads(json.dumps(data))["instances"][0]["indices"] == {
        "bus.i2c.bus_id": 3, "bus.i2c.address": 4, "current": 5, "shunt": 6,
    }  # fmt: skip

    airframe = tmp_path / "vehicle.airframe"
    airframe.write_text(proposal.airframe())
    assert "param set-default INA238#0[6] 0.000299930573\n" in airframe.read_text()
    store_file = tmp_path / "vehicle.store"
    result = run_airframe(airframe, store_file, tmp_path)
    assert result.returncode == 0, result.stderr
    store = load_store(store_file, monkeypatch)
    assert store.get("INA238#0.current") == 327
    assert store.get("INA238#0.bus.i2c.address") == 0x45
    assert store.get("AK09916#0.rotation") == 0


def test_clamping_rotation_and_twice_found(tmp_path: Path, devtypes: devid.DevtypeTable) -> None:
    extra = tmp_path / "tst"
    extra.mkdir()
    (extra / "Tst5883.1.0.dsdl").write_text(  # no driver declaration, no rotation field
        "# TST5883\n# @max_instances 2\n\nuint4 p_version\npx.Bus.1.0 bus\n# Bus\n"
        "# @default i2c.address 0x1E\n\nuint3 gain\n@sealed\n"
    )
    (extra / "Lis2mdl.1.0.dsdl").write_text(  # a rotation field without @min/@max
        "# LIS2MDL\n# @max_instances 1\n\nuint4 p_version\npx.Bus.1.0 bus\nuint2 rotation\n"
        "@sealed\n"
    )
    import px4params

    schema = px4params.load_schema([extra], use_env=False, include_dronecan=False,
                                   cache_dir=tmp_path / "cache")  # fmt: skip
    rows: list[tuple[str, object, int]] = [
        ("SENS_EN_INA226", 1, 6),
        ("INA226_CURRENT", 500.0, 9),
        ("SENS_EN_TST5883", 1, 6),  # enabled and calibrated: one instance
        ("CAL_MAG0_ID", TST5883_I2C1, 6),
        ("CAL_MAG0_ROT", 3, 6),
        ("CAL_MAG1_ID", AK09916_I2C1, 6),
        ("CAL_MAG1_ROT", 100, 6),
        ("CAL_MAG2_ID", devid.encode("i2c", 2, 0x0C, 0x09), 6),
        ("CAL_MAG2_ROT", -1, 6),
        ("CAL_MAG3_ID", devid.encode("i2c", 1, 0x1E, 0x0A), 6),
        ("CAL_MAG3_ROT", 5, 6),
    ]
    proposal = migrate.migrate(migrate.read_config(params_file(tmp_path / "p", rows)), schema,
                               devtypes)  # fmt: skip
    names = [i.name for i in proposal.instances]
    assert names == ["INA226#0", "TST5883#0", "AK09916#0", "LIS2MDL#0"]
    ina, tst, ak0, lis = proposal.instances
    assert tst.notes == [
        f"also CAL_MAG0_ID = {TST5883_I2C1}: TST5883 (MAG), I2C bus 1, address 0x1E",
        "CAL_MAG0_ROT = 3 stays a classic parameter: calibration applies it; the driver's "
        "rotation is 0 (rc.sensors starts it without -R)",
    ]
    assert ina.values["current"] == 200
    assert ina.notes[0] == "INA226_CURRENT = 500 A becomes current = 200 A (uint10, 1..200)"
    # The driver's rotation is 0 whatever calibration's is (100 is not even a rotation).
    assert ak0.values["rotation"] == 0 and lis.values["rotation"] == 0
    # PX4's metadata: -1 is "Internal": the board's script starts that compass.
    (internal,) = [o for o in proposal.left_out if o.found.startswith("CAL_MAG2_ID")]
    assert internal.reason == "board"
    assert internal.line.endswith(": CAL_MAG2_ROT = -1 (Internal): started by the board's script")
    assert proposal.not_carried == []


def test_empty_and_disabled(tmp_path: Path, devtypes: devid.DevtypeTable) -> None:
    rows: list[tuple[str, object, int]] = [("SENS_EXT_I2C_PRB", 0, 6), ("MC_ROLL_P", 6.5, 9)]
    proposal = migrate.migrate(migrate.read_config(params_file(tmp_path / "p", rows)),
                               table=devtypes)  # fmt: skip
    assert proposal.instances == []
    assert "# No device could be carried over.\n" in proposal.airframe()
    assert proposal.replaced == [
        "SENS_EXT_I2C_PRB = 0: probing was off; the manifest starts the devices it lists"
    ]
    report = proposal.report()
    assert "Instances proposed: none\n" in report and "Not carried over: none\n" in report


# -- errors -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "{path}: cannot read: No such file or directory"),
        (
            b"\xff\xfe\x00binary",
            "{path}:1: neither a ULog file nor a QGC .params text file (byte 0xFF is not UTF-8)",
        ),
        # a Latin-1 letter in a QGC header comment: its line is named
        (
            b"# Onboard parameters for Vehicle 1\n# Vehicle: Caf\xe9\n1\t1\tSYS_AUTOSTART\t1\t6\n",
            "{path}:2: neither a ULog file nor a QGC .params text file (byte 0xE9 is not UTF-8)",
        ),
        # QGC writes each parameter once: two values, which one did the vehicle hold?
        (
            b"1\t1\tCAL_MAG1_ID\t396809\t6\n1\t1\tCAL_MAG1_ID\t592905\t6\n",
            "{path}:2: CAL_MAG1_ID: also set on line 1, to 396809",
        ),
        (b"# only comments\n\n", "{path}: no parameters (not a QGC .params file?)"),
        (
            b"# x\n1\t1\tSYS_AUTOSTART\t4001\n",
            "{path}:2: expected 5 TAB-separated columns (vehicle-id, component-id, name, value, "
            "type), got 4",
        ),
        (
            b"1\t1\tSYS_AUTOSTART\t40.5\t6\n",
            "{path}:1: SYS_AUTOSTART: value '40.5' is not an integer (type 6)",
        ),
        (b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0), "{path}: the log has no parameters"),
        (
            b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0) + b"\xff" * 5 + b"\x00garbage",
            "{path}: not a readable ULog file (a damaged message before byte 29: pyulog stepped "
            "back 65537 bytes over it, past the file's start)",
        ),
    ],
)
def test_read_errors(tmp_path: Path, content: bytes | None, message: str) -> None:
    path = tmp_path / "config"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(migrate.MigrationError) as caught:
        migrate.read_config(path)
    assert str(caught.value) == message.format(path=path)


def cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "px4params", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )


def test_cli(tmp_path: Path) -> None:
    tsv = tmp_path / "devtypes.tsv"
    tsv.write_text(DEVTYPES)
    path = params_file(tmp_path / "vehicle.params", ROWS)
    r = cli("migrate", str(path), "--devtypes", str(tsv))  # airframe out, report beside it
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("# Device manifest migrated by px4params from vehicle.params")
    assert r.stderr.startswith(f"Migration of {path} (QGC .params, 17 parameters)\n")
    r = cli("migrate", str(path), "--devtypes", str(tsv), "--json")
    assert r.returncode == 0, r.stderr
    document = json.loads(r.stdout)
    assert [i["name"] for i in document["instances"]] == ["INA238#0", "AK09916#0", "HMC5883#0"]
    assert document["airframe"].startswith("# Device manifest")

    r = cli("migrate", str(path), "--table", "legacy", "--devtypes", str(tsv))
    assert r.returncode == 2
    assert r.stderr.splitlines()[-1] == (
        "px4params migrate: error: --devtypes is the current table's source; it does not go "
        "with --table legacy"
    )
    r = cli("migrate", str(path), "--devtypes", str(tsv), "-o", str(tmp_path / "no" / "x"))
    assert r.returncode == 1
    assert r.stderr == f"px4params: error: {tmp_path / 'no' / 'x'}: cannot write: No such file " \
        "or directory\n"  # fmt: skip
    r = cli("migrate", str(tmp_path / "missing.params"), "--devtypes", str(tsv))
    assert r.returncode == 1
    assert r.stderr == (
        f"px4params: error: {tmp_path / 'missing.params'}: cannot read: No such file or directory\n"
    )
    r = cli("migrate", str(path), "--devtypes", str(tmp_path / "nope.tsv"))
    assert r.returncode == 1 and r.stderr.startswith("px4params: error: ")
    assert r.stderr.count("\n") == 1 and "nope.tsv" in r.stderr
    r = cli("migrate", str(path), "--table", "legacy", "-o", str(tmp_path / "legacy.airframe"))
    assert r.returncode == 0, r.stderr  # legacy table: no AK09916 code, so no instance from it
    assert "param add AK09916" not in (tmp_path / "legacy.airframe").read_text()
    r = cli("migrate", "--help")
    assert r.returncode == 0 and "examples:" in r.stdout


def test_float_settings_round_to_nearest_and_disabled_sensors_stay_out(
    tmp_path: Path, devtypes: devid.DevtypeTable
) -> None:
    """199.6 A is 200 A, not 199 (math.floor(v + 0.5), not floored); an I2C magnetometer
    calibrated but disabled (CAL_MAG0_EN = 0 before PX4 1.12, CAL_MAG1_PRIO = 0 since: issue
    34, defect 2) is left out: an instance would make a sensor PX4 does not use a required
    one."""
    rows: list[tuple[str, object, int]] = [
        ("SENS_EN_INA238", 1, 6),
        ("INA238_CURRENT", 199.6, 9),
        ("CAL_MAG0_ID", AK09916_I2C1, 6),
        ("CAL_MAG0_EN", 0, 6),
        ("CAL_MAG1_ID", HMC5883_I2C1, 6),
        ("CAL_MAG1_PRIO", 0, 6),
    ]
    proposal = migrate.migrate(migrate.read_config(params_file(tmp_path / "p", rows)), None,
                               devtypes)  # fmt: skip
    (ina,) = proposal.instances
    assert ina.values["current"] == 200
    assert [(o.found, o.reason) for o in proposal.left_out] == [
        (f"CAL_MAG0_ID = {AK09916_I2C1}", "disabled"),
        (f"CAL_MAG1_ID = {HMC5883_I2C1}", "disabled"),
    ]
    assert proposal.left_out[1].line == (
        f"CAL_MAG1_ID = {HMC5883_I2C1}: HMC5883 (MAG), I2C bus 1, address 0x1E: disabled "
        "(CAL_MAG1_PRIO = 0): not proposed, an instance would make it required"
    )


def test_an_internal_magnetometer_is_the_boards(tmp_path: Path) -> None:
    """Issue 34, defect 1: CAL_MAG0_ROT = -1 is PX4's "Internal": the board's script starts the
    compass (fmu-v5: `ist8310 -I -R 10 start`), so it is no manifest instance."""
    ist8310 = devid.encode("i2c", 1, 0x0E, 0x06)
    rows: list[tuple[str, object, int]] = [("CAL_MAG0_ID", ist8310, 6), ("CAL_MAG0_ROT", -1, 6)]
    proposal = migrate.migrate(migrate.read_config(params_file(tmp_path / "p", rows)), None,
                               devid.load_table("px4-v1.13"))  # fmt: skip
    assert proposal.instances == []
    assert proposal.not_in_manifest == [
        f"CAL_MAG0_ID = {ist8310}: IST8310 (MAG), I2C bus 1, address 0x0E: CAL_MAG0_ROT = -1 "
        "(Internal): started by the board's script"
    ]


def test_qgc_offline_editing_params_file() -> None:
    """QGC's offline-editing sample: every calibration slot empty, three rangefinder drivers
    off: nothing to carry, the three listed as not enabled."""
    config = migrate.read_config(shared_file("qgc_offline_editing_v1.4.params"))
    proposal = migrate.migrate(config, None, "legacy")
    assert proposal.instances == [] and proposal.not_in_manifest == []
    assert {"SENS_EN_LL40LS", "SENS_EN_MB12XX", "SENS_EN_SF0X"} <= set(proposal.disabled)


def test_qgc_mocklink_params_file() -> None:
    """QGC's MockLink (a simulated PX4): its sensors are the simulator's, bus type 0, which the
    driver guide's table names ACCELSIM/GYROSIM/MAGSIM codes; none is an I2C device."""
    config = migrate.read_config(shared_file("qgc_px4_mocklink.params"))
    proposal = migrate.migrate(config, None, "legacy")
    assert proposal.instances == []
    found = {line.split(" = ")[0]: line for line in proposal.not_in_manifest}
    assert set(found) == {"CAL_ACC0_ID", "CAL_ACC1_ID", "CAL_GYRO0_ID", "CAL_MAG0_ID"}
    assert "CAL_ACC0_ID = 1376264: GYROSIM (ACC), bus type 0, bus 1" in found["CAL_ACC0_ID"]
    assert "CAL_ACC1_ID = 1310728: ACCELSIM (ACC), bus type 0, bus 1" in found["CAL_ACC1_ID"]
    assert "GYROSIM (GYR)" in found["CAL_GYRO0_ID"] and "ACCELSIM (MAG)" in found["CAL_MAG0_ID"]
    assert config.skipped == [
        "component 2: 1 parameters (not the autopilot's)",
        "component 3: 1 parameters (not the autopilot's)",
    ]


# -- a legacy float rounded into an integer field (issue 40) -----------------------------------
# ``px4params migrate`` rounds a legacy float setting that feeds an integer field to the
# nearest integer, a value exactly between two integers upwards (migrate.py: "rounded and
# clamped"; ``math.floor(v + 0.5)``): ``INA238_CURRENT`` (PX4's INA238 driver: the maximum
# expected current, a float in A) feeds the INA238 type's ``current`` (uint10, whole A), so
# 2.5 A becomes 3 A. Issue 40: with Python's ``round`` (half to even: 2.5 -> 2) the suite stayed
# green, as its values were never halves.
#
# Checked end to end: the proposed airframe file is run into a store, and the store's value read.


CLI = [sys.executable, "-m", "px4params"]


def _cli(*args: str, cwd: Path) -> str:
    result = subprocess.run(
        [*CLI, *args], capture_output=True, text=True, timeout=120, cwd=cwd, check=False
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


@pytest.mark.issue40
@pytest.mark.parametrize(
    ("legacy", "expected"),
    [("2.5", 3), ("100.5", 101), ("2.4999", 2), ("7.5", 8)],
)
def test_a_legacy_value_exactly_between_two_integers_rounds_half_up(
    tmp_path: Path, legacy: str, expected: int
) -> None:
    # A QGC .params file: vehicle, component, name, value, MAVLink type (6 INT32, 9 REAL32).
    rows = [("SENS_EN_INA238", "1", 6), ("INA238_CURRENT", legacy, 9)]
    old = tmp_path / "old.params"
    old.write_text("".join(f"1\t1\t{name}\t{value}\t{kind}\n" for name, value, kind in rows))
    # No device IDs to decode: the legacy table, so that no current table (../shared) is needed.
    _cli("migrate", str(old), "--table", "legacy", "-o", "new.airframe", cwd=tmp_path)
    _cli("run", "new.airframe", "--store", "vehicle.store", cwd=tmp_path)
    store = px4params.Store.load(tmp_path / "vehicle.store", classic=BUNDLED_CLASSIC)
    assert store.instances("INA238") == ["INA238#0"]
    assert store.get("INA238#0.current") == expected
