"""Instructions per codec call, counted by valgrind's callgrind (stable where this machine's
times are not): runs ``benches/instructions.rs`` (``cargo bench --no-run`` builds it with the
bench profile, as criterion's figures are) N times and 0 times, and divides the difference.

    python benches/instructions.py [--n 2000] [--compact] [OP ...]

``--compact`` counts the firmware build of the core (feature ``compact``: every value through
one small walk, built for size; see ``benches/size.py``). ``encode``/``decode`` run the codec
from and into a leaf list as a host does (the encoder and decoder over a source and a sink);
``encode_leaves``/``decode_leaves`` as firmware calls it, through the walk in ``compact``.

Skips with a message when valgrind is not installed.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OPS = [
    "battery/encode", "battery/decode", "battery/encode_leaves", "battery/decode_leaves",
    "ina238/encode", "ina238/decode", "ina238/encode_leaves", "ina238/decode_leaves",
    "ina238/get_leaf4", "ina238/table_get_leaf4", "ina238/table_read4", "store/get_leaf4",
    "store/read4", "battery/receive", "battery/receive_into", "battery/transfer_crc",
    "node_status/encode", "node_status/decode", "node_status/encode_leaves",
    "node_status/decode_leaves", "file_read_response/encode",
    "file_read_response/decode",
]  # fmt: skip


def build(compact: bool) -> Path:
    """The instructions bench binary, built as `cargo bench` builds it."""
    features = "alloc,compact" if compact else "alloc"
    out = subprocess.run(
        ["cargo", "bench", "-p", "px4params-core", "--features", features, "--bench",
         "instructions", "--no-run", "--message-format", "json"],
        cwd=ROOT, capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    for line in out.splitlines():
        message = json.loads(line)
        artifact = message.get("reason") == "compiler-artifact" and message.get("executable")
        if artifact and message["target"]["name"] == "instructions":
            return Path(message["executable"])
    raise SystemExit("instructions: cargo did not report the bench binary")


def count(binary: Path, op: str, n: int) -> int:
    proc = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", str(binary), op, str(n)],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    match = re.search(r"Collected : (\d+)", proc.stderr)
    assert match, proc.stderr
    return int(match.group(1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=2000)
    parser.add_argument("--compact", action="store_true", help="the core's firmware build")
    parser.add_argument("ops", nargs="*", default=OPS, metavar="OP")
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        print("instructions: valgrind is not installed (Debian: apt-get install valgrind)")
        return 0
    binary = build(args.compact)
    print(f"{'call':28} {'instructions':>12}")
    for op in args.ops:
        per_call = (count(binary, op, args.n) - count(binary, op, 0)) / args.n
        print(f"{op:28} {per_call:>12.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
