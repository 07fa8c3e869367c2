"""``px4params health``'s "first failure" line names the device lost earliest in time, whatever
order the log lists the devices in (docs/autostart.md: "names the first device that was lost,
and when"). Issue 40: with the first failure taken in list order, the suite stayed green, as
its only bench loses one device.

The expected answers come from the bench files written here: a power monitor on a quiet bus
that stops answering at ``dies_after`` is lost after that moment, and before the other one's.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from px4params.cli.main import main

REPO = Path(__file__).resolve().parents[1]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"  # INA238#0 bus 1, INA238#1 bus 2

BENCH = """\
[bench]
name = "both power monitors lost"

[[device]]
chip = "INA238"
bus = "i2c"
bus_id = 1
address = 0x45
dies_after = {first}

[[device]]
chip = "INA238"
bus = "i2c"
bus_id = 2
address = 0x45
dies_after = {second}

[[device]]
chip = "AK09916"
bus = "i2c"
bus_id = 1
address = 0x0C
"""


@pytest.mark.parametrize(
    ("first", "second", "earlier", "died"),
    [(7.0, 3.0, "INA238#1", 3.0), (3.0, 7.0, "INA238#0", 3.0)],
    ids=["second-listed-lost-first", "first-listed-lost-first"],
)
def test_first_failure_names_the_device_lost_earliest_in_time(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    first: float,
    second: float,
    earlier: str,
    died: float,
) -> None:
    bench = tmp_path / "lost.bench.toml"
    bench.write_text(BENCH.format(first=first, second=second))
    log = tmp_path / "run.ulg"
    argv = ["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(bench)]
    assert main([*argv, "--duration", "10", "--ulog", str(log)]) == 1  # arming refused
    capsys.readouterr()
    assert main(["health", str(log)]) == 1
    lines = capsys.readouterr().out.splitlines()
    # Both were lost: each one's story has a driver reset.
    for name in ("INA238#0", "INA238#1"):
        at = next(n for n, line in enumerate(lines) if line.startswith(f"{name} (ina238 on "))
        end = next(n for n in range(at + 1, len(lines)) if not lines[n].startswith(" "))
        assert any(line.endswith("s  lost (driver reset)") for line in lines[at:end]), name
    failure = next(line for line in lines if line.startswith("first failure: "))
    match = re.fullmatch(r"first failure: (\S+) \(ina238\) at (\d+\.\d\d) s: .+", failure)
    assert match, failure
    assert match[1] == earlier
    # Lost after it stopped answering, and before the other one stopped.
    assert died < float(match[2]) < max(first, second)
