"""The C ABI (crates/px4params-ffi) at the end of its tables: the last parameter in ID order is
a parameter like any other (it opens, a new instance starts from its type's default, it is
saved), and an ID one beyond the table is refused with ``PX4P_ERR_NO_SUCH_PARAM``. Issue 40:
with the table bound in store open taken as ``param_count - 1``, the suite stayed green: its
C checks use the INA238, in the middle of the table.

The expected values come from the DSDL by hand: the last parameter is the VL53L1X
(dsdl/px/Vl53l1x.1.0.dsdl), leaves in depth-first order (docs/codec.md): [0] p_version,
[1] bus._tag (0: i2c, the union's first variant), [2] bus.i2c.p_version, [3] bus.i2c.bus_id
(no default: 0), [4] bus.i2c.address (``@default i2c.address 0x29``, VL53L1X_BASEADDR), [5]
rotation (``@default 25``, PX4's ROTATION_DOWNWARD_FACING); the type is version 1.0, so both
p_version leaves hold minor version 0.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import px4params
import pytest
from metadata_support import require_compilers
from px4params.store.classic import BUNDLED_CLASSIC

ROOT = Path(__file__).resolve().parent.parent
FFI = ROOT / "crates" / "px4params-ffi"
CLI = [sys.executable, "-m", "px4params"]

EXPECTED = """\
open: 0 PX4P_OK
add the last parameter: 0 PX4P_OK
value [0]: PX4P_OK kind 1: 0
value [1]: PX4P_OK kind 1: 0
value [2]: PX4P_OK kind 1: 0
value [3]: PX4P_OK kind 1: 0
value [4]: PX4P_OK kind 1: 41
value [5]: PX4P_OK kind 1: 25
default [0]: PX4P_OK kind 1: 0
default [1]: PX4P_OK kind 1: 0
default [2]: PX4P_OK kind 1: 0
default [3]: PX4P_OK kind 1: 0
default [4]: PX4P_OK kind 1: 41
default [5]: PX4P_OK kind 1: 25
add beyond the table: -3 PX4P_ERR_NO_SUCH_PARAM
get beyond the table: -3 PX4P_ERR_NO_SUCH_PARAM
get a leaf beyond the table: -3 PX4P_ERR_NO_SUCH_PARAM
instances beyond the table: -3 PX4P_ERR_NO_SUCH_PARAM
save: 0 PX4P_OK
"""


def _run(command: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, f"{command}: {proc.stderr[-4000:]}"
    return proc


@pytest.fixture(scope="module")
def last_param(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/firmware/last_param.c built against the generated tables and the C ABI's static
    library, as a firmware build would."""
    if shutil.which("cargo") is None:
        pytest.skip("cargo is not installed: the C ABI cannot be built")
    gcc, _ = require_compilers()
    _run(["cargo", "build", "-q", "-p", "px4params-ffi", "--release"], ROOT)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    lib = target / "release" / "libpx4params_ffi.a"
    build = tmp_path_factory.mktemp("last_param")
    _run([*CLI, "metadata", "--header", "px4_params.h", "--firmware", "px4_param_tables.c"], build)
    _run(
        [gcc, "-std=c11", "-Wall", "-Wextra", "-Werror", f"-I{FFI / 'include'}", "-I.",
         str(ROOT / "tests" / "firmware" / "last_param.c"), "px4_param_tables.c", str(lib),
         "-lpthread", "-ldl", "-o", "last_param"],
        build,
    )  # fmt: skip
    return build / "last_param"


def test_the_c_abi_opens_a_store_whose_last_parameter_is_in_the_table(last_param: Path) -> None:
    header = (last_param.parent / "px4_params.h").read_text()
    ids = {name: int(n) for name, n in re.findall(r"PX4_PARAM_(\w+) = (\d+),", header)}
    count = len(ids)
    assert max(ids.values()) == count - 1
    assert ids["VL53L1X"] == count - 1, "the last parameter is no longer the VL53L1X"
    saved = last_param.parent / "from_c.store"
    out = _run([str(last_param), str(saved)], last_param.parent).stdout
    assert out == EXPECTED
    # The file the C ABI wrote, read by px4params: the new instance with its type's defaults.
    store = px4params.Store.load(saved, classic=BUNDLED_CLASSIC)
    assert store.instances("VL53L1X") == ["VL53L1X#0"]
    assert store.get("VL53L1X#0.bus.i2c.address") == 0x29
    assert store.get("VL53L1X#0.rotation") == 25
