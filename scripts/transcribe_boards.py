"""Write python/px4params/data/boards.toml from PX4-Autopilot git trees (a maintainer's tool).

Reads, at each snapshot, every ``boards/<vendor>/<model>/init/rc.board_sensors`` with the
board's ``src/i2c.cpp`` (or ``src/board_config.h``) and ``ROMFS/px4fmu_common/init.d/rc.sensors``
(where i2c.cpp numbers buses from 0, as on NXP's Kinetis and S32K, also the board's NuttX
defconfig and its chip's ``PX4_BUS_OFFSET``, which PX4 adds to make them its own; where the
board's scripts start a driver with ``-S``, its ``src/spi.cpp`` and the chip's ``SPI::Bus``
numbers, which ``-S -b N`` counts through), and writes
the facts in px4params' own format: which drivers start, on which bus, with which options, under
which shell conditions. Nothing of PX4's text is copied but driver names, options and
conditions. A board's consecutive snapshots with the same facts share one row.

    python scripts/transcribe_boards.py OUT.toml \\
        v1.14.0=/path/PX4-Autopilot.git@v1.14.0:"tag v1.14.0" ... main=/path@<sha>:"branch main"

tests/test_boards.py checks every row against the line it cites where the git dirs are at hand.
The kinds of sensors (KINDS), the labels and the i2c_launcher's table are written by hand.
"""

from __future__ import annotations

import json
import re
import shlex
import subprocess
import sys
from collections.abc import Iterable
from typing import Any

KINDS: dict[str, str] = {
    **dict.fromkeys(
        [
            "ak09916",
            "ak09940a",
            "ak8963",
            "bmm150",
            "bmm350",
            "hmc5883",
            "iis2mdc",
            "ist8308",
            "ist8310",
            "lis2mdl",
            "lis3mdl",
            "lsm303agr",
            "mmc5983ma",
            "qmc5883",
            "qmc5883l",
            "qmc5883p",
            "rm3100",
        ],
        "mag",
    ),
    **dict.fromkeys(
        [
            "bmp280",
            "bmp388",
            "bmp581",
            "dps310",
            "icp201xx",
            "lps22hb",
            "lps25h",
            "mpc2520",
            "mpl3115a2",
            "ms5611",
            "spa06",
            "spl06",
        ],
        "baro",
    ),
    **dict.fromkeys(
        [
            "adis16448",
            "adis16470",
            "adis16477",
            "adis16497",
            "adis16507",
            "adis16607",
            "bmi055",
            "bmi085",
            "bmi088",
            "bmi088_i2c",
            "bmi270",
            "fxas21002c",
            "fxos8701cq",
            "icm20602",
            "icm20608g",
            "icm20649",
            "icm20689",
            "icm20948",
            "icm42605",
            "icm42670p",
            "icm42688p",
            "icm45686",
            "iim42652",
            "iim42653",
            "ism330dlc",
            "l3gd20",
            "lsm303d",
            "lsm6dsv",
            "mpu6000",
            "mpu6500",
            "mpu9250",
            "mpu9250_i2c",
            "sch16t",
        ],
        "imu",
    ),
    **dict.fromkeys(["ina226", "ina228", "ina238", "voxlpm", "batt_smbus", "batmon"], "power"),
}
#: Started without being a device on a bus, or on a serial, PWM or GPIO line.
NOT_BUS_DEVICES = set(
    [
        "adc",
        "aerofc_adc",
        "board_adc",
        "i2c_launcher",
        "gps",
        "teseo_gps",
        "voxl_esc",
        "modal_io",
        "pwm_input",
        "ll40ls_pwm",
        "pga460",
        "srf05",
        "safety_button",
        "heater",
        "sensors",
        "pps_capture",
        "auterion_autostarter",
        "neopixel",
        "afbrs50",
        "pm_selector_auterion",
        "pca9685_pwm_out",
        "rgbled_apa102",
    ]
)
#: Drivers whose -M ("Enable Magnetometer") also starts a compass.
WITH_MAGNETOMETER = ("icm20948", "mpu9250")
LABELS = {
    "px4_fmu-v2": "Pixhawk 1 (FMUv2)",
    "px4_fmu-v3": "Pixhawk 2 / Pixhawk 1 2MB (FMUv3)",
    "px4_fmu-v4": "Pixracer (FMUv4)",
    "px4_fmu-v4pro": "Pixhawk 3 Pro (FMUv4-Pro)",
    "px4_fmu-v5": "Pixhawk 4 (FMUv5)",
    "px4_fmu-v5x": "Pixhawk 5X (FMUv5X)",
    "px4_fmu-v6c": "Pixhawk 6C (FMUv6C)",
    "px4_fmu-v6u": "FMUv6U",
    "px4_fmu-v6x": "Pixhawk 6X (FMUv6X)",
    "px4_fmu-v6xrt": "Pixhawk 6X-RT (FMUv6X-RT)",
    "cubepilot_cubeorange": "CubePilot Cube Orange",
    "cubepilot_cubeorangeplus": "CubePilot Cube Orange+",
    "cubepilot_cubeyellow": "CubePilot Cube Yellow",
    "cuav_nora": "CUAV Nora",
    "cuav_x7pro": "CUAV X7 Pro",
    "cuav_7-nano": "CUAV 7-Nano",
    "cuav_fmu-v6x": "CUAV Pixhawk V6X",
    "holybro_durandal-v1": "Holybro Durandal",
    "holybro_pix32v5": "Holybro Pix32 v5",
    "holybro_kakutef7": "Holybro Kakute F7",
    "holybro_kakuteh7": "Holybro Kakute H7",
    "ark_fmu-v6x": "ARK FMUv6X",
    "ark_pi6x": "ARK Pi6X",
    "modalai_fc-v1": "ModalAI Flight Core v1",
    "modalai_fc-v2": "ModalAI Flight Core v2",
    "nxp_fmuk66-v3": "NXP FMUK66 v3",
    "nxp_mr-tropic": "NXP MR-Tropic",
    "nxp_tropic-community": "NXP Tropic Community",
    "nxp_mr-canhubk3": "NXP MR-CANHUBK3",
}
#: BOARD_NAME of src/drivers/boards/<board>/board_config.h before the boards/ folder (v1.7.3).
LEGACY_VER_HW = {
    "px4_fmu-v2": ["PX4FMU_V2"],
    "px4_fmu-v4": ["PX4FMU_V4"],
    "px4_fmu-v4pro": ["PX4FMU_V4PRO"],
    "px4_fmu-v5": ["PX4FMU_V5"],
}
#: src/systemcmds/i2c_launcher, read by hand: (releases, args, [(driver, address, line)]).
LAUNCHER = (
    (
        ["v1.15.0"],
        "-X -b {bus} -t {bus} start",
        "i2c_launcher.cpp line 166: the battery index is the bus",
        [("ina226", 0x41, 74), ("ina228", 0x45, 75), ("ina238", 0x45, 76)],
    ),
    (
        ["v1.18", "main"],
        "-X -b {bus} -t {index} start",
        "i2c_launcher.cpp line 172; {index}: its -t option, else the bus",
        [("ina226", 0x41, 76), ("ina228", 0x45, 77), ("ina238", 0x45, 78)],
    ),
)
#: Options that take a value (when the next word is not an option or a verb).
VALUE_FLAGS = {"-b", "-a", "-R", "-t", "-c", "-f", "-m", "-T", "-M", "-C", "-i", "-d", "-r", "-o"}
SHELL_ONLY = ("set", "unset", "param", "echo", "sh", ".", "usleep", "mft")
START_KEYS = ["driver", "kind", "bus_kind", "bus", "address", "rotation", "internal", "args"]
DEVICE_KEYS = [*START_KEYS, "when", "line"]
SWITCH_KEYS = ["param", *DEVICE_KEYS]


# -- reading the shell scripts -------------------------------------------------------------------


def strip_comment(line: str) -> str:
    """The line without its ``#`` comment (a ``#`` inside quotes stays)."""
    out, quote = [], ""
    for ch in line:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#":
            break
        out.append(ch)
    return "".join(out).strip()


def condition(words: list[str]) -> str:
    """An ``if``'s test in the table's words (``hw_type in A,B``, ``P == 1``, ``$V == yes``)."""
    negated = bool(words) and words[0] == "!"
    w = words[1:] if negated else words
    if w[:2] == ["ver", "hwtypecmp"]:
        text = "hw_type in " + ",".join(w[2:])
    elif w[:2] == ["ver", "hwbasecmp"]:
        text = "hw_base in " + ",".join(w[2:])
    elif w[:2] == ["ver", "hwcmp"]:
        text = "board in " + ",".join(w[2:])
    elif w[:2] in (["param", "compare"], ["param", "greater"]):
        name, value = [x for x in w[2:] if x != "-s"][:2]
        text = f"{name} {'==' if w[1] == 'compare' else '>'} {value}"
    elif w and w[0] == "[":
        text = " ".join(x.replace("${", "$").replace("}", "") for x in w[1:-1])
        text = text.replace(" = ", " == ")
    elif "start" in w:
        text = f"{w[0]} started ({' '.join(w[1:])})"
    else:
        text = " ".join(w)
    return "not " + text if negated else text


def negate(text: str) -> str:
    return text[4:] if text.startswith("not ") else "not " + text


def options(words: list[str]) -> dict[str, Any]:
    """A start command's driver, options with values, bare flags and options as written."""
    found: dict[str, Any] = {"driver": words[0], "args": " ".join(words[1:]), "flags": set()}
    i = 1
    while i < len(words):
        word = words[i]
        value = words[i + 1] if i + 1 < len(words) else ""
        if word in VALUE_FLAGS and value and not value.startswith("-") and value != "start":
            found[word] = value
            i += 2
            continue
        if word.startswith("-"):
            found["flags"].add(word)
        i += 1
    return found


def starts(text: str) -> list[tuple[int, list[str], list[str]]]:
    """Every ``... start`` command of a script: (line, words, conditions around it)."""
    stack: list[str] = []
    found = []
    for number, raw in enumerate(text.split("\n"), 1):
        for part in strip_comment(raw).split(";"):
            try:
                words = shlex.split(part)
            except ValueError:
                words = part.split()
            if not words:
                continue
            head = words[0]
            if head == "if":
                test = words[1:]
                if "start" in test:  # `if ! drv start`: the start happens, the body is a fallback
                    command = test[1:] if test[0] == "!" else test
                    found.append((number, command, list(stack)))
                stack.append(condition(test))
            elif head == "elif":
                stack[-1] = negate(stack[-1]) + " and " + condition(words[1:])
            elif head == "else":
                stack[-1] = negate(stack[-1])
            elif head == "fi":
                if stack:  # px4_fmu-v6xrt at v1.15.0 has one fi too many
                    stack.pop()
            elif head in SHELL_ONLY or head == "then":
                continue
            elif "start" in words:
                found.append((number, words, list(stack)))
    return found


def switch_param(text: str) -> str | None:
    body = text.removeprefix("not ")
    match = re.match(r"([A-Z][A-Z0-9_]+) (==|>) ", body)
    return match.group(1) if match else None


def launcher_keys(path: str, launcher: list[tuple[int, str, int]]) -> list[str]:
    """A board row's ``i2c_launcher_*`` keys from its script's launcher starts (bus,
    conditions, line). A bus started twice is refused: the table cites one line per bus, and
    the later line would stand for both."""
    launched = sorted(launcher)
    buses = [b for b, _, _ in launched]
    twice = [b for b in dict.fromkeys(buses) if buses.count(b) > 1]
    if twice:
        lines = ", ".join(str(n) for n in sorted(n for b, _, n in launched if b == twice[0]))
        raise AssertionError(
            f"{path}: 'i2c_launcher start -b {twice[0]}' on lines {lines}: the board table "
            "cites one line per launcher bus"
        )
    keys = [f"i2c_launcher_buses = {json.dumps(buses)}"]
    if launched:
        keys += [f"i2c_launcher_lines = {json.dumps([n for _, _, n in launched])}"]
    when = "; ".join(f"bus {b}: {c}" for b, c, _ in launcher if c)
    if when:
        keys += [f"i2c_launcher_when = {json.dumps(when)}"]
    return keys


def facts(
    text: str,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]], list[tuple[int, str, int]]]:
    """A script's devices, switch starts and ``i2c_launcher`` (bus, conditions, line)."""
    devices: list[dict[str, Any]] = []
    switches: list[dict[str, Any]] = []
    launcher: list[tuple[int, str, int]] = []
    for number, words, conditions in starts(text):
        opts = options(words)
        driver, flags = words[0], opts["flags"]
        if driver == "i2c_launcher":
            if "-b" in opts:
                launcher.append((int(opts["-b"]), " and ".join(conditions), number))
            continue
        if driver in NOT_BUS_DEVICES:
            continue
        if flags & {"-s", "-S"}:
            bus_kind, internal = "SPI", "-s" in flags
        elif flags & {"-I", "-X"}:
            bus_kind, internal = "I2C", "-I" in flags
        else:
            print(f"left out (no bus option): {' '.join(words)}", file=sys.stderr)
            continue
        row = {
            "driver": driver,
            "kind": KINDS.get(driver, "other"),
            "bus_kind": bus_kind,
            "bus": int(opts["-b"]) if opts.get("-b", "").isdigit() else None,
            "address": int(opts["-a"], 0) if "-a" in opts else None,
            "rotation": int(opts["-R"]) if "-R" in opts else None,
            "internal": internal,
            "args": opts["args"],
            "when": " and ".join(conditions),
            "line": number,
        }
        params = [p for p in map(switch_param, conditions) if p]
        positive = [switch_param(c) for c in conditions if switch_param(c) and c[:4] != "not "]
        rows = switches if params else devices
        if params:
            row = {"param": (positive or params)[0], **row}
        rows.append(row)
        if driver in WITH_MAGNETOMETER and "-M" in flags:
            rows.append(dict(row, kind="mag"))
    return devices, switches, launcher


# initI2CBusExternal(N), or initI2CBusExternal(PX4_BUS_NUMBER_TO_PX4(N)) on chips that number
# their buses from 0 (the macro adds the chip's PX4_BUS_OFFSET: PX4 numbers buses from 1).
_I2C_BUS = re.compile(r"initI2CBus(External|Internal)\((?:PX4_BUS_NUMBER_TO_PX4\((\d+)\)|(\d+))\)")


def i2c_buses(
    files: dict[str, str], offsets: dict[str, tuple[int, str]]
) -> tuple[list[int], list[int], str, str, list[int]]:
    """A board's external and internal I2C buses, the file they come from, where the bus
    offset they needed comes from ("" when none was needed), and the line of each of the
    external then the internal buses in that file (the first that names it)."""
    external: dict[int, int] = {}  # bus -> line
    internal: dict[int, int] = {}
    offset_source = ""
    if "src/i2c.cpp" not in files:
        text, name = files.get("src/board_config.h", ""), "src/board_config.h"
        for m in re.finditer(r"#define\s+PX4_I2C_BUS_(EXPANSION\d*|ONBOARD)\s+(\d+)\b", text):
            kind = internal if m[1] == "ONBOARD" else external
            kind.setdefault(int(m[2]), text.count("\n", 0, m.start()) + 1)
        name = name if external or internal else ""
    else:
        text, name = files["src/i2c.cpp"], "src/i2c.cpp"
        for m in _I2C_BUS.finditer(text):
            kind_name, from_zero, number = m.groups()
            if from_zero:
                offset, offset_source = chip_bus_offset(files, offsets)
                bus = int(from_zero) + offset
            else:
                bus = int(number)
            kind = external if kind_name == "External" else internal
            kind.setdefault(bus, text.count("\n", 0, m.start()) + 1)
    lines = [external[b] for b in sorted(external)] + [internal[b] for b in sorted(internal)]
    return sorted(external), sorted(internal), name, offset_source, lines


#: What a board's ``board_get_hw_version()`` compares equal to, as ``ver hwtypecmp`` names the
#: same hardware (read by hand in boards/px4/fmu-v3/src/init.c at the snapshots, fmu-v2's the
#: same file: ``HW_VER_FMUV3`` is ``HW_VER_SIMPLE(HW_VER_FMUV3_STATE)`` (board_common.h) and
#: the version ``HW_VER_SIMPLE(hw_version)``; the one state is the one that makes the hardware
#: type "V30": ``case HW_VER_FMUV3_STATE: hw_type[1]++; hw_type[2] = '0'``, and a Pixhack v3
#: forced to it alike, lines 388-390 and 412-414 at main).
HW_VERSION_TYPES = {"HW_VER_FMUV3": "V30"}
# The one form of a board's own px4_i2c_bus_external read: every bus external on one hardware
# version, else every bus but one (fmu-v2 and fmu-v3; `bus.bus` before v1.14.0).
_OVERRIDE = re.compile(
    r"bool px4_i2c_bus_external\((?:const px4_i2c_bus_t &bus|int bus)\)\s*\{\s*"
    r"if \((?P<version>\w+) == board_get_hw_version\(\)\) \{\s*(?:/\*[^*]*\*/\s*)?"
    r"return true;\s*\} else \{\s*if \(bus(?:\.bus)? != (?P<bus>\d+)\) \{\s*return true;\s*\}"
    r"\s*\}\s*return false;\s*\}"
)


def bus_override(
    files: dict[str, str], external: list[int], internal: list[int]
) -> dict[str, Any] | None:
    """``external_i2c_buses_when`` of a board whose board_config.h defines
    BOARD_OVERRIDE_I2C_BUS_EXTERNAL: the hardware type under which every bus is external, and
    the line of that test in src/i2c.cpp; refused where its i2c.cpp says anything else (or its
    other branch is not the lists)."""
    config = files.get("src/board_config.h", "")
    if not re.search(r"^#define\s+BOARD_OVERRIDE_I2C_BUS_EXTERNAL\b", config, re.M):
        return None
    text = files.get("src/i2c.cpp", "")
    found = _OVERRIDE.search(text)
    where = f"{files['path']}: src/board_config.h defines BOARD_OVERRIDE_I2C_BUS_EXTERNAL"
    if found is None:
        raise SystemExit(
            f"{where}, but its src/i2c.cpp's px4_i2c_bus_external is not 'if (HW_VER_... == "
            "board_get_hw_version()) every bus external, else every bus but one'"
        )
    version, bus = found["version"], int(found["bus"])
    if version not in HW_VERSION_TYPES:
        raise SystemExit(
            f"{where}: no hardware type known for {version} ({list(HW_VERSION_TYPES)})"
        )
    every = sorted({*external, *internal})
    if internal != [bus] or external != [b for b in every if b != bus]:
        raise SystemExit(
            f"{where}: elsewhere every bus but {bus} is external, not src/i2c.cpp's lists "
            f"(external {external}, internal {internal})"
        )
    line = text.count("\n", 0, text.index("if (", found.start())) + 1
    return {"when": f"hw_type in {HW_VERSION_TYPES[version]}", "buses": every, "line": line}


def chip_bus_offset(files: dict[str, str], offsets: dict[str, tuple[int, str]]) -> tuple[int, str]:
    """The board's chip's PX4_BUS_OFFSET: the first chip flag of PX4's list (the order its
    CMake tests them in) that the board's NuttX defconfig sets."""
    config = files.get("nuttx-config/nsh/defconfig", "")
    chosen = set(re.findall(r"^(CONFIG_\w+)=y$", config, re.M))
    for flag, (offset, source) in offsets.items():
        if flag in chosen:
            return offset, f"{source} (PX4_BUS_OFFSET {offset}, {flag})"
    raise SystemExit(
        f"{files['path']}: src/i2c.cpp numbers buses with PX4_BUS_NUMBER_TO_PX4, but no chip flag "
        f"of its nuttx-config/nsh/defconfig has a PX4_BUS_OFFSET (expected one of {list(offsets)})"
    )


def bus_offsets(git_dir: str, commit: str) -> dict[str, tuple[int, str]]:
    """{NuttX chip flag: (PX4_BUS_OFFSET, the micro_hal.h defining it)}, in the order PX4's CMake
    (px4_os_determine_build_chip) tests the flags; chips whose header defines none are left out."""
    cmake = git(git_dir, "show", f"{commit}:platforms/nuttx/cmake/px4_impl_os.cmake") or ""
    chips = re.findall(
        r"\((CONFIG_\w+)\)\s*set\(CHIP_MANUFACTURER \"(\w+)\"\)\s*set\(CHIP \"(\w+)\"\)", cmake
    )
    offsets: dict[str, tuple[int, str]] = {}
    for flag, maker, chip in chips:
        path = f"platforms/nuttx/src/px4/{maker}/{chip}/include/px4_arch/micro_hal.h"
        header = git(git_dir, "show", f"{commit}:{path}") or ""
        defined = re.search(r"^#define\s+PX4_BUS_OFFSET\s+(\d+)", header, re.M)
        if defined:
            offsets[flag] = (int(defined.group(1)), path)
    return offsets


#: {(NuttX chip flag, chip): ({SPI::Bus name: PX4's bus number}, the hw_description.h defining
#: them)}
Chips = dict[tuple[str, str], tuple[dict[str, int], str]]
_SPI_ENUM = re.compile(r"namespace SPI\s*\{.*?enum class Bus\s*\{(?P<names>[^}]*)\}", re.S)
_INCLUDED = re.compile(r'#include "\.\./\.\./\.\./(\w+)/include/px4_arch/hw_description\.h"')


def spi_bus_numbers(git_dir: str, commit: str) -> Chips:
    """Each chip's ``SPI::Bus`` enum (its ``hw_description.h``, or the common one it includes),
    the numbers PX4 gives an spi.cpp's buses, in the order PX4's CMake tests the chip flags."""
    cmake = git(git_dir, "show", f"{commit}:platforms/nuttx/cmake/px4_impl_os.cmake") or ""
    chips = re.findall(
        r"\((CONFIG_\w+)\)\s*set\(CHIP_MANUFACTURER \"(\w+)\"\)\s*set\(CHIP \"(\w+)\"\)", cmake
    )
    found: Chips = {}
    for flag, maker, chip in chips:
        path = f"platforms/nuttx/src/px4/{maker}/{chip}/include/px4_arch/hw_description.h"
        header = git(git_dir, "show", f"{commit}:{path}") or ""
        included = _INCLUDED.search(header)
        if not _SPI_ENUM.search(header) and included:
            path = path.replace(f"/{chip}/", f"/{included[1]}/")
            header = git(git_dir, "show", f"{commit}:{path}") or ""
        enum = _SPI_ENUM.search(header)
        if enum is None:
            continue
        numbers, value = {}, 0
        for item in enum["names"].split(","):
            name, _, given = (part.strip() for part in item.partition("="))
            if not name:
                continue
            value = int(given) if given else value + 1
            numbers[name] = value
        found[flag, chip] = (numbers, path)
    return found


_SPI_BUS = re.compile(r"initSPIBus(External)?\(SPI::Bus::(\w+)")


def spi_buses(files: dict[str, str], chips: Chips) -> dict[str, Any] | None:
    """A board's external SPI buses in the order of its ``px4_spi_buses`` (PX4's SPIBusIterator
    counts them for ``-S -b N``), with the line of each in src/spi.cpp and the header numbering
    them; None where it has no spi.cpp or one table per hardware revision (not read here)."""
    text = files.get("src/spi.cpp")
    if text is None or "px4_spi_buses_all_hw" in text:
        return None
    config = files.get("nuttx-config/nsh/defconfig", "")
    chosen = set(re.findall(r"^(CONFIG_\w+)=y$", config, re.M))
    # The flag PX4's CMake tests, else (a flag Kconfig derives, such as CONFIG_STM32_STM32F4XXX)
    # the chip the defconfig names: CONFIG_ARCH_CHIP_STM32F412CE is an stm32f4.
    named = [f.removeprefix("CONFIG_ARCH_CHIP_").lower() for f in chosen]
    chip = next((c for c in chips if c[0] in chosen), None) or next(
        (c for c in chips if any(n.startswith(c[1]) for n in named)), None
    )
    if chip is None:
        raise SystemExit(
            f"{files['path']}: no chip flag of its nuttx-config/nsh/defconfig has an SPI::Bus "
            f"enum (expected one of {[flag for flag, _ in chips]})"
        )
    numbers, source = chips[chip]
    buses, lines = [], []
    for m in _SPI_BUS.finditer(text):
        if m[1]:
            if m[2] not in numbers:
                raise SystemExit(
                    f"{files['path']}: src/spi.cpp's SPI::Bus::{m[2]} is not in {source}"
                )
            buses.append(numbers[m[2]])
            lines.append(text.count("\n", 0, m.start()) + 1)
    return {"buses": buses, "lines": lines, "source": source}


# -- reading the trees ---------------------------------------------------------------------------


def git(git_dir: str, *args: str) -> str | None:
    done = subprocess.run(
        ["git", f"--git-dir={git_dir}", *args], capture_output=True, text=True, check=False
    )
    return done.stdout if done.returncode == 0 else None


# I2CBusIterator::next's -X case where -b counts external buses (v1.11.0; PX4 787f9c1213, first
# in v1.12.0, made it the bus number: `_bus == bus_data.bus`)
_X_B_COUNTS = re.compile(r"if \(_bus == _external_bus_counter \|\| _bus == -1\)")


def x_b_counts_external(git_dir: str, commit: str) -> bool:
    """Whether the tree's platforms/common/i2c.cpp takes ``-X -b N`` as the N-th external bus."""
    text = git(git_dir, "show", f"{commit}:platforms/common/i2c.cpp")
    if text is None or "I2CBusIterator::next" not in text:
        raise SystemExit(f"{git_dir}@{commit}: no I2CBusIterator::next in platforms/common/i2c.cpp")
    return _X_B_COUNTS.search(text) is not None


def read_snapshot(
    git_dir: str, rev: str
) -> tuple[str, str, bool, str, dict[str, dict[str, str]], dict[str, tuple[int, str]], Chips]:
    """(commit, date, whether -X -b counts external buses, rc.sensors, {board: {file: text}},
    the chips' bus offsets, the chips' SPI bus numbers) of one tree."""
    commit = (git(git_dir, "rev-parse", f"{rev}^{{commit}}") or "").strip()
    if not commit:
        raise SystemExit(f"{git_dir}: no commit {rev!r}")
    date = (git(git_dir, "log", "-1", "--format=%cs", commit) or "").strip()
    rc_sensors = git(git_dir, "show", f"{commit}:ROMFS/px4fmu_common/init.d/rc.sensors") or ""
    boards: dict[str, dict[str, str]] = {}
    for path in (git(git_dir, "ls-tree", "-r", "--name-only", commit, "boards") or "").split():
        if not path.endswith("/init/rc.board_sensors"):
            continue
        folder = path.removesuffix("/init/rc.board_sensors")
        _, vendor, model = folder.split("/")
        files = {"path": path, "init/rc.board_sensors": git(git_dir, "show", f"{commit}:{path}")}
        extras = ("src/i2c.cpp", "src/spi.cpp", "src/board_config.h", "nuttx-config/nsh/defconfig")
        for extra in extras:
            text = git(git_dir, "show", f"{commit}:{folder}/{extra}")
            if text is not None:
                files[extra] = text
        boards[f"{vendor}_{model}"] = files  # type: ignore[assignment]
    counts = x_b_counts_external(git_dir, commit)
    offsets, spi = bus_offsets(git_dir, commit), spi_bus_numbers(git_dir, commit)
    return commit, date, counts, rc_sensors, boards, offsets, spi


# -- writing TOML ----------------------------------------------------------------------------------


def inline(row: dict[str, Any], keys: Iterable[str]) -> str:
    parts = []
    for key in keys:
        value = row.get(key)
        if value is None or value == "":
            continue
        if isinstance(value, bool):
            parts.append(f"{key} = {'true' if value else 'false'}")
        elif key == "address":
            parts.append(f"{key} = 0x{value:02x}")
        elif isinstance(value, int):
            parts.append(f"{key} = {value}")
        else:
            parts.append(f"{key} = {json.dumps(value)}")
    return "{ " + ", ".join(parts) + " }"


def same(rows: list[dict[str, Any]]) -> str:
    """What two snapshots must share to be one row (not the line numbers)."""
    return json.dumps([{k: v for k, v in r.items() if k != "line"} for r in rows], sort_keys=True)


def main(argv: list[str]) -> None:
    if len(argv) < 2:
        raise SystemExit(__doc__)
    out_path, specs = argv[0], argv[1:]
    snapshots = []
    for spec in specs:
        match = re.fullmatch(r"([^=]+)=([^@]+)@([^:]+):(.+)", spec)
        if not match:
            raise SystemExit(f"{spec!r} is not RELEASE=GITDIR@REV:REF")
        release, git_dir, rev, ref = match.groups()
        snapshots.append((release, ref, *read_snapshot(git_dir, rev)))

    out: list[str] = [
        "# PX4 boards: what each board's startup script starts, per PX4 release.",
        "#",
        "# Facts transcribed from PX4-Autopilot (github.com/PX4/PX4-Autopilot) at the snapshots",
        "# below by scripts/transcribe_boards.py; the format and the wording are px4params' own.",
        "# Read by px4params.vehicle.boards (its docstring describes every key). A [[board]] row",
        "# holds one board over the snapshots in `releases` during which its facts did not",
        "# change; `line` is the line of the start command in the newest of them.",
        "",
    ]
    for release, ref, commit, date, counts, *_ in snapshots:
        out += ["[[snapshot]]", f"release = {json.dumps(release)}", f"ref = {json.dumps(ref)}"]
        out += [f"commit = {json.dumps(commit)}", f"date = {json.dumps(date)}"]
        out += ["x_b_counts_external = true", ""] if counts else [""]

    for releases, args, note, probes in LAUNCHER:
        out += ["[[i2c_launcher]]", f"releases = {json.dumps(releases)}"]
        out += ['path = "src/systemcmds/i2c_launcher/i2c_launcher.hpp"']
        out += [f"args = {json.dumps(args)}  # {note}", "probe = ["]
        for driver, address, line in probes:
            probe = {"driver": driver, "kind": "power", "address": address, "line": line}
            out.append(f"  {inline(probe, ['driver', 'kind', 'address', 'line'])},")
        out += ["]", ""]

    groups: list[tuple[str, list[str], list[dict[str, Any]]]] = []
    for release, _, _, _, _, rc_sensors, *_ in snapshots:
        devices, switches, _ = facts(rc_sensors)
        assert not devices, devices  # rc.sensors starts by switch only (v1.11.0 .. main)
        if groups and groups[-1][0] == same(switches):
            groups[-1][1].append(release)
            groups[-1] = (groups[-1][0], groups[-1][1], switches)
        else:
            groups.append((same(switches), [release], switches))
    for _, releases, switches in groups:
        out += ["[[rc_sensors]]", f"releases = {json.dumps(releases)}"]
        out += ['path = "ROMFS/px4fmu_common/init.d/rc.sensors"', "switch = ["]
        out += [f"  {inline(r, SWITCH_KEYS)}," for r in switches]
        out += ["]", ""]

    names = sorted({name for *_, boards, _, _ in snapshots for name in boards})
    for name in names:
        rows: list[dict[str, Any] | None] = []
        for release, _, _, _, _, _, boards, offsets, spi_numbers in snapshots:
            files = boards.get(name)
            if files is None:
                rows.append(None)
                continue
            devices, switches, launcher = facts(files["init/rc.board_sensors"])
            external, internal, buses_file, offset_source, bus_lines = i2c_buses(files, offsets)
            override = bus_override(files, external, internal)
            buses = [(bus, when) for bus, when, _ in launcher]  # not the line numbers
            unlined = {k: v for k, v in (override or {}).items() if k != "line"}
            spi = None
            if any(r["bus_kind"] == "SPI" and not r["internal"] for r in devices + switches):
                spi = spi_buses(files, spi_numbers)
            spi_key = spi and [spi["buses"], spi["source"]]
            key = same(devices + switches) + json.dumps([buses, external, internal, unlined])
            key += json.dumps(spi_key)
            last = rows[-1] if rows else None
            if last is not None and last["key"] == key:
                last["releases"].append(release)
                last.update(devices=devices, switches=switches, launcher=launcher)
                last.update(override=override, bus_lines=bus_lines, spi=spi)
            else:
                rows.append(
                    {
                        "key": key,
                        "releases": [release],
                        "devices": devices,
                        "switches": switches,
                        "launcher": launcher,
                        "external": external,
                        "internal": internal,
                        "path": files["path"],
                        "buses_file": buses_file,
                        "offset_source": offset_source,
                        "override": override,
                        "bus_lines": bus_lines,
                        "spi": spi,
                    }
                )
        for row in rows:
            if row is None:
                continue
            vendor, model = name.split("_", 1)
            ver_hw = [name.upper().replace("-", "_"), *LEGACY_VER_HW.get(name, [])]
            out += ["[[board]]", f"name = {json.dumps(name)}"]
            out += [f"label = {json.dumps(LABELS.get(name, f'{vendor} {model}'))}"]
            out += [f"ver_hw = {json.dumps(ver_hw)}", f"releases = {json.dumps(row['releases'])}"]
            out += [f"path = {json.dumps(row['path'])}"]
            if row["offset_source"]:
                # i2c.cpp numbers these buses from 0 (PX4_BUS_NUMBER_TO_PX4): PX4's numbers here.
                out += [f"# buses: src/i2c.cpp's numbers + {row['offset_source']}"]
            out += [f"external_i2c_buses = {json.dumps(row['external'])}"]
            out += [f"internal_i2c_buses = {json.dumps(row['internal'])}"]
            if row["buses_file"]:
                folder = row["path"].removesuffix("init/rc.board_sensors")
                out += [f"i2c_buses_path = {json.dumps(folder + row['buses_file'])}"]
                out += [f"i2c_buses_lines = {json.dumps(row['bus_lines'])}"]
            if row["override"]:
                # px4_i2c_bus_external is the board's own (BOARD_OVERRIDE_I2C_BUS_EXTERNAL)
                keys = ["when", "buses", "line"]
                out += [f"external_i2c_buses_when = {inline(row['override'], keys)}"]
            if row["spi"]:
                # -S -b N: the N-th of these (-S alone: the first), PX4's numbers (SPI::Bus)
                folder = row["path"].removesuffix("init/rc.board_sensors")
                out += [
                    f"# SPI buses: spi.cpp's SPI::Bus names, numbered by {row['spi']['source']}"
                ]
                out += [f"external_spi_buses = {json.dumps(row['spi']['buses'])}"]
                out += [f"spi_buses_path = {json.dumps(folder + 'src/spi.cpp')}"]
                out += [f"spi_buses_lines = {json.dumps(row['spi']['lines'])}"]
            out += launcher_keys(row["path"], row["launcher"])
            out += ["device = ["] + [f"  {inline(r, DEVICE_KEYS)}," for r in row["devices"]]
            out += ["]", "switch = ["] + [f"  {inline(r, SWITCH_KEYS)}," for r in row["switches"]]
            out += ["]", ""]
    with open(out_path, "w", encoding="utf-8") as f:
        f.write("\n".join(out))


if __name__ == "__main__":
    main(sys.argv[1:])
