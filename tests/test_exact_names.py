"""Names are exact, as PX4's: ASCII digits only, upper case, no padding. PX4 finds a parameter by
comparing its name byte for byte (``param_find`` uses ``strcmp``), so ``ina238#0`` or ``INA238#٣``
(an Arabic-Indic three) name nothing there; here they are refused with the exact name as a hint,
at the one place names are parsed (``Key.parse``) and for destructured (MAVLink) names."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import px4params
import pytest
from px4params.errors import InstanceError
from px4params.store.store import Key

EXACT = "names are exact, in upper case with ASCII digits and no spaces, as PX4's"


@pytest.mark.parametrize(
    ("text", "hint"),
    [
        ("INA238#\u0663", "INA238#3"),  # Arabic-Indic digit three
        ("INA238#\u0661[4]", "INA238#1[4]"),
        ("INA238#\uff11", "INA238#1"),  # fullwidth digit one
        ("ina238#0", "INA238#0"),
        ("Ina238#0.bus.i2c.address", "INA238#0.bus.i2c.address"),
        (" INA238#0", "INA238#0"),
        ("INA238#0 ", "INA238#0"),
        ("INA238#0\t", "INA238#0"),
        ("sys_autostart", "SYS_AUTOSTART"),
    ],
)
def test_an_inexact_name_is_refused_with_the_exact_one(text: str, hint: str) -> None:
    with pytest.raises(InstanceError) as e:
        Key.parse(text)
    assert str(e.value) == f"'{text}' is not a parameter name: {EXACT} (did you mean {hint}?)"


def test_no_instance_is_added_under_an_inexact_name() -> None:
    store = px4params.Store()
    for text in ("INA238#\u0663", "ina238#3", "INA238#3 ", "ina238"):
        with pytest.raises(InstanceError, match="did you mean INA238"):
            store.add(text)
    assert list(store.names()) == []
    assert store.add("INA238#3") == "INA238#3"
    assert "ina238#3" not in store and " INA238#3" not in store and "INA238#3" in store
    with pytest.raises(InstanceError, match=rf"^'ina238' is not a parameter name: {EXACT} \("):
        store.instances("ina238")


def test_a_destructured_name_is_exact_too() -> None:
    from px4params.store.flat import resolve_flat

    store = px4params.Store()
    store.add("INA238#1")
    assert resolve_flat(store, "INA238_1C") == "INA238#1[4]"
    for text in ("ina238_1c", "INA238_1C ", " INA238_1C"):
        with pytest.raises(InstanceError) as e:
            resolve_flat(store, text)
        assert str(e.value) == (
            f"'{text}' is not a destructured parameter name (did you mean INA238_1C?)"
        )
    assert "ina238_1c" not in store.destructured
    assert store.destructured.mask_spec("ina238_inst") is None


def test_the_cli_refuses_them_and_changes_nothing(tmp_path: Path) -> None:
    store = tmp_path / "vehicle.store"
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp_path / "cache"))

    def cli(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, "-m", "px4params", "param", "--store", str(store), *args],
            capture_output=True,
            text=True,
            env=env,
            timeout=120,
        )

    assert cli("add", "INA238#0").returncode == 0
    before = store.read_bytes()
    for args, hint in (
        (("add", "INA238#\u0663"), "INA238#3"),
        (("add", "ina238#1"), "INA238#1"),
        (("set", "INA238#0.current ", "100"), "INA238#0.current"),
        (("set", "ina238_0p", "100"), "INA238_0P"),
    ):
        result = cli(*args)
        assert (result.returncode, result.stdout) == (1, "")
        assert result.stderr == (
            f"px4params: error: '{args[1]}' is not a parameter name: {EXACT} "
            f"(did you mean {hint}?)\n"
        )
    assert store.read_bytes() == before
