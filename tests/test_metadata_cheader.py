"""The generated C header (px4params.gcs.cheader): it compiles as C11 and C++17 without warnings,
has the talk's struct, and its encode/decode functions give the Rust codec's bytes."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from pathlib import Path

import px4params
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from metadata_support import (
    Harness,
    harness_source,
    input_tokens,
    require_compilers,
    same_leaf_values,
    wide_value_strategy,
    write_tst,
)
from px4params.gcs.cheader import c_type_names, generate_header, guard_from_filename
from px4params.store.spec import parameter_specs
from strategies import budget, value_strategy

BUNDLED = px4params.load_schema(use_env=False)
PARAMS = [s.name for s in parameter_specs(BUNDLED)]
TESTED_PARAMS = [*PARAMS, "EVERYTHING_SH"]
TALK = {"bus": {"i2c": {"bus_id": 1, "address": 0x45}}, "current": 200, "shunt": 0.0003}
C_FLAGS = ["-std=c11", "-Wall", "-Wextra", "-Werror"]
# The header's C++ part includes the C ABI's px4params.hpp.
FFI_INCLUDE = str(Path(__file__).resolve().parent.parent / "crates" / "px4params-ffi" / "include")
CXX_FLAGS = ["-std=c++17", "-Wall", "-Werror", f"-I{FFI_INCLUDE}"]


def slow(examples: int) -> settings:
    return settings(
        max_examples=budget(examples),
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
    )


def compile_ok(command: list[str], cwd: Path) -> None:
    proc = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-4000:]


@pytest.fixture(scope="module")
def compilers() -> tuple[str, str]:
    return require_compilers()


@pytest.fixture(scope="module")
def tst_schema(tmp_path_factory: pytest.TempPathFactory) -> px4params.Schema:
    return px4params.load_schema([write_tst(tmp_path_factory.mktemp("tst"))], use_env=False)


def spec_type(schema: px4params.Schema, name: str) -> px4params.DataType:
    return next(s for s in parameter_specs(schema) if s.name == name).data_type


# --- the header itself --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def header_text() -> str:
    return generate_header(BUNDLED, parameter_specs(BUNDLED), guard="PX4_PARAMS_H")


def test_the_talks_struct_and_defines(header_text: str) -> None:
    assert (
        "struct px_Ina238 {\n"
        "    uint8_t p_version;\n"
        "    struct px_Bus bus;\n"
        "    uint16_t current;\n"
        "    float shunt;\n"
        "};"
    ) in header_text
    assert (
        "struct px_Bus {\n"
        "    uint8_t union_tag; /* enum px_Bus_tag */\n"
        "    union {\n"
        "        struct px_I2c i2c;\n"
        "        struct px_Spi spi;\n"
    ) in header_text
    assert "    PX_BUS_TAG_I2C = 0,\n" in header_text
    ina = BUNDLED["px.Ina238"]
    assert f"#define PX_INA238_MAX_SIZE {ina.max_bytes}\n" in header_text
    assert f"#define PX_INA238_VERSION_MINOR {ina.version[1]}\n" in header_text  # type: ignore[index]
    assert "#define PX4_PARAM_INA238_MAX_INSTANCES 4\n" in header_text
    assert "typedef struct px_Ina238 px4_param_INA238_t;\n" in header_text
    enum = header_text[header_text.index("enum px4_param_id {") :]
    ids = [f"    PX4_PARAM_{name} = {i}," for i, name in enumerate(PARAMS)]
    assert enum.startswith("\n".join(["enum px4_param_id {", *ids]))
    assert f"    PX4_PARAM_COUNT = {len(PARAMS)}\n}};" in enum
    assert (
        header_text.startswith("/*")
        and "#ifndef PX4_PARAMS_H\n#define PX4_PARAMS_H\n" in header_text
    )
    assert "static inline int px_Ina238_encode(const struct px_Ina238 *msg" in header_text
    assert "static inline int px_Ina238_decode(const uint8_t *buffer, size_t size" in header_text


def test_the_header_compiles_as_c11_and_cpp17(
    compilers: tuple[str, str], header_text: str, tmp_path: Path
) -> None:
    gcc, gxx = compilers
    (tmp_path / "px4_params.h").write_text(header_text, encoding="utf-8")
    (tmp_path / "use.c").write_text('#include "px4_params.h"\n', encoding="utf-8")
    (tmp_path / "use.cpp").write_text('#include "px4_params.h"\n', encoding="utf-8")
    compile_ok([gcc, *C_FLAGS, "-c", "use.c", "-o", "use_c.o"], tmp_path)
    compile_ok([gxx, *CXX_FLAGS, "-c", "use.cpp", "-o", "use_cpp.o"], tmp_path)
    # Stricter still: pedantic C11, -Wextra for C++ too.
    compile_ok([gcc, *C_FLAGS, "-Wpedantic", "-c", "use.c", "-o", "use_c.o"], tmp_path)
    compile_ok([gxx, *CXX_FLAGS, "-Wextra", "-c", "use.cpp", "-o", "use_cpp.o"], tmp_path)


def test_every_type_compiles_too(
    compilers: tuple[str, str], tst_schema: px4params.Schema, tmp_path: Path
) -> None:
    # Arrays, padding, signed and 64-bit fields, empty structs, several versions of one type.
    structs = [k for k, d in tst_schema.model["types"].items() if d["kind"] == "struct"]
    text = generate_header(tst_schema, parameter_specs(tst_schema), extra_types=structs)
    assert "struct px_Ina238_1_0 {" in text and "struct px_Ina238 {" in text
    assert "#define PX4_PARAM_EVERYTHING_SH_SHARED 1" in text
    (tmp_path / "all.h").write_text(text, encoding="utf-8")
    (tmp_path / "use.c").write_text('#include "all.h"\n', encoding="utf-8")
    (tmp_path / "use.cpp").write_text('#include "all.h"\n', encoding="utf-8")
    gcc, gxx = compilers
    compile_ok([gcc, *C_FLAGS, "-c", "use.c", "-o", "use_c.o"], tmp_path)
    compile_ok([gxx, *CXX_FLAGS, "-c", "use.cpp", "-o", "use_cpp.o"], tmp_path)


TALK_PROGRAM = r"""
#include <stdio.h>
#include "px4_params.h"

int main(void)
{
    struct px_Ina238 ina238_data;
    memset(&ina238_data, 0, sizeof ina238_data);
    ina238_data.bus.union_tag = PX_BUS_TAG_I2C;
    ina238_data.bus.i2c.bus_id = 1;
    ina238_data.bus.i2c.address = 0x45;
    ina238_data.current = 200;
    ina238_data.shunt = 0.0003f;
    uint8_t buffer[PX4_PARAM_INA238_MAX_SIZE];
    const int n = px_Ina238_encode(&ina238_data, buffer, false);
    for (int i = 0; i < n; i++) {
        printf("%02x", buffer[i]);
    }
    struct px_Ina238 back;
    const int used = px_Ina238_decode(buffer, (size_t)n, &back, false);
    printf(" %d bus_type: %d, address: %d, current: %d, instances: %d\n", used,
           back.bus.union_tag, back.bus.i2c.address, back.current,
           PX4_PARAM_INA238_MAX_INSTANCES);
    return 0;
}
"""


@pytest.mark.parametrize("language", ["c", "c++"])
def test_the_talks_example_in_c(
    compilers: tuple[str, str], header_text: str, tmp_path: Path, language: str
) -> None:
    gcc, gxx = compilers
    (tmp_path / "px4_params.h").write_text(header_text, encoding="utf-8")
    source = tmp_path / ("talk.c" if language == "c" else "talk.cpp")
    source.write_text(TALK_PROGRAM, encoding="utf-8")
    command = [gcc, *C_FLAGS] if language == "c" else [gxx, *CXX_FLAGS]
    compile_ok([*command, source.name, "-o", "talk"], tmp_path)
    out = subprocess.run(
        [str(tmp_path / "talk")], capture_output=True, text=True, check=True, timeout=30
    ).stdout.split()
    expected = BUNDLED["px.Ina238"].encode(TALK, tao=False)
    assert out[0] == expected.hex()
    assert out[1:] == [
        str(len(expected)),
        "bus_type:",
        "0,",
        "address:",
        "69,",
        "current:",
        "200,",
        "instances:",
        "4",
    ]


def test_guard_from_filename() -> None:
    assert guard_from_filename("build/px4_params.h") == "PX4_PARAMS_H"
    assert guard_from_filename("C:\\out\\my-params.hpp") == "MY_PARAMS_HPP"
    assert guard_from_filename("1st.h") == "PX4PARAMS_1ST_H"
    assert guard_from_filename(None) == "PX4PARAMS_PARAMETERS_H"


# --- the functions, against the Rust codec ------------------------------------------------------


@pytest.fixture(scope="module")
def harness(
    compilers: tuple[str, str],
    tst_schema: px4params.Schema,
    tmp_path_factory: pytest.TempPathFactory,
) -> Iterator[Harness]:
    """One harness for the parameters and every DroneCAN struct type, kept running."""
    gcc, _ = compilers
    base = tmp_path_factory.mktemp("harness")
    specs = parameter_specs(tst_schema)
    types = tst_schema.model["types"]
    structs = sorted(k for k, d in types.items() if d["kind"] == "struct")
    tested = [spec_type(tst_schema, n).key for n in TESTED_PARAMS] + structs
    tested = list(dict.fromkeys(tested))
    (base / "params.h").write_text(
        generate_header(tst_schema, specs, extra_types=structs), encoding="utf-8"
    )
    names = c_type_names(tst_schema, [s.data_type.key for s in specs] + structs)
    (base / "harness.c").write_text(
        harness_source(types, "params.h", names, tested), encoding="utf-8"
    )
    compile_ok([gcc, *C_FLAGS, "-O1", "harness.c", "-o", "harness"], base)
    running = Harness(base / "harness", tested)
    yield running
    running.close()


def check_encoding(
    harness: Harness,
    schema: px4params.Schema,
    data_type: px4params.DataType,
    value: object,
    *,
    tao: bool,
    saturate: bool,
) -> None:
    tokens = input_tokens(schema.model["types"], data_type.key, value)
    data, used, decoded = harness.encode(data_type.key, tokens, tao)
    assert data.hex() == data_type.encode(value, tao=tao, saturate=saturate).hex()  # type: ignore[arg-type]
    assert used == len(data)
    assert same_leaf_values(decoded, data_type.leaves(data, tao=tao)), decoded


@pytest.mark.parametrize("name", TESTED_PARAMS)
@slow(80)
@given(data=st.data())
def test_parameters_encode_like_the_rust_codec(
    name: str, data: st.DataObject, harness: Harness, tst_schema: px4params.Schema
) -> None:
    data_type = spec_type(tst_schema, name)
    value = data.draw(value_strategy(tst_schema.model["types"], data_type.key))
    check_encoding(harness, tst_schema, data_type, value, tao=False, saturate=False)


@pytest.mark.parametrize("name", TESTED_PARAMS)
@slow(60)
@given(data=st.data())
def test_out_of_range_members_saturate_like_the_rust_codec(
    name: str, data: st.DataObject, harness: Harness, tst_schema: px4params.Schema
) -> None:
    # C structs can hold what the fields cannot (a uint16_t for a uint10): encode applies the
    # cast modes, as the Rust codec does with saturate=True.
    data_type = spec_type(tst_schema, name)
    value = data.draw(wide_value_strategy(tst_schema.model["types"], data_type.key))
    check_encoding(harness, tst_schema, data_type, value, tao=False, saturate=True)


@pytest.mark.parametrize("name", TESTED_PARAMS)
@slow(80)
@given(raw=st.binary(max_size=48), tao=st.booleans())
def test_any_bytes_decode_like_the_rust_codec(
    name: str, raw: bytes, tao: bool, harness: Harness, tst_schema: px4params.Schema
) -> None:
    data_type = spec_type(tst_schema, name)
    rc, values = harness.decode(data_type.key, raw, tao)
    try:
        data_type.decode(raw, tao=tao)
    except px4params.DecodeError as e:
        text = str(e)
        if "too long" in text:
            assert 0 <= rc < len(raw), text  # C leaves trailing bytes to the caller
        elif "truncated" in text:
            assert rc == -1, text
        elif "union tag" in text:
            assert rc == -2, text
        else:
            assert rc == -3, text
    else:
        assert rc == len(raw)
        assert same_leaf_values(values, data_type.leaves(raw, tao=tao))


STRUCTS = sorted(k for k, d in BUNDLED.model["types"].items() if d["kind"] == "struct")


@pytest.mark.parametrize("key", STRUCTS)
@slow(6)
@given(data=st.data(), tao=st.booleans())
def test_every_bundled_struct_type(
    key: str, data: st.DataObject, tao: bool, harness: Harness
) -> None:
    # Beyond parameters: DroneCAN's own types for arrays, padding and tail array optimization.
    value = data.draw(value_strategy(BUNDLED.model["types"], key))
    check_encoding(harness, BUNDLED, BUNDLED[key], value, tao=tao, saturate=False)


def test_encode_refuses_a_bad_union_tag_and_a_long_array(
    harness: Harness, tst_schema: px4params.Schema
) -> None:
    ina = spec_type(tst_schema, "INA238")
    tokens = input_tokens(tst_schema.model["types"], ina.key, TALK)
    assert tokens[1] == "0"  # the bus tag
    assert harness.encode_status(ina.key, [tokens[0], "7", *tokens[5:]], False) == -2
    everything = spec_type(tst_schema, "EVERYTHING_SH")
    value = {
        "wrap": 1,
        "signed_value": 0,
        "flag": False,
        "triple": [1, 2, 3],
        "items": [],
        "choice": {"number": 1},
        "pair": [0.0, 0.0],
        "loose": 0.0,
        "tail": [1, 2, 3, 4],
    }
    tokens = input_tokens(tst_schema.model["types"], everything.key, value)
    assert tokens[-5:] == ["4", "1", "2", "3", "4"]
    assert (
        harness.encode_status(everything.key, [*tokens[:-5], "5", "1", "2", "3", "4", "5"], False)
        == -3
    )
