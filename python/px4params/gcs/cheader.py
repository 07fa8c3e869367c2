"""A C header for firmware: one struct per parameter type, sizes, instance counts, parameter
identifiers, and C functions that encode and decode the structs with the DroneCAN rules.

The talk's shape::

    struct px_Ina238 { uint8_t p_version; struct px_Bus bus; uint16_t current; float shunt; };

Unions are a ``union_tag`` plus an anonymous C union of the variants (``ina.bus.union_tag``,
``ina.bus.i2c.address``, as on the talk's slide); dynamic arrays a struct of ``len`` and
``data[max]``; ``float16`` is a ``float``; ``voidN`` padding has no member.

The functions are ``static inline`` in the header itself (no separate ``.c``): the header is
all a firmware build needs, a translation unit pays only for what it calls, and unused
``static inline`` functions draw no warnings. For each type ``T``::

    int T_encode(const struct T *msg, uint8_t buffer[T_MAX_SIZE], bool tao);
    int T_decode(const uint8_t *buffer, size_t size, struct T *msg, bool tao);

``encode`` returns the number of bytes written, ``decode`` the number of bytes the value took
(whole bytes after it are the caller's business); both return a negative
``PX4PARAMS_ERR_*`` on failure. ``encode`` fills in ``p_version`` itself and applies the
fields' cast modes (``saturated`` clamps, ``truncated`` keeps the low bits). ``tao`` is the
tail array optimization: off for stored parameters and CAN FD, on for classic CAN transfers.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from px4params.dsdl.model import Field
from px4params.dsdl.schema import Schema
from px4params.gcs.metadata import length_bits, min_bits, tag_bits
from px4params.store.spec import ParamSpec

__all__ = ["c_member_name", "c_type_names", "generate_header", "guard_from_filename"]

_C_KEYWORDS = frozenset(
    """auto break case char const continue default do double else enum extern float for goto if
    inline int long register restrict return short signed sizeof static struct switch typedef union
    unsigned void volatile while bool true false alignas alignof and and_eq asm catch char16_t
    char32_t class compl constexpr const_cast decltype delete dynamic_cast explicit export friend
    mutable namespace new noexcept not not_eq nullptr operator or or_eq private protected public
    reinterpret_cast static_assert static_cast template this thread_local throw try typeid
    typename using virtual wchar_t xor xor_eq""".split()  # noqa: SIM905 (a word list reads better)
)

# Shared by every generated header (guarded, so that two generated headers can be included
# together). Bit order: most significant bit first within each byte; a multi-byte scalar is
# stored little-endian with its top N%8 bits last (DroneCAN's "stream order").
_HELPERS = r"""
#ifndef PX4PARAMS_CODEC_HELPERS
#define PX4PARAMS_CODEC_HELPERS

/* Errors returned (negated) by the *_encode / *_decode functions. */
#define PX4PARAMS_ERR_TRUNCATED (-1)    /* decode: the data ends inside the value */
#define PX4PARAMS_ERR_UNION_TAG (-2)    /* a union tag that selects no variant */
#define PX4PARAMS_ERR_ARRAY_LENGTH (-3) /* a dynamic array longer than its maximum */

static inline uint64_t px4params_mask(unsigned bits)
{
    return bits >= 64u ? UINT64_MAX : ((UINT64_C(1) << bits) - 1u);
}

/* DroneCAN stream order: the whole low bytes first, then the top bits%8 bits. */
static inline uint64_t px4params_to_stream(uint64_t value, unsigned bits)
{
    const unsigned whole = bits / 8u;
    const unsigned rest = bits % 8u;
    uint64_t out = 0;
    for (unsigned i = 0; i < whole; i++) {
        out = (out << 8) | ((value >> (8u * i)) & 0xFFu);
    }
    if (rest != 0u) {
        out = (out << rest) | ((value >> (8u * whole)) & px4params_mask(rest));
    }
    return out;
}

static inline uint64_t px4params_from_stream(uint64_t stream, unsigned bits)
{
    const unsigned whole = bits / 8u;
    const unsigned rest = bits % 8u;
    uint64_t value = 0;
    if (rest != 0u) {
        value = (stream & px4params_mask(rest)) << (8u * whole);
        stream >>= rest;
    }
    for (unsigned i = 0; i < whole; i++) {
        value |= ((stream >> (8u * (whole - 1u - i))) & 0xFFu) << (8u * i);
    }
    return value;
}

/* Writes the low `bits` bits of `stream`, most significant first, at bit offset *bit. The
 * buffer is zeroed up front, so only ones are written. */
static inline void px4params_put(uint8_t *buffer, size_t *bit, uint64_t stream, unsigned bits)
{
    for (unsigned i = 0; i < bits; i++) {
        const size_t at = *bit + i;
        if ((stream >> (bits - 1u - i)) & 1u) {
            buffer[at / 8u] = (uint8_t)(buffer[at / 8u] | (0x80u >> (at % 8u)));
        }
    }
    *bit += bits;
}

static inline int px4params_get(const uint8_t *buffer, size_t size_bits, size_t *bit,
                                unsigned bits, uint64_t *stream)
{
    if (size_bits < *bit || size_bits - *bit < bits) {
        return PX4PARAMS_ERR_TRUNCATED;
    }
    uint64_t out = 0;
    for (unsigned i = 0; i < bits; i++) {
        const size_t at = *bit + i;
        out = (out << 1) | (uint64_t)((buffer[at / 8u] >> (7u - at % 8u)) & 1u);
    }
    *bit += bits;
    *stream = out;
    return 0;
}

static inline void px4params_put_uint(uint8_t *buffer, size_t *bit, uint64_t value,
                                      unsigned bits, bool truncated)
{
    const uint64_t max = px4params_mask(bits);
    if (value > max && !truncated) {
        value = max;
    }
    px4params_put(buffer, bit, px4params_to_stream(value & max, bits), bits);
}

static inline void px4params_put_int(uint8_t *buffer, size_t *bit, int64_t value, unsigned bits,
                                     bool truncated)
{
    const int64_t max = (int64_t)(px4params_mask(bits) >> 1);
    const int64_t min = -max - 1;
    if (!truncated) {
        value = value > max ? max : (value < min ? min : value);
    }
    px4params_put(buffer, bit, px4params_to_stream((uint64_t)value & px4params_mask(bits), bits),
                  bits);
}

/* float -> IEEE binary16 as libuavcan/libcanard: nearest, ties away from zero; overflow gives
 * infinity; NaN 0x7FFF (keeping its sign). */
static inline uint16_t px4params_f16_from_float(float value)
{
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    const uint32_t sign = (bits >> 16) & 0x8000u;
    bits &= 0x7FFFFFFFu;
    if (bits > 0x7F800000u) {
        return (uint16_t)(sign | 0x7FFFu);
    }
    if (bits == 0x7F800000u) {
        return (uint16_t)(sign | 0x7C00u);
    }
    const int32_t exp = (int32_t)(bits >> 23) - 127;
    if (exp < -25) { /* below half the smallest subnormal */
        return (uint16_t)sign;
    }
    const uint32_t mant = (bits & 0x7FFFFFu) | 0x800000u; /* value = mant * 2^(exp - 23) */
    if (exp < -14) {                                      /* subnormal: units of 2^-24 */
        const uint32_t shift = (uint32_t)(-1 - exp);
        return (uint16_t)(sign | ((mant + (1u << (shift - 1u))) >> shift));
    }
    uint32_t rounded = (mant + 0x1000u) >> 13; /* half a float16 ulp first: ties away */
    int32_t exp16 = exp + 15;
    if (rounded == 0x800u) {
        rounded = 0x400u;
        exp16++;
    }
    if (exp16 >= 31) {
        return (uint16_t)(sign | 0x7C00u);
    }
    return (uint16_t)(sign | ((uint32_t)exp16 << 10) | (rounded - 0x400u));
}

static inline float px4params_float_from_f16(uint16_t half)
{
    const uint32_t sign = (uint32_t)(half & 0x8000u) << 16;
    const uint32_t exp = (half >> 10) & 0x1Fu;
    const uint32_t mant = half & 0x3FFu;
    uint32_t bits;
    if (exp == 0u) {
        const float magnitude = (float)mant * 5.9604644775390625e-8f; /* exact: mant * 2^-24 */
        memcpy(&bits, &magnitude, sizeof bits);
        bits |= sign;
    } else if (exp == 31u) {
        bits = sign | 0x7F800000u | (mant << 13);
    } else {
        bits = sign | ((exp + 112u) << 23) | (mant << 13);
    }
    float out;
    memcpy(&out, &bits, sizeof out);
    return out;
}

static inline void px4params_put_f16(uint8_t *buffer, size_t *bit, float value, bool truncated)
{
    /* Finite values beyond float16's range: saturated fields clamp, truncated ones overflow. */
    if (value > 65504.0f && value <= FLT_MAX) {
        value = truncated ? INFINITY : 65504.0f;
    } else if (value < -65504.0f && value >= -FLT_MAX) {
        value = truncated ? -INFINITY : -65504.0f;
    }
    px4params_put(buffer, bit, px4params_to_stream(px4params_f16_from_float(value), 16u), 16u);
}

static inline void px4params_put_f32(uint8_t *buffer, size_t *bit, float value)
{
    uint32_t raw;
    memcpy(&raw, &value, sizeof raw);
    px4params_put(buffer, bit, px4params_to_stream(raw, 32u), 32u);
}

static inline void px4params_put_f64(uint8_t *buffer, size_t *bit, double value)
{
    uint64_t raw;
    memcpy(&raw, &value, sizeof raw);
    px4params_put(buffer, bit, px4params_to_stream(raw, 64u), 64u);
}

static inline int px4params_get_uint(const uint8_t *buffer, size_t size_bits, size_t *bit,
                                     unsigned bits, uint64_t *value)
{
    uint64_t stream = 0;
    const int err = px4params_get(buffer, size_bits, bit, bits, &stream);
    *value = px4params_from_stream(stream, bits);
    return err;
}

static inline int px4params_get_int(const uint8_t *buffer, size_t size_bits, size_t *bit,
                                    unsigned bits, int64_t *value)
{
    uint64_t raw = 0;
    const int err = px4params_get_uint(buffer, size_bits, bit, bits, &raw);
    if (bits < 64u && ((raw >> (bits - 1u)) & 1u)) {
        raw |= ~px4params_mask(bits); /* sign extension */
    }
    memcpy(value, &raw, sizeof raw);
    return err;
}

static inline int px4params_get_f16(const uint8_t *buffer, size_t size_bits, size_t *bit,
                                    float *value)
{
    uint64_t raw = 0;
    const int err = px4params_get_uint(buffer, size_bits, bit, 16u, &raw);
    *value = px4params_float_from_f16((uint16_t)raw);
    return err;
}

static inline int px4params_get_f32(const uint8_t *buffer, size_t size_bits, size_t *bit,
                                    float *value)
{
    uint64_t raw = 0;
    const int err = px4params_get_uint(buffer, size_bits, bit, 32u, &raw);
    const uint32_t narrow = (uint32_t)raw;
    memcpy(value, &narrow, sizeof narrow);
    return err;
}

static inline int px4params_get_f64(const uint8_t *buffer, size_t size_bits, size_t *bit,
                                    double *value)
{
    uint64_t raw = 0;
    const int err = px4params_get_uint(buffer, size_bits, bit, 64u, &raw);
    memcpy(value, &raw, sizeof raw);
    return err;
}

#endif /* PX4PARAMS_CODEC_HELPERS */
"""


def guard_from_filename(filename: str | None) -> str:
    """``px4_params.h`` -> ``PX4_PARAMS_H`` (a default for stdout)."""
    base = (filename or "px4params_parameters.h").replace("\\", "/").rsplit("/", 1)[-1]
    guard = re.sub(r"[^A-Za-z0-9]", "_", base).upper()
    return guard if re.match(r"[A-Z]", guard) else f"PX4PARAMS_{guard}"


def generate_header(
    schema: Schema,
    specs: Sequence[ParamSpec],
    *,
    guard: str = "PX4PARAMS_PARAMETERS_H",
    extra_types: Iterable[str] = (),
) -> str:
    """The header for the parameters ``specs`` (their types and every type they use), plus
    ``extra_types`` (keys) and theirs."""
    return _Generator(schema).header(specs, guard, list(extra_types))


def c_type_names(schema: Schema, roots: Iterable[str]) -> dict[str, str]:
    """The C struct name of every type the ``roots`` (keys) use, in declaration order:
    ``px.Ina238.1.1`` -> ``px_Ina238`` (an older version also used gets ``_1_0``)."""
    generator = _Generator(schema)
    keys = generator.needed(list(roots))
    generator.assign_names(keys)
    return {key: generator.c_names[key] for key in keys}


def c_member_name(name: str) -> str:
    """A DSDL field name as a C member (C/C++ keywords get a trailing underscore)."""
    return _Generator.member(name)


class _Generator:
    def __init__(self, schema: Schema) -> None:
        self.schema = schema
        self.c_names: dict[str, str] = {}

    # -- names and order -------------------------------------------------------------------

    def needed(self, roots: Sequence[str]) -> list[str]:
        """Every type the roots use, each after the types it uses."""
        order: list[str] = []
        seen: set[str] = set()

        def visit(key: str) -> None:
            if key in seen:
                return
            seen.add(key)
            for field in self.schema.type_def(key).fields:
                spec = field.type
                while spec["kind"] in ("array", "dynarray"):
                    spec = spec["elem"]
                if spec["kind"] == "ref":
                    visit(spec["name"])
            order.append(key)

        for root in roots:
            visit(root)
        return order

    def assign_names(self, keys: Sequence[str]) -> None:
        # The newest version of a name is plain px_Bus; an older one also needed is px_Bus_1_0.
        by_name: dict[str, list[str]] = {}
        for key in keys:
            by_name.setdefault(self.schema.type_def(key).name, []).append(key)
        for name, versions in by_name.items():
            base = name.replace(".", "_")
            ranked = sorted(versions, key=lambda k: self.schema.type_def(k).version or (0, 0))
            for key in ranked[:-1]:
                major, minor = self.schema.type_def(key).version or (0, 0)
                self.c_names[key] = f"{base}_{major}_{minor}"
            self.c_names[ranked[-1]] = base

    def cname(self, key: str) -> str:
        return self.c_names[key]

    @staticmethod
    def member(name: str) -> str:
        return f"{name}_" if name in _C_KEYWORDS else name

    @staticmethod
    def macro(text: str) -> str:
        return re.sub(r"[^A-Za-z0-9]", "_", text).upper()

    def array_struct(self, key: str, field: str) -> str:
        return f"{self.cname(key)}_{field}_array"

    def scalar_ctype(self, spec: Mapping[str, Any]) -> str:
        kind = spec["kind"]
        if kind == "bool":
            return "bool"
        bits = int(spec["bits"])
        if kind == "float":
            return "double" if bits == 64 else "float"
        width = next(w for w in (8, 16, 32, 64) if bits <= w)
        return f"{'u' if kind == 'uint' else ''}int{width}_t"

    def elem_ctype(self, spec: Mapping[str, Any]) -> str:
        if spec["kind"] == "ref":
            return f"struct {self.cname(spec['name'])}"
        return self.scalar_ctype(spec)

    # -- the header ------------------------------------------------------------------------

    def header(self, specs: Sequence[ParamSpec], guard: str, extra: list[str]) -> str:
        roots = [s.data_type.key for s in specs] + extra
        keys = self.needed(roots)
        self.assign_names(keys)
        out: list[str] = [
            "/*",
            " * Generated by `px4params metadata --header`: do not edit.",
            " *",
            " * One struct per parameter type (DSDL), its largest encoding (_MAX_SIZE, bytes), the",
            " * parameters' identifiers and instance counts, and static inline functions that",
            " * encode and decode the structs with the DroneCAN serialization rules:",
            " *   int T_encode(const struct T *msg, uint8_t buffer[T_MAX_SIZE], bool tao);",
            " *   int T_decode(const uint8_t *buffer, size_t size, struct T *msg, bool tao);",
            " * returning the bytes written / used, or a negative PX4PARAMS_ERR_*. encode fills in",
            " * p_version and applies the cast modes (saturated clamps, truncated keeps low bits).",
            " * Stored parameters use tao = false (no tail array optimization).",
            " */",
            f"#ifndef {guard}",
            f"#define {guard}",
            "",
            "#include <float.h>",
            "#include <math.h>",
            "#include <stdbool.h>",
            "#include <stddef.h>",
            "#include <stdint.h>",
            "#include <string.h>",
            "",
            "#ifdef __cplusplus",
            'extern "C" {',
            "#endif",
            _HELPERS.rstrip("\n"),
        ]
        for key in keys:
            out += ["", *self.type_decl(key)]
        for key in keys:
            out += ["", *self.encoder(key), "", *self.decoder(key)]
        out += ["", *self.parameters(specs)]
        out += ["", "#ifdef __cplusplus", "}", "#endif", "", *self.cxx(specs)]
        out += ["", f"#endif /* {guard} */", ""]
        return "\n".join(out)

    def cxx(self, specs: Sequence[ParamSpec]) -> list[str]:
        """For C++ (unless PX4PARAMS_NO_CXX): each type's codec and each parameter's typed id
        for the API of ``px4params.hpp`` (``load_and_decode_param<px_Ina238>(px4::params::
        INA238, 0, data)``, ``param_find_instances(params::INA238)``)."""
        out = [
            "#if defined(__cplusplus) && !defined(PX4PARAMS_NO_CXX)",
            '#include "px4params.hpp"',
            "",
            "namespace px4 {",
            "namespace params {",
        ]
        for key in dict.fromkeys(s.data_type.key for s in specs):
            name = self.cname(key)
            out += [
                "",
                "template <>",
                f"struct codec<struct {name}> {{",
                f"    static constexpr size_t max_size = {self.macro(name)}_MAX_SIZE;",
                f"    static int encode(const struct {name} &value, uint8_t *buffer) {{",
                f"        return {name}_encode(&value, buffer, false);",
                "    }",
                "    static int decode(const uint8_t *buffer, size_t size,",
                f"                      struct {name} &value) {{",
                f"        return {name}_decode(buffer, size, &value, false);",
                "    }",
                "};",
            ]
        out.append("")
        for s in specs:
            name, macro = self.cname(s.data_type.key), self.macro(s.name)
            out.append(f"constexpr param<struct {name}> {macro}{{PX4_PARAM_{macro}}};")
        out += ["", "}  // namespace params", "}  // namespace px4", "#endif"]
        return out

    def type_decl(self, key: str) -> list[str]:
        declared = self.schema.type_def(key)
        name = self.cname(key)
        macro = self.macro(name)
        data_type = self.schema[key]
        doc = declared.doc.short
        lines = [f"/* {key}{': ' + doc if doc else ''} */"]
        version = declared.version
        if version:
            lines += [
                f"#define {macro}_VERSION_MAJOR {version[0]}",
                f"#define {macro}_VERSION_MINOR {version[1]}",
            ]
        lines += [
            f"#define {macro}_MAX_SIZE {data_type.max_bytes}",
            f"#define {macro}_MAX_BITS {data_type.max_bits}",
        ]
        fields = declared.data_fields
        for f in fields:
            if f.kind == "dynarray":
                spec = f.type
                len_type = self.scalar_ctype({"kind": "uint", "bits": length_bits(spec["max"])})
                lines += [
                    f"struct {self.array_struct(key, f.name)} {{",
                    f"    {len_type} len;",
                    f"    {self.elem_ctype(spec['elem'])} data[{spec['max']}];",
                    "};",
                ]
        members = [self.member_decl(key, f) for f in fields]
        if declared.is_union:
            lines.append(f"enum {name}_tag {{")
            lines += [f"    {macro}_TAG_{self.macro(f.name)} = {i}," for i, f in enumerate(fields)]
            lines += [
                "};",
                f"struct {name} {{",
                f"    uint8_t union_tag; /* enum {name}_tag */",
                "    union {",
                *[f"        {m}" for m in members],
                "    };",
                "};",
            ]
        else:
            # C has no empty structs; a placeholder keeps C and C++ layouts equal.
            body = members or ["uint8_t dummy; /* no fields */"]
            lines += [f"struct {name} {{", *[f"    {m}" for m in body], "};"]
        return lines

    def member_decl(self, key: str, field: Field) -> str:
        spec, name = field.type, self.member(field.name)
        if spec["kind"] == "dynarray":
            return f"struct {self.array_struct(key, field.name)} {name};"
        if spec["kind"] == "array":
            return f"{self.elem_ctype(spec['elem'])} {name}[{spec['len']}];"
        return f"{self.elem_ctype(spec)} {name};"

    # -- encoding --------------------------------------------------------------------------

    def encoder(self, key: str) -> list[str]:
        declared = self.schema.type_def(key)
        name = self.cname(key)
        lines = [
            f"static inline int {name}_encode_bits(const struct {name} *msg, uint8_t *buffer, "
            "size_t *bit, bool tao)",
            "{",
            "    (void)msg;",
            "    (void)buffer;",
            "    (void)bit;",
            "    (void)tao;",
            "    int err = 0;",
            "    (void)err;",
        ]
        fields = declared.fields
        if declared.is_union:
            bits = tag_bits(len(fields))
            lines.append("    switch (msg->union_tag) {")
            for i, f in enumerate(fields):
                lines.append(f"    case {i}:")
                lines.append(f"        px4params_put_uint(buffer, bit, {i}u, {bits}u, false);")
                lines += self.encode_value(
                    f.type, f"msg->{self.member(f.name)}", "tao", 2, key, f.name
                )
                lines.append("        break;")
            lines += ["    default:", "        return PX4PARAMS_ERR_UNION_TAG;", "    }"]
        else:
            for i, f in enumerate(fields):
                tail = "tao" if i == len(fields) - 1 else "false"
                spec = f.type
                if spec["kind"] == "void":
                    lines.append(f"    *bit += {spec['bits']}u; /* void{spec['bits']} */")
                elif declared.versioned and f.name == "p_version":
                    version = (declared.version or (0, 0))[1]
                    lines.append(
                        f"    px4params_put_uint(buffer, bit, {version}u, {spec['bits']}u, false);"
                        " /* p_version: the type's version */"
                    )
                else:
                    lines += self.encode_value(
                        spec, f"msg->{self.member(f.name)}", tail, 1, key, f.name
                    )
        lines += ["    return 0;", "}", ""]
        lines += [
            f"static inline int {name}_encode(const struct {name} *msg, "
            f"uint8_t buffer[{self.macro(name)}_MAX_SIZE], bool tao)",
            "{",
            f"    memset(buffer, 0, {self.macro(name)}_MAX_SIZE);",
            "    size_t bit = 0;",
            f"    const int err = {name}_encode_bits(msg, buffer, &bit, tao);",
            "    return err < 0 ? err : (int)((bit + 7u) / 8u);",
            "}",
        ]
        return lines

    def encode_value(
        self, spec: Mapping[str, Any], expr: str, tail: str, depth: int, key: str, field: str
    ) -> list[str]:
        pad = "    " * depth
        kind = spec["kind"]
        if kind == "ref":
            callee = self.cname(spec["name"])
            return [
                f"{pad}err = {callee}_encode_bits(&{expr}, buffer, bit, {tail});",
                f"{pad}if (err < 0) {{",
                f"{pad}    return err;",
                f"{pad}}}",
            ]
        if kind == "array":
            n = spec["len"]
            last = f"{tail} && i == {n - 1}u" if tail != "false" else "false"
            return [
                f"{pad}for (size_t i = 0; i < {n}u; i++) {{",
                *self.encode_value(spec["elem"], f"{expr}[i]", last, depth + 1, key, field),
                f"{pad}}}",
            ]
        if kind == "dynarray":
            max_len, len_bits = spec["max"], length_bits(spec["max"])
            tail_capable = min_bits(self.schema, spec["elem"]) >= 8
            lines = []
            width = next(w for w in (8, 16, 32, 64) if len_bits <= w)
            if max_len < (1 << width) - 1:
                # (When the length's C type tops out at max, the check could never fail.)
                lines += [
                    f"{pad}if ((size_t){expr}.len > {max_len}u) {{",
                    f"{pad}    return PX4PARAMS_ERR_ARRAY_LENGTH;",
                    f"{pad}}}",
                ]
            implied = (
                f"{tail} && {'true' if tail_capable else 'false'}" if tail != "false" else "false"
            )
            lines += [
                f"{pad}{{",
                f"{pad}    const bool implied = {implied}; /* tail array optimization */",
                f"{pad}    if (!implied) {{",
                f"{pad}        px4params_put_uint(buffer, bit, {expr}.len, {len_bits}u, false);",
                f"{pad}    }}",
                f"{pad}    for (size_t i = 0; i < (size_t){expr}.len; i++) {{",
                *self.encode_value(
                    spec["elem"],
                    f"{expr}.data[i]",
                    f"{tail} && !implied && i + 1u == (size_t){expr}.len"
                    if tail != "false"
                    else "false",
                    depth + 2,
                    key,
                    field,
                ),
                f"{pad}    }}",
                f"{pad}}}",
            ]
            return lines
        truncated = "true" if spec.get("cast") == "truncated" else "false"
        if kind == "bool":
            return [f"{pad}px4params_put_uint(buffer, bit, {expr} ? 1u : 0u, 1u, false);"]
        bits = int(spec["bits"])
        if kind == "uint":
            return [f"{pad}px4params_put_uint(buffer, bit, {expr}, {bits}u, {truncated});"]
        if kind == "int":
            return [f"{pad}px4params_put_int(buffer, bit, {expr}, {bits}u, {truncated});"]
        if bits == 16:
            return [f"{pad}px4params_put_f16(buffer, bit, {expr}, {truncated});"]
        return [f"{pad}px4params_put_f{bits}(buffer, bit, {expr});"]

    # -- decoding --------------------------------------------------------------------------

    def decoder(self, key: str) -> list[str]:
        declared = self.schema.type_def(key)
        name = self.cname(key)
        lines = [
            f"static inline int {name}_decode_bits(const uint8_t *buffer, size_t size_bits, "
            f"size_t *bit, struct {name} *msg, bool tao)",
            "{",
            "    (void)buffer;",
            "    (void)size_bits;",
            "    (void)bit;",
            "    (void)msg;",
            "    (void)tao;",
            "    int err = 0;",
            "    (void)err;",
        ]
        fields = declared.fields
        if declared.is_union:
            bits = tag_bits(len(fields))
            lines += [
                "    uint64_t tag = 0;",
                f"    err = px4params_get_uint(buffer, size_bits, bit, {bits}u, &tag);",
                "    if (err < 0) {",
                "        return err;",
                "    }",
                "    msg->union_tag = (uint8_t)tag;",
                "    switch (tag) {",
            ]
            for i, f in enumerate(fields):
                lines.append(f"    case {i}:")
                lines += self.decode_value(f.type, f"msg->{self.member(f.name)}", "tao", 2)
                lines.append("        break;")
            lines += ["    default:", "        return PX4PARAMS_ERR_UNION_TAG;", "    }"]
        else:
            for i, f in enumerate(fields):
                tail = "tao" if i == len(fields) - 1 else "false"
                spec = f.type
                if spec["kind"] == "void":
                    lines += [
                        "    {",
                        "        uint64_t skipped = 0;",
                        f"        err = px4params_get(buffer, size_bits, bit, {spec['bits']}u, "
                        "&skipped);",
                        "        if (err < 0) {",
                        "            return err;",
                        "        }",
                        "    }",
                    ]
                else:
                    lines += self.decode_value(spec, f"msg->{self.member(f.name)}", tail, 1)
        lines += ["    return 0;", "}", ""]
        lines += [
            f"static inline int {name}_decode(const uint8_t *buffer, size_t size, "
            f"struct {name} *msg, bool tao)",
            "{",
            "    size_t bit = 0;",
            f"    const int err = {name}_decode_bits(buffer, size * 8u, &bit, msg, tao);",
            "    return err < 0 ? err : (int)((bit + 7u) / 8u);",
            "}",
        ]
        return lines

    def decode_value(self, spec: Mapping[str, Any], expr: str, tail: str, depth: int) -> list[str]:
        pad = "    " * depth
        check = [f"{pad}if (err < 0) {{", f"{pad}    return err;", f"{pad}}}"]
        kind = spec["kind"]
        if kind == "ref":
            callee = self.cname(spec["name"])
            return [
                f"{pad}err = {callee}_decode_bits(buffer, size_bits, bit, &{expr}, {tail});",
                *check,
            ]
        if kind == "array":
            n = spec["len"]
            last = f"{tail} && i == {n - 1}u" if tail != "false" else "false"
            return [
                f"{pad}for (size_t i = 0; i < {n}u; i++) {{",
                *self.decode_value(spec["elem"], f"{expr}[i]", last, depth + 1),
                f"{pad}}}",
            ]
        if kind == "dynarray":
            max_len, len_bits = spec["max"], length_bits(spec["max"])
            len_type = self.scalar_ctype({"kind": "uint", "bits": len_bits})
            inner = "    " * (depth + 1)
            lines = []
            if tail != "false" and min_bits(self.schema, spec["elem"]) >= 8:
                # Tail array optimization: the elements take every remaining whole byte.
                lines += [
                    f"{pad}if ({tail}) {{",
                    f"{inner}size_t n = 0;",
                    f"{inner}while (size_bits - *bit >= 8u) {{",
                    f"{inner}    if (n == {max_len}u) {{",
                    f"{inner}        return PX4PARAMS_ERR_ARRAY_LENGTH;",
                    f"{inner}    }}",
                    *self.decode_value(spec["elem"], f"{expr}.data[n]", "false", depth + 2),
                    f"{inner}    n++;",
                    f"{inner}}}",
                    f"{inner}{expr}.len = ({len_type})n;",
                    f"{pad}}} else {{",
                ]
                body_depth = depth + 1
            else:
                body_depth = depth
            bpad = "    " * body_depth
            lines += [
                f"{bpad}{{",
                f"{bpad}    uint64_t n = 0;",
                f"{bpad}    err = px4params_get_uint(buffer, size_bits, bit, {len_bits}u, &n);",
                f"{bpad}    if (err < 0) {{",
                f"{bpad}        return err;",
                f"{bpad}    }}",
                f"{bpad}    if (n > {max_len}u) {{",
                f"{bpad}        return PX4PARAMS_ERR_ARRAY_LENGTH;",
                f"{bpad}    }}",
                f"{bpad}    {expr}.len = ({len_type})n;",
                f"{bpad}    for (size_t i = 0; i < (size_t)n; i++) {{",
                *self.decode_value(
                    spec["elem"],
                    f"{expr}.data[i]",
                    f"{tail} && i + 1u == (size_t)n" if tail != "false" else "false",
                    body_depth + 2,
                ),
                f"{bpad}    }}",
                f"{bpad}}}",
            ]
            if body_depth != depth:
                lines.append(f"{pad}}}")
            return lines
        if kind == "bool":
            return [
                f"{pad}{{",
                f"{pad}    uint64_t raw = 0;",
                f"{pad}    err = px4params_get_uint(buffer, size_bits, bit, 1u, &raw);",
                f"{pad}    {expr} = raw != 0u;",
                f"{pad}}}",
                *check,
            ]
        bits = int(spec["bits"])
        ctype = self.scalar_ctype(spec)
        if kind in ("uint", "int"):
            raw_type = "uint64_t" if kind == "uint" else "int64_t"
            return [
                f"{pad}{{",
                f"{pad}    {raw_type} raw = 0;",
                f"{pad}    err = px4params_get_{kind}(buffer, size_bits, bit, {bits}u, &raw);",
                f"{pad}    {expr} = ({ctype})raw;",
                f"{pad}}}",
                *check,
            ]
        return [f"{pad}err = px4params_get_f{bits}(buffer, size_bits, bit, &{expr});", *check]

    # -- parameters ------------------------------------------------------------------------

    def parameters(self, specs: Sequence[ParamSpec]) -> list[str]:
        lines = [
            "/* Parameter identifiers (in name order) and instance counts. */",
            "enum px4_param_id {",
            *[f"    PX4_PARAM_{self.macro(s.name)} = {i}," for i, s in enumerate(specs)],
            f"    PX4_PARAM_COUNT = {len(specs)}",
            "};",
        ]
        for s in specs:
            macro = f"PX4_PARAM_{self.macro(s.name)}"
            lines.append("")
            lines.append(f"/* {s.name}: {s.data_type.key} */")
            lines.append(f"typedef struct {self.cname(s.data_type.key)} px4_param_{s.name}_t;")
            lines.append(f'#define {macro}_NAME "{s.name}"')
            if s.shared:
                lines.append(f"#define {macro}_SHARED 1 /* one value shared by all instances */")
            else:
                lines.append(f"#define {macro}_MAX_INSTANCES {s.max_instances}")
            lines.append(f"#define {macro}_SLOTS {s.slots}")
            lines.append(
                f"#define {macro}_MAX_SIZE {self.macro(self.cname(s.data_type.key))}_MAX_SIZE"
            )
        return lines
