"""Bytes of the store, in memory and on disk, against the same configuration held as PX4 flat
parameters in PX4's BSON parameter file.

The flat baseline gives every leaf of every configured instance (``p_version`` excluded) its own
flat parameter, named as the destructured MAVLink names are (``INA238_0A``, ...), each a BSON
element of a type byte, the NUL-terminated name and a 4-byte value, in one BSON document (a
4-byte length and a closing NUL). That is what PX4 would save for the same information.

    python benches/store_size.py
"""

from __future__ import annotations

import string
import sys

import px4params
from px4params.store.file import encode_file

SLOT_BYTES = 6  # the core's per-instance state: two u16 lengths and a u8 of flags, padded


def bson_size(names: list[str]) -> int:
    return 4 + sum(1 + len(n) + 1 + 4 for n in names) + 1


def flat_names(store: px4params.Store) -> list[str]:
    names = []
    for name in store.names():
        if "#" not in name:
            continue
        param, _, number = name.partition("#")
        leaves = [leaf for leaf in store.leaves(name) if not leaf.path.endswith("p_version")]
        names += [f"{param}_{number}{string.ascii_uppercase[i]}" for i in range(len(leaves))]
    return names


def memory(store: px4params.Store) -> int:
    slots, size = store.capacity
    return size + slots * SLOT_BYTES


def talk_ina238(store: px4params.Store) -> None:
    store.add("INA238#0")
    store.set_default("INA238#0[3]", 1)
    store.set_default("INA238#0[4]", 0x45)
    store.set_default("INA238#0[5]", 200)
    store.set_default("INA238#0[6]", 0.0003)


def full_manifest(store: px4params.Store) -> None:
    """Every bundled parameter with all its instances, each on its own I2C bus and address."""
    for spec in store.specs:
        for i in range(spec.slots):
            name = store.add(spec.name) if not spec.shared else spec.name
            store.set(f"{name}.bus.i2c.bus_id", 1 + i)
            store.set(f"{name}.bus.i2c.address", 0x10 + i)


def main() -> int:
    schema = px4params.load_schema(use_env=False)
    rows = []
    for label, build in (("talk's INA238#0", talk_ina238), ("full manifest", full_manifest)):
        store = px4params.Store(schema)
        build(store)
        flat = bson_size(flat_names(store))
        disk = len(encode_file(store))
        mem = memory(store)
        instances = sum(1 for n in store.names() if "#" in n)
        rows.append((label, instances, flat, disk, mem))
    print(
        f"{'configuration':18} {'inst':>4} {'flat BSON':>9} {'disk':>6} {'disk/flat':>9} "
        f"{'memory':>7} {'memory/flat':>11}"
    )
    for label, instances, flat, disk, mem in rows:
        print(
            f"{label:18} {instances:4} {flat:9} {disk:6} {disk / flat:9.1%} {mem:7} "
            f"{mem / flat:11.1%}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
