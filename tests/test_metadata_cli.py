"""``px4params metadata``: parameters.json and the C header from the command line."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import px4params
import pytest
from metadata_support import real_parameters_json, write_tst
from px4params.cli.main import main
from px4params.gcs.cheader import generate_header
from px4params.gcs.metadata import build_parameters_json
from px4params.store import flat
from px4params.store.classic import CLASSIC_ENV
from px4params.store.spec import parameter_specs

SCHEMA = px4params.load_schema(use_env=False)
PARAMS = [s.name for s in parameter_specs(SCHEMA)]
#: Destructured names: every letter of every instance slot.
FLAT = sum(
    len(flat.layout(s.data_type)) * s.slots + (0 if s.shared else 1)  # + the instance mask
    for s in parameter_specs(SCHEMA)
)


@pytest.fixture(autouse=True)
def _clean_env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(CLASSIC_ENV, raising=False)
    monkeypatch.delenv("PX4PARAMS_DSDL_PATH", raising=False)


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    try:
        code = main(list(argv))
    except SystemExit as e:  # argparse usage errors
        code = int(e.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


def small_classic(path: Path, *names: str) -> Path:
    entries = [{"name": n, "type": "Int32", "default": 1, "group": "G"} for n in names]
    path.write_text(json.dumps({"version": 1, "parameters": entries}), encoding="utf-8")
    return path


def test_json_without_classic_parameters(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    target = tmp_path / "parameters.json"
    code, out, err = run(capsys, "metadata", "--json", str(target))
    assert (code, err) == (0, "")
    assert out == (
        f"wrote {target}: {len(PARAMS)} structured ({FLAT} destructured names) + 0 classic "
        "parameters\n"
    )
    document = json.loads(target.read_text(encoding="utf-8"))
    assert document == build_parameters_json(SCHEMA)
    assert [e["name"] for e in document["parameters"]][: len(PARAMS)] == PARAMS


def test_json_with_the_real_classic_parameters(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    real = real_parameters_json()
    target = tmp_path / "parameters.json"
    code, out, _ = run(capsys, "metadata", "--json", str(target), "--classic", str(real))
    assert code == 0
    classic = len(json.loads(real.read_text(encoding="utf-8"))["parameters"])
    assert out == (
        f"wrote {target}: {len(PARAMS)} structured ({FLAT} destructured names) + {classic} "
        "classic parameters\n"
    )
    assert json.loads(target.read_text(encoding="utf-8")) == build_parameters_json(SCHEMA, real)


def test_classic_parameters_from_the_environment(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(CLASSIC_ENV, str(small_classic(tmp_path / "env.json", "FROM_ENV")))
    code, out, _ = run(capsys, "metadata", "--json", "-")
    assert code == 0
    names = [e["name"] for e in json.loads(out)["parameters"]]
    assert names[: len(PARAMS) + 1] == ["FROM_ENV", *PARAMS]
    assert len(names) == 1 + len(PARAMS) + FLAT
    # --classic wins over the environment.
    given = small_classic(tmp_path / "given.json", "GIVEN_A", "GIVEN_B")
    code, out, _ = run(capsys, "metadata", "--json", "-", "--classic", str(given))
    assert [e["name"] for e in json.loads(out)["parameters"]][:3] == [
        "GIVEN_A",
        "GIVEN_B",
        PARAMS[0],
    ]


def test_header(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    target = tmp_path / "px4_params.h"
    code, out, _ = run(capsys, "metadata", "--header", str(target))
    assert code == 0
    assert out == f"wrote {target}: C header for {len(PARAMS)} parameters\n"
    expected = generate_header(SCHEMA, parameter_specs(SCHEMA), guard="PX4_PARAMS_H")
    assert target.read_text(encoding="utf-8") == expected


def test_both_and_stdout(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    code, out, _ = run(capsys, "metadata", "--json", str(tmp_path / "p.json"), "--header", "-")
    assert code == 0
    # stdout is the header alone: no "wrote" line mixed in.
    assert out == generate_header(SCHEMA, parameter_specs(SCHEMA))
    assert json.loads((tmp_path / "p.json").read_text(encoding="utf-8")) == (
        build_parameters_json(SCHEMA)
    )


def test_extra_dsdl_folders(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    root = write_tst(tmp_path)
    code, out, _ = run(capsys, "metadata", "--json", "-", "--dsdl", str(root))
    assert code == 0
    entry = next(e for e in json.loads(out)["parameters"] if e["name"] == "EVERYTHING_SH")
    assert entry["max_instances"] is None and entry["dsdl_type"] == "tst.Everything.1.0"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([], "give --json FILE, --header FILE, --firmware FILE.c, or several"),
        (
            ["--json", "-", "--header", "-"],
            "only one of --json, --header and --firmware can write to stdout (-)",
        ),
        (
            ["--header", "-", "--firmware", "-"],
            "only one of --json, --header and --firmware can write to stdout (-)",
        ),
        (
            ["--header", "x.h", "--classic", "p.json"],
            "--classic goes with --json (the header has no classic parameters)",
        ),
    ],
)
def test_usage_errors(
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    argv: list[str],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "metadata", *argv)
    assert code == 2 and out == ""
    assert err.splitlines()[-1] == f"px4params metadata: error: {message}"
    assert list(tmp_path.iterdir()) == []


def test_failures_write_nothing(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    header = tmp_path / "px4_params.h"
    missing = tmp_path / "missing.json"
    code, out, err = run(
        capsys, "metadata", "--header", str(header), "--json", "-", "--classic", str(missing)
    )
    assert (code, out) == (1, "")
    assert err == f"px4params: error: {missing}: cannot read: No such file or directory\n"
    assert not header.exists()


@pytest.mark.parametrize(
    ("setup", "message"),
    [
        ("clash", "parameter INA238 is both structured ({key}) and classic (in {classic})"),
        ("notjson", "{classic}: not JSON: Expecting value: line 1 column 1 (char 0)"),
        ("unwritable", "{target}: cannot write: No such file or directory"),
    ],
)
def test_failures(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, setup: str, message: str
) -> None:
    classic = tmp_path / "classic.json"
    target = tmp_path / "out.json"
    if setup == "clash":
        small_classic(classic, "INA238")
    elif setup == "notjson":
        classic.write_text("", encoding="utf-8")
    else:
        small_classic(classic, "X_ONE")
        target = tmp_path / "no" / "such" / "dir" / "out.json"
    code, out, err = run(capsys, "metadata", "--json", str(target), "--classic", str(classic))
    assert (code, out) == (1, "")
    expected = message.format(key=SCHEMA["px.Ina238"].key, classic=classic, target=target)
    assert err == f"px4params: error: {expected}\n"


def test_help_has_an_example(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "metadata", "--help")
    assert code == 0
    assert "example:\n  px4params metadata --json parameters.json --header" in out
    assert "$PX4PARAMS_PARAMETERS_JSON" in out and "--header FILE" in out
    code, out, _ = run(capsys, "--help")
    assert "metadata" in out


def test_no_traceback_from_the_real_command(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != CLASSIC_ENV}
    proc = subprocess.run(
        [sys.executable, "-m", "px4params", "metadata", "--json", "-", "--classic", "nope.json"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 1 and proc.stdout == ""
    assert proc.stderr == "px4params: error: nope.json: cannot read: No such file or directory\n"
