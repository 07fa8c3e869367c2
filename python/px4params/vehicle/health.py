"""The health of a store's manifest, as a node reports it: one line per configured device and
the worst state, from the configuration alone or from a boot on the simulated bench.

Without a bench only the configuration can be judged: an instance its driver cannot start (no
driver, a bus kind it does not take, bus 0, a reserved address, a location taken twice) is a
warning. With a bench the manifest is booted (:func:`simbench.run`) and each device's health
is what the commander reports. Either is recomputed only when the store's values change.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from px4params.vehicle.autostart import configured
from px4params.vehicle.drivers import Drivers, load_drivers

if TYPE_CHECKING:
    from px4params.store.store import Store
    from px4params.vehicle.simbench import Bench

__all__ = ["DeviceHealth", "ManifestHealth", "worst"]

#: From good to bad, as the bench names them.
LEVELS = ("nominal", "warning", "critical")


class DeviceHealth(NamedTuple):
    instance: str
    #: ``nominal``, ``warning`` or ``critical``.
    health: str
    #: ``ina238 INA238#1 on I2C bus 2 address 0x45: critical: no answer ...``
    line: str


def worst(devices: list[DeviceHealth]) -> str:
    """The worst health of ``devices`` (``nominal`` for none)."""
    return max((d.health for d in devices), key=LEVELS.index, default="nominal")


class ManifestHealth:
    """Health of ``store``'s configured instances; ``bench`` (a bench file) boots them for
    ``duration`` simulated seconds."""

    def __init__(self, store: Store, bench: str | None = None, *, duration: float = 10.0) -> None:
        self.store = store
        self.drivers: Drivers = load_drivers(None, store.specs)
        self.duration = duration
        self._bench: Bench | None = None
        if bench is not None:
            from px4params.vehicle.simbench import load_bench

            self._bench = load_bench(bench, self.drivers)  # errors now, before serving
        self._key: bytes | None = None
        self._devices: list[DeviceHealth] = []

    def devices(self) -> list[DeviceHealth]:
        """One entry per configured instance, in start order."""
        key = self._state()
        if key != self._key:
            self._devices = self._compute()
            self._key = key
        return list(self._devices)

    def _state(self) -> bytes:
        """Every structured instance's name and stored bytes: what the judgement depends on."""
        store = self.store
        parts = [
            str(key).encode() + b"=" + store.encoded(key)
            for key in store.instance_keys()
            if store.spec(key.param) is not None
        ]
        return b";".join(parts)

    def _compute(self) -> list[DeviceHealth]:
        manifest = configured(self.store, self.drivers)
        if self._bench is None:
            found = []
            for c in manifest:
                driver = c.driver.name if c.driver else "(no driver)"
                if c.problems:
                    line = (
                        f"{driver} {c.instance} on {c.location}: warning: {'; '.join(c.problems)}"
                    )
                    found.append(DeviceHealth(c.instance, "warning", line))
                else:
                    line = f"{driver} {c.instance} on {c.location}: configured"
                    found.append(DeviceHealth(c.instance, "nominal", line))
            return found
        from px4params.vehicle.simbench import run

        result = run(self._bench, self.drivers, manifest, duration=self.duration)
        return [DeviceHealth(i.name, i.health, i.failure_line()) for i in result.instances]
