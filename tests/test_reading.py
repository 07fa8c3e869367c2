"""Strict and bounded inputs (issue 35): the one file reader, strict JSON/TOML/.params inputs,
DSDL folders walked once, airframe lines in linear time, caches that cannot lie, output errors,
truncated logs and the servers' durations. The catalogue of bad inputs (``test_cli_bad_inputs.py``)
runs every file kind as a FIFO, a device, a folder, a link loop and an over-size file."""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from px4params.errors import InputFileError
from px4params.reading import FileKind, check_file, open_file, read_bytes, read_text

ROOT = Path(__file__).resolve().parents[1]
AIRFRAME = ROOT / "examples" / "two_batteries.airframe"
CLI = [sys.executable, "-m", "px4params"]
SMALL = FileKind("a test file", 10)


def cli(
    *args: str, cwd: Path | None = None, timeout: float = 60, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*CLI, *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=cwd,
        env=env,
        check=False,
    )


@pytest.fixture
def store(tmp_path: Path) -> Path:
    path = tmp_path / "v.store"
    assert cli("run", str(AIRFRAME), "--store", str(path)).returncode == 0
    return path


# -- 1: one bounded reader ----------------------------------------------------------------------


def test_a_regular_file_within_its_cap_is_read_whole(tmp_path: Path) -> None:
    path = tmp_path / "ten"
    path.write_bytes(b"0123456789")
    assert read_bytes(path, SMALL) == b"0123456789"
    assert read_text(path, SMALL) == "0123456789"
    assert check_file(path, SMALL).st_size == 10
    with open_file(path, SMALL) as f:
        assert f.read() == b"0123456789"


def test_a_file_over_its_cap_is_refused_with_both_sizes(tmp_path: Path) -> None:
    path = tmp_path / "eleven"
    path.write_bytes(b"0" * 11)
    message = f"^{path}: too large for a test file \\(11 bytes; at most 10 bytes\\)$"
    for read in (read_bytes, check_file, open_file):
        with pytest.raises(InputFileError, match=message) as caught:
            read(path, SMALL)
    # An OSError too: callers that report "cannot read: {strerror}" report it.
    assert isinstance(caught.value, OSError) and caught.value.filename == str(path)
    big = tmp_path / "big"
    with open(big, "wb") as f:
        f.truncate(17 * 1024 * 1024 + 1)  # sparse: no disk used
    from px4params.reading import STORE

    with pytest.raises(InputFileError, match=r"too large for a store file \(17 MiB; at most 16"):
        read_bytes(big, STORE)


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path: Path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for read in (read_bytes, check_file, open_file):
        with pytest.raises(InputFileError, match=f"^{fifo}: is a FIFO \\(named pipe\\), not a"):
            read(fifo, SMALL)


def test_devices_folders_and_sockets_are_refused_before_reading(tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match=r"^/dev/zero: is a character device, not a regular"):
        read_bytes("/dev/zero", SMALL)
    with pytest.raises(InputFileError, match=f"^{tmp_path}: is a folder, not a file$"):
        read_bytes(tmp_path, SMALL)
    path = tmp_path / "sock"
    server = socket.socket(socket.AF_UNIX)
    try:
        server.bind(str(path))
        with pytest.raises(InputFileError, match=f"^{path}: is a socket, not a regular file$"):
            read_bytes(path, SMALL)
    finally:
        server.close()


def test_a_device_is_not_even_opened(monkeypatch: pytest.MonkeyPatch) -> None:
    """Opening some devices does something (a watchdog's starts it): refused on its status."""
    opened: list[str] = []
    real_open = os.open
    monkeypatch.setattr(os, "open", lambda path, *a: opened.append(path) or real_open(path, *a))
    with pytest.raises(InputFileError, match="character device"):
        read_bytes("/dev/zero", SMALL)
    assert opened == []


def test_a_link_loop_and_a_missing_file_are_the_system_errors(tmp_path: Path) -> None:
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    with pytest.raises(OSError, match="Too many levels of symbolic links"):
        read_bytes(loop, SMALL)
    with pytest.raises(FileNotFoundError):
        read_bytes(tmp_path / "missing", SMALL)


def test_every_product_read_goes_through_the_reader() -> None:
    """No module but the reader opens a file for reading (writes, the package's own data and
    the ground-station codec, which stands alone, excepted)."""
    allowed = {
        "reading.py": "the reader",
        "gcs/codec.py": "copied into ground stations: imports nothing of px4params",
        "vehicle/devid.py": "the bundled era tables (package data)",
        "vehicle/boards.py": "the bundled value_sets.toml (package data)",
        "cli/commands/examples.py": "the bundled examples (package data) and the copies it makes",
        "dsdl/loader.py": "the bundled value_sets.toml (package data)",
        "migrate/axes.py": "the bundled driver_axes.toml (package data)",
        "store/file.py": "the backup copy of the file being saved (the write path)",
        "store/session.py": "the lock file",
        "writing.py": "an output's first bytes: a store file is not written over",
    }
    package = ROOT / "python" / "px4params"
    found = []
    for path in package.rglob("*.py"):
        name = path.relative_to(package).as_posix()
        for number, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#")[0]
            reads = re.search(r"(?<![\w.])open\(|\.read_text\(|\.read_bytes\(", code)
            if reads and '"w"' not in code and '"wb"' not in code and name not in allowed:
                found.append(f"{name}:{number}: {line.strip()}")
    assert found == []


@pytest.mark.parametrize(
    ("args", "where"),
    [
        (("encode", "px.Ina238", "-"), "<stdin>:1"),
        (("decode", "px.Ina238", "-"), "<stdin>:1"),
        (("frames", "px.Ina238", "-", "--dtid", "1"), "<stdin>"),
    ],
)
def test_an_endless_stdin_is_refused_at_its_cap(args: tuple[str, ...], where: str) -> None:
    with open("/dev/zero") as zero:
        result = subprocess.run(
            [*CLI, *args], stdin=zero, capture_output=True, text=True, timeout=20, check=False
        )
    assert result.returncode == 1
    assert result.stderr == (
        f"px4params: error: {where}: longer than 1,048,576 characters (an endless input?)\n"
    )


# -- 2: strict inputs ---------------------------------------------------------------------------


def _export(store: Path, tmp_path: Path) -> str:
    exported = tmp_path / "e.json"
    assert cli("param", "--store", str(store), "export", str(exported)).returncode == 0
    return exported.read_text()


@pytest.mark.parametrize("verb", ["load", "import"])
def test_a_misspelled_top_level_key_of_a_json_export_changes_nothing(
    verb: str, store: Path, tmp_path: Path
) -> None:
    text = _export(store, tmp_path).replace('"instances"', '"instancez"')
    bad = tmp_path / "t.json"
    bad.write_text(text)
    before = store.read_bytes()
    result = cli("param", "--store", str(store), verb, str(bad))
    assert result.returncode == 1
    assert result.stderr == (
        f"px4params: error: {bad}: unknown top-level key 'instancez' (did you mean "
        "'instances'?); nothing was changed\n"
    )
    assert store.read_bytes() == before


@pytest.mark.parametrize(
    ("body", "says"),
    [
        ('"instances": null', "'instances' must be an object, not null; nothing was changed"),
        ('"classic": []', "'classic' must be an object, not an array; nothing was changed"),
        ('"instances": {"INA238#0": {"valeu": {}}}', "unknown key 'valeu' (did you mean 'value'?)"),
        ('"instances": {"INA238#0": []}', 'INA238#0: expected {"value": ..., "default": ...}'),
        ('"instances": {"INA238#0.current": {"value": 1}}', "holds whole structured parameters"),
        ('"instances": {"SYS_AUTOSTART": {"value": 1}}', "holds whole structured parameters"),
        ('"classic": {"INA238#0": 1}', "INA238#0: not a classic parameter of this store"),
        ('"comment": "x"', "unknown top-level key 'comment' (expected: format, version"),
    ],
)
def test_wrong_shapes_in_a_json_export_are_named(
    body: str, says: str, store: Path, tmp_path: Path
) -> None:
    bad = tmp_path / "t.json"
    bad.write_text('{"format": "px4params", "version": 1, ' + body + "}")
    before = store.read_bytes()
    result = cli("param", "--store", str(store), "import", str(bad))
    assert result.returncode == 1 and says in result.stderr, result.stderr
    assert result.stderr.startswith(f"px4params: error: {bad}: ") and result.stderr.count("\n") == 1
    assert store.read_bytes() == before


def test_a_params_file_setting_one_parameter_twice_is_refused(store: Path, tmp_path: Path) -> None:
    bad = tmp_path / "twice.params"
    bad.write_text("1\t1\tSYS_AUTOSTART\t4001\t6\n1\t1\tINA238_0C\t70\t6\n1\t1\tINA238_0C\t71\t6\n")
    before = store.read_bytes()
    result = cli("param", "--store", str(store), "import", str(bad))
    assert result.returncode == 1
    assert result.stderr == f"px4params: error: {bad}:3: INA238_0C: also set on line 2\n"
    assert store.read_bytes() == before


def test_an_export_still_loads_back_to_the_same_store(store: Path, tmp_path: Path) -> None:
    _export(store, tmp_path)
    before = store.read_bytes()
    result = cli("param", "--store", str(store), "load", str(tmp_path / "e.json"))
    assert result.returncode == 0, result.stderr
    assert store.read_bytes() == before


@pytest.mark.parametrize(
    ("kind", "text", "says"),
    [
        ("bench", "benchz = 1\n", "unknown top-level key 'benchz' (did you mean 'bench'?)"),
        ("bench", "bus = 1\n", "'bus' must be [[bus]] tables"),
        ("bench", "[[bus]]\nkind = []\n", "kind [] is not a simulated bus kind"),
        ("drivers", "drivers = 1\n", "unknown top-level key 'drivers' (expected [[driver]]"),
        (
            "drivers",
            '[[driver]]\nname = "x"\nparameter = "INA238"\nchip = "INA238"\norder = 1\n'
            "devtype = 1\nrate_hz = 1\nbuses = [{}]\n",
            "unknown bus kind {}",
        ),
        ("drivers", '[[driver]]\nname = "x"\nnope = 1\n', "unknown key 'nope' (expected: name,"),
    ],
)
def test_toml_inputs_name_unknown_keys_and_wrong_shapes(
    kind: str, text: str, says: str, store: Path, tmp_path: Path
) -> None:
    bad = tmp_path / f"bad.{kind}.toml"
    bad.write_text(text)
    bench = ROOT / "examples" / "two_batteries.bench.toml"
    args = (
        ["--bench", str(bad)] if kind == "bench" else ["--bench", str(bench), "--drivers", str(bad)]
    )
    result = cli("autostart", "run", "--store", str(store), *args)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert result.stderr.startswith(f"px4params: error: {bad}: ") and says in result.stderr, (
        result.stderr
    )


# -- 3: DSDL folders ----------------------------------------------------------------------------


def _root_with_one_type(tmp_path: Path) -> Path:
    root = tmp_path / "acme"
    root.mkdir()
    (root / "Thing.1.0.dsdl").write_text("uint8 x\n@sealed\n")
    return root


def test_a_link_cycle_in_a_dsdl_root_ends_and_each_folder_is_read_once(tmp_path: Path) -> None:
    root = _root_with_one_type(tmp_path)
    (root / "up").symlink_to("..")  # the folder holding the root: the root again, and more
    (root / "again").symlink_to(".")  # the root itself
    (root / "a").symlink_to("b")  # a two-link cycle
    (root / "b").symlink_to("a")
    result = cli("types", "--dsdl", str(root), env={**os.environ, "PX4PARAMS_DSDL_PATH": ""})
    assert result.returncode == 0, result.stderr
    assert [line.split()[0] for line in result.stdout.splitlines() if "acme" in line] == [
        "acme.Thing.1.0"
    ]


@pytest.mark.parametrize(
    ("root", "says"),
    [
        ("/", "/: the file system's root is not a DSDL root namespace folder"),
        ("/usr", "/usr: DSDL root holds more than 10,000 files and folders"),
    ],
)
def test_a_system_folder_as_dsdl_root_is_refused_quickly(root: str, says: str) -> None:
    entries = zip(range(10_001), Path("/usr").rglob("*"), strict=False)
    if root == "/usr" and sum(1 for _ in entries) <= 10_000:
        pytest.skip("this /usr holds fewer than 10,000 entries")
    result = cli("types", env={**os.environ, "PX4PARAMS_DSDL_PATH": root}, timeout=20)
    assert result.returncode == 1
    assert result.stderr.startswith(f"px4params: error: {says}"), result.stderr


def test_dsdl_folders_deeper_than_the_cap_are_refused(tmp_path: Path) -> None:
    root = _root_with_one_type(tmp_path)
    deep = root
    for _ in range(17):
        deep = deep / "n"
    deep.mkdir(parents=True)
    result = cli("types", "--dsdl", str(root), env={**os.environ, "PX4PARAMS_DSDL_PATH": ""})
    assert result.returncode == 1
    assert "DSDL folders nested deeper than 16 levels" in result.stderr, result.stderr


def test_a_definition_that_is_a_link_loop_is_named(tmp_path: Path) -> None:
    root = _root_with_one_type(tmp_path)
    (root / "A.1.0.dsdl").symlink_to("B.1.0.dsdl")
    (root / "B.1.0.dsdl").symlink_to("A.1.0.dsdl")
    result = cli("types", "--dsdl", str(root), env={**os.environ, "PX4PARAMS_DSDL_PATH": ""})
    assert result.returncode == 1
    assert re.fullmatch(
        f"px4params: error: {root}/[AB].1.0.dsdl: cannot read DSDL file: Too many levels of "
        "symbolic links\n",
        result.stderr,
    ), result.stderr


# -- 4: airframe lines in linear time -----------------------------------------------------------


def _run_airframe(store: Path, tmp_path: Path, text: str) -> subprocess.CompletedProcess[str]:
    airframe = tmp_path / "frame.airframe"
    airframe.write_text(text)
    return cli("run", str(airframe), "--store", str(store), timeout=20)


def test_a_megabyte_line_is_refused_at_once_naming_file_and_line(
    store: Path, tmp_path: Path
) -> None:
    before = store.read_bytes()
    result = _run_airframe(store, tmp_path, "# one\nparam set SYS_AUTOSTART " + "1" * 1_000_000)
    assert result.returncode == 1
    assert result.stderr == (
        f"px4params: error: {tmp_path}/frame.airframe:2: line of 1,000,024 characters (at most "
        "65,536)\n"
    )
    assert store.read_bytes() == before


def test_doubling_a_variable_stops_at_the_line_cap(store: Path, tmp_path: Path) -> None:
    before = store.read_bytes()
    text = "set A x\n" + "set A $A$A\n" * 40
    result = _run_airframe(store, tmp_path, text)
    assert result.returncode == 1
    # A holds 2**15 characters after line 16; line 17 would make 2**16 + 2.
    assert result.stderr == (
        f"px4params: error: {tmp_path}/frame.airframe:17: the line expands to more than 65,536 "
        "characters\n"
    )
    assert store.read_bytes() == before


def test_a_long_value_within_the_cap_is_split_as_the_shell_splits_it(
    store: Path, tmp_path: Path
) -> None:
    padding = " " * 60_000
    value = (
        '{"bus": {"i2c": {"bus_id": 2, "address": 70}}, "current": 100,'
        + padding
        + '"shunt": 0.001}'
    )
    text = f'param set INA238#0 \'{value}\'\nset V "a \\"b\\" c"\nparam set SYS_AUTOSTART 4001\n'
    result = _run_airframe(store, tmp_path, text)
    assert result.returncode == 0, result.stderr
    shown = cli("param", "--store", str(store), "show", "-q", "INA238#0.bus.i2c.address")
    assert shown.stdout.strip() == "70"


@pytest.mark.parametrize(
    "line",
    [
        'a b  \'c d\' "e \\" \\\\ \\$ f" g\\ h \'\' "" i\'j\'"k"',
        "'unterminated",
        '"open \\',
        "trailing \\",
        "\t x\ty \r",
    ],
)
def test_airframe_words_are_shlex_words(line: str) -> None:
    import shlex

    from px4params.errors import CommandError
    from px4params.nsh.airframe import _words

    try:
        expected: list[str] | str = shlex.split(line)
    except ValueError as e:
        expected = str(e)
    try:
        got: list[str] | str = _words(line)
    except CommandError as e:
        got = str(e)
    assert got == expected


# -- 5: caches that cannot lie -----------------------------------------------------------------


def _env(cache: Path) -> dict[str, str]:
    return {**os.environ, "PX4PARAMS_CACHE_DIR": str(cache), "PX4PARAMS_DSDL_PATH": ""}


def _edit_keeping_mtime(path: Path, old: str, new: str) -> None:
    """Replaces ``old`` by ``new`` (same length) in place, then puts the modification time back,
    as ``cp -p`` onto an existing file or ``rsync -t`` leave an edited file."""
    st = path.stat()
    text = path.read_text()
    assert len(old) == len(new) and old in text
    path.write_text(text.replace(old, new))
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert path.stat().st_mtime_ns == st.st_mtime_ns and path.stat().st_size == st.st_size


def test_a_dsdl_edit_with_its_mtime_restored_is_seen(tmp_path: Path) -> None:
    root = _root_with_one_type(tmp_path)
    definition = root / "Thing.1.0.dsdl"
    an_hour_ago = int((definition.stat().st_mtime - 3600) * 1e9)
    os.utime(definition, ns=(an_hour_ago, an_hour_ago))  # not "racy": keyed by its stamp alone
    env = _env(tmp_path / "cache")
    first = cli("encode", "acme.Thing", '{"x": 5}', "--dsdl", str(root), env=env)
    assert first.returncode == 0, first.stderr
    _edit_keeping_mtime(definition, "uint8 x", "uint8 y")
    second = cli("encode", "acme.Thing", '{"y": 5}', "--dsdl", str(root), env=env)
    assert second.returncode == 0, second.stderr
    assert second.stdout == first.stdout


def test_a_parameters_json_edit_with_its_mtime_restored_is_seen(
    store: Path, tmp_path: Path
) -> None:
    classic = tmp_path / "parameters.json"
    classic.write_text(
        '{"version": 1, "parameters": [{"name": "SYS_AUTOSTART", "type": "Int32", '
        '"default": 1111}]}'
    )
    an_hour_ago = int((classic.stat().st_mtime - 3600) * 1e9)
    os.utime(classic, ns=(an_hour_ago, an_hour_ago))
    env = _env(tmp_path / "cache")
    args = ("param", "--store", str(tmp_path / "new.store"), "--classic", str(classic))
    first = cli(*args, "show", "-q", "SYS_AUTOSTART", env=env)
    assert first.stdout.strip() == "1111", first.stderr
    _edit_keeping_mtime(classic, "1111", "2222")
    second = cli(*args, "show", "-q", "SYS_AUTOSTART", env=env)
    assert second.stdout.strip() == "2222", second.stderr


def _rewrite_cache_entry(cache: Path, kind: str, change: object) -> Path:
    """Changes the value cached in ``cache``'s ``KIND-*.marshal`` with ``change(value)`` and
    writes it back with a valid CRC, as something else than px4params could."""
    import binascii
    import marshal

    (path,) = cache.glob(f"{kind}-*.marshal")
    data = path.read_bytes()
    key, value = marshal.loads(data[8:])
    value = change(value)  # type: ignore[operator]
    body = marshal.dumps((key, value))
    path.write_bytes(data[:4] + binascii.crc32(body).to_bytes(4, "little") + body)
    return path


def _without_fields(model: dict) -> dict:  # type: ignore[type-arg]
    import marshal

    definition = marshal.loads(model["types"]["px.Ina238.1.1"])
    del definition["fields"]
    model["types"]["px.Ina238.1.1"] = marshal.dumps(definition)
    return model


def _bits_text(model: dict) -> dict:  # type: ignore[type-arg]
    import marshal

    definition = marshal.loads(model["types"]["px.Ina238.1.1"])
    definition["fields"][0]["type"]["bits"] = "four"
    model["types"]["px.Ina238.1.1"] = marshal.dumps(definition)
    return model


def _newest_wrong(model: dict) -> dict:  # type: ignore[type-arg]
    model["newest"]["px.Ina238"] = "px.Ina238.1.0"
    return model


def _refs_wrong(model: dict) -> dict:  # type: ignore[type-arg]
    model["refs"]["px.Ina238.1.1"] = []
    return model


def _types_garbage(model: dict) -> dict:  # type: ignore[type-arg]
    model["types"]["px.Ina238.1.1"] = b"\x00not marshal"
    return model


@pytest.fixture(scope="module")
def warm_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A cache folder holding the bundled model and classic parameters (built once)."""
    cache = tmp_path_factory.mktemp("warm") / "cache"
    result = cli("param", "--store", str(cache.parent / "v.store"), "show", env=_env(cache))
    assert result.returncode == 0, result.stderr
    return cache


@pytest.mark.parametrize(
    ("kind", "change", "says"),
    [
        ("model", _without_fields, "type px.Ina238.1.1: no 'kind' of struct or union, or no"),
        ("model", _bits_text, "type px.Ina238.1.1: a field type of the wrong shape: {'kind'"),
        ("model", _newest_wrong, "'newest' does not name the newest version of each type"),
        ("model", _refs_wrong, "type px.Ina238.1.1: its list of referenced types is not"),
        ("model", _types_garbage, "type px.Ina238.1.1: cannot unpack it"),
        ("model", lambda model: {**model, "types": []}, "'types' is not a table of packed"),
        ("classic", lambda rows: [[1, 2]], "not a list of classic parameters"),
    ],
)
def test_a_cache_entry_of_the_wrong_shape_is_rebuilt_with_a_note(
    kind: str, change: object, says: str, store: Path, tmp_path: Path, warm_cache: Path
) -> None:
    import shutil

    cache = tmp_path / "cache"
    shutil.copytree(warm_cache, cache)
    env = _env(cache)
    show = ("param", "--store", str(store), "show", "-q", "INA238#0.bus.i2c.address")
    expected = cli(*show, env=env)
    assert expected.returncode == 0 and expected.stdout.strip() == "69", expected.stderr
    path = _rewrite_cache_entry(cache, kind, change)
    noted = cli(*show, env=env)
    assert noted.returncode == 0, noted.stderr
    assert noted.stdout == expected.stdout
    assert noted.stderr.startswith(f"px4params: note: {path}: {says}")
    assert noted.stderr.endswith("; rebuilding it\n") and noted.stderr.count("\n") == 1
    again = cli(*show, env=env)  # rebuilt: no note
    assert again.returncode == 0 and again.stderr == "" and again.stdout == expected.stdout


# -- 6: output errors ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args",
    [
        ("param", "--store", "{store}", "show"),
        ("param", "--store", "{store}", "show", "-l", "INA238#0"),
        ("types",),
        ("--help",),  # argparse ignores a failed write of its help
        ("param", "--help"),
        ("--version",),
    ],
)
def test_a_full_disk_for_the_output_is_one_line(args: tuple[str, ...], store: Path) -> None:
    words = [a.replace("{store}", str(store)) for a in args]
    with open("/dev/full", "w") as full:
        result = subprocess.run(
            [*CLI, *words], stdout=full, stderr=subprocess.PIPE, text=True, timeout=60, check=False
        )
    assert result.returncode == 1
    assert result.stderr == "px4params: error: cannot write the output: No space left on device\n"


@pytest.mark.parametrize(
    "args", [("param", "--store", "{store}", "show"), ("types",), ("devid", "--list")]
)
def test_a_reader_that_went_away_ends_the_command_quietly(
    args: tuple[str, ...], store: Path
) -> None:
    words = [a.replace("{store}", str(store)) for a in args]
    process = subprocess.Popen(
        [*CLI, *words], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stdout is not None and process.stderr is not None
    process.stdout.close()  # as `| head -0` does: every write meets a closed pipe
    try:
        err = process.stderr.read()
        status = process.wait(timeout=60)
    finally:
        process.kill()
    assert err == ""
    assert status == 141  # 128 + SIGPIPE, as shells report `yes | head -1`


# -- 7: health of a log cut short ---------------------------------------------------------------


@pytest.fixture(scope="module")
def faults_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A log of the faults bench, written by the product (INA238#1 is lost at 6.9 s)."""
    log = tmp_path_factory.mktemp("log") / "run.ulg"
    result = cli(
        "autostart",
        "run",
        "--airframe",
        str(AIRFRAME),
        "--bench",
        str(ROOT / "examples" / "two_batteries_faults.bench.toml"),
        "--ulog",
        str(log),
    )
    assert result.returncode == 1 and log.exists(), result.stderr
    return log


def test_a_whole_log_has_no_warning(faults_log: Path) -> None:
    result = cli("health", str(faults_log))
    assert result.stdout.splitlines()[0].endswith("arming refused at the end")
    assert "warning: the log ends" not in result.stdout
    assert "INA238#1 (ina238) at 6.50 s" in result.stdout


def test_health_of_a_log_cut_short_says_so_and_from_when(faults_log: Path, tmp_path: Path) -> None:
    from pyulog import ULog

    data = faults_log.read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[: len(data) // 2])
    # The oracle: the last moment the cut file holds, as pyulog reads it.
    ulog = ULog(str(cut))
    last = max([ulog.last_timestamp] + [m.timestamp for m in ulog.logged_messages]) / 1e6
    assert last < 6.9  # cut before INA238#1 was lost
    result = cli("health", str(cut))
    assert result.returncode == 1 and "Traceback" not in result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].endswith(f"arming refused at {last:.2f} s, where the log ends")
    assert lines[1] == (
        f"warning: the log ends at {last:.2f} s without the run's clean end (cut short?): its "
        f"story is uncertain from {last:.2f} s on, and nothing after is known"
    )
    # The device lost later is not said to end nominal: its state is as of the log's end.
    index = lines.index(next(line for line in lines if line.startswith("INA238#1 ")))
    assert f"  at {last:.2f} s, where the log ends: nominal;" in "\n".join(lines[index:])
    assert "at the end:" not in result.stdout
    as_json = cli("health", str(cut), "--json")
    import json

    assert json.loads(as_json.stdout)["log_cut_at"] == pytest.approx(last)


def test_a_log_missing_only_its_last_bytes_is_cut_short_too(
    faults_log: Path, tmp_path: Path
) -> None:
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(faults_log.read_bytes()[:-3])
    result = cli("health", str(cut))
    assert result.returncode == 1
    assert result.stdout.splitlines()[1].startswith("warning: the log ends at 10.00 s without")


def test_a_log_cut_before_the_commanders_first_answer_says_no_answer_not_refused(
    faults_log: Path, tmp_path: Path
) -> None:
    # The header said "arming refused at 0.00 s" while the body said "commander: no answer
    # logged": the commander had answered nothing yet.
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(faults_log.read_bytes()[:3000])
    result = cli("health", str(cut))
    assert result.returncode == 1
    lines = result.stdout.splitlines()
    assert lines[0].endswith(": no arming answer logged at 0.00 s, where the log ends"), lines[0]
    assert "commander: no answer logged" in lines
    assert "arming refused" not in result.stdout


# -- 8: durations -------------------------------------------------------------------------------


@pytest.mark.parametrize("value", ["nan", "-1", "inf", "0", "-inf", "1e400", "86401", "soon"])
@pytest.mark.parametrize(
    "command",
    [
        ("mavlink", "serve", "--store", "{store}", "--bench-duration"),
        ("dronecan", "serve", "--slcan-pty", "--store", "{store}", "--bench-duration"),
        ("autostart", "run", "--store", "{store}", "--bench", "{bench}", "--duration"),
    ],
    ids=["mavlink", "dronecan", "autostart"],
)
def test_a_duration_that_is_not_a_time_is_refused_as_the_line_is_read(
    command: tuple[str, ...], value: str, store: Path
) -> None:
    bench = ROOT / "examples" / "two_batteries.bench.toml"
    words = [w.replace("{store}", str(store)).replace("{bench}", str(bench)) for w in command]
    words[-1] += f"={value}"  # (argparse takes "-inf" after a space for an option)
    result = cli(*words, timeout=20)  # a server that started would not return
    assert result.returncode == 2
    option = command[-1]
    assert result.stderr.splitlines()[-1] == (
        f"px4params {command[0]} {command[1]}: error: argument {option}: expected seconds more "
        f"than 0 and at most 86400, not '{value}'"
    )


def test_a_response_timeout_that_is_not_a_time_is_refused() -> None:
    result = cli(
        "dronecan", "param", "list", "--slcan", "/nonexistent", "--node", "1", "--timeout", "nan"
    )
    assert result.returncode == 2
    assert result.stderr.splitlines()[-1].endswith(
        "error: argument --timeout: expected seconds more than 0 and at most 3600, not 'nan'"
    )


# -- a byte order mark --------------------------------------------------------------------------

BOM = b"\xef\xbb\xbf"  # UTF-8's byte order mark, which Windows Notepad writes first


def test_a_byte_order_mark_is_no_part_of_the_first_line(tmp_path: Path) -> None:
    path = tmp_path / "bom.txt"
    path.write_bytes(BOM + b"param add INA238#0\n")
    assert read_text(path, FileKind("a text", 100)) == "param add INA238#0\n"
    path.write_bytes(BOM + b"x\xff")  # what is not text is still said at its own offset
    with pytest.raises(UnicodeDecodeError) as e:
        read_text(path, FileKind("a text", 100))
    assert e.value.start == 4


def test_files_saved_with_a_byte_order_mark_read_as_without(tmp_path: Path) -> None:
    # An airframe file was "unknown command '\ufeffparam'"; a QGC .params file "expected 5
    # TAB-separated columns, got 6" on its comment line; a bench "not TOML".
    airframe = tmp_path / "bom.airframe"
    airframe.write_bytes(BOM + AIRFRAME.read_bytes())
    done = cli("run", str(airframe), "--store", str(tmp_path / "a.store"))
    assert (done.returncode, done.stderr) == (0, "")
    params = tmp_path / "bom.params"
    params.write_bytes(BOM + b"# Onboard parameters\n1\t1\tSYS_AUTOSTART\t4001\t6\n")
    done = cli("param", "--store", str(tmp_path / "a.store"), "import", str(params))
    assert (done.returncode, done.stderr) == (0, "")
    shown = cli("param", "--store", str(tmp_path / "a.store"), "show", "-q", "SYS_AUTOSTART")
    assert shown.stdout == "4001\n"
    plain = tmp_path / "plain.params"
    plain.write_bytes(params.read_bytes()[len(BOM) :])
    with_bom = cli("migrate", str(params), "--json")
    without = cli("migrate", str(plain), "--json")
    assert with_bom.returncode == without.returncode == 0
    assert with_bom.stdout.replace("bom.params", "plain.params") == without.stdout
