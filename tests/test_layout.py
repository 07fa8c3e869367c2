"""The package's shape, beyond what import-linter checks (`lint-imports`, contracts in
pyproject.toml): who may call the compiled extension, and that ``import px4params`` stays cheap."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "python" / "px4params"

#: The codec (dsdl), the store and the CAN transfer wrapper are the native extension's callers.
NATIVE_CALLERS = ("dsdl/", "store/", "links/can_transfer.py")


def _imports_native(path: Path) -> bool:
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (
            node.module == "px4params._native"
            or (node.module == "px4params" and any(a.name == "_native" for a in node.names))
        ):
            return True
        if isinstance(node, ast.Import) and any(a.name == "px4params._native" for a in node.names):
            return True
    return False


def test_only_the_codec_store_and_transfer_layers_call_the_extension() -> None:
    callers = sorted(
        path.relative_to(PACKAGE).as_posix()
        for path in PACKAGE.rglob("*.py")
        if _imports_native(path)
    )
    assert callers, "nobody imports px4params._native: the scan is broken"
    outside = [c for c in callers if not c.startswith(NATIVE_CALLERS)]
    assert outside == []


def test_import_px4params_loads_no_subpackage() -> None:
    code = (
        "import sys, px4params\nprint(sorted(m for m in sys.modules if m.startswith('px4params.')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_public_names_import_on_first_use() -> None:
    import px4params

    assert px4params.Store.__module__ == "px4params.store.store"
    assert issubclass(px4params.StoreFileError, px4params.Px4ParamsError)
    assert set(px4params.__all__) <= set(dir(px4params))


def test_version_is_pyprojects() -> None:
    import tomllib

    import px4params

    with open(PACKAGE.parents[1] / "pyproject.toml", "rb") as f:
        assert px4params.__version__ == tomllib.load(f)["project"]["version"]
