"""``px4params.errors``: every exception class of the package is defined there (the house rule),
read from the source with ``ast`` so that no module has to be imported to be checked."""

from __future__ import annotations

import ast
import builtins
from pathlib import Path

import pytest
from px4params import errors

PACKAGE = Path(errors.__file__).parent

#: Modules allowed their own exception classes, with the reason.
EXEMPT = {
    # Copied into ground stations as one file: it imports nothing of px4params (the
    # import-linter contract "the ground-station codec stands alone").
    "gcs/codec.py",
}

_BUILTIN_EXCEPTIONS = {
    name
    for name, value in vars(builtins).items()
    if isinstance(value, type) and issubclass(value, BaseException)
}


def _base_name(base: ast.expr) -> str | None:
    """``ValueError`` for ``ValueError``, ``SerialException`` for ``serial.SerialException``."""
    if isinstance(base, ast.Name):
        return base.id
    if isinstance(base, ast.Attribute):
        return base.attr
    return None


def exception_classes(sources: dict[str, str]) -> dict[str, list[str]]:
    """``{module path: [class name, ...]}`` of the classes that derive from an exception: a
    built-in one, one of ``errors.py``, any such class of the sources, or a base named like
    an exception (``...Error``, ``...Exception``) from another library."""
    trees = {path: ast.parse(text, path) for path, text in sources.items()}
    classes = [
        (path, node)
        for path, tree in trees.items()
        for node in ast.walk(tree)
        if isinstance(node, ast.ClassDef)
    ]
    known = set(_BUILTIN_EXCEPTIONS)
    found: dict[str, list[str]] = {}
    changed = True
    while changed:  # a class may derive from one defined further on, or in another module
        changed = False
        for path, node in classes:
            if node.name in found.get(path, []):
                continue
            names = {_base_name(b) for b in node.bases} - {None}
            if any(n in known or n.endswith(("Error", "Exception")) for n in names if n):
                known.add(node.name)
                found.setdefault(path, []).append(node.name)
                changed = True
    return found


def _package_sources() -> dict[str, str]:
    return {
        path.relative_to(PACKAGE).as_posix(): path.read_text(encoding="utf-8")
        for path in sorted(PACKAGE.rglob("*.py"))
    }


def test_every_exception_class_is_defined_in_errors() -> None:
    found = exception_classes(_package_sources())
    elsewhere = {path: names for path, names in found.items() if path != "errors.py"}
    assert {path: elsewhere[path] for path in elsewhere if path not in EXEMPT} == {}
    # The scan sees them: errors.py's classes and the exempt module's.
    assert {"Px4ParamsError", "StoreError", "TagValueError"} <= set(found["errors.py"])
    assert "GcsCodecError" in found["gcs/codec.py"]


@pytest.mark.parametrize(
    "source",
    [
        "class Refused(Exception):\n    pass\n",
        "class Odd(KeyError, dict):\n    pass\n",
        "from px4params.errors import StoreError\nclass Full(StoreError):\n    pass\n",
        "import serial\nclass Gone(serial.SerialException):\n    pass\n",
        "class B(A):\n    pass\nclass A(ValueError):\n    pass\n",
        "def f():\n    class Inner(RuntimeError):\n        pass\n",
    ],
)
def test_the_scan_finds_an_exception_class_planted_outside_errors(source: str) -> None:
    sources = _package_sources()
    sources["store/planted.py"] = source
    assert exception_classes(sources).get("store/planted.py")


def test_the_scan_leaves_other_classes_alone() -> None:
    source = "class Table(dict):\n    pass\nclass View(Table):\n    pass\n"
    assert exception_classes({"store/planted.py": source}) == {}


def test_moved_public_errors_still_import_from_their_modules() -> None:
    from px4params.links import dronecan_client, slcan

    assert slcan.SlcanError is errors.SlcanError
    assert dronecan_client.DronecanError is errors.DronecanError
    assert issubclass(errors.SlcanError, errors.Px4ParamsError)
    assert issubclass(errors.DronecanError, errors.Px4ParamsError)


def test_all_lists_every_public_exception_of_errors() -> None:
    public = {
        name
        for name, value in vars(errors).items()
        if isinstance(value, type)
        and issubclass(value, BaseException)
        and value.__module__ == errors.__name__
        and issubclass(value, errors.Px4ParamsError)
    }
    assert public == set(errors.__all__)
