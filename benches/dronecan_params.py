"""DroneCAN parameter service timings: ``px4params dronecan serve`` on a pseudo-terminal with the
example airframe's manifest and a real PX4 ``parameters.json`` (../shared/data, else the bundled
classic set), asked through SLCAN by ``px4params``' own client and by pydronecan:

* GetSet round trip: one read by name, median of ``--reads``;
* full enumeration: GetSet by index from 0 until the empty name, ``--runs`` times (median).

    .venv/bin/python benches/dronecan_params.py [--reads 300] [--runs 3]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from dronecan_bus import PX4PARAMS, served  # noqa: E402

SHARED = Path(os.environ.get("PX4PARAMS_SHARED_DATA") or ROOT.parent / "shared" / "data")


def ours(path: str, reads: int, runs: int) -> tuple[list[float], list[float], int]:
    from px4params.links.dronecan_client import DronecanParamClient
    from px4params.links.slcan import SlcanHost, open_serial

    host = SlcanHost(open_serial(path))
    host.start()
    client = DronecanParamClient(host, 1)
    trips = []
    for _ in range(reads):
        start = time.perf_counter()
        assert client.get("INA238_1_I2C_ADDRESS") is not None
        trips.append(time.perf_counter() - start)
    totals, count = [], 0
    for _ in range(runs):
        start = time.perf_counter()
        count = sum(1 for _ in client.list())
        totals.append(time.perf_counter() - start)
    host.stop()
    return trips, totals, count


def pydronecan(path: str, runs: int) -> list[float]:
    import dronecan

    node = dronecan.make_node(path, node_id=100, bitrate=1_000_000)
    getset = dronecan.uavcan.protocol.param.GetSet
    totals = []
    try:
        for _ in range(runs):
            start = time.perf_counter()
            for index in range(8192):
                got: list = []
                node.request(getset.Request(index=index), 1, got.append, timeout=2)
                while not got:
                    node.spin(0.001)
                if got[0] is None or not bytes(got[0].response.name):
                    break
            totals.append(time.perf_counter() - start)
    finally:
        node.close()
    return totals


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--reads", type=int, default=300)
    p.add_argument("--runs", type=int, default=3)
    args = p.parse_args()
    classic = SHARED / "px4_parameters.json"
    extra = ["--classic", str(classic)] if classic.is_file() else []
    with tempfile.TemporaryDirectory() as work:
        store = Path(work) / "vehicle.store"
        airframe = str(ROOT / "examples/two_batteries.airframe")
        run = [*PX4PARAMS, "run", airframe, "--store", str(store)]
        subprocess.run(run, check=True, capture_output=True)
        with served(store, *extra) as path:
            trips, totals, count = ours(path, args.reads, args.runs)
            theirs = pydronecan(path, args.runs)
    source = classic if extra else "the bundled classic set"
    print(f"{count} parameters (classic from {source}), {args.reads} reads, {args.runs} runs")
    ms = 1000 * statistics.median(trips)
    print(f"GetSet by name, round trip (px4params client): median {ms:.2f} ms")
    print(f"full enumeration by index, px4params client: median {statistics.median(totals):.2f} s")
    print(f"full enumeration by index, pydronecan:       median {statistics.median(theirs):.2f} s")


if __name__ == "__main__":
    main()
