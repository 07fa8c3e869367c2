"""``px4params completion names`` (``px4params.cli.commands.completion``): the names a shell
completes are the names the commands take, written by the naming rule (``NAME#N`` for instance
N of an instanced parameter, counted from 0; ``NAME`` for a shared one: docs/store.md), with a
leaf's path after a dot. The expected names are written here by hand from that rule and from
the DSDL (``dsdl/px/Ina238.1.1.dsdl``: ``@max_instances 4``; an I2C bus is ``bus.i2c.bus_id``
and ``bus.i2c.address``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from px4params.cli.main import main

#: A parameter shared by all instances (``@param`` without ``@max_instances``): its name has
#: no ``#N``, nor have its leaves'.
SHARED = """\
# Settings every gadget shares
# @param GADGET_SHARED

uint8 gain
# Gain
# @default 3

@sealed
"""


@pytest.fixture
def store(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    root = tmp_path / "acme"
    root.mkdir()
    (root / "GadgetShared.1.0.dsdl").write_text(SHARED)
    monkeypatch.setenv("PX4PARAMS_DSDL_PATH", str(root))
    monkeypatch.delenv("PX4PARAMS_PARAMETERS_JSON", raising=False)
    path = tmp_path / "vehicle.store"
    monkeypatch.setenv("PX4PARAMS_STORE", str(path))
    return path


def names(capsys: pytest.CaptureFixture[str]) -> list[str]:
    assert main(["completion", "names"]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    return out.splitlines()


def test_instance_slots_and_leaves_are_named_by_the_rule(
    store: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Instance 2 alone: its number, not its position among the instances, names it.
    assert main(["param", "add", "INA238#2"]) == 0
    capsys.readouterr()
    found = names(capsys)
    ina238 = [n for n in found if n == "INA238" or n.startswith("INA238#")]
    slots = [n for n in ina238 if "." not in n]
    assert slots == ["INA238", "INA238#0", "INA238#1", "INA238#2", "INA238#3"]
    leaves = [n for n in ina238 if "." in n]
    assert "INA238#2.bus.i2c.bus_id" in leaves and "INA238#2.bus.i2c.address" in leaves
    assert all(n.startswith("INA238#2.") for n in leaves), leaves  # only what exists
    # Each completed leaf is a name the commands take: shown as the store has it.
    assert main(["param", "show", "INA238#2"]) == 0
    shown = capsys.readouterr().out
    assert "INA238#2 [" in shown


def test_a_shared_parameter_and_its_leaves_have_no_instance_number(
    store: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    found = names(capsys)
    assert "GADGET_SHARED" in found
    assert "GADGET_SHARED.gain" in found
    assert not [n for n in found if n.startswith("GADGET_SHARED#")]
    assert main(["param", "set", "GADGET_SHARED.gain", "5"]) == 0  # the name the command takes
    capsys.readouterr()
    assert "GADGET_SHARED.gain" in names(capsys)


def test_a_classic_parameter_is_completed_without_leaves(
    store: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    found = names(capsys)
    assert "SYS_AUTOSTART" in found
    assert not [n for n in found if n.startswith(("SYS_AUTOSTART.", "SYS_AUTOSTART#"))]
