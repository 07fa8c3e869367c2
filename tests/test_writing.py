"""Every file a command is asked to write goes through the one safe writer
(``px4params.writing``): ``metadata --json/--header/--firmware``, ``migrate -o``,
``health --timeline``, ``autostart run --timeline/--events/--ulog``. Only a regular file is
replaced, or a new one made; a FIFO (which hung the command), a socket or a folder is refused
with one line naming it, left as it was, and no temporary file stays behind."""

from __future__ import annotations

import os
import resource
import signal
import socket
import stat
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
CLI = [sys.executable, "-m", "px4params"]
AIRFRAME = REPO / "examples" / "two_batteries.airframe"
BENCH = REPO / "examples" / "two_batteries.bench.toml"
PARAMS = REPO / "examples" / "two_batteries.params"


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def _socket(path: Path) -> Path:
    with socket.socket(socket.AF_UNIX) as s:
        s.bind(str(path))
    return path


def _directory(path: Path) -> Path:
    path.mkdir()
    return path


def _px4params(tmp: Path, *argv: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp / "cache"))
    env["PX4PARAMS_STORE"] = str(tmp / "vehicle.store")
    # a FIFO opened for writing without a reader blocks: the bound says "does not hang"
    return subprocess.run(
        [*CLI, *argv], capture_output=True, text=True, env=env, cwd=tmp, timeout=120
    )


def _ulog(tmp: Path) -> Path:
    log = tmp / "run.ulg"
    ran = _px4params(
        tmp, "autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(BENCH),
        "--ulog", str(log),
    )  # fmt: skip
    assert log.is_file(), ran.stderr
    return log


#: Each command with its output file as ``{out}``; ``{log}`` is a bench run's ULog.
COMMANDS = {
    "metadata --json": ["metadata", "--json", "{out}"],
    "metadata --header": ["metadata", "--header", "{out}"],
    "metadata --firmware": ["metadata", "--firmware", "{out}"],
    "migrate -o": ["migrate", str(PARAMS), "-o", "{out}"],
    "health --timeline": ["health", "{log}", "--timeline", "{out}"],
    "autostart run --timeline": [
        "autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(BENCH), "--timeline",
        "{out}",
    ],
    "autostart run --events": [
        "autostart", "run", "--airframe", str(AIRFRAME), "--bench", str(BENCH), "--events",
        "{out}",
    ],
}  # fmt: skip


def _argv(command: str, out: Path, tmp: Path) -> list[str]:
    log = str(_ulog(tmp)) if command.startswith("health") else ""
    return [a.format(out=out, log=log) for a in COMMANDS[command]]


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


@pytest.mark.parametrize(
    ("make", "kind"),
    [(_fifo, "a FIFO"), (_socket, "a socket"), (_directory, "a directory")],
    ids=["fifo", "socket", "directory"],
)
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_an_output_that_is_not_a_regular_file_is_refused(
    tmp_path: Path, command: str, make: Callable[[Path], Path], kind: str
) -> None:
    out = tmp_path / "outputs" / "out"
    out.parent.mkdir()
    make(out)
    mode = os.lstat(out).st_mode
    result = _px4params(tmp_path, *_argv(command, out, tmp_path))
    assert result.returncode == 1, result.stdout
    assert result.stderr == f"px4params: error: {out}: cannot write: {kind}, not a regular file\n"
    assert os.lstat(out).st_mode == mode
    assert _leftovers(out.parent) == []


@pytest.mark.parametrize("command", ["migrate -o", "health --timeline", "metadata --header"])
def test_a_regular_file_is_replaced_whole(tmp_path: Path, command: str) -> None:
    out = tmp_path / "outputs" / "out"
    out.parent.mkdir()
    out.write_text("x" * 1_000_000, encoding="utf-8")  # longer than any of the outputs
    os.chmod(out, 0o640)
    result = _px4params(tmp_path, *_argv(command, out, tmp_path))
    assert result.returncode in (0, 1), result.stderr  # health: 1 when the run may not arm
    assert f"wrote {out}" in result.stdout or f"to {out}" in result.stdout, result.stdout
    text = out.read_text(encoding="utf-8")
    assert "x" * 100 not in text and len(text) < 1_000_000
    assert {"migrate -o": "param set", "health --timeline": "<svg"}.get(command, "#") in text
    assert stat.S_IMODE(os.stat(out).st_mode) == 0o640  # the file's mode is kept
    assert _leftovers(out.parent) == []


def test_a_failed_write_leaves_the_old_file_and_no_temporary_file(tmp_path: Path) -> None:
    """A write that fails half way (here the file size limit, ``ulimit -f``: EFBIG) keeps
    the file as it was, and the temporary file is removed."""
    out = tmp_path / "outputs" / "out.svg"
    out.parent.mkdir()
    out.write_text("old", encoding="utf-8")
    log = _ulog(tmp_path)

    def small_files() -> None:  # in the child: no SIGXFSZ, writes past 4 KiB fail
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))

    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp_path / "cache"))
    result = subprocess.run(
        [*CLI, "health", str(log), "--timeline", str(out)],
        capture_output=True, text=True, env=env, timeout=120, preexec_fn=small_files,
    )  # fmt: skip
    assert result.returncode == 1
    assert result.stderr == f"px4params: error: {out}: cannot write: File too large\n"
    assert out.read_text(encoding="utf-8") == "old"
    assert sorted(p.name for p in out.parent.iterdir()) == ["out.svg"]


def _copies(tmp: Path) -> dict[str, Path]:
    """Copies of the inputs a command may be pointed back at (the example files stay as they
    are)."""
    names = {"airframe": AIRFRAME, "bench": BENCH, "params": PARAMS}
    copies = {name: tmp / path.name for name, path in names.items()}
    for name, path in names.items():
        copies[name].write_bytes(path.read_bytes())
    copies["log"] = _ulog(tmp)
    classic = tmp / "classic.json"
    classic.write_text('{"version": 1, "parameters": []}\n')
    copies["classic"] = classic
    return copies


#: An output pointed at an input of the same command, or at another output of it: (argv with
#: {name} for the copies, the path refused as written, what it is).
SAME_FILE = [
    (["migrate", "{params}", "-o", "{params}"], "{params}", "the input file {params}"),
    (["migrate", "{params}", "-o", "./two_batteries.params"], "./two_batteries.params",
     "the input file {params}"),
    (["health", "{log}", "--timeline", "{log}"], "{log}", "the input file {log}"),
    (["autostart", "run", "--airframe", "{airframe}", "--bench", "{bench}", "--events",
      "{bench}"], "{bench}", "the input file {bench}"),
    (["autostart", "run", "--airframe", "{airframe}", "--bench", "{bench}", "--ulog",
      "{airframe}"], "{airframe}", "the input file {airframe}"),
    (["autostart", "run", "--airframe", "{airframe}", "--timeline", "t.svg", "--events",
      "t.svg"], "t.svg", "another output of this command"),
    (["metadata", "--json", "{classic}", "--classic", "{classic}"], "{classic}",
     "the input file {classic}"),
    (["metadata", "--json", "m.json", "--header", "m.json"], "m.json",
     "another output of this command"),
]  # fmt: skip


@pytest.mark.parametrize(("argv", "refused", "what"), SAME_FILE)
def test_an_output_that_is_an_input_or_another_output_is_refused(
    tmp_path: Path, argv: list[str], refused: str, what: str
) -> None:
    # migrate x.params -o x.params replaced the vehicle's file with the airframe, exit 0
    copies = {name: str(path) for name, path in _copies(tmp_path).items()}
    before = {name: Path(path).read_bytes() for name, path in copies.items()}
    result = _px4params(tmp_path, *(a.format(**copies) for a in argv))
    assert result.returncode == 1
    assert result.stderr == (
        f"px4params: error: {refused.format(**copies)}: is {what.format(**copies)}: give the "
        "output another path\n"
    )
    assert {name: Path(path).read_bytes() for name, path in copies.items()} == before
    assert not (tmp_path / "t.svg").exists() and not (tmp_path / "m.json").exists()


def test_metadata_refuses_to_write_over_the_classic_file_the_environment_names(
    tmp_path: Path,
) -> None:
    # --classic X --json X was refused, but X given by $PX4PARAMS_PARAMETERS_JSON was written
    # over with the metadata: PX4's parameters.json lost, every later command failing.
    classic = _copies(tmp_path)["classic"]
    before = classic.read_bytes()
    env = {k: v for k, v in os.environ.items() if not k.startswith("PX4PARAMS_")}
    env["PX4PARAMS_CACHE_DIR"] = os.environ.get("PX4PARAMS_CACHE_DIR", str(tmp_path / "cache"))
    env["PX4PARAMS_PARAMETERS_JSON"] = str(classic)
    result = subprocess.run(
        [*CLI, "metadata", "--json", "classic.json"],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert (result.returncode, result.stderr) == (
        1,
        f"px4params: error: classic.json: is the input file {classic}: give the output another "
        "path\n",
    )
    assert classic.read_bytes() == before


@pytest.mark.parametrize(
    "argv",
    [
        ["migrate", "{params}", "-o", "{store}"],
        ["metadata", "--json", "{store}"],
        ["health", "{log}", "--timeline", "{store}"],
        ["autostart", "run", "--airframe", "{airframe}", "--ulog", "{store}"],
    ],
)
def test_no_report_airframe_or_log_is_written_over_a_store_file(
    tmp_path: Path, argv: list[str]
) -> None:
    # Each replaced an existing store with no backup ('param save' keeps one).
    copies = {name: str(path) for name, path in _copies(tmp_path).items()}
    store = tmp_path / "old.store"
    assert _px4params(tmp_path, "run", copies["airframe"], "--store", str(store)).returncode == 0
    before = store.read_bytes()
    result = _px4params(tmp_path, *(a.format(store=store, **copies) for a in argv))
    assert (result.returncode, result.stderr) == (
        1,
        f"px4params: error: {store}: is a px4params store file: give the output another path "
        "(or move the store first)\n",
    )
    assert store.read_bytes() == before
