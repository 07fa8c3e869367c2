"""``px4params run FILE``: airframe and startup files of ``param`` lines, as PX4 runs them.

What a file may hold, line by line:

- ``param VERB ...``: any verb of ``px4params param`` (the talk's five lines work verbatim);
- ``set VAR value`` and ``$VAR`` / ``${VAR}`` in later lines;
- ``if param compare|greater ...`` / ``then`` / ``else`` / ``fi`` blocks (nestable);
- ``echo ...``; comments (``#`` at the start of a line) and blank lines.

A failing line is reported as ``FILE:LINE: message`` and stops the run; nothing of the file is
kept (all or nothing: the store file is written once, when every line succeeded). With
``keep_going`` every failing line is reported, the lines that succeeded are kept and saved, and
the run still fails.
"""

from __future__ import annotations

import argparse
import os
import re
from dataclasses import dataclass, field
from typing import NoReturn, TextIO

from px4params.errors import CommandError, NshArgumentError, Px4ParamsError
from px4params.nsh import param
from px4params.numbers import abbreviated
from px4params.reading import AIRFRAME, not_text, read_text
from px4params.status import EXIT_OK
from px4params.store.session import Session

_VAR = re.compile(r"\$(?:\{([A-Za-z_][A-Za-z0-9_]*)\}|([A-Za-z_][A-Za-z0-9_]*))")

#: The longest line, as written and after ``$VAR`` expansion (PX4's NSH reads lines of 128
#: characters; ours may hold a whole value as JSON). Lines stay bounded, so a file is read in
#: time linear in its size, and ``set A $A$A`` repeated cannot double a line without end.
MAX_LINE = 64 * 1024

#: One piece of a line split into shell words (POSIX quoting, as ``shlex.split``, which takes
#: quadratic time on long words): blanks, '...', "..." (``\"`` and ``\\`` escaped), ``\x``, a
#: run of plain characters, or a quote or backslash left open.
_PIECE = re.compile(
    r"""(?P<blank>[ \t\r\n]+)|'(?P<single>[^']*)'|"(?P<double>(?:[^"\\]|\\.)*)"|\\(?P<escaped>.)"""
    r"""|(?P<plain>[^ \t\r\n'"\\]+)|(?P<open>['"\\])""",
    re.DOTALL,
)
_DOUBLE_ESCAPE = re.compile(r'\\(["\\])')
_OPEN_ESCAPE = re.compile(r'(?:[^"\\]|\\.)*\\', re.DOTALL)


class _Parser(argparse.ArgumentParser):
    """Reports usage errors as exceptions instead of exiting: a bad line is one error."""

    def error(self, message: str) -> NoReturn:
        raise NshArgumentError(message)


def _param_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="param", add_help=False)
    verbs = parser.add_subparsers(
        dest="verb_name", required=True, metavar="VERB", parser_class=_Parser
    )
    param.add_verbs(verbs, argparse.RawDescriptionHelpFormatter)
    return parser


@dataclass
class _Block:
    """An ``if`` block: whether its condition held and which branch is running."""

    condition: bool
    line: int
    in_else: bool = False
    seen_then: bool = False
    #: Its condition failed (a refused ``param compare``): neither branch runs.
    failed: bool = False
    #: Every block around it was running when it opened (and stays so while it is open: only
    #: the innermost block changes branch): a line's running is known from the innermost
    #: block alone, in time independent of the depth.
    outer: bool = True

    def active(self) -> bool:
        return (
            self.outer and self.seen_then and not self.failed and (self.condition != self.in_else)
        )


@dataclass
class Run:
    """The outcome of running a file."""

    errors: list[str] = field(default_factory=list)
    lines_run: int = 0
    #: Lines passed over without ``files`` (``FILE:LINE: why``).
    skipped: list[str] = field(default_factory=list)


#: The ``param`` verbs that read or write a file other than the store's own when given one.
FILE_VERBS = ("save", "export", "load", "import")


def run_file(
    path: str, session: Session, *, keep_going: bool, err: TextIO, files: bool = True
) -> Run:
    """Runs ``path`` against ``session``'s store; saves it once when the file succeeded (or,
    with ``keep_going``, when anything succeeded). Without ``files`` (text a web page gave),
    a line that would read or write another file (:data:`FILE_VERBS` with a FILE) is passed
    over and listed in :attr:`Run.skipped`: nothing outside the text is touched."""
    try:
        lines = read_text(path, AIRFRAME).splitlines()
    except OSError as e:
        raise CommandError(f"{path}: cannot read: {e.strerror}") from None
    except UnicodeDecodeError as e:
        raise CommandError(f"{path}: {not_text(e)}") from None
    session.autosave = False
    parser = _param_parser()
    variables: dict[str, str] = {}
    blocks: list[_Block] = []
    result = Run()
    for number, raw in enumerate(lines, start=1):
        where = f"{path}:{number}"
        try:
            _line(raw, parser, session, variables, blocks, where, number, result, files)
        except (CommandError, Px4ParamsError, NshArgumentError, ValueError) as e:
            result.errors.append(f"{where}: {e}")
            print(f"px4params: error: {where}: {e}", file=err)
            if not keep_going:
                return result
    if blocks:
        message = f"{path}:{blocks[-1].line}: 'if' without 'fi'"
        result.errors.append(message)
        print(f"px4params: error: {message}", file=err)
        if not keep_going:
            return result
    # A file that changes nothing (only comments) still makes the store it was run for: the
    # next command then finds one instead of being told to run this file.
    new_store = not os.path.exists(session.path)
    if (session.changed or session.deferred or new_store) and (not result.errors or keep_going):
        session.save()
    return result


def _line(
    raw: str,
    parser: argparse.ArgumentParser,
    session: Session,
    variables: dict[str, str],
    blocks: list[_Block],
    where: str,
    number: int,
    result: Run,
    files: bool = True,
) -> None:
    if len(raw) > MAX_LINE:
        raise CommandError(f"line of {len(raw):,} characters (at most {MAX_LINE:,})")
    text = raw.strip()
    if not text or text.startswith("#"):
        return
    running = blocks[-1].active() if blocks else True
    if running and text.split(None, 1)[0] in (".", "source"):
        # Before $VAR: PX4's airframes start with `. ${R}etc/init.d/rc.mc_defaults`, whose
        # $R (the ROMFS root) would be the error named, and setting it would not help.
        raise CommandError(
            f"'{abbreviated(text)}' runs another script, which px4params does not (a file runs "
            "its own lines: copy the param lines of that script in, or leave the line out)"
        )
    # A line of a branch that does not run is read for its if/then/else/fi alone: its $VAR
    # may be one that branch sets (as a shell, which expands a line only to run it).
    words = _words(_expand(text, variables) if running else text)
    if not words:
        return
    head = words[0]
    if head in ("then", "else", "fi"):
        _block_word(head, words, blocks)
        return
    if head == "if":
        # A condition inside a branch that does not run is not evaluated, but still nests. One
        # that fails still opens its block, which then runs neither branch (with --keep-going
        # the lines after it are read on, and its then/else/fi must not be orphans).
        try:
            condition = running and _condition(words[1:], parser, session)
        except (CommandError, Px4ParamsError, NshArgumentError, ValueError):
            blocks.append(_Block(False, number, failed=True, outer=running))
            raise
        blocks.append(_Block(condition, number, outer=running))
        return
    if blocks and not blocks[-1].seen_then:
        raise CommandError("expected 'then' after 'if'")
    if not running:
        return
    result.lines_run += 1
    if head == "set":
        if len(words) != 3 or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", words[1]):
            raise CommandError("set takes a variable name and one value: set VAR value")
        variables[words[1]] = words[2]
    elif head == "echo":
        print(" ".join(words[1:]), file=session.out)
    elif head == "param":
        args = _parse(parser, words[1:])
        if not files and args.verb_name in FILE_VERBS and getattr(args, "file", None):
            why = "not run here: it would read or write a file on this computer"
            result.skipped.append(f"{where}: param {args.verb_name} {args.file}: {why}")
            return
        if not files and args.verb_name in ("load", "import"):  # without FILE: the store's
            why = "not run here: it would read the vehicle's saved store"
            result.skipped.append(f"{where}: param {args.verb_name}: {why}")
            return
        status = args.verb(session, args)
        # compare and greater answer with their status; set-default -s of a parameter this
        # build lacks fails silently and the script runs on, as PX4's scripts do (the reason
        # -s exists). Any other failure has said why and stops the file.
        answered = args.verb_name in ("compare", "greater")
        skipped = args.verb_name == "set-default" and args.silent
        if status != EXIT_OK and not answered and not skipped:
            raise CommandError(f"param {args.verb_name} failed")
    else:
        raise CommandError(
            f"unknown command '{head}' (airframe files run param, set, echo and if/then/else/fi)"
        )


def _block_word(word: str, words: list[str], blocks: list[_Block]) -> None:
    if len(words) != 1:
        raise CommandError(f"'{word}' stands alone on its line")
    if not blocks:
        raise CommandError(f"'{word}' without 'if'")
    block = blocks[-1]
    if word == "then":
        if block.seen_then:
            raise CommandError("a second 'then' in one 'if'")
        block.seen_then = True
    elif word == "else":
        if not block.seen_then or block.in_else:
            raise CommandError("'else' must follow 'then' once")
        block.in_else = True
    else:
        if not block.seen_then:
            raise CommandError("'fi' before 'then'")
        blocks.pop()


def _condition(words: list[str], parser: argparse.ArgumentParser, session: Session) -> bool:
    if len(words) < 2 or words[0] != "param" or words[1] not in ("compare", "greater"):
        raise CommandError("'if' takes a 'param compare' or 'param greater' command")
    args = _parse(parser, words[1:])
    return bool(args.verb(session, args) == EXIT_OK)


def _parse(parser: argparse.ArgumentParser, words: list[str]) -> argparse.Namespace:
    try:
        return parser.parse_args(words)
    except NshArgumentError as e:
        # NSH passes a '#' after a command on as a word: say so where argparse cannot.
        comment = next((w for w in words if w.startswith("#")), None)
        hint = f" (a '{comment}' after a command is no comment: give comments a line of their own)"
        raise CommandError(f"param: {e}{hint if comment else ''}") from None


def _expand(text: str, variables: dict[str, str]) -> str:
    """``text`` with ``$VAR`` and ``${VAR}`` replaced, at most :data:`MAX_LINE` characters."""
    size = len(text)

    def value(match: re.Match[str]) -> str:
        nonlocal size
        name = match.group(1) or match.group(2)
        if name not in variables:
            raise CommandError(f"${name} is not set (set {name} value)")
        size += len(variables[name]) - len(match.group(0))
        if size > MAX_LINE:
            raise CommandError(f"the line expands to more than {MAX_LINE:,} characters")
        return variables[name]

    return _VAR.sub(value, text)


def _words(text: str) -> list[str]:
    """``text`` split into words as a POSIX shell quotes them (``shlex.split``'s rules and
    errors), in one pass."""
    words: list[str] = []
    word: list[str] | None = None  # the word being read; None between words
    for piece in _PIECE.finditer(text):
        kind = piece.lastgroup
        if kind == "blank":
            if word is not None:
                words.append("".join(word))
                word = None
            continue
        if kind == "open":  # (a double quote open at a last backslash: that backslash's error)
            open_escape = piece.group() == '"' and _OPEN_ESCAPE.fullmatch(text, piece.end())
            escape = piece.group() == "\\" or open_escape
            raise CommandError("No escaped character" if escape else "No closing quotation")
        part = piece.group(kind or "plain")
        if kind == "double":
            part = _DOUBLE_ESCAPE.sub(r"\1", part)
        if word is None:
            word = []
        word.append(part)
    if word is not None:
        words.append("".join(word))
    return words
