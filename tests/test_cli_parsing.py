"""The command line's two interpreters (``px4params.cli.parsing``) against each other: whatever
command line the small one accepts, argparse, given the same declaration, reads into the same
namespace; whatever it refuses, argparse parses (help, usage, errors are argparse's own).

Command lines come from the grammar (hypothesis: options, abbreviations, values, ``--``,
negative numbers, ...) and from every ``px4params`` command the README, docs and ``--help``
epilogs show (``tests/test_doc_examples.py`` finds them).
"""

from __future__ import annotations

import contextlib
import io
import shlex
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from px4params.cli import parsing
from px4params.cli.main import COMMANDS, _command_in, declare, main
from strategies import budget
from test_doc_examples import HELP, PAGES, page_examples

REPO = Path(__file__).resolve().parents[1]


def _argparse_reads(parser: parsing.ArgumentParser, argv: list[str]) -> tuple[Any, str]:
    """argparse's namespace of ``argv`` (None when it exits) and what it printed."""
    real = parser.argparse()
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        try:
            return real.parse_args(argv), out.getvalue()
        except SystemExit:
            return None, out.getvalue()


def check(argv: list[str]) -> dict[str, Any] | None:
    """Both interpreters on ``argv``, declared as ``px4params`` declares it; the small one's
    values (None: it left ``argv`` to argparse)."""
    parser = declare(_command_in(argv) or "", argv)
    fast = parsing._parse(parser, argv)
    namespace, printed = _argparse_reads(parser, argv)
    if fast is not None:
        assert namespace is not None, f"{argv}: accepted, but argparse says\n{printed}"
        assert vars(namespace) == fast, argv
    return fast


# -- command lines from the grammar ------------------------------------------------------------

FULL = declare()

#: Words that are values, positionals, or look like options without being ones.
WORDS = [
    *("x", "-", "", "0", "1", "7", "-1", "-1.5", "--", "-x", "--x", "-ax", "1.5", "nan"),
    *("INA238#0", "INA238#0[4]", "INA238#0.bus.i2c.address", "0x45", "a=b", "two words"),
    *("bash", "names", "legacy", "auto", "1000000", "10", "127.0.0.1:14550", "host:99999"),
    *("uavcan.protocol.NodeStatus", "39300000000700", "-h", "--help", "-a-b"),
]


def _paths(parser: parsing.ArgumentParser, path: tuple[str, ...] = ()) -> list[Any]:
    """Every parser of the grammar: the words that pick it and the parsers on the way."""
    found = [(path, [parser])]
    if parser._subparsers is not None:
        for name, child in parser._subparsers.choices.items():
            found += [(p, [parser, *chain]) for p, chain in _paths(child, (*path, name))]
    return found


PATHS = _paths(FULL)


PLAIN = ["x", "-", "", "0", "7", "1.5", "INA238#0", "INA238#0[4]", "0x45", "a=b", "two words"]


def _values(argument: Any) -> st.SearchStrategy[str]:
    """Words for ``argument``: its choices, numbers for a number, else plain words, and now
    and then one that its type refuses or that looks like an option."""
    if argument.choices is not None:
        good = st.sampled_from([str(c) for c in argument.choices])
    elif argument.type in (int, float) or argument.type is not None:
        good = st.sampled_from(["0", "1", "5", "127", "2.5", "127.0.0.1:14550"])
    else:
        good = st.sampled_from(PLAIN)
    return st.one_of(good, good, good, st.sampled_from(WORDS))


@st.composite
def _level(draw: st.DrawFn, parser: Any, leaf: bool) -> list[list[str]]:
    """Well-formed pieces of one parser's part of a command line: each option with its value,
    and (for the last parser) each positional word."""
    pieces: list[list[str]] = []
    options = sorted({id(a): a for a in parser._options.values() if a.action != "help"}.items())
    for _, argument in options:
        if draw(st.integers(0, 3)):
            continue
        name = draw(st.sampled_from(argument.option_strings))
        if not argument.takes_value:
            pieces.append([name])
        elif name.startswith("--") and draw(st.booleans()):
            pieces.append([f"{name}={draw(_values(argument))}"])
        else:
            pieces.append([name, draw(_values(argument))])
    if leaf:
        for argument in parser._positionals:
            count = {None: 1, "?": draw(st.integers(0, 1))}.get(
                argument.nargs, draw(st.integers(argument.nargs == "+", 3))
            )
            pieces += [[draw(_values(argument))] for _ in range(count)]
    return pieces


@st.composite
def command_lines(draw: st.DrawFn) -> list[str]:
    """Command lines of the grammar: well-formed ones (options in any order, between the
    positionals), then now and then a word added, dropped or changed."""
    path, chain = draw(st.sampled_from(PATHS))
    argv: list[str] = []
    for level, parser in enumerate(chain):
        leaf = level == len(path)
        pieces = draw(_level(parser, leaf))
        if leaf:
            pieces = draw(st.permutations(pieces))
        argv += [word for piece in pieces for word in piece]
        if not leaf:
            argv.append(path[level])
    for _ in range(draw(st.integers(0, 2)) if draw(st.booleans()) else 0):
        options = sorted(chain[-1]._options) or ["--x"]
        longs = [o for o in options if o.startswith("--")] or ["--x"]
        shorts = [o[1] for o in options if len(o) == 2] or ["x"]
        word = draw(
            st.one_of(
                st.sampled_from(options),
                st.sampled_from(WORDS),
                st.sampled_from(list(COMMANDS)),
                st.builds(lambda o, n: o[:n], st.sampled_from(longs), st.integers(3, 8)),
                st.builds(
                    lambda a, b: f"-{a}{b}", st.sampled_from(shorts), st.sampled_from(shorts)
                ),
            )
        )
        at = draw(st.integers(0, len(argv)))
        change = draw(st.sampled_from(["add", "drop", "replace"]))
        if change == "add" or not argv or at == len(argv):
            argv.insert(at, word)
        elif change == "drop":
            del argv[at]
        else:
            argv[at] = word
    return argv


@settings(max_examples=budget(400), deadline=None)
@given(command_lines())
@example(["param", "show", "A", "-a", "B"])  # positionals split by an option: argparse errs
@example(["param", "compare", "N", "V", "-s", "W"])
@example(["param", "--dsdl", "x", "--classic=--", "add", "x"])  # argparse: classic=[]
def test_what_the_small_interpreter_accepts_argparse_reads_alike(argv: list[str]) -> None:
    check(argv)


# -- the command lines users read --------------------------------------------------------------


def _documented() -> list[list[str]]:
    """The ``px4params`` command lines of the pages and the epilogs (each command of a shell
    line, without its redirections)."""
    lines = [e.command for page in PAGES for e in page_examples(page)[0]]
    lines += [e.command for _, examples in HELP for e in examples]
    found = []
    for line in lines:
        lexer = shlex.shlex(_without_comment(line), posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        lexer.commenters = ""
        words: list[str] = []
        for token in [*lexer, ";"]:
            if token and set(token) <= set("|&;<>()"):
                if words[:1] == ["px4params"]:
                    found.append(words[1:])
                words = []
            elif not (words and words[-1] in (">", "2>")):
                words.append(token)
    return found


def _without_comment(line: str) -> str:
    """``line`` up to its shell comment (a ``#`` that starts a word: ``INA238#2`` has none)."""
    quote = ""
    for i, char in enumerate(line):
        if quote:
            quote = "" if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i]
    return line


DOCUMENTED = _documented()


def test_documented_command_lines_are_found() -> None:
    assert len(DOCUMENTED) >= 60
    assert ["param", "show", "-l", "INA238#2"] in DOCUMENTED


@pytest.mark.parametrize("argv", DOCUMENTED, ids=" ".join)
def test_documented_command_lines(argv: list[str]) -> None:
    check(argv)


def test_the_everyday_command_lines_need_no_argparse() -> None:
    everyday = [
        ["param", "show"],
        ["param", "show", "-l", "INA238#0"],
        ["param", "--store", "v.store", "show", "-c", "--json", "INA*"],
        ["param", "set", "INA238#0[4]", "0x45"],
        ["param", "set-default", "-s", "INA238#0[6]", "0.0003"],
        ["param", "compare", "INA238#0.current", "200", "100"],
        ["decode", "uavcan.protocol.NodeStatus", "39300000000700"],
        ["decode", "--dsdl", "a", "--dsdl=b", "T", "--no-tao", "-"],
        ["encode", "px.Ina238", '{"current": 200}', "--defaults"],
        ["run", "examples/two_batteries.airframe", "--store", "v.store"],
        ["autostart", "plan", "--store", "v.store", "--json"],
        ["autostart", "run", "--airframe", "a", "--bench", "b", "--seed", "3"],
        ["dronecan", "serve", "--slcan-pty", "--node-id", "5", "--bitrate", "500000"],
        ["devid", "0x24010a", "--table", "legacy"],
    ]
    for argv in everyday:
        assert check(argv) is not None, argv
    assert check(["param", "show"]) == {
        "command": "param",
        "func": check(["param", "show"])["func"],  # type: ignore[index]
        "store": None,
        "classic": None,
        "dsdl": None,
        "verb_name": "show",
        "verb": check(["param", "show"])["verb"],  # type: ignore[index]
        "all": False,
        "changed": False,
        "quiet": False,
        "leaves": False,
        "json": False,
        "filters": [],
    }


def test_what_argparse_decides_goes_to_argparse() -> None:
    for argv in (
        [],
        ["--help"],
        ["param", "show", "-h"],
        ["param", "show", "--js"],  # an abbreviation (of --json)
        ["param", "show", "-ac"],  # combined flags
        ["param", "set", "X", "-1"],  # a negative number
        ["param", "show", "--", "-a"],
        ["param", "set", "X"],  # missing
        ["param", "bogus"],
        ["completion", "zsh"],  # not a choice
        ["dronecan", "serve", "--slcan-pty", "--node-id", "0"],  # the type refuses it
        ["dronecan", "serve", "--slcan-pty", "--slcan", "x"],  # exclusive
        ["dronecan", "serve", "--node-id", "3"],  # one of an exclusive group is required
        ["mavlink", "serve"],  # a required option
        ["decode", "--no-tao=1", "T", "H"],
        ["decode", "T", "H", "extra"],
    ):
        assert check(argv) is None, argv


# -- argparse's messages -------------------------------------------------------------------------


def _cli(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            status = main(argv)
        except SystemExit as e:
            status = int(e.code or 0)
    return status, err.getvalue()


def test_usage_errors_are_argparses() -> None:
    status, err = _cli(["param", "set", "X"])
    assert status == 2
    assert err.startswith(
        "usage: px4params param set [-h] [--store FILE] [--classic JSON] [--dsdl DIR]\n"
        "                           [--force]\n"
        "                           name value [fail]\n"
    )
    assert err.endswith("error: the following arguments are required: value\n")
    status, err = _cli(["dronecan", "serve", "--slcan-pty", "--node-id", "0"])
    assert status == 2
    assert "argument --node-id: '0' is not a DroneCAN node ID (expected 1..127)" in err
    for argv in (["param", "show", "--bogus"], ["decode", "T"], ["bogus"], []):
        parser = declare(_command_in(argv) or "", argv)
        assert _cli(argv) == (2, _argparse_reads(parser, argv)[1]), argv


def test_a_commands_own_usage_error_is_argparses(tmp_path: Path) -> None:
    """``parser.error()`` of a recorded parser (``devid``, ``metadata``, ...) is argparse's, with
    the usage of that parser."""
    status, err = _cli(["devid"])
    assert status == 2
    assert err.startswith("usage: px4params devid [-h]")
    assert err.endswith(
        "px4params devid: error: give device IDs, or one of --encode, --log FILE, --list\n"
    )


def test_help_is_argparses() -> None:
    for argv in (["--help"], ["param", "--help"], ["param", "show", "-h"], ["autostart", "-h"]):
        parser = declare(_command_in(argv) or "", argv)
        out = io.StringIO()
        with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
            parser.parse_args(argv)
        assert out.getvalue() == _argparse_reads(parser, argv)[1]
        assert out.getvalue().startswith(" ".join(["usage: px4params", *argv[:-1], "[-h]"]))


def test_the_namespace_is_argparses_alike() -> None:
    a, b = parsing.Namespace(x=1, y=[2]), parsing.Namespace(x=1, y=[2])
    assert a == b and "x" in a and "z" not in a and repr(a) == "Namespace(x=1, y=[2])"
    assert a != parsing.Namespace(x=1) and a != object()


def test_short_commands_import_neither_argparse_nor_re(tmp_path: Path) -> None:
    """argparse (and ``re``, ``gettext``, ``locale`` with it) costs a short command about as much
    as Python's start: the everyday command lines run without it (the DSDL model cached)."""
    store = tmp_path / "v.store"
    airframe = REPO / "examples" / "two_batteries.airframe"
    run = [sys.executable, "-m", "px4params"]
    subprocess.run(
        [*run, "run", str(airframe), "--store", str(store)], check=True, capture_output=True
    )
    for command in (
        ["param", "--store", str(store), "show"],
        ["param", "--store", str(store), "show", "-l", "INA238#0"],
        ["decode", "uavcan.protocol.NodeStatus", "39300000000700"],
    ):
        code = (
            "import sys; from px4params.cli.main import main; status = main(sys.argv[1:]); "
            "assert not {'argparse', 're', 'json'} & set(sys.modules), sorted(sys.modules); "
            "sys.exit(status)"
        )
        subprocess.run([*run, *command], check=True, capture_output=True)  # the model cached
        out = subprocess.run([sys.executable, "-c", code, *command], capture_output=True, text=True)
        assert out.returncode == 0, (command, out.stderr[-3000:])
