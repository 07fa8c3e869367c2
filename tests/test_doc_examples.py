"""Every command example users read runs and succeeds: the ```sh blocks of README.md and docs/,
and the examples in every ``--help`` epilog. Documentation that rots fails here.

Conventions for whoever writes a page or a help text:

- Every non-comment line of a ```sh block is a command; a line ending in ``\\`` continues on
  the next. A page's blocks run in order, in one scratch folder per page with nothing beside
  it, as a user who installed the wheel has it (``px4params`` on PATH): a page that uses
  ``examples/`` runs ``px4params examples`` first, and no page reads ``../shared/data``
  (except those in ``READS_SHARED_DATA``, until their data is in the package).
- Each page writes its own store files (``airframe.store``, ``autostart.store``, ...), so that
  a reader who follows two pages in one folder does not run an airframe twice on one store.
- A command expected to fail says so in its comment: ``# ... exit status N``.
- ``<!-- examples: skip (REASON) -->`` on the line before a block skips that block.
- Commands that set up the checkout itself (``bash scripts/...``, ``source .venv/...``) are not
  run: the test suite is already running inside what they set up.
- ``--help`` examples run in a scratch folder holding the example files (``px4params
  examples``), the example airframe's store (as
  ``px4params.store`` and ``vehicle.store``), a QGC export of it (``vehicle.params``), a copy
  (``backup.store``) and the shared sample log as ``flight.ulg`` / ``old.ulg``.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from shared_data import CURRENT_TSV, PARAMETERS_JSON, SAMPLE_LOG, SHARED_DATA, shared_file

REPO = Path(__file__).resolve().parents[1]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
SKIP_MARK = re.compile(r"<!--\s*examples:\s*skip\s*\((?P<reason>[^)]*)\)\s*-->")
EXIT_STATUS = re.compile(r"#.*\bexit status (?P<status>\d+)")
SETUP_COMMANDS = ("bash scripts/", "source .venv/", ". .venv/", "git clone", "cd ")
#: --help examples that cannot run in a test, and why.
HELP_EXCEPTIONS = {
    "px4params mavlink serve": "a server: it runs until stopped (tests/test_mavlink.py runs it)",
    "px4params gui": "a server: it runs until stopped (tests/test_gui.py runs it)",
    "px4params dronecan serve": "a server: it runs until stopped (tests/test_dronecan.py runs it)",
    "px4params dronecan param": (
        "needs a DroneCAN node on an SLCAN line (tests/test_dronecan.py runs it against one)"
    ),
}
TIMEOUT = 120
#: Pages whose examples still read ../shared/data, and why (the rest may not): they run as in
#: the checkout, with ``examples/`` and ``../shared`` beside them.
#: Pages whose examples may read ../shared/data (none: a user has no such folder).
READS_SHARED_DATA: dict[str, str] = {}


class Example:
    """One command of a page or an epilog, where it was written, and the exit status it
    expects."""

    def __init__(self, where: str, command: str) -> None:
        self.where = where
        self.command = command
        match = EXIT_STATUS.search(command)
        self.status = int(match["status"]) if match else 0

    def __repr__(self) -> str:
        return f"{self.where}: {self.command}"


def _commands(lines: list[tuple[int, str]], source: str) -> list[Example]:
    """The commands of a block's ``(line number, text)`` lines, continuations joined."""
    examples: list[Example] = []
    pending = ""
    first = 0
    for number, text in lines:
        stripped = text.strip()
        if not pending and (not stripped or stripped.startswith("#")):
            continue
        if not pending:
            first = number
        if stripped.endswith("\\"):
            pending += stripped[:-1] + " "
            continue
        examples.append(Example(f"{source}:{first}", pending + stripped))
        pending = ""
    assert not pending, f"{source}:{first}: a continued command never ends"
    return examples


def page_examples(page: Path) -> tuple[list[Example], list[str]]:
    """The runnable commands of a page, and the skipped blocks with their reasons."""
    lines = page.read_text(encoding="utf-8").splitlines()
    examples: list[Example] = []
    skipped: list[str] = []
    source = page.relative_to(REPO).as_posix()
    i = 0
    previous = ""
    while i < len(lines):
        line = lines[i]
        if line.strip() in ("```sh", "```bash", "```shell"):
            start = i + 1
            end = start
            while end < len(lines) and lines[end].strip() != "```":
                end += 1
            block = [(n + 1, lines[n]) for n in range(start, end)]
            mark = SKIP_MARK.search(previous)
            if mark:
                skipped.append(f"{source}:{start}: {mark['reason']}")
            else:
                examples += [
                    e for e in _commands(block, source) if not e.command.startswith(SETUP_COMMANDS)
                ]
            i = end + 1
            previous = ""
            continue
        if line.strip():
            previous = line
        i += 1
    return examples, skipped


def help_examples() -> list[tuple[str, list[Example]]]:
    """Each parser with an epilog and the ``px4params`` commands in it."""
    from px4params.cli.main import build_parser

    found: list[tuple[str, list[Example]]] = []

    def walk(parser: argparse.ArgumentParser, path: str) -> None:
        if parser.epilog:
            lines = [(n, t) for n, t in enumerate(parser.epilog.splitlines(), start=1)]
            # Only the command lines (and their continuations); output lines are not run.
            picked: list[tuple[int, str]] = []
            continuing = False
            for number, text in lines:
                if text.strip().startswith("px4params ") or continuing:
                    picked.append((number, text))
                    continuing = text.rstrip().endswith("\\")
            examples = _commands(picked, f"{path} --help")
            if examples:
                found.append((path, examples))
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, f"{path} {name}")

    walk(build_parser(), "px4params")
    return found


def _scratch(tmp_path: Path, shared: bool = False) -> Path:
    """``tmp/work``, empty; with ``shared``, ``../shared`` as in the checkout."""
    work = tmp_path / "work"
    work.mkdir()
    if shared and SHARED_DATA.is_dir():
        (tmp_path / "shared").symlink_to(SHARED_DATA.parent)
    return work


def _env() -> dict[str, str]:
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith("PX4PARAMS_") or k in ("PX4PARAMS_CACHE_DIR", "PX4PARAMS_SHARED_DATA")
    }
    env["PATH"] = os.path.dirname(sys.executable) + os.pathsep + env.get("PATH", "")
    return env


def _run(example: Example, cwd: Path, env: dict[str, str]) -> None:
    try:
        proc = subprocess.run(
            ["bash", "-c", example.command],
            cwd=cwd,
            env=env,
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
            stdin=subprocess.DEVNULL,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"{example}: still running after {TIMEOUT} s")
    assert proc.returncode == example.status, (
        f"{example}: exit status {proc.returncode}, expected {example.status}\n"
        f"stdout: {proc.stdout[-2000:]}\nstderr: {proc.stderr[-2000:]}"
    )
    assert "Traceback" not in proc.stderr, f"{example}: {proc.stderr}"


def _needs_shared(examples: list[Example]) -> bool:
    return any("../shared/" in e.command for e in examples)


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(REPO).as_posix())
def test_page_examples_run(page: Path, tmp_path: Path) -> None:
    examples, _skipped = page_examples(page)
    if not examples:
        pytest.skip(f"{page.name} has no command examples")
    if _needs_shared(examples) and not (SHARED_DATA / SAMPLE_LOG).is_file():
        pytest.skip(f"{page.name} uses ../shared/data, absent here ({SHARED_DATA})")
    source = page.relative_to(REPO).as_posix()
    work = _scratch(tmp_path, shared=source in READS_SHARED_DATA)
    if source in READS_SHARED_DATA:
        (work / "examples").symlink_to(REPO / "examples")
    env = _env()
    for example in examples:
        _run(example, work, env)


def test_pages_read_no_shared_data() -> None:
    for page in PAGES:
        source = page.relative_to(REPO).as_posix()
        if source not in READS_SHARED_DATA:
            assert not _needs_shared(page_examples(page)[0]), f"{source} reads ../shared"


def _stores_written(examples: list[Example]) -> set[str]:
    """The store files a page's commands name with ``--store``."""
    return {m[1] for e in examples for m in re.finditer(r"--store[ =](\S+)", e.command)}


def test_pages_write_their_own_stores() -> None:
    # A reader following two pages in one folder would run the example airframe twice on one
    # store ("INA238#0: instance exists already"): each page names its own.
    owner: dict[str, str] = {}
    for page in PAGES:
        source = page.relative_to(REPO).as_posix()
        for store in _stores_written(page_examples(page)[0]):
            assert owner.setdefault(store, source) == source, (
                f"{store} is written by {owner[store]} and {source}"
            )
    assert owner["vehicle.store"] == "README.md" and owner["airframe.store"] == "docs/airframes.md"


def test_skipped_blocks_give_a_reason() -> None:
    for page in PAGES:
        _examples, skipped = page_examples(page)
        for entry in skipped:
            assert entry.split(": ", 1)[1].strip(), f"{entry}: a skip needs its reason"


def test_readme_and_docs_have_examples() -> None:
    # The extraction itself is tested: a page without its fences parsed would pass vacuously.
    counts = {page.name: len(page_examples(page)[0]) for page in PAGES}
    assert counts["README.md"] >= 3
    assert sum(counts.values()) >= 60, counts


def _prepare_help_scratch(tmp_path: Path, env: dict[str, str], examples: list[Example]) -> Path:
    work = _scratch(tmp_path, shared=True)
    airframe = "examples/two_batteries.airframe"
    commands = [
        "px4params examples",
        f"px4params run {airframe}",
        "px4params param export vehicle.params",
        "cp px4params.store backup.store",
    ]
    # vehicle.store too, unless the examples write it themselves with 'px4params run'.
    if not any(e.command.startswith("px4params run ") for e in examples):
        commands.append("cp px4params.store vehicle.store")
    for command in commands:
        subprocess.run(["bash", "-c", command], cwd=work, env=env, check=True, capture_output=True)
    log = SHARED_DATA / SAMPLE_LOG
    if log.is_file():
        for name in ("flight.ulg", "old.ulg"):
            shutil.copy(log, work / name)
    return work


HELP = help_examples()


@pytest.mark.parametrize("parser, examples", HELP, ids=[path for path, _ in HELP])
def test_help_examples_run(parser: str, examples: list[Example], tmp_path: Path) -> None:
    env = _env()
    work = _prepare_help_scratch(tmp_path, env, examples)
    needing = [e for e in examples if _needs_shared_data(e.command)]
    if needing and not (SHARED_DATA / CURRENT_TSV).is_file():
        # the later examples of an epilog may use what these make: run them all or none
        pytest.skip(f"{parser}: {len(needing)} examples need {SHARED_DATA}, absent here")
    ran = 0
    for example in examples:
        if any(example.command.startswith(prefix) for prefix in HELP_EXCEPTIONS):
            continue
        _run(example, work, env)
        ran += 1
    if not ran:
        first = examples[0].command
        why = next(why for prefix, why in HELP_EXCEPTIONS.items() if first.startswith(prefix))
        pytest.skip(f"{parser}: {why}")


def _needs_shared_data(command: str) -> bool:
    """A flight log, or today's devtype table (the default of devid and migrate, which
    px4params does not ship)."""
    uses_table = command.startswith(("px4params devid", "px4params migrate"))
    current_table = uses_table and "--table legacy" not in command
    return ".ulg" in command or "../shared/" in command or current_table


def test_help_examples_are_found() -> None:
    commands = [e.command for _, examples in HELP for e in examples]
    assert any(c.startswith("px4params param show") for c in commands)
    # Continuation lines are joined into one command.
    assert any(
        "--timeline run.svg" in c and c.startswith("px4params autostart run") for c in commands
    )
    assert len(HELP) >= 30


def test_help_text_is_plain_text() -> None:
    """No reStructuredText markup (``x``, :mod:, ...) in any help text users see."""
    from px4params.cli.main import build_parser

    def texts(parser: argparse.ArgumentParser) -> list[str]:
        out = [parser.description or "", parser.epilog or "", parser.format_help()]
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    out += texts(sub)
        return out

    for text in texts(build_parser()):
        assert "``" not in text and ":mod:" not in text and ":func:" not in text, text[:300]


def test_store_page_classic_example_with_px4s_parameters_json(tmp_path: Path) -> None:
    """The page's skipped block on classic parameters, with a real PX4 ``parameters.json``
    (a reader has one from a PX4 build; px4params does not ship it)."""
    shared = shared_file(PARAMETERS_JSON)
    work = _scratch(tmp_path)
    shutil.copy(shared, work / "px4_parameters.json")
    text = (REPO / "docs" / "store.md").read_text(encoding="utf-8")
    block = text[text.index("## Classic parameters") :].split("```sh\n", 1)[1].split("```", 1)[0]
    lines = [(n, t) for n, t in enumerate(block.splitlines(), start=1)]
    examples = _commands(lines, "docs/store.md (classic parameters)")
    assert [e.command.split()[-2:] for e in examples] == [["MPC_XY_VEL_MAX", "8"], ["show", "-c"]]
    env = _env()
    for example in examples:
        _run(example, work, env)
    shown = subprocess.run(
        ["bash", "-c", examples[-1].command], cwd=work, env=env, capture_output=True, text=True
    ).stdout
    assert "+ MPC_XY_VEL_MAX [-1,1040] : 8" in shown  # as the page shows it
