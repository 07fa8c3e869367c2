"""Instructions per codec call, counted by valgrind's callgrind (stable where this machine's
times are not): runs ``benches/instructions.rs`` (``cargo bench --no-run`` builds it with the
bench profile, as criterion's figures are) N times and 0 times, and divides the difference.

    python benches/instructions.py [--n 2000] [--compact] [OP ...]
    python benches/instructions.py --table [--compact] [--before REV] [--c DIR] [--rounds 9]
        [--aligned-loops]

``--compact`` counts the firmware build of the core (feature ``compact``: no plans, built
for size; see ``benches/size.py``). ``encode``/``decode`` run the codec from and into a leaf
list over a source and a sink (the straight plan where the build has it, then the one loop of
``crates/px4params-core/src/interp.rs``); ``encode_leaves``/``decode_leaves`` as firmware calls
them, through the walk in ``compact``.

``--table`` prints the rows issue 39 sets targets for, side by side: this tree's counts and
times, those of the core at ``--before`` (built in a worktree of its own, ``/tmp/px4params-
before-REV``, with this tree's bench harness, so that both run the same calls), and the C
baseline's (``--c``, default ``../shared/anchors/dronecan-c``: dronecan_dsdlc-generated C on
libcanard v0, built here with ``cc -O2``), with the ratios to C; with ``--compact``, of both
cores' firmware builds. Times are medians of
``--rounds`` rounds in which each build times its call and then the C code's on the same
message in the same process (the rounds of the two builds alternate), so that this machine's
drift falls on all alike; ratios of times are taken within one process. ``--aligned-loops``
builds both trees with their loops aligned to 64 bytes, so that a row whose code did not
change keeps its time (without it, a change elsewhere can move it by 5-15%). Cargo runs under
``flock $PX4PARAMS_BUILD_LOCK`` when that is set (shared machines).

Skips with a message when valgrind is not installed.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OPS = [
    "battery/encode", "battery/decode", "battery/encode_leaves", "battery/decode_leaves",
    "ina238/encode", "ina238/decode", "ina238/encode_leaves", "ina238/decode_leaves",
    "ina238/get_leaf4", "ina238/table_get_leaf4", "ina238/table_read4", "store/get_leaf4",
    "store/read4", "battery/receive", "battery/receive_into", "battery/transfer_crc",
    "battery/frames_decode",
    "node_status/encode", "node_status/decode", "node_status/encode_leaves",
    "node_status/decode_leaves", "file_read_response/encode",
    "file_read_response/decode",
]  # fmt: skip
# The table's rows: ours, and the C baseline's op (cbench.c) where it has one.
TABLE = [
    ("battery/encode", "bat_enc"), ("battery/decode", "bat_dec"),
    ("node_status/encode", "ns_enc"), ("node_status/decode", "ns_dec"),
    ("file_read_response/encode", "rd0_enc"), ("file_read_response/decode", "rd0_dec"),
    ("battery/receive", None), ("battery/receive_into", None),
    ("battery/receive_decode", None), ("battery/receive_into_decode", None),
    ("battery/encode_leaves", None), ("battery/decode_leaves", None),
]  # fmt: skip
C_DIR = ROOT.parent / "shared" / "anchors" / "dronecan-c"


def locked(command: list[str]) -> list[str]:
    """`command` under the shared build lock, when one is named."""
    lock = os.environ.get("PX4PARAMS_BUILD_LOCK")
    return ["flock", lock, "nice", *command] if lock else command


# Loops aligned to 64 bytes (the op cache's line on this machine's Zen 4): where the linker
# puts unchanged code otherwise moves its time (BatteryInfo's decode, 1,220 instructions in
# both, took 63.6 ns before a change to the transfer code and 68.9 ns after it).
ALIGNED_LOOPS = "-C llvm-args=-align-loops=64"


def build(compact: bool, root: Path = ROOT, target: Path | None = None,
          aligned: bool = False) -> Path:  # fmt: skip
    """The instructions bench binary of the tree at `root`, built as `cargo bench` builds it
    (with `aligned`, its loops aligned, in a target dir of its own)."""
    features = "alloc,compact" if compact else "alloc"
    env = dict(os.environ)
    if aligned:
        env["RUSTFLAGS"] = f"{env.get('RUSTFLAGS', '')} {ALIGNED_LOOPS}".strip()
        target = (target or ROOT / "target") / "aligned-loops"
    if target is not None:
        env["CARGO_TARGET_DIR"] = str(target)
    out = subprocess.run(
        locked(["cargo", "bench", "-p", "px4params-core", "--features", features, "--bench",
                "instructions", "--no-run", "--message-format", "json"]),
        cwd=root, capture_output=True, text=True, check=True, env=env,
    ).stdout  # fmt: skip
    for line in out.splitlines():
        message = json.loads(line)
        artifact = message.get("reason") == "compiler-artifact" and message.get("executable")
        if artifact and message["target"]["name"] == "instructions":
            return Path(message["executable"])
    raise SystemExit("instructions: cargo did not report the bench binary")


def collected(command: list[str]) -> int:
    proc = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *command],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    match = re.search(r"Collected : (\d+)", proc.stderr)
    assert match, proc.stderr
    return int(match.group(1))


def count(binary: Path, op: str, n: int) -> int:
    return collected([str(binary), op, str(n)])


def per_call(command: list[str], n: int) -> float:
    """Instructions of one call: (N calls - 0 calls) / N; `command` takes OP N last."""
    return (collected([*command, str(n)]) - collected([*command, "0"])) / n


def before_tree(rev: str) -> tuple[Path, Path]:
    """A worktree of `rev` (made once) with this tree's bench harness; its target dir."""
    tree = Path(f"/tmp/px4params-before-{rev}")
    if not tree.exists():
        subprocess.run(["git", "worktree", "add", "--detach", str(tree), rev], cwd=ROOT,
                       check=True, capture_output=True)  # fmt: skip
    shutil.copy(ROOT / "benches" / "instructions.rs", tree / "benches" / "instructions.rs")
    return tree, tree / "target"


def build_c(c_dir: Path, out: Path) -> tuple[Path, Path]:
    """The C baseline as a program (for callgrind) and a shared library (for timing)."""
    out.mkdir(parents=True, exist_ok=True)
    sources = [
        "cbench.c",
        "libcanard/canard.c",
        *sorted(str(p.relative_to(c_dir)) for p in (c_dir / "generated" / "src").glob("*.c")),
    ]
    flags = ["-O2", "-DNDEBUG", "-Ilibcanard", "-Igenerated/include"]
    exe, lib = out / "cbench_O2", out / "libcbench_O2.so"
    subprocess.run(["cc", *flags, *sources, "-o", str(exe)], cwd=c_dir, check=True)
    subprocess.run(["cc", *flags, "-DSHARED", "-shared", "-fPIC", *sources, "-o", str(lib)],
                   cwd=c_dir, check=True)  # fmt: skip
    return exe, lib


def timed(binary: Path, op: str, lib: Path, iters: int) -> tuple[float, float | None]:
    """One round: ours and C's nanoseconds per call, in one process."""
    env = dict(os.environ, PX4PARAMS_CBENCH=str(lib))
    out = subprocess.run(
        locked([str(binary), "time", "3", str(iters), op]),
        capture_output=True, text=True, check=True, env=env,
    ).stdout.split()  # fmt: skip
    return float(out[0]), None if out[1] == "-" else float(out[1])


def table(args: argparse.Namespace) -> int:
    after = build(args.compact, aligned=args.aligned_loops)
    tree, target = before_tree(args.before)
    before = build(args.compact, tree, target, aligned=args.aligned_loops)
    c_exe, c_lib = build_c(args.c, Path("/tmp/px4params-cbench"))
    rows = []
    for op, c_op in TABLE:
        ours = [per_call([str(b), op], args.n) for b in (before, after)]
        c = per_call([str(c_exe), "count", c_op], args.n) if c_op else None
        times: dict[str, list[float]] = {"before": [], "after": [], "c_before": [], "c_after": []}
        for _ in range(args.rounds):
            for name, binary in (("before", before), ("after", after)):
                rust_ns, c_ns = timed(binary, op, c_lib, args.iters)
                times[name].append(rust_ns)
                if c_ns is not None:
                    times[f"c_{name}"].append(c_ns)
        med = {k: statistics.median(v) if v else None for k, v in times.items()}
        rows.append((op, ours, c, med))
    build_name = "compact (firmware)" if args.compact else "host"
    if args.aligned_loops:
        build_name += f", both with {ALIGNED_LOOPS}"
    print(f"{build_name} build; before: {args.before}; after: this tree; C: {args.c.name} "
          "(cc -O2); "
          f"instructions per call (callgrind), ns per call (median of {args.rounds} rounds, "
          "C timed beside each build in one process)")  # fmt: skip
    print(f"| {'row':28} | instr before | instr after | instr C | after/C | ns before | "
          "ns after | ns C | after/C time |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for op, (b, a), c, med in rows:
        c_ns = med["c_after"]
        ratio = f"{a / c:.2f}" if c else "-"
        time_ratio = f"{med['after'] / c_ns:.2f}" if c_ns else "-"
        print(f"| {op:28} | {b:,.0f} | {a:,.0f} | {f'{c:,.0f}' if c else '-'} | {ratio} | "
              f"{med['before']:.1f} | {med['after']:.1f} | {f'{c_ns:.1f}' if c_ns else '-'} | "
              f"{time_ratio} |")  # fmt: skip
    flat = {op: med for op, _, _, med in rows}
    for name in ("receive_decode", "receive_into_decode"):
        for when in ("before", "after"):
            extra = flat[f"battery/{name}"][when] - flat["battery/decode"][when]
            print(f"battery/{name} over the flat decode, {when}: {extra:+.1f} ns")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=2000)
    parser.add_argument("--compact", action="store_true", help="the core's firmware build")
    parser.add_argument("--table", action="store_true", help="before/after/C, with times")
    parser.add_argument("--before", default="1fac7b2", help="the revision to compare with")
    parser.add_argument("--c", type=Path, default=C_DIR, help="the C baseline's directory")
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--aligned-loops", action="store_true",
                        help=f"build both trees with {ALIGNED_LOOPS} (a time then moves with "
                             "the code, not with where it lands)")  # fmt: skip
    parser.add_argument("--iters", type=int, default=200_000)
    parser.add_argument("ops", nargs="*", default=OPS, metavar="OP")
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        print("instructions: valgrind is not installed (Debian: apt-get install valgrind)")
        return 0
    if args.table:
        return table(args)
    binary = build(args.compact)
    print(f"{'call':28} {'instructions':>12}")
    for op in args.ops:
        per = (count(binary, op, args.n) - count(binary, op, 0)) / args.n
        print(f"{op:28} {per:>12.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
