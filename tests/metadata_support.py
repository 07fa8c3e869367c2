"""Shared by the metadata tests: a DSDL set with every kind of field, value strategies with
out-of-range numbers, and a C harness that drives the generated header's functions."""

from __future__ import annotations

import math
import shutil
import subprocess
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pytest
from hypothesis import strategies as st
from px4params.gcs.cheader import c_member_name
from shared_data import PARAMETERS_JSON, shared_file

#: A parameter type with every field kind our DSDL has: truncated and signed integers, bool,
#: static and dynamic arrays (of scalars and of structs), a union with primitive, array and
#: struct variants selected by a path default, padding inside and outside nested structs,
#: float16/32/64, and a tail-capable last array. Shared (``@param`` without max_instances).
TST_FILES = {
    "Item.1.0.dsdl": """\
# An item
uint4 p_version
int5 offset
# Offset
# @unit mm
# @min -10
# @max 10
bool enabled
void3
float32 gain
@sealed
""",
    "Choice.1.0.dsdl": """\
# A choice
@union
int12 number
# A number
float64 precise
# A precise number
uint8[<=5] text
# Some text
Item.1.0 item
# An item
@sealed
""",
    "Everything.1.0.dsdl": """\
# Everything
# Every kind of field, shared by all instances.
# @param EVERYTHING_SH
# @group Test

uint4 p_version
truncated uint3 wrap
# Wraps around
# @default 5
int7 signed_value
# @default -3
bool flag
# @default true
uint8[3] triple
Item.1.0[<=3] items
Choice.1.0 choice
# @default item.offset 2
void2
float16[2] pair
truncated float16 loose
uint8[<=4] tail
@sealed
""",
}
TST_KEY = "tst.Everything.1.0"


def write_tst(base: Path) -> Path:
    """Writes the ``tst`` root namespace folder under ``base``; returns it."""
    root = base / "tst"
    root.mkdir(parents=True, exist_ok=True)
    for name, text in TST_FILES.items():
        (root / name).write_text(text, encoding="utf-8")
    return root


def real_parameters_json() -> Path:
    return shared_file(PARAMETERS_JSON)


def require_compilers() -> tuple[str, str]:
    gcc, gxx = shutil.which("gcc"), shutil.which("g++")
    if gcc is None or gxx is None:
        pytest.skip("gcc and g++ are needed to compile the generated header")
    return gcc, gxx


# --- values ---------------------------------------------------------------------------------


def c_width(bits: int) -> int:
    return next(w for w in (8, 16, 32, 64) if bits <= w)


def _plain_nan(value: float) -> float:
    """A NaN with its sign but no payload. The harness reads numbers as text, which carries a
    NaN's sign and not its payload bits, while the Rust codec keeps the bits Python gives it:
    a NaN with a payload would differ for that reason alone, not for a cast mode, which is what
    these tests compare."""
    return math.copysign(math.nan, value) if math.isnan(value) else value


def wide_value_strategy(types: Mapping[str, Any], key: str) -> st.SearchStrategy[Any]:
    """Values whose numbers fill the C members rather than the DSDL fields: integers over the
    whole uint8_t/int16_t/... range, floats over float32 (out-of-range ones included), so that
    encoding has to saturate or truncate."""
    memo: dict[str, st.SearchStrategy[Any]] = {}

    def scalar(spec: Mapping[str, Any]) -> st.SearchStrategy[Any]:
        kind = spec["kind"]
        if kind == "bool":
            return st.booleans()
        bits = int(spec["bits"])
        if kind == "uint":
            return st.integers(0, (1 << c_width(bits)) - 1)
        if kind == "int":
            half = 1 << (c_width(bits) - 1)
            return st.integers(-half, half - 1)
        floats = st.floats(allow_nan=True) if bits == 64 else st.floats(width=32, allow_nan=True)
        return floats.map(_plain_nan)

    def of(spec: Mapping[str, Any]) -> st.SearchStrategy[Any]:
        kind = spec["kind"]
        if kind == "ref":
            return composite(spec["name"])
        if kind == "array":
            return st.lists(of(spec["elem"]), min_size=spec["len"], max_size=spec["len"])
        if kind == "dynarray":
            return st.lists(of(spec["elem"]), max_size=min(spec["max"], 6))
        return scalar(spec)

    def composite(name: str) -> st.SearchStrategy[Any]:
        if name not in memo:
            definition = types[name]
            fields = [f for f in definition["fields"] if f["type"]["kind"] != "void"]
            if definition["kind"] == "union":
                memo[name] = st.one_of(
                    *[of(f["type"]).map(lambda v, n=f["name"]: {n: v}) for f in fields]
                )
            else:
                memo[name] = st.fixed_dictionaries(
                    {f["name"]: of(f["type"]) for f in fields if f["name"] != "p_version"}
                )
        return memo[name]

    return composite(key)


def float_token(value: Any) -> str:
    number = float(value) if not isinstance(value, str) else float(value.lower())
    if math.isnan(number):
        return "-nan" if math.copysign(1.0, number) < 0 else "nan"  # the sign reaches float16
    if math.isinf(number):
        return "inf" if number > 0 else "-inf"
    return number.hex()


def input_tokens(types: Mapping[str, Any], key: str, value: Any) -> list[str]:
    """``value`` as the harness reads it: every field in declaration order, union tags and
    dynamic array lengths before their contents (the ``[k]`` order), p_version included."""
    out: list[str] = []

    def walk(spec: Mapping[str, Any], v: Any) -> None:
        kind = spec["kind"]
        if kind == "ref":
            definition = types[spec["name"]]
            fields = [f for f in definition["fields"] if f["type"]["kind"] != "void"]
            if definition["kind"] == "union":
                ((name, inner),) = v.items()
                out.append(str([f["name"] for f in fields].index(name)))
                walk(next(f["type"] for f in fields if f["name"] == name), inner)
                return
            for f in fields:
                if f["name"] == "p_version" and f["name"] not in v:
                    out.append("0")  # encode fills in the version; the harness reads a token
                else:
                    walk(f["type"], v[f["name"]])
        elif kind in ("array", "dynarray"):
            if kind == "dynarray":
                out.append(str(len(v)))
            for item in v:
                walk(spec["elem"], item)
        elif kind == "bool":
            out.append("1" if v else "0")
        elif kind == "float":
            out.append(float_token(v))
        else:
            out.append(str(int(v)))

    walk({"kind": "ref", "name": key}, value)
    return out


def same_leaf_values(tokens: list[str], leaves: list[Any]) -> bool:
    """The harness's printed values equal the Rust leaves (NaN equals NaN)."""
    if len(tokens) != len(leaves):
        return False
    for token, leaf in zip(tokens, leaves, strict=True):
        if isinstance(leaf.value, float):
            got = float.fromhex(token) if "0x" in token else float(token)
            if not (got == leaf.value or (math.isnan(got) and math.isnan(leaf.value))):
                return False
        elif int(token) != int(leaf.value):
            return False
    return True


# --- the C harness ----------------------------------------------------------------------------


def harness_source(
    types: Mapping[str, Any], header: str, names: Mapping[str, str], tested: list[str]
) -> str:
    """A C program that reads lines ``<type#> <tao> e <tokens>`` (encode the value, then decode
    the bytes) or ``<type#> <tao> d <hex>`` (decode) and prints ``E <n> <hex> D <rc> <tokens>``
    or ``D <rc> <tokens>``. ``names``: every needed type key -> C name, in declaration order."""
    lines = [
        "#include <inttypes.h>",
        "#include <stdio.h>",
        "#include <stdlib.h>",
        f'#include "{header}"',
        "",
        'static char *tok(void) { char *t = strtok(NULL, " \\n"); return t ? t : (char *)"0"; }',
        "static uint64_t rd_u(void) { return strtoull(tok(), NULL, 10); }",
        "static int64_t rd_i(void) { return strtoll(tok(), NULL, 10); }",
        "static double rd_f(void) { return strtod(tok(), NULL); }",
        'static void pu(uint64_t v) { printf(" %" PRIu64, v); }',
        'static void pi(int64_t v) { printf(" %" PRId64, v); }',
        'static void pf(double v) { printf(" %a", v); }',
    ]

    def scalar_io(spec: Mapping[str, Any], expr: str, ctype: str) -> tuple[str, str]:
        kind = spec["kind"]
        if kind == "bool":
            return f"{expr} = rd_u() != 0;", f"pu({expr} ? 1u : 0u);"
        if kind == "uint":
            return f"{expr} = ({ctype})rd_u();", f"pu({expr});"
        if kind == "int":
            return f"{expr} = ({ctype})rd_i();", f"pi({expr});"
        cast = "double" if spec["bits"] == 64 else "float"
        return f"{expr} = ({cast})rd_f();", f"pf((double){expr});"

    def ctype(spec: Mapping[str, Any]) -> str:
        kind = spec["kind"]
        if kind == "bool":
            return "bool"
        if kind == "float":
            return "double" if spec["bits"] == 64 else "float"
        return f"{'u' if kind == 'uint' else ''}int{c_width(int(spec['bits']))}_t"

    def io(spec: Mapping[str, Any], expr: str, depth: int) -> tuple[list[str], list[str]]:
        pad = "    " * depth
        kind = spec["kind"]
        if kind == "ref":
            name = names[spec["name"]]
            return [f"{pad}read_{name}(&{expr});"], [f"{pad}print_{name}(&{expr});"]
        if kind in ("array", "dynarray"):
            var = f"i{depth}"
            if kind == "array":
                count, item = str(spec["len"]), f"{expr}[{var}]"
                read_head: list[str] = []
                print_head: list[str] = []
            else:
                count, item = f"(size_t){expr}.len", f"{expr}.data[{var}]"
                lentype = f"uint{c_width(max(spec['max'].bit_length(), 1))}_t"
                read_head = [f"{pad}{expr}.len = ({lentype})rd_u();"]
                print_head = [f"{pad}pu({expr}.len);"]
            r, p = io(spec["elem"], item, depth + 1)
            loop = f"{pad}for (size_t {var} = 0; {var} < {count}; {var}++) {{"
            return (
                [*read_head, loop, *r, f"{pad}}}"],
                [*print_head, loop, *p, f"{pad}}}"],
            )
        r1, p1 = scalar_io(spec, expr, ctype(spec))
        return [pad + r1], [pad + p1]

    for key, name in names.items():
        definition = types[key]
        fields = [f for f in definition["fields"] if f["type"]["kind"] != "void"]
        reads: list[str] = []
        prints: list[str] = []
        if definition["kind"] == "union":
            reads += ["    m->union_tag = (uint8_t)rd_u();", "    switch (m->union_tag) {"]
            prints += ["    pu(m->union_tag);", "    switch (m->union_tag) {"]
            for i, f in enumerate(fields):
                r, p = io(f["type"], f"m->{c_member_name(f['name'])}", 2)
                reads += [f"    case {i}:", *r, "        break;"]
                prints += [f"    case {i}:", *p, "        break;"]
            reads += ["    default: break;", "    }"]
            prints += ["    default: break;", "    }"]
        else:
            for f in fields:
                r, p = io(f["type"], f"m->{c_member_name(f['name'])}", 1)
                reads += r
                prints += p
        lines += [
            f"static void read_{name}(struct {name} *m) {{",
            "    (void)m;",
            *reads,
            "}",
            f"static void print_{name}(const struct {name} *m) {{",
            "    (void)m;",
            *prints,
            "}",
        ]

    lines += ["static char line[1 << 20];", "static uint8_t buffer[1 << 16];"]
    for number, key in enumerate(tested):
        name = names[key]
        lines += [
            f"static void run{number}(char mode, bool tao) {{",
            f"    static struct {name} m;",
            "    memset(&m, 0, sizeof m);",
            "    size_t size = 0;",
            "    if (mode == 'e') {",
            f"        read_{name}(&m);",
            f"        const int n = {name}_encode(&m, buffer, tao);",
            '        printf("E %d ", n);',
            '        for (int i = 0; i < n; i++) printf("%02x", buffer[i]);',
            '        if (n <= 0) printf("-");',
            "        size = n < 0 ? 0u : (size_t)n;",
            "        memset(&m, 0, sizeof m);",
            "    } else {",
            "        const char *hex = tok();",
            "        if (hex[0] == '-') hex++; /* '-' stands for no bytes */",
            "        while (hex[0] && hex[1]) {",
            "            unsigned byte = 0;",
            '            sscanf(hex, "%2x", &byte);',
            "            buffer[size++] = (uint8_t)byte;",
            "            hex += 2;",
            "        }",
            "    }",
            f"    const int rc = {name}_decode(buffer, size, &m, tao);",
            '    printf(" D %d", rc);',
            f"    if (rc >= 0) print_{name}(&m);",
            '    printf("\\n");',
            "}",
        ]
    lines += [
        "int main(void) {",
        "    while (fgets(line, sizeof line, stdin)) {",
        '        const int type = atoi(strtok(line, " \\n"));',
        "        const bool tao = rd_u() != 0;",
        "        const char mode = tok()[0];",
        "        switch (type) {",
        *[f"        case {n}: run{n}(mode, tao); break;" for n in range(len(tested))],
        '        default: printf("?\\n");',
        "        }",
        "        fflush(stdout);",
        "    }",
        "    return 0;",
        "}",
        "",
    ]
    return "\n".join(lines)


class Harness:
    """The compiled harness, kept running: one line in, one line out."""

    def __init__(self, executable: Path, tested: list[str]) -> None:
        self.index = {key: n for n, key in enumerate(tested)}
        self.proc = subprocess.Popen(
            [str(executable)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            bufsize=1,
        )

    def _ask(self, line: str) -> list[str]:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        return self.proc.stdout.readline().split()

    def encode(self, key: str, tokens: list[str], tao: bool) -> tuple[bytes, int, list[str]]:
        """(C's encoding, C's decode result for it, the decoded values)."""
        out = self._ask(f"{self.index[key]} {int(tao)} e {' '.join(tokens)}")
        assert out[0] == "E" and out[3] == "D", out
        return bytes.fromhex(out[2].strip("-")), int(out[4]), out[5:]

    def encode_status(self, key: str, tokens: list[str], tao: bool) -> int:
        out = self._ask(f"{self.index[key]} {int(tao)} e {' '.join(tokens)}")
        return int(out[1])

    def decode(self, key: str, data: bytes, tao: bool) -> tuple[int, list[str]]:
        out = self._ask(f"{self.index[key]} {int(tao)} d {data.hex() or '-'}")
        assert out[0] == "D", out
        return int(out[1]), out[2:]

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait(timeout=10)
