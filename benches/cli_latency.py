"""Wall time of short ``px4params`` commands against the bare interpreter, measured in the same
run with the runs interleaved (this machine is noisy), bytecode cached as users have it, the
DSDL model cached; and what ``import px4params`` costs (``-X importtime``, cumulative).

Targets (issue 13): ``param show`` and ``decode`` median <= 2.5x ``python -c pass``;
``import px4params`` <= 25 ms.

    python benches/cli_latency.py [--runs 30]

What keeps them there: the everyday command lines are parsed without argparse
(``px4params.cli.parsing``), and these commands import neither ``re`` nor ``json`` (``re``
alone costs a third of Python's start); nor must the console script (uv's does not, pip's
imports ``re``). On a busy machine compare instruction counts, which load does not change:

    valgrind --tool=callgrind --callgrind-out-file=/dev/null px4params param show
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time


def once(argv: list[str], env: dict[str, str], cwd: str) -> float:
    start = time.perf_counter()
    subprocess.run(argv, env=env, cwd=cwd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def import_ms(env: dict[str, str], cwd: str) -> float:
    """``import px4params``, cumulative microseconds of its line in ``-X importtime``."""
    out = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", "import px4params"],
        env=env,
        cwd=cwd,
        capture_output=True,
        text=True,
        check=True,
    ).stderr
    match = re.search(r"\|\s*(\d+) \| px4params$", out, re.M)
    assert match, out
    return int(match.group(1)) / 1000


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=30)
    args = parser.parse_args()
    cli = os.path.join(os.path.dirname(sys.executable), "px4params")
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, PX4PARAMS_STORE=os.path.join(tmp, "bench.store"))
        env.pop("PYTHONDONTWRITEBYTECODE", None)  # as users run it: bytecode written and reused
        examples = os.path.join(os.path.dirname(__file__), "..", "examples")
        airframe = os.path.join(examples, "two_batteries.airframe")
        subprocess.run(
            [cli, "run", airframe], env=env, cwd=tmp, check=True, stdout=subprocess.DEVNULL
        )
        commands = {
            "python -c pass (baseline)": [sys.executable, "-c", "pass"],
            "px4params param show": [cli, "param", "show"],
            "px4params param show -l INA238#0": [cli, "param", "show", "-l", "INA238#0"],
            "px4params decode NodeStatus": [
                cli,
                "decode",
                "uavcan.protocol.NodeStatus",
                "39300000000700",
            ],
            "px4params --help": [cli, "--help"],
        }
        for argv in commands.values():  # warm the model cache, bytecode and the OS caches
            once(argv, env, tmp)
            once(argv, env, tmp)
        times: dict[str, list[float]] = {label: [] for label in commands}
        for _ in range(args.runs):
            for label, argv in commands.items():
                times[label].append(once(argv, env, tmp))
        imports = [import_ms(env, tmp) for _ in range(args.runs)]
    base = statistics.median(times["python -c pass (baseline)"])
    print(f"{'command':36} {'median':>8} {'min':>8} {'vs baseline':>11}")
    for label, values in times.items():
        median = statistics.median(values)
        print(f"{label:36} {median * 1e3:6.1f}ms {min(values) * 1e3:6.1f}ms {median / base:10.2f}x")
    print(
        f"import px4params (-X importtime, cumulative): median {statistics.median(imports):.1f} ms"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
