"""Python API speed against pydronecan, measured in the same run on the same values.

Run: python benches/python_api.py  (prints one line per type and operation, and the ratio).
"""

from __future__ import annotations

import sys
import timeit
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import px4params
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
CASES = [
    ("uavcan.equipment.power.BatteryInfo", BATTERY),
    ("uavcan.protocol.NodeStatus", NODE_STATUS),
]


def best(stmt, repeat: int = 5) -> float:
    """Best time per call in seconds."""
    timer = timeit.Timer(stmt)
    number, _ = timer.autorange()
    return min(timer.repeat(repeat=repeat, number=number)) / number


def main() -> None:
    schema = px4params.load_schema(use_env=False)
    print(f"{'type':<38} {'op':<7} {'px4params':>11} {'pydronecan':>11} {'ratio':>7}")
    for key, value in CASES:
        t = schema[key]
        obj = fill(new_value(key), value)
        data = t.encode(value)
        assert bytes(transport.bytes_from_bits(obj._pack(True))) == data
        ours_enc = best(lambda t=t, value=value: t.encode(value))
        theirs_enc = best(lambda obj=obj: transport.bytes_from_bits(obj._pack(True)))
        ours_dec = best(lambda t=t, data=data: t.decode(data))
        theirs_dec = best(lambda key=key, data=data: unpack(key, data, tao=True))
        for op, ours, theirs in (
            ("encode", ours_enc, theirs_enc),
            ("decode", ours_dec, theirs_dec),
        ):
            print(
                f"{key:<38} {op:<7} {ours * 1e9:>9.0f}ns {theirs * 1e9:>9.0f}ns "
                f"{theirs / ours:>6.1f}x"
            )
    store_rows(schema)


def store_rows(schema: px4params.Schema) -> None:
    """Reading one leaf of an instance by name, against a dict lookup (a flat parameter
    table's cost) in the same run."""
    store = px4params.Store(schema, classic=[])
    for n in range(4):
        store.add(f"INA238#{n}")
    flat = {f"INA238_{n}P": 327 for n in range(4)}
    ours = best(lambda: store.get("INA238#3.current"))
    theirs = best(lambda: flat["INA238_3P"])
    label = 'Store.get("INA238#3.current")'
    print(
        f"\n{label:<38} {'get':<7} {ours * 1e9:>9.0f}ns {theirs * 1e9:>9.0f}ns (dict) "
        f"{ours / theirs:>6.1f}x slower"
    )


if __name__ == "__main__":
    main()
