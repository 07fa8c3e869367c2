"""Small frictions a new user met (issue 38): a failed all-or-nothing run prints nothing on
stdout; reading a store that does not exist leaves no lock file; ``--store`` is taken after the
verb too; counts of one are singular."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest
from px4params.cli.main import build_parser, main

REPO = Path(__file__).resolve().parents[1]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"


def run(capsys: pytest.CaptureFixture[str], *words: str) -> tuple[int, str, str]:
    status = main(list(words))
    out, err = capsys.readouterr()
    return status, out, err


def test_a_failed_run_prints_only_its_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    airframe = tmp_path / "bad.airframe"
    airframe.write_text("param add INA238#0\nparam add INA238#1\nparam add BOGUS#0\n")
    store = tmp_path / "v.store"
    status, out, err = run(capsys, "run", str(airframe), "--store", str(store))
    # Nothing of the file is kept, so nothing of it is shown as done.
    assert (status, out) == (1, "")
    assert err == f"px4params: {airframe}:3: unknown parameter 'BOGUS'\n"
    assert not store.exists()
    # With --keep-going the lines that succeeded are kept: they are shown.
    status, out, err = run(capsys, "run", str(airframe), "--store", str(store), "--keep-going")
    assert (status, out) == (1, "INA238#0\nINA238#1\n")
    assert store.exists()


def test_a_run_that_succeeds_prints_what_its_lines_print(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(capsys, "run", str(AIRFRAME), "--store", str(tmp_path / "v.store"))
    assert (status, out, err) == (0, "INA238#0\nINA238#1\nAK09916#0\n", "")


@pytest.mark.parametrize(
    "verb",
    [
        ["show"],
        ["show", "-c"],
        ["status"],
        ["flat"],
        ["find", "INA"],
        ["instances", "INA238"],
        ["compare", "SYS_AUTOSTART", "0"],
    ],
)
def test_reading_a_store_that_does_not_exist_leaves_no_file(
    verb: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    main(["param", *verb])
    capsys.readouterr()
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_writing_verbs_still_lock(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("PX4PARAMS_STORE", raising=False)
    assert run(capsys, "param", "add", "INA238#0")[0] == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["px4params.store", "px4params.store.lock"]


def test_store_after_the_verb(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = str(tmp_path / "v.store")
    assert run(capsys, "run", str(AIRFRAME), "--store", store)[0] == 0
    before = run(capsys, "param", "--store", store, "show", "-l", "INA238#0")
    after = run(capsys, "param", "show", "-l", "INA238#0", "--store", store)
    assert before == after and before[1].startswith("[0] p_version")
    # after the verb it wins over the one before it
    assert run(capsys, "param", "--store", "other.store", "show", "--store", store) == run(
        capsys, "param", "show", "--store", store
    )
    assert run(capsys, "param", "set", "INA238#0.current", "150", "--store", store)[0] == 0
    assert run(capsys, "param", "--store", store, "show", "-q", "INA238#0.current")[1] == "150\n"


def _leaves(
    parser: argparse.ArgumentParser, path: str, above: set[str]
) -> list[tuple[str, set[str], set[str]]]:
    """Every command line's last parser, the options its parents take and its own."""
    own = {o for a in parser._actions for o in a.option_strings}
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        return [(path, above, own)]
    found = []
    for name, sub in subs[0].choices.items():
        found += _leaves(sub, f"{path} {name}", above | own)
    return found


def test_every_command_takes_its_store_options_after_the_verb() -> None:
    leaves = _leaves(build_parser(), "px4params", set())
    checked = 0
    for path, above, own in leaves:
        for option in ("--store", "--classic", "--dsdl"):
            if option in above:
                assert option in own, f"{path}: {option} only before the verb"
                checked += 1
        if "--store" in above | own:
            checked += 1
    assert checked > 20  # param's verbs, run, autostart plan and run, gui, servers ...


def test_counts_of_one_are_singular(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = tmp_path / "run.ulg"
    faults = REPO / "examples" / "two_batteries_faults.bench.toml"
    argv = ["autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(faults)]
    assert run(capsys, *argv, "--ulog", str(log))[0] == 1
    story = run(capsys, "health", str(log))[1]
    # INA238#1 is lost once: one reset, which the story counts as one timeout
    assert ", 1 timeout, " in story and "1 timeouts" not in story
    migrated = tmp_path / "legacy.airframe"
    params = REPO / "examples" / "two_batteries.params"
    status, out, _ = run(capsys, "migrate", "--table", "legacy", str(params), "-o", str(migrated))
    assert status == 0
    # the legacy table does not know the AK09916 (devtype 0x09): INA238#0 alone
    assert out.endswith(f"\nwrote {migrated}: 1 instance\n")
