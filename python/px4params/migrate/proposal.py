"""What :func:`px4params.migrate.migrate` proposes: the instances, what is left out and why,
what is assumed, and the airframe file, report and JSON made of them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from px4params.migrate.config import OldConfig
from px4params.store.key import Key

__all__ = ["LeftOut", "Proposal", "ProposedInstance"]


@dataclass
class ProposedInstance:
    """One instance of the manifest, its values and why it is proposed."""

    name: str
    #: Where it comes from, e.g. ``CAL_MAG1_ID 592905: AK09916 (MAG), I2C bus 1, address 0x0C``.
    origin: str
    #: Field path -> value, in the order to set them.
    values: dict[str, Any]
    notes: list[str] = field(default_factory=list)
    #: Filled in by :func:`migrate`: path -> ``[k]`` index.
    indices: dict[str, int] = field(default_factory=dict)
    #: ``name`` parsed (once): what the store is given.
    key: Key = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.key = Key.parse(self.name)


@dataclass
class LeftOut:
    """A device found (a device ID, a boot console line) that is not part of the manifest."""

    #: Where it was found: ``CAL_MAG0_ID, CAL_MAG3_ID`` or ``boot console line 35``.
    found: str
    #: What it is, e.g. ``IST8310 (MAG), I2C bus 4, address 0x0C``.
    device: str
    #: Why, as a word: ``board`` (started by the board's script), ``disabled``, ``dronecan``,
    #: ``simulation``, ``other bus``, ``kind`` (its devtype is another kind of sensor than
    #: the calibration slot's: a devtype table of another era).
    reason: str
    #: The report's line.
    line: str
    #: Of a device the board's script starts: whether the board's scripts of later releases
    #: still start it, one line citing the file's start and each change; None where nothing
    #: was compared (no board row started it, or no later release is known).
    later: str | None = None

    def as_dict(self) -> dict[str, str | None]:
        return {
            "found": self.found,
            "device": self.device,
            "reason": self.reason,
            "line": self.line,
            "later": self.later,
        }


@dataclass
class Proposal:
    """What :func:`migrate` proposes: the instances and the report."""

    config: OldConfig
    table: str
    instances: list[ProposedInstance] = field(default_factory=list)
    #: Devices found that are not part of the manifest, with the reason.
    left_out: list[LeftOut] = field(default_factory=list)
    #: What the migration cannot know and assumed instead (a bus, a board, the era), one line
    #: each.
    assumptions: list[str] = field(default_factory=list)
    #: The board whose table was used (its PX4 name), None without one.
    board: str | None = None
    #: The release the proposal is made for (``--target-release``), None: the file's own.
    target_release: str | None = None
    #: The releases after the file's whose board scripts were compared with its own.
    compared: list[str] = field(default_factory=list)
    #: Parameters whose job the manifest takes over.
    replaced: list[str] = field(default_factory=list)
    #: ``SENS_EN_*`` parameters that are 0: no driver to carry over.
    disabled: list[str] = field(default_factory=list)
    #: What could not be carried over, one line each, never dropped silently.
    not_carried: list[str] = field(default_factory=list)
    #: Parameters that were used to build the proposal.
    used: set[str] = field(default_factory=set)

    @property
    def not_in_manifest(self) -> list[str]:
        """The report lines of :attr:`left_out`."""
        return [item.line for item in self.left_out]

    @property
    def unchanged(self) -> int:
        """Parameters left as they are (classic parameters, not part of the manifest)."""
        return len(set(self.config.params) - self.used)

    def airframe(self) -> str:
        """The airframe file: ``param add`` / ``param set-default`` lines with comments."""
        lines = [
            f"# Device manifest migrated by px4params from {Path(self.config.source).name} "
            f"({self.config.kind})",
            "# Review before use: see the migration report.",
        ]
        if self.config.cut:
            lines.append(
                "# Warning: the log is cut short or damaged: devices logged after the break are "
                "missing here."
            )
        if not self.instances:
            lines.append("# No device could be carried over.")
        for inst in self.instances:
            lines += ["", f"# {inst.name}: {inst.origin}", f"param add {inst.name}"]
            for path, value in inst.values.items():
                lines.append(f"# [{inst.indices[path]}] {path}")
                lines.append(
                    f"param set-default {inst.name}[{inst.indices[path]}] {_text(path, value)}"
                )
        return "\n".join(lines) + "\n"

    def report(self) -> str:
        c = self.config
        out = [f"Migration of {c.source} ({c.kind}, {len(c.params)} parameters)"]
        out += [f"  {d}" for d in c.details]
        out.append(f"  device IDs decoded with the {self.table} devtype table")
        out.append(f"  board: {self.board}" if self.board else "  board: not known")
        if self.target_release:
            out.append(f"  proposed for PX4 {self.target_release} (--target-release)")
        if self.compared:
            span = " .. ".join(dict.fromkeys((self.compared[0], self.compared[-1])))
            out.append(f"  the board's scripts compared with PX4 {span}")

        def section(title: str, rows: list[str]) -> None:
            out.append("")
            out.append(f"{title}:" if rows else f"{title}: none")
            out.extend(f"  {r}" for r in rows)

        rows = []
        for inst in self.instances:
            rows.append(f"{inst.name}: {inst.origin}")
            shown = ", ".join(f"{p} = {_text(p, v)}" for p, v in inst.values.items())
            rows.append(f"  {shown}")
            rows.extend(f"  note: {n}" for n in inst.notes)
        section("Instances proposed", rows)
        section(
            "Sensors found but not in the manifest",
            [
                row
                for item in self.left_out
                for row in (item.line, *([f"  later: {item.later}"] if item.later else []))
            ],
        )
        section("Not known, assumed", self.assumptions)
        section("Replaced by the manifest", self.replaced)
        if self.disabled:
            out.append(f"  not enabled, nothing to carry over: {', '.join(self.disabled)}")
        section("Not carried over", self.not_carried + [f"{s}" for s in c.skipped])
        out.append("")
        out.append(
            f"Unchanged: {self.unchanged} other parameters stay classic parameters "
            "(calibration, tuning, ...); the manifest does not replace them."
        )
        return "\n".join(out) + "\n"

    def as_dict(self) -> dict[str, Any]:
        return {
            "source": self.config.source,
            "kind": self.config.kind,
            "parameters": len(self.config.params),
            "details": self.config.details,
            "log_cut": self.config.cut,
            "table": self.table,
            "board": self.board,
            "version": ".".join(map(str, self.config.version)) if self.config.version else None,
            "target_release": self.target_release,
            "compared_releases": self.compared,
            "assumptions": self.assumptions,
            "left_out": [item.as_dict() for item in self.left_out],
            "instances": [
                {
                    "name": i.name,
                    "origin": i.origin,
                    "values": {p: _json(v) for p, v in i.values.items()},
                    "indices": i.indices,
                    "notes": i.notes,
                }
                for i in self.instances
            ],
            "not_in_manifest": self.not_in_manifest,
            "replaced": self.replaced,
            "disabled": self.disabled,
            "not_carried": self.not_carried + self.config.skipped,
            "unchanged": self.unchanged,
            "airframe": self.airframe(),
        }


def _text(path: str, value: Any) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return f"{value:.9g}"
    if path.endswith("address"):
        return f"0x{value:02X}"
    return str(value)


def _json(value: Any) -> Any:
    return value if not isinstance(value, float) or math.isfinite(value) else str(value)
