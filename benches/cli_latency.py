"""Wall time of ``px4params param show`` on a warm cache (model and bytecode; target: 150 ms),
with the bare interpreter start as the baseline measured in the same run.

    python benches/cli_latency.py [--runs 20]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time


def timed(argv: list[str], env: dict[str, str], runs: int) -> list[float]:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(argv, env=env, check=True, stdout=subprocess.DEVNULL)
        times.append(time.perf_counter() - start)
    return times


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=20)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, PX4PARAMS_STORE=os.path.join(tmp, "bench.store"))
        # As users run it: with compiled bytecode cached (this machine's environment turns
        # writing it off, which would make every run compile every module again).
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        cli = [sys.executable, "-m", "px4params"]
        for line in ("param add INA238#0", "param set-default INA238#0[4] 0x45"):
            subprocess.run(cli + line.split(), env=env, check=True, stdout=subprocess.DEVNULL)
        timed([*cli, "param", "show"], env, 2)  # warm the model cache and the OS caches
        rows = [
            ("python -c pass (baseline)", timed([sys.executable, "-c", "pass"], env, args.runs)),
            ("px4params param show", timed([*cli, "param", "show"], env, args.runs)),
            (
                "px4params param show -l INA238#0",
                timed([*cli, "param", "show", "-l", "INA238#0"], env, args.runs),
            ),
        ]
    base = statistics.median(rows[0][1])
    print(f"{'command':36} {'median':>8} {'min':>8} {'vs baseline':>11}")
    for label, times in rows:
        median = statistics.median(times)
        print(f"{label:36} {median * 1e3:6.1f}ms {min(times) * 1e3:6.1f}ms {median / base:10.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
