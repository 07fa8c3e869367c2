"""The typed schema model (``px4params.dsdl.model``): every tag a DSDL file declares, read into
its named value; a model whose tag has the wrong shape refused with one line naming the type,
the field and the tag. The expected values are read off the DSDL text written here."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from px4params.dsdl.model import NO_DOC, type_def
from px4params.dsdl.schema import Schema, load_schema
from px4params.errors import DsdlError

TAGS_DSDL = """\
# Every tag
# A type declaring each type tag.
# @group Sensors
# @category Developer
# @max_instances 3
# @param EVERY_TAG
# @reboot_required true

uint8 p_version
# Layout version

int16 offset
# Offset
# Offset added to the reading.
# @unit mm
# @default -0x10
# @min -1000
# @max 1000
# @decimal 1
# @increment 5
# @reboot_required false

uint8 flags
# Flags
# @bit 0 First
# @bit 7 Last
# @value 1 One
# @value 0x80 Big
# @format hex

px.I2c.1.0 i2c
# Where it is
# @default address 0x45

float32 gain
# @default 1e-3

bool enabled

void3
@sealed
"""


@pytest.fixture(scope="module")
def schema(tmp_path_factory: pytest.TempPathFactory) -> Schema:
    root = tmp_path_factory.mktemp("dsdl") / "ext"
    root.mkdir()
    (root / "EveryTag.1.0.dsdl").write_text(TAGS_DSDL)
    return load_schema(
        [root],
        include_dronecan=False,
        use_env=False,
        cache_dir=tmp_path_factory.mktemp("cache"),
    )


def test_every_type_tag_gives_its_typed_value(schema: Schema) -> None:
    declared = schema.type_def("ext.EveryTag")
    assert declared.key == "ext.EveryTag.1.0"
    assert (declared.name, declared.version, declared.is_union) == ("ext.EveryTag", (1, 0), False)
    assert declared.versioned and declared.service is None
    assert declared.file is not None and Path(declared.file).name == "EveryTag.1.0.dsdl"
    doc = declared.doc
    assert (doc.short, doc.long) == ("Every tag", "A type declaring each type tag.")
    assert (doc.group, doc.category, doc.max_instances) == ("Sensors", "Developer", 3)
    assert (doc.param, doc.reboot_required) == ("EVERY_TAG", True)
    assert doc.declares_parameter
    # The compiled type reads the same record (one per schema).
    assert schema["ext.EveryTag"].type_def is declared
    assert schema["ext.EveryTag"].doc is doc


def test_every_field_tag_gives_its_typed_value(schema: Schema) -> None:
    declared = schema.type_def("ext.EveryTag.1.0")
    assert [f.name for f in declared.fields] == [
        "p_version",
        "offset",
        "flags",
        "i2c",
        "gain",
        "enabled",
        "",
    ]
    assert [f.kind for f in declared.fields] == [
        "uint",
        "int",
        "uint",
        "ref",
        "float",
        "bool",
        "void",
    ]
    assert [f.name for f in declared.data_fields][-1] == "enabled"
    offset = declared.field("offset")
    assert offset is not None
    d = offset.doc
    assert (d.short, d.long, d.unit) == ("Offset", "Offset added to the reading.", "mm")
    assert (d.minimum, d.maximum, d.default, d.declared_default) == (-1000, 1000, -16, -16)
    assert (d.decimal_places, d.increment, d.reboot_required) == (1, 5, False)
    assert (d.values, d.bits, d.display_format, d.path_defaults) == ((), (), None, None)
    flags = declared.field("flags")
    assert flags is not None
    assert flags.doc.bits == ((0, "First"), (7, "Last"))
    assert flags.doc.values == ((1, "One"), (0x80, "Big"))
    assert flags.doc.display_format == "hex"
    assert flags.doc.minimum is None and flags.doc.unit is None
    i2c = declared.field("i2c")
    assert i2c is not None
    assert i2c.doc.path_defaults == {"address": 0x45}
    assert i2c.doc.declared_default == {"address": 0x45} and i2c.doc.default is None
    gain = declared.field("gain")
    assert gain is not None and gain.doc.default == pytest.approx(1e-3)
    assert declared.field("enabled") is not None
    assert declared.field("enabled").doc is NO_DOC  # type: ignore[union-attr]
    assert declared.field("") is None and declared.field("nope") is None


def test_a_leaf_path_finds_its_field(schema: Schema) -> None:
    data_type = schema["ext.EveryTag"]
    address = data_type.field_at("i2c.address")
    assert address is not None and address.name == "address"
    assert data_type.field_at("offset").doc.unit == "mm"  # type: ignore[union-attr]
    assert data_type.field_at("i2c.nope") is None
    assert data_type.field_at("offset.deeper") is None
    # An array's field describes its elements: cells[3].volts ends at volts.
    battery = load_schema(use_env=False)["px.BattSmbus"]
    cells = [f for f in battery.type_def.data_fields if f.kind in ("array", "dynarray")]
    for field in cells:
        assert battery.field_at(f"{field.name}[0]") == field


def _definition(tags: dict[str, Any], type_tags: dict[str, Any] | None = None) -> dict[str, Any]:
    """A hand-built model type with one field ``shunt`` carrying ``tags``."""
    return {
        "name": "x.Shunt",
        "version": [1, 0],
        "kind": "struct",
        "dialect": "dsdl",
        "file": "/dsdl/x/Shunt.1.0.dsdl",
        "doc": {"short": "", "long": "", "tags": type_tags or {}},
        "fields": [
            {
                "name": "shunt",
                "type": {"kind": "float", "bits": 16, "cast": "saturated"},
                "line": 7,
                "doc": {"short": "Shunt", "long": "", "tags": tags},
            }
        ],
    }


@pytest.mark.parametrize(
    ("tags", "message"),
    [
        ({"min": "0.1"}, "x.Shunt.1.0.shunt: @min expects a number, got '0.1'"),
        ({"max": True}, "x.Shunt.1.0.shunt: @max expects a number, got True"),
        ({"unit": ""}, "x.Shunt.1.0.shunt: @unit expects text, got ''"),
        ({"unit": 5}, "x.Shunt.1.0.shunt: @unit expects text, got 5"),
        ({"decimal": -1}, "x.Shunt.1.0.shunt: @decimal expects a whole number of at least 0"),
        ({"format": "oct"}, "x.Shunt.1.0.shunt: @format expects hex, got 'oct'"),
        ({"default": "x"}, "x.Shunt.1.0.shunt: @default expects a number or true/false"),
        ({"default": {"a.b": [1]}}, "x.Shunt.1.0.shunt: @default expects a number or true"),
        ({"value": [[1]]}, "x.Shunt.1.0.shunt: @value expects [number, description], got [1]"),
        ({"value": 3}, "x.Shunt.1.0.shunt: @value expects a list of [number, description]"),
        ({"bit": [[-1, "x"]]}, "x.Shunt.1.0.shunt: @bit expects a whole number of at least 0"),
        ({"reboot_required": 1}, "x.Shunt.1.0.shunt: @reboot_required expects true or false"),
        ({"mni": 1}, "x.Shunt.1.0.shunt: @mni is not a field tag (expected one of unit, min,"),
    ],
)
def test_a_malformed_field_tag_is_one_line_naming_type_field_and_tag(
    tags: dict[str, Any], message: str
) -> None:
    (shunt,) = type_def("x.Shunt.1.0", _definition(tags)).fields  # tags not read yet
    with pytest.raises(DsdlError) as caught:
        assert not shunt.doc  # read when first asked for
    text = str(caught.value)
    assert "\n" not in text
    assert text.startswith("/dsdl/x/Shunt.1.0.dsdl:7: " + message), text


@pytest.mark.parametrize(
    ("tags", "message"),
    [
        ({"default": "x"}, "x.Shunt.1.0.shunt: @default expects a number or true/false, got 'x'"),
        ({"default": {"": 1}}, "x.Shunt.1.0.shunt: @default expects field paths, got ''"),
    ],
)
def test_a_default_read_alone_is_refused_in_the_docs_words(
    tags: dict[str, Any], message: str
) -> None:
    """A store's defaults read ``@default`` alone (Field.declared_default), refused as the
    whole doc would refuse it."""
    (shunt,) = type_def("x.Shunt.1.0", _definition(tags)).fields
    with pytest.raises(DsdlError) as caught:
        assert shunt.declared_default is None
    assert str(caught.value) == "/dsdl/x/Shunt.1.0.dsdl:7: " + message


def test_a_default_is_read_without_the_other_tags() -> None:
    """Only what is asked for is read: the default of a field whose @min is malformed is
    there; its doc, asked for, is refused."""
    (shunt,) = type_def("x.Shunt.1.0", _definition({"default": 0.5, "min": "low"})).fields
    assert shunt.declared_default == 0.5
    with pytest.raises(DsdlError, match=r"shunt: @min expects a number, got 'low'$"):
        assert not shunt.doc
    path = {"default": {"i2c.address": 0x45}}
    (bus,) = type_def("x.Shunt.1.0", _definition(path)).fields
    assert bus.declared_default == {"i2c.address": 0x45} == bus.doc.declared_default
    assert type_def("x.Shunt.1.0", _definition({})).fields[0].declared_default is None


def test_every_bundled_default_read_alone_is_the_docs() -> None:
    types = load_schema(use_env=False).model["types"]
    for key, definition in types.items():
        alone = type_def(key, definition).fields  # (not kept: read again here)
        whole = type_def(key, definition).fields
        for field, again in zip(alone, whole, strict=True):
            assert field.declared_default == again.doc.declared_default, (key, field.name)


@pytest.mark.parametrize(
    ("tags", "message"),
    [
        ({"max_instances": 0}, "x.Shunt.1.0: @max_instances expects a whole number of at least 1"),
        ({"max_instances": "4"}, "x.Shunt.1.0: @max_instances expects a whole number"),
        ({"group": None}, "x.Shunt.1.0: @group expects text, got None"),
        ({"unit": "A"}, "x.Shunt.1.0: @unit is not a type tag (expected one of group, category"),
    ],
)
def test_a_malformed_type_tag_is_one_line_naming_type_and_tag(
    tags: dict[str, Any], message: str
) -> None:
    with pytest.raises(DsdlError) as caught:
        assert not type_def("x.Shunt.1.0", _definition({}, tags)).doc
    assert str(caught.value).startswith("/dsdl/x/Shunt.1.0.dsdl: " + message), caught.value


def test_a_doc_of_the_wrong_shape_is_refused() -> None:
    definition = _definition({})
    definition["fields"][0]["doc"] = ["not", "a", "table"]
    (shunt,) = type_def("x.Shunt.1.0", definition).fields
    with pytest.raises(DsdlError, match=r"x\.Shunt\.1\.0\.shunt: doc is not a table"):
        assert not shunt.doc
    with pytest.raises(DsdlError, match=r"x\.Shunt\.1\.0\.shunt: doc is not a table"):
        assert shunt.declared_default is None


def test_a_hand_built_schema_is_refused_where_its_tags_are_first_read() -> None:
    """A schema made from a model dict reads a type's tags when a layer first asks for them:
    the store's defaults read ``@default`` (no store is built over a bad one); a field's range
    is read by the first write it checks, which is refused naming the bad tag."""
    import px4params

    bad_default = _definition({"default": "high"}, {"max_instances": 2})
    with pytest.raises(DsdlError, match=r"x\.Shunt\.1\.0\.shunt: @default expects a number"):
        px4params.Store(Schema({"types": {"x.Shunt.1.0": bad_default}}), classic=[])
    bad_min = _definition({"min": "low"}, {"max_instances": 2})
    store = px4params.Store(Schema({"types": {"x.Shunt.1.0": bad_min}}), classic=[])
    store.add("SHUNT#0")
    with pytest.raises(DsdlError, match=r"x\.Shunt\.1\.0\.shunt: @min expects a number"):
        store.set("SHUNT#0.shunt", 0.5)
    assert store.get("SHUNT#0.shunt") == 0


def test_each_tag_is_read_in_one_place() -> None:
    """No module outside the model reads a doc comment's tags from the dict (the lookups the
    typed model replaced: ``["doc"]``, ``.get("tags")`` ...)."""
    package = Path(__file__).resolve().parents[1] / "python" / "px4params"
    allowed = {"dsdl/model.py", "dsdl/loader.py", "dsdl/cache.py"}
    patterns = ('["doc"]', 'get("doc"', 'get("tags"', '["tags"]')
    found = [
        f"{path.relative_to(package)}: {pattern}"
        for path in package.rglob("*.py")
        if str(path.relative_to(package)) not in allowed
        for pattern in patterns
        if pattern in path.read_text()
    ]
    assert found == []


def test_the_bundled_types_read_without_error() -> None:
    schema = load_schema(use_env=False)
    declared = [schema.type_def(key) for key in schema]
    ina = schema.type_def("px.Ina238")
    assert ina.doc.max_instances == 4 and ina.doc.group == "Sensors"
    shunt = ina.field("shunt")
    assert shunt is not None and shunt.doc.unit == "Ohm"
    assert len(declared) == len(schema)
