"""Python API speed against its baselines, measured in the same run on the same values: the
codec against pydronecan (``_pack`` of a prebuilt value object, and ``unpack``), reading one
leaf of an instance by name against a dict lookup (a flat parameter table's cost). The
``_many`` rows are the batch calls, per message of a batch of 100, against pydronecan's one
message (it has no batch call); the ``decode_struct`` rows decode into a ``StructValue``, an
object with the fields as attributes, as pydronecan's ``unpack`` does.

    python benches/python_api.py [--runs 5] [--instructions] [--rows TEXT ...]
    python benches/python_api.py --against OLD.so [--runs 5] [--rows TEXT ...]

Each row is timed ``--runs`` times, ours and the baseline one after the other (this machine is
noisy), best of timeit's repeats each time; the median of the runs is printed, with the ratio
and issue 18's target. A call is timed as the statement a user writes (``t.encode(value)``,
its names local to timeit's loop, as ``python -m timeit`` times it), not through a lambda,
whose own call (about 20 ns) would be counted on both sides. ``--instructions`` adds
valgrind's instruction counts per call: callgrind counts only inside the timed loop (run
through ``operator.call``, which nothing else here calls), N calls minus none, divided by N,
with the collector off and a fixed hash seed. Loading the schema and the modules is never
counted (it costs some 5.5 billion instructions and varies by millions from run to run).

``--against OLD.so`` times our side of each row with another build of ``px4params._native``
(loaded beside this one, as its own module) and with this one, in one process, the two one
after the other for each row of each run, taking turns to go first; it prints the medians
and their ratio (this build's over the other's: below 1 is faster). With ``--instructions``
it adds each build's instructions per call inside the binding only (callgrind collecting in
its entry points, ``BINDING_ENTRY_POINTS``), and their difference.
"""

from __future__ import annotations

import argparse
import gc
import importlib.machinery
import importlib.util
import operator
import os
import re
import shutil
import statistics
import subprocess
import sys
import timeit
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import px4params
import px4params._native
from dronecan import transport
from dronecan_oracle import fill, new_value, unpack

BATTERY = {
    "temperature": 300.5,
    "voltage": 16.8,
    "current": -12.25,
    "average_power_10sec": 201.0,
    "remaining_capacity_wh": 55.5,
    "full_charge_capacity_wh": 99.0,
    "hours_to_full_charge": 0.0,
    "status_flags": 3,
    "state_of_health_pct": 97,
    "state_of_charge_pct": 80,
    "state_of_charge_pct_stdev": 2,
    "battery_id": 1,
    "model_instance_id": 123456,
    "model_name": list(b"PX4 smart battery 6S"),
}
NODE_STATUS = {
    "uptime_sec": 12345,
    "health": 0,
    "mode": 0,
    "sub_mode": 0,
    "vendor_specific_status_code": 7,
}
# A tail array of structs, and a struct of unions (issue 39: every type by a value program).
ARRAY_COMMAND = {
    "commands": [{"actuator_id": i, "command_type": 1, "command_value": 0.25 * i} for i in range(4)]
}
PARAM_RESPONSE = {
    "value": {"integer_value": 5},
    "default_value": {"integer_value": 1},
    "max_value": {"integer_value": 10},
    "min_value": {"integer_value": 0},
    "name": list(b"INA238_CUR"),
}
BATTERY_KEY = "uavcan.equipment.power.BatteryInfo"
NODE_STATUS_KEY = "uavcan.protocol.NodeStatus"
ARRAY_COMMAND_KEY = "uavcan.equipment.actuator.ArrayCommand"
PARAM_RESPONSE_KEY = "uavcan.protocol.param.GetSet.Response"

# Row name -> (what the baseline is, how the target is read, the target).
ROWS = {
    "BatteryInfo encode": ("pydronecan", "faster", 100.0),
    "BatteryInfo decode": ("pydronecan", "faster", 150.0),
    "NodeStatus encode": ("pydronecan", "faster", 60.0),
    "NodeStatus decode": ("pydronecan", "faster", 100.0),
    "BatteryInfo decode_struct": ("pydronecan", "faster", 150.0),
    "NodeStatus decode_struct": ("pydronecan", "faster", 100.0),
    "BatteryInfo encode_many": ("pydronecan", "faster", 100.0),
    "BatteryInfo decode_many": ("pydronecan", "faster", 150.0),
    "NodeStatus encode_many": ("pydronecan", "faster", 60.0),
    "NodeStatus decode_many": ("pydronecan", "faster", 100.0),
    # Issue 39's rows: no target of issue 18; as BatteryInfo's.
    "ArrayCommand encode": ("pydronecan", "faster", 100.0),
    "ArrayCommand decode": ("pydronecan", "faster", 150.0),
    "GetSet.Response encode": ("pydronecan", "faster", 100.0),
    "GetSet.Response decode": ("pydronecan", "faster", 150.0),
    'Store.get("INA238#3.current")': ("dict lookup", "at most", 0.5e-6),
}
#: Messages per batch call in the ``_many`` rows.
BATCH = 100
#: Where callgrind counts a whole call: the timed loop, which ``--loop`` runs (alone) through
#: ``operator.call``.
LOOP_ENTRY_POINTS = ("_operator_call",)
#: Where callgrind counts the binding's own work: the functions CPython calls in it for the
#: codec rows (the fast-call methods, and pyo3's wrappers of the others).
BINDING_ENTRY_POINTS = ("_native::fastcall::*", "_native::DataType::__pymethod_*")


@dataclass(frozen=True)
class Call:
    """A statement to time, and the objects it names (local variables of timeit's loop)."""

    statement: str
    names: dict[str, Any]

    def timer(self) -> timeit.Timer:
        setup = "; ".join(f"{name} = _names[{name!r}]" for name in self.names) or "pass"
        return timeit.Timer(self.statement, setup=setup, globals={"_names": self.names})

    def run(self) -> object:
        """The statement's value, once (to check it)."""
        return eval(self.statement, {}, self.names)


def calls() -> dict[str, tuple[Call, Call, int]]:
    """Each row's two calls (ours, the baseline) and how many messages our call handles;
    checked to agree first."""
    schema = px4params.load_schema(use_env=False)
    made: dict[str, tuple[Call, Call, int]] = {}
    for name, key, value in (
        ("BatteryInfo", BATTERY_KEY, BATTERY),
        ("NodeStatus", NODE_STATUS_KEY, NODE_STATUS),
        ("ArrayCommand", ARRAY_COMMAND_KEY, ARRAY_COMMAND),
        ("GetSet.Response", PARAM_RESPONSE_KEY, PARAM_RESPONSE),
    ):
        t = schema[key]
        obj = fill(new_value(key), value)
        data = t.encode(value)
        pack = Call(
            "bytes_from_bits(obj._pack(True))",
            {"bytes_from_bits": transport.bytes_from_bits, "obj": obj},
        )
        unpack_one = Call(
            "unpack(key, data, tao=True)", {"unpack": unpack, "key": key, "data": data}
        )
        assert bytes(pack.run()) == data  # type: ignore[arg-type]
        made[f"{name} encode"] = (Call("t.encode(value)", {"t": t, "value": value}), pack, 1)
        made[f"{name} decode"] = (Call("t.decode(data)", {"t": t, "data": data}), unpack_one, 1)
        typed = Call("t.decode_struct(data)", {"t": t, "data": data})
        assert typed.run()._asdict() == t.decode(data)  # type: ignore[attr-defined]
        made[f"{name} decode_struct"] = (typed, unpack_one, 1)
        values, items = [dict(value) for _ in range(BATCH)], [data] * BATCH
        assert t.encode_many(values) == items and t.decode_many(items) == [t.decode(data)] * BATCH
        made[f"{name} encode_many"] = (Call("t.encode_many(v)", {"t": t, "v": values}), pack, BATCH)
        many = Call("t.decode_many(d)", {"t": t, "d": items})
        made[f"{name} decode_many"] = (many, unpack_one, BATCH)
    store = px4params.Store(schema, classic=[])
    for n in range(4):
        store.add(f"INA238#{n}")
    flat = {f"INA238_{n}P": 327 for n in range(4)}
    get = Call('store.get("INA238#3.current")', {"store": store})
    lookup = Call('flat["INA238_3P"]', {"flat": flat})
    assert get.run() == lookup.run()
    made['Store.get("INA238#3.current")'] = (get, lookup, 1)
    kept = {row: c for row, c in made.items() if row in ROWS}
    return dict(sorted(kept.items(), key=lambda row: list(ROWS).index(row[0])))


def best(call: Call, repeat: int = 5) -> float:
    """Best time per call in seconds."""
    timer = call.timer()
    number, _ = timer.autorange()
    return min(timer.repeat(repeat=repeat, number=number)) / number


def instructions(
    row: str, side: str, seconds_per_call: float, against: Path | None = None
) -> float:
    """Instructions per call of one side of ``row`` (``ours``, ``baseline``; or ``before``,
    ``after`` with ``against``, the other build), under callgrind, counted only where
    ``--loop`` times the calls (the binding's entry points for ``before``/``after``): as many
    calls as take a fiftieth of a second natively, minus none."""
    n = min(20_000, max(500, int(0.02 / seconds_per_call)))
    entry_points = BINDING_ENTRY_POINTS if against else LOOP_ENTRY_POINTS
    toggles = [f"--toggle-collect={name}" for name in entry_points]
    extra = ["--against", str(against)] if against else []

    def count(times: int) -> int:
        err = subprocess.run(
            [
                "valgrind",
                "--tool=callgrind",
                "--callgrind-out-file=/dev/null",
                "--collect-atstart=no",
                *toggles,
                sys.executable,
                __file__,
                "--loop",
                row,
                side,
                str(times),
                *extra,
            ],
            capture_output=True,
            text=True,
            check=True,
            env=dict(os.environ, PYTHONHASHSEED="0"),
        ).stderr
        match = re.search(r"refs:\s+([\d,]+)", err)
        assert match, err
        return int(match.group(1).replace(",", ""))

    return (count(n) - count(0)) / n


def loop(row: str, side: str, n: int, against: Path | None) -> None:
    """Runs one side of ``row`` ``n`` times through ``operator.call`` (what callgrind counts),
    with the collector off so that no collection falls inside the calls."""
    if side in ("before", "after"):
        assert against, "--loop before/after needs --against OLD.so"
        native = load_native(against) if side == "before" else px4params._native
        call = calls_with(native)[row]
    else:
        call = calls()[row][("ours", "baseline").index(side)]
    timer = call.timer()
    gc.disable()
    operator.call(timer.timeit, n)


def show(row: str, ours: float, theirs: float, ours_ir: float | None, theirs_ir: float | None):
    _, how, target = ROWS[row]
    if how == "faster":
        ratio, met = f"{theirs / ours:7.1f}x", theirs / ours >= target
        goal = f">= {target:.0f}x"
    else:
        ratio, met = f"{ours / theirs:7.1f}x slower", ours <= target
        goal = f"<= {target * 1e6:.1f} us"
    line = f"{row:<31} {ours * 1e9:>8.0f} ns {theirs * 1e9:>9.0f} ns {ratio:>14}  {goal:<10}"
    line += " met" if met else " not met"
    if ours_ir is not None and theirs_ir is not None:
        line += f"   {ours_ir:>8.0f} {theirs_ir:>9.0f} Ir ({theirs_ir / ours_ir:.1f}x)"
    print(line, flush=True)


def load_native(path: Path) -> ModuleType:
    """Another build of ``px4params._native``, loaded beside this one (its own module)."""
    name = "px4params_before._native"
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def calls_with(native: ModuleType) -> dict[str, Call]:
    """Our side of each codec row, run by the build ``native`` (on its own ``DataType``s,
    compiled from the same definitions). The store row is left out: a store is made through
    the Python package, which uses this build."""
    schema = px4params.load_schema(use_env=False)
    compiled = native.Schema(dict(schema._definitions.items()))
    made = {}
    for row, (ours, _, _) in calls().items():
        if "t" in ours.names:
            names = dict(ours.names, t=compiled.get(ours.names["t"].key))
            made[row] = Call(ours.statement, names)
            assert repr(made[row].run()) == repr(ours.run())
    return made


def against(old_so: Path, rows: list[str] | None, runs: int, counted: bool) -> None:
    """Our side of each row with ``old_so`` and with this build, in one process, the two
    timed one after the other for each row of each run (see the module); with the binding's
    instructions per call of each when ``counted``."""
    sides = {
        "before": calls_with(load_native(old_so)),
        "after": calls_with(px4params._native),
    }
    per = {row: n for row, (_, _, n) in calls().items() if row in sides["after"]}
    if rows:
        per = {row: n for row, n in per.items() if any(text in row for text in rows)}
    times: dict[str, dict[str, list[float]]] = {side: {row: [] for row in per} for side in sides}
    for run in range(runs):
        for row in per:
            for side in ("before", "after") if run % 2 == 0 else ("after", "before"):
                times[side][row].append(best(sides[side][row]) / per[row])
    print(f"{os.cpu_count()} CPUs, Python {sys.version.split()[0]}, {runs} runs, medians")
    print(f"before: {old_so}\nafter:  {Path(px4params._native.__file__).resolve()}")
    head = f"{'':<31} {'before':>11} {'after':>11} {'after/before':>13}"
    print(head + ("   binding Ir: before    after  change" if counted else ""))
    for row in per:
        before = statistics.median(times["before"][row])
        after = statistics.median(times["after"][row])
        line = f"{row:<31} {before * 1e9:>8.0f} ns {after * 1e9:>8.0f} ns {after / before:>13.2f}"
        if counted:
            # Per message, as the times: a batch row's call counts `per` messages.
            ir = {
                side: instructions(row, side, t * per[row], old_so) / per[row]
                for side, t in (("before", before), ("after", after))
            }
            change = ir["after"] - ir["before"]
            line += f"   {ir['before']:>17.1f} {ir['after']:>8.1f} {change:>+7.1f}"
        print(line, flush=True)


def which_valgrind() -> str | None:
    """valgrind's path, or None (said on stderr)."""
    found = shutil.which("valgrind")
    if not found:
        print("valgrind is missing: no instruction counts", file=sys.stderr)
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--instructions", action="store_true")
    parser.add_argument("--rows", nargs="+", metavar="TEXT", help="only rows naming any TEXT")
    parser.add_argument("--against", type=Path, metavar="OLD.so", help="compare with this build")
    parser.add_argument("--loop", nargs=3, metavar=("ROW", "SIDE", "N"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.loop:
        row, side, n = args.loop
        loop(row, side, int(n), args.against)
        return
    if args.instructions and not which_valgrind():
        args.instructions = False
    if args.against:
        against(args.against, args.rows, args.runs, args.instructions)
        return
    made = calls()
    if args.rows:
        made = {row: c for row, c in made.items() if any(text in row for text in args.rows)}
    times: dict[str, tuple[list[float], list[float]]] = {row: ([], []) for row in made}
    for _ in range(args.runs):
        for row, (ours, theirs, per) in made.items():
            times[row][0].append(best(ours) / per)
            times[row][1].append(best(theirs))
    print(f"{os.cpu_count()} CPUs, Python {sys.version.split()[0]}, {args.runs} runs, medians")
    print(f"{'':<31} {'px4params':>11} {'baseline':>12} {'ratio':>14}  target")
    for row in made:
        ours, theirs = (statistics.median(t) for t in times[row])
        per = made[row][2]
        counts = (
            (instructions(row, "ours", ours * per) / per, instructions(row, "baseline", theirs))
            if args.instructions
            else (None, None)
        )
        show(row, ours, theirs, *counts)


if __name__ == "__main__":
    main()
