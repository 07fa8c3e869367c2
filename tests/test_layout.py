"""The package's shape, beyond what import-linter checks (`lint-imports`, contracts in
pyproject.toml): who may call the compiled extension, and that ``import px4params`` stays cheap."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

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


def test_init_stub_is_what_init_exports() -> None:
    """Type checkers read ``__init__.pyi`` instead of ``__init__.py``, whose names come from a
    table at run time: the stub re-exports (``X as X``) each name of the table from the module
    the table names, and declares nothing else but ``__all__`` and ``__version__``. (mypy, in
    scripts/test.sh, checks that each such module has the name.)"""
    import px4params

    tree = ast.parse((PACKAGE / "__init__.pyi").read_text(encoding="utf-8"))
    imported = [
        (alias.name, alias.asname, node.module)
        for node in tree.body
        if isinstance(node, ast.ImportFrom)
        for alias in node.names
    ]
    assert all(name == asname for name, asname, _ in imported)
    assert {name: module for name, _, module in imported} == px4params._EXPORTS
    assert len(imported) == len(px4params._EXPORTS)
    declared = {
        node.target.id
        for node in tree.body
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name)
    }
    assert declared == {"__all__", "__version__"}
    assert [type(node) for node in tree.body if not isinstance(node, ast.ImportFrom)] == [
        ast.Expr,  # the docstring
        ast.AnnAssign,
        ast.AnnAssign,
    ]


def test_version_is_pyprojects() -> None:
    import tomllib

    import px4params

    with open(PACKAGE.parents[1] / "pyproject.toml", "rb") as f:
        assert px4params.__version__ == tomllib.load(f)["project"]["version"]


def test_short_commands_do_not_import_typing(tmp_path: Path) -> None:
    """``typing`` costs a short command 5 ms: ``param show`` and ``decode`` run without it
    (``px4params._records``)."""
    store = tmp_path / "v.store"
    airframe = PACKAGE.parents[1] / "examples" / "two_batteries.airframe"
    run = [sys.executable, "-m", "px4params"]
    subprocess.run(
        [*run, "run", str(airframe), "--store", str(store)], check=True, capture_output=True
    )
    for command in (
        ["param", "--store", str(store), "show"],
        ["decode", "uavcan.protocol.NodeStatus", "39300000000700"],
    ):
        out = subprocess.run(
            [sys.executable, "-X", "importtime", "-m", "px4params", *command],
            capture_output=True,
            text=True,
            check=True,
        )
        imported = [line.rsplit("|", 1)[-1].strip() for line in out.stderr.splitlines()]
        assert "px4params.store.store" in imported or "px4params.dsdl.schema" in imported
        assert "typing" not in imported, command


def test_records_are_named_tuples() -> None:
    from px4params._records import NamedTuple

    class Point(NamedTuple):
        """A point."""

        x: int
        y: int = 2

        @property
        def total(self) -> int:
            return self.x + self.y

    p = Point(1)
    assert (p, p.total, p._replace(y=5), Point.__doc__) == ((1, 2), 3, (1, 5), "A point.")
    assert repr(p) == "Point(x=1, y=2)" and Point._fields == ("x", "y")
    assert Point.__module__ == __name__
    with pytest.raises(TypeError, match="fields without a default cannot follow"):

        class Bad(NamedTuple):
            a: int = 1
            b: int
