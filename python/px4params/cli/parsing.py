"""The command line's grammar, declared once, and two interpreters of it.

Each command's ``add_parser`` declares its options with argparse's API (``add_parser``,
``add_argument``, ``add_mutually_exclusive_group``, ``set_defaults``, ...). Here that API
records the declaration instead of building argparse's parsers: importing argparse (with
``re``, ``gettext`` and ``locale``) costs a short command about as much as starting Python.

- :meth:`ArgumentParser.parse_args` reads the well-formed command lines that run every day
  (``param show -l INA238#0``, ``decode TYPE HEX``) itself, into the namespace argparse would
  give;
- anything it does not fully understand (``-h``, an unknown or abbreviated option, a value its
  type refuses, a missing argument, ``--``, ``-1``, ``-abc``, ...) goes to argparse: the
  declaration is replayed into argparse's parsers (:meth:`ArgumentParser.argparse`), which
  parse the command line again, so help, usage and every error message are argparse's own.

The small interpreter accepts only what argparse's versions read alike (those of Python 3.11,
3.12 and 3.13 were compared): positionals in one run, or each taking exactly one word; options
by their exact names; no ``--``; no word starting with ``-`` that a parser above might take for
an abbreviation of its own options. ``tests/test_cli_parsing.py`` checks that whatever it
accepts, argparse reads the same.

A type function reports a bad value with :func:`type_error` (argparse's ``ArgumentTypeError``,
imported when a value is bad).
"""

from __future__ import annotations

import os
import sys

from px4params._records import TYPE_CHECKING
from px4params.errors import LeftToArgparse

if TYPE_CHECKING:
    import argparse
    from collections.abc import Callable, Iterable, Sequence
    from typing import Any, NoReturn, TypeVar

    _Result = TypeVar("_Result")

__all__ = [
    "SUPPRESS",
    "ArgumentParser",
    "Namespace",
    "RawDescriptionHelpFormatter",
    "type_error",
]

#: argparse's marker for "no default, no attribute" (the same string).
SUPPRESS = "==SUPPRESS=="

#: The actions the small interpreter runs (argparse's names for them).
_FLAGS = ("store_true", "store_false", "store_const", "append_const", "count")
_VALUED = ("store", "append")


def _suppressed(value: object) -> bool:
    return isinstance(value, str) and value == SUPPRESS


class _ArgparseName:
    """Stands for a class of argparse's (a help formatter) until argparse is imported."""

    def __init__(self, name: str) -> None:
        self.name = name

    def __repr__(self) -> str:
        return f"argparse.{self.name}"


#: ``formatter_class=RawDescriptionHelpFormatter``: argparse's class of that name on replay.
RawDescriptionHelpFormatter: Any = _ArgparseName("RawDescriptionHelpFormatter")


def type_error(message: str) -> Exception:
    """argparse's ``ArgumentTypeError(message)``, for a type function to raise: argparse reports
    ``message`` as it is (other exceptions become "invalid <type> value")."""
    import argparse

    return argparse.ArgumentTypeError(message)


class Namespace:
    """What argparse's ``Namespace`` is to a command: the parsed values as attributes."""

    def __init__(self, **kwargs: Any) -> None:
        self.__dict__.update(kwargs)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Namespace):
            return NotImplemented
        return vars(self) == vars(other)

    __hash__ = None  # type: ignore[assignment]  # unhashable, as argparse's Namespace

    def __contains__(self, key: str) -> bool:
        return key in self.__dict__

    def __repr__(self) -> str:
        return f"Namespace({', '.join(f'{k}={v!r}' for k, v in self.__dict__.items())})"


# -- the declaration ---------------------------------------------------------------------------


class _Book:
    """One declaration, call by call in the order it was made, to replay into argparse."""

    def __init__(self) -> None:
        self.calls: list[tuple[object, str, tuple[Any, ...], dict[str, Any], object]] = []
        self.real: dict[int, Any] | None = None  # id(recorded) -> argparse's object, once replayed


class _Recorded:
    """Something of the declaration that argparse would have built (a parser, a group, an
    argument, the subcommands)."""

    _book: _Book

    def _record(
        self, method: str, args: tuple[Any, ...], kwargs: dict[str, Any], result: _Result
    ) -> _Result:
        self._book.calls.append((self, method, args, kwargs, result))
        return result

    def _argparse_object(self) -> Any:
        """argparse's object this one stands for (the declaration replayed once)."""
        real = _replay(self._book)
        return real[id(self)]


class _Argument(_Recorded):
    """An argument as declared (argparse's ``Action``)."""

    def __init__(self, book: _Book, names: tuple[str, ...], kwargs: dict[str, Any]) -> None:
        self._book = book
        self.option_strings = [n for n in names if n[:1] == "-"]
        # What the small interpreter does not run makes every command line go to argparse.
        self.understood = len(self.option_strings) == len(names) or len(names) == 1
        self.action = kwargs.get("action", "store")
        self.nargs = kwargs.get("nargs")
        self.const = kwargs.get("const")
        self.type = kwargs.get("type")
        self.choices = kwargs.get("choices")
        self.required = bool(kwargs.get("required", False))
        if self.option_strings:
            self.dest = kwargs.get("dest") or _dest_of(self.option_strings)
            self.understood &= all(
                (o.startswith("--") and len(o) > 2)
                or (len(o) == 2 and o[1] != "-" and not o[1].isdigit())
                for o in self.option_strings
            )
            if self.action in _VALUED:
                self.understood &= self.nargs is None
            elif self.action in _FLAGS:
                self.understood &= "nargs" not in kwargs and "type" not in kwargs
            else:
                self.understood &= self.action == "help"
        else:
            self.dest = names[0] if names else kwargs.get("dest", "")
            self.understood &= (
                self.action == "store"
                and "dest" not in kwargs
                and self.nargs in (None, "?", "*", "+")
                and not (self.choices is not None and self.nargs in ("*", "+"))
            )
        defaults = {"store_true": False, "store_false": True, "help": SUPPRESS}
        self.default = kwargs.get("default", defaults.get(self.action))
        if self.action == "store_true":
            self.const = True
        elif self.action == "store_false":
            self.const = False
        if self.action == "help":
            self.dest = SUPPRESS
        self.understood &= callable(self.type) or self.type is None

    @property
    def takes_value(self) -> bool:
        return self.action in _VALUED

    def __repr__(self) -> str:
        return f"<argument {'/'.join(self.option_strings) or self.dest}>"


def _dest_of(option_strings: list[str]) -> str:
    """argparse's ``dest`` of an option: its first long name (else its first) without the
    dashes, ``-`` made ``_``."""
    long_names = [o for o in option_strings if len(o) > 1 and o[1] == "-"]
    return (long_names or option_strings)[0].lstrip("-").replace("-", "_")


class _Container(_Recorded):
    """What arguments are added to: a parser or a group of one."""

    _parser: ArgumentParser

    def add_argument(self, *names: str, **kwargs: Any) -> _Argument:
        parser = self._parser
        declared = kwargs
        if "default" not in kwargs and names:  # argparse: the parser's default for its dest
            dest = kwargs.get("dest") or (
                _dest_of(list(names)) if names[0][:1] == "-" else names[0]
            )
            if dest in parser._defaults:
                kwargs = dict(kwargs, default=parser._defaults[dest])
        argument = _Argument(self._book, names, kwargs)
        parser._add(argument)
        if isinstance(self, _Group) and self.exclusive:
            self.arguments.append(argument)
            parser._understood &= bool(argument.option_strings)
        return self._record("add_argument", names, declared, argument)

    def add_mutually_exclusive_group(self, **kwargs: Any) -> _Group:
        group = _Group(self._parser, exclusive=True, required=bool(kwargs.get("required")))
        self._parser._groups.append(group)
        return self._record("add_mutually_exclusive_group", (), kwargs, group)


class _Group(_Container):
    """An argument group, or a mutually exclusive one."""

    def __init__(self, parser: ArgumentParser, *, exclusive: bool, required: bool = False) -> None:
        self._book = parser._book
        self._parser = parser
        self.exclusive = exclusive
        self.required = required
        self.arguments: list[_Argument] = []


class ArgumentParser(_Container):
    """A parser as declared, with argparse's API for declaring one (see the module doc)."""

    def __init__(self, *args: Any, _book: _Book | None = None, **kwargs: Any) -> None:
        self._book = _Book() if _book is None else _book
        self._parser = self
        self._defaults: dict[str, Any] = {}
        self._options: dict[str, _Argument] = {}
        self._actions: list[_Argument] = []
        self._positionals: list[_Argument] = []
        self._groups: list[_Group] = []
        self._subparsers: _Subparsers | None = None
        self._above: list[ArgumentParser] = []  # the parsers whose subcommand this one is
        understood: tuple[str, ...] = (
            "prog",
            "usage",
            "description",
            "epilog",
            "formatter_class",
            "add_help",
        )
        understood += ("help", "parents", "allow_abbrev", "exit_on_error")
        self._understood = not args and all(k in understood for k in kwargs)
        if _book is None:  # a parser of its own: its construction starts the book
            self._record("", args, kwargs, self)
        if kwargs.get("add_help", True):
            self._add(_Argument(self._book, ("-h", "--help"), {"action": "help"}))
        for parent in kwargs.get("parents", ()):
            self._understood &= isinstance(parent, ArgumentParser)
            if isinstance(parent, ArgumentParser):
                self._inherit(parent)

    def __setattr__(self, name: str, value: Any) -> None:
        """``p.description = ...`` (argparse's attributes, set on argparse's parser)."""
        if name.startswith("_"):
            object.__setattr__(self, name, value)
        else:
            self._understood &= name in ("description", "epilog", "usage")
            self._record("__setattr__", (name, value), {}, None)

    def _add(self, argument: _Argument) -> None:
        self._understood &= argument.understood
        self._actions.append(argument)
        if argument.option_strings:
            for name in argument.option_strings:
                self._options[name] = argument
        else:
            self._positionals.append(argument)

    def _inherit(self, parent: ArgumentParser) -> None:
        """argparse's ``parents=[parent]``: its arguments, exclusive groups and defaults."""
        self._understood &= parent._understood and parent._subparsers is None
        for argument in parent._actions:
            self._add(argument)
        for group in parent._groups:
            copy = _Group(self, exclusive=group.exclusive, required=group.required)
            copy.arguments = list(group.arguments)
            self._groups.append(copy)
        self._defaults.update(parent._defaults)

    def add_argument_group(self, *args: Any, **kwargs: Any) -> _Group:
        group = _Group(self, exclusive=False)
        return self._record("add_argument_group", args, kwargs, group)

    def add_subparsers(self, **kwargs: Any) -> _Subparsers:
        subparsers = _Subparsers(self, kwargs)
        self._understood &= self._subparsers is None
        self._subparsers = subparsers
        self._actions.append(subparsers.argument)
        self._positionals.append(subparsers.argument)
        return self._record("add_subparsers", (), kwargs, subparsers)

    def set_defaults(self, **kwargs: Any) -> None:
        self._defaults.update(kwargs)
        for argument in self._actions:
            if argument.dest in kwargs:
                argument.default = kwargs[argument.dest]
        self._record("set_defaults", (), kwargs, None)

    # -- the two interpreters

    def parse_args(self, args: Sequence[str] | None = None) -> Any:
        """The namespace of ``args`` (default: the command line), as argparse gives it; usage
        errors and ``--help`` exit as argparse does."""
        words = list(sys.argv[1:] if args is None else args)
        values = _parse(self, words)
        if values is not None:
            return Namespace(**values)
        return self.argparse().parse_args(words)

    def argparse(self) -> argparse.ArgumentParser:
        """argparse's parser declared as this one (every parser of the declaration is built,
        once)."""
        parser: argparse.ArgumentParser = self._argparse_object()
        return parser

    def error(self, message: str) -> NoReturn:
        """argparse's usage error: usage and ``message`` on stderr, exit status 2."""
        self.argparse().error(message)

    def print_help(self, file: Any = None) -> None:
        self.argparse().print_help(file)

    def format_help(self) -> str:
        return self.argparse().format_help()

    def format_usage(self) -> str:
        return self.argparse().format_usage()


class _Subparsers(_Recorded):
    """``add_subparsers()``: a positional that picks a parser by name."""

    def __init__(self, parser: ArgumentParser, kwargs: dict[str, Any]) -> None:
        self._book = parser._book
        self._parent = parser
        self.choices: dict[str, ArgumentParser] = {}
        understood = ("dest", "required", "metavar", "title", "description", "help")
        parser._understood &= all(k in understood for k in kwargs)
        self.argument = _Argument(self._book, (), {"dest": kwargs.get("dest", SUPPRESS)})
        self.argument.nargs = "A..."
        self.argument.required = bool(kwargs.get("required", False))

    def add_parser(self, name: str, **kwargs: Any) -> ArgumentParser:
        parser = ArgumentParser(_book=self._book, **kwargs)
        parser._understood &= "aliases" not in kwargs and "prog" not in kwargs
        parser._above = [*self._parent._above, self._parent]
        self.choices[name] = parser
        return self._record("add_parser", (name,), kwargs, parser)


# -- argparse's interpreter: the declaration replayed ------------------------------------------


def _replay(book: _Book) -> dict[int, Any]:
    """Every call of ``book`` made again on argparse's objects (once per book); argparse's
    object of each recorded one, by ``id``."""
    if book.real is not None:
        return book.real
    argparse = _argparse()
    real: dict[int, Any] = {}

    def of(value: Any) -> Any:
        if isinstance(value, _ArgparseName):
            return getattr(argparse, value.name)
        if _suppressed(value):
            return argparse.SUPPRESS  # (argparse tells it by identity)
        return value

    for target, method, args, kwargs, result in book.calls:
        # (a parser given as a default stays the recorded one: its error() is argparse's)
        kwargs = {k: of(v) for k, v in kwargs.items()}
        if "parents" in kwargs:
            kwargs["parents"] = [p._argparse_object() for p in kwargs["parents"]]
        if not method:  # the book's first parser
            made = _Parser(*args, **kwargs)
        else:
            made = getattr(real[id(target)], method)(*args, **kwargs)
        if result is not None:
            real[id(result)] = made
    book.real = real
    return real


def _argparse() -> Any:
    """argparse, imported now (and :class:`_Parser` made)."""
    global _Parser
    import argparse
    import re

    if _Parser is None:
        # Words argparse takes for values, not options: its own negative numbers (-1, -.5) and
        # those a parameter's value is also written as (-1e-3, -0x10, -inf), which it read as
        # an unknown option ("the following arguments are required: value"). No option of
        # ours looks like one.
        negative = re.compile(
            r"^-(\d[\d_]*(\.\d*)?|\.\d+)(e[-+]?\d+)?$|^-0[xbo][\da-f_]+$|^-(inf|infinity|nan)$",
            re.IGNORECASE,
        )

        class Parser(argparse.ArgumentParser):
            """argparse's parser whose help formatter takes the terminal's width from ``os``
            (argparse asks ``shutil``, which costs every command 3 ms to import), and which
            reads the negative numbers above as values. Subparsers are of this class too
            (argparse makes them of their parent's)."""

            def __init__(self, *args: Any, **kwargs: Any) -> None:
                super().__init__(*args, **kwargs)
                self._negative_number_matcher = negative

            def _get_formatter(self) -> argparse.HelpFormatter:
                global _width
                if _width is None:  # argparse makes a formatter for every argument: ask once
                    _width = _terminal_width()
                # typeshed's formatter_class takes prog alone; argparse's formatters take width.
                return self.formatter_class(prog=self.prog, width=_width - 2)  # type: ignore[call-arg]

            def _print_message(self, message: str, file: Any = None) -> None:
                # argparse ignores a failed write; --help's failing (a full disk) is reported
                # by px4params.cli.main as any command's output error
                if file is sys.stdout and message:
                    file.write(message)
                    return
                super()._print_message(message, file)

        _Parser = Parser
    return argparse


#: argparse's parser with the terminal's width (made by :func:`_argparse`).
_Parser: Any = None
_width: int | None = None


def _terminal_width() -> int:
    """As ``shutil.get_terminal_size()`` finds it: $COLUMNS, the terminal, else 80."""
    try:
        return int(os.environ["COLUMNS"])
    except (KeyError, ValueError):
        pass
    try:
        # (no stdout at all: the AttributeError below)
        return os.get_terminal_size(sys.__stdout__.fileno()).columns or 80  # type: ignore[union-attr]
    except (AttributeError, ValueError, OSError):
        return 80


# -- the small interpreter ---------------------------------------------------------------------


def _parse(parser: ArgumentParser, words: list[str]) -> dict[str, Any] | None:
    """The values of ``words`` as argparse would set them, or None to let argparse parse
    them."""
    try:
        return _parse_level(parser, words)
    except LeftToArgparse:
        return None


def _parse_level(parser: ArgumentParser, words: list[str]) -> dict[str, Any]:
    """One parser's part of argparse's ``parse_known_args``: its defaults, its options and
    positionals, and with a subcommand the subcommand's parser on the words after it."""
    if not parser._understood:
        raise LeftToArgparse
    values: dict[str, Any] = {}
    for argument in parser._actions:
        dest, default = argument.dest, argument.default
        if not _suppressed(dest) and dest not in values and not _suppressed(default):
            values[dest] = default
    for dest, default in parser._defaults.items():
        values.setdefault(dest, default)
    seen: list[_Argument] = []
    present: list[_Argument] = []  # seen with a value other than the default (argparse's test)
    positional_words: list[str] = []
    runs = 0  # runs of positional words, between options
    after_option = True
    i = 0
    while i < len(words):
        word = words[i]
        if word[:1] != "-" or word == "-":
            if parser._subparsers is not None:
                values.update(_subcommand(parser, word, words[i + 1 :]))
                seen.append(parser._subparsers.argument)
                break
            runs += after_option
            after_option = False
            positional_words.append(word)
            i += 1
            continue
        after_option = True
        argument, word, i = _option(parser, words, i)
        seen.append(argument)
        if word is None:  # a flag (argparse: its value is [], never its default)
            present.append(argument)
            _flag(argument, values)
            continue
        value = _converted(argument, word)
        if value is not argument.default:
            present.append(argument)
        if argument.action == "store":
            values[argument.dest] = value
        else:  # append
            items = values.get(argument.dest)
            if items is not None and not isinstance(items, list):
                raise LeftToArgparse
            values[argument.dest] = [*(items or ()), value]
    if parser._subparsers is None:
        positionals = _positionals(parser._positionals, positional_words, runs)
        for argument, taken in positionals:
            values[argument.dest] = taken
            seen.append(argument)
            if taken is not argument.default:
                present.append(argument)
    for argument in parser._actions:
        if argument in seen:
            continue
        if argument.required:
            raise LeftToArgparse  # argparse: "the following arguments are required"
        default = argument.default
        if (
            isinstance(default, str)
            and argument.dest in values
            and values[argument.dest] is default
        ):
            values[argument.dest] = _typed(argument, default)
    for group in parser._groups:
        if not group.exclusive:
            continue
        given = [a for a in group.arguments if a in present]
        if len(given) > 1 or (group.required and not given):
            raise LeftToArgparse  # "not allowed with argument", "one of the arguments is required"
    return values


def _flag(argument: _Argument, values: dict[str, Any]) -> None:
    """What a flag (an option taking no value) does to the values."""
    if argument.action in ("store_const", "store_true", "store_false"):
        values[argument.dest] = argument.const
    elif argument.action == "append_const":
        items = values.get(argument.dest)
        if items is not None and not isinstance(items, list):
            raise LeftToArgparse
        values[argument.dest] = [*(items or ()), argument.const]
    else:  # count
        count = values.get(argument.dest)
        if count is not None and not isinstance(count, int):
            raise LeftToArgparse
        values[argument.dest] = (count or 0) + 1


def _subcommand(parser: ArgumentParser, word: str, rest: list[str]) -> dict[str, Any]:
    """The subcommand ``word`` picks, run on the words after it; its values override."""
    assert parser._subparsers is not None
    if len(parser._positionals) != 1:
        raise LeftToArgparse  # positionals before the subcommand: argparse's matching decides
    child = parser._subparsers.choices.get(word)
    if child is None:
        raise LeftToArgparse  # argparse: "invalid choice"
    values: dict[str, Any] = {}
    if not _suppressed(parser._subparsers.argument.dest):
        values[parser._subparsers.argument.dest] = word
    values.update(_parse_level(child, rest))
    return values


def _option(parser: ArgumentParser, words: list[str], i: int) -> tuple[_Argument, Any, int]:
    """The option at ``words[i]``, its word of value (None for a flag) and where the next
    word is."""
    word = words[i]
    name, equals, explicit = word.partition("=") if word.startswith("--") else (word, "", "")
    argument = parser._options.get(name)
    if argument is None or argument.action == "help":
        raise LeftToArgparse  # unknown, abbreviated, -abc, -1, --, -h
    for above in parser._above:  # a parser above that might read the word as its abbreviation
        for option in above._options:
            if option != name and (
                option.startswith(name) or (name[1] != "-" and option == name[:2])
            ):
                raise LeftToArgparse
    if not argument.takes_value:
        if equals:
            raise LeftToArgparse  # argparse: "ignored explicit argument"
        return argument, None, i + 1
    if equals:
        if explicit == "--":
            raise LeftToArgparse  # argparse drops a value '--' (3.11: --opt=-- sets [])
        return argument, explicit, i + 1
    if i + 1 == len(words) or (words[i + 1][:1] == "-" and words[i + 1] != "-"):
        raise LeftToArgparse  # argparse: "expected one argument" (or -1 as a value)
    return argument, words[i + 1], i + 2


def _positionals(
    arguments: list[_Argument], words: list[str], runs: int
) -> Iterable[tuple[_Argument, Any]]:
    """Each positional and its value, as argparse matches ``words`` to them: in order, each
    taking as many as it can while those after it still get their least."""
    least = {None: 1, "?": 0, "*": 0, "+": 1}
    most = {None: 1, "?": 1, "*": len(words), "+": len(words)}
    if runs > 1 and any(a.nargs is not None for a in arguments):
        raise LeftToArgparse  # positionals split by options: argparse versions differ
    if not sum(least[a.nargs] for a in arguments) <= len(words):
        raise LeftToArgparse  # argparse: "the following arguments are required"
    start = 0
    matched = []
    for k, argument in enumerate(arguments):
        after = sum(least[a.nargs] for a in arguments[k + 1 :])
        count = min(most[argument.nargs], len(words) - start - after)
        taken = words[start : start + count]
        start += count
        if argument.nargs is None:
            value = _converted(argument, taken[0])
        elif argument.nargs == "?":
            if taken:
                value = _converted(argument, taken[0])
            else:
                value = argument.default
                if isinstance(value, str):
                    value = _converted(argument, value)
        elif not taken and argument.nargs == "*":
            value = argument.default if argument.default is not None else []
        else:
            value = [_converted(argument, w) for w in taken]
        matched.append((argument, value))
    if start != len(words):
        raise LeftToArgparse  # argparse: "unrecognized arguments"
    return matched


def _converted(argument: _Argument, word: str) -> Any:
    """``word`` through the argument's type, checked against its choices."""
    value = _typed(argument, word)
    if argument.choices is not None and value not in argument.choices:
        raise LeftToArgparse  # argparse: "invalid choice"
    return value


def _typed(argument: _Argument, word: str) -> Any:
    convert: Callable[[str], Any] | None = argument.type
    if convert is None:
        return word
    try:
        return convert(word)
    except Exception:
        raise LeftToArgparse from None  # argparse reports it (or raises it, as it does)
