"""``px4params examples [DIR]``: the example files ship in the package (``px4params.data``'s
``examples/``), the checkout's ``examples/`` links to them, and the command copies them out
without ever overwriting a different file."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from px4params.cli.commands.examples import DEFAULT_DIR, bundled_examples
from px4params.cli.main import main
from px4params.data import EXAMPLES_DIR
from px4params.formats import qgc_params

REPO = Path(__file__).resolve().parents[1]
EXPECTED = [
    "two_batteries.airframe",
    "two_batteries.bench.toml",
    "two_batteries.params",
    "two_batteries_faults.bench.toml",
]


def run(capsys: pytest.CaptureFixture[str], *words: str) -> tuple[int, str, str]:
    status = main(["examples", *words])
    out, err = capsys.readouterr()
    return status, out, err


def test_the_package_ships_the_examples_the_checkout_links_to() -> None:
    assert bundled_examples() == EXPECTED
    for name in EXPECTED:
        link = REPO / "examples" / name
        assert link.is_symlink(), f"{link}: the checkout's copy must be the package's"
        assert link.resolve() == (Path(EXAMPLES_DIR) / name).resolve()


def test_copies_into_examples_by_default(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    status, out, err = run(capsys)
    assert (status, err) == (0, "")
    assert out.splitlines() == [f"wrote {DEFAULT_DIR}/{name}" for name in EXPECTED]
    for name in EXPECTED:
        assert (tmp_path / "examples" / name).read_bytes() == (
            REPO / "examples" / name
        ).read_bytes()
    # Again: the same files are left alone, and it says so.
    status, out, err = run(capsys)
    assert (status, err) == (0, "")
    assert out.startswith("4 already there with the same content: examples/two_batteries.airframe")


def test_dir_dot_copies_beside(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    assert run(capsys, ".")[0] == 0
    assert sorted(os.listdir(tmp_path)) == EXPECTED


def test_never_overwrites_a_different_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "two_batteries.params").write_text("1\t1\tSYS_AUTOSTART\t1\t6\n")
    status, out, err = run(capsys, str(folder))
    assert (status, out) == (1, "")
    assert err == (
        f"px4params: error: {folder}/two_batteries.params exists and differs from the bundled "
        "example: nothing copied (move it away or choose another DIR)\n"
    )
    assert sorted(os.listdir(folder)) == ["two_batteries.params"]  # nothing else written
    assert (folder / "two_batteries.params").read_text() == "1\t1\tSYS_AUTOSTART\t1\t6\n"


def test_dir_that_is_a_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "examples"
    path.write_text("")
    assert run(capsys, str(path)) == (
        1,
        "",
        f"px4params: error: {path}: exists and is not a folder\n",
    )


def test_dir_that_is_a_dangling_link(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "examples"
    path.symlink_to(tmp_path / "gone")
    assert run(capsys, str(path)) == (
        1,
        "",
        f"px4params: error: {path}: a symbolic link to {tmp_path}/gone, which does not exist "
        "(create that folder or choose another DIR)\n",
    )
    (tmp_path / "gone").mkdir()  # through a link to a folder: copied there
    assert run(capsys, str(path))[0] == 0
    assert sorted(os.listdir(tmp_path / "gone")) == EXPECTED


def test_help_names_every_file(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["examples", "--help"]) == 0
    out = capsys.readouterr().out
    listed = [line.split()[0] for line in out.splitlines() if line.startswith("  two_")]
    assert sorted(listed) == EXPECTED


def test_the_params_file_is_a_qgc_export_of_the_example_vehicle() -> None:
    """Read as QGC writes the format: five TAB-separated columns, floats with 18 decimals; the
    values are those of the airframe (200 A, 0.3 mOhm) and the compass's device ID, 592905 =
    0x090C09: devtype 0x09 (AK09916), address 0x0C, I2C (bus type 1) bus 1."""
    path = REPO / "examples" / "two_batteries.params"
    text = path.read_text()
    rows = {r.name: (r.value, r.type) for r in qgc_params.read(text, str(path))}
    assert rows["SENS_EN_INA238"] == (1, 6)
    assert rows["INA238_CURRENT"] == (200.0, 9)
    assert rows["INA238_SHUNT"][0] == pytest.approx(0.0003, rel=1e-6)
    assert rows["CAL_MAG1_ID"] == (592905, 6)
    assert 592905 == (0x09 << 16) | (0x0C << 8) | (1 << 3) | 1
    data_lines = [line for line in text.splitlines() if line and not line.startswith("#")]
    assert all(line.count("\t") == 4 for line in data_lines)
    assert [line.split("\t")[2] for line in data_lines] == sorted(rows)  # QGC sorts by name
