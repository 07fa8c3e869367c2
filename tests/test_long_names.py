"""DroneCAN's long names of destructured parameters (``px4params.store.long_names``), held to
the rules they come from: ``uavcan.protocol.param.GetSet``'s name is ``uint8[<=92]`` (DroneCAN
DSDL, ``uavcan/protocol/param/11.GetSet.uavcan``), so a name of 92 characters is carried and one
of 93 cannot be; a name is the instance and the leaf's path (docs, the module's doc), and no
two parameters may answer to one name (a GetSet by name must find exactly one)."""

from __future__ import annotations

from pathlib import Path

import px4params
import pytest
from px4params.errors import FlatError
from px4params.store.classic import ClassicParam
from px4params.store.long_names import MAX_LONG_NAME_LEN, LongNames

pytestmark = pytest.mark.issue40


def _store(tmp_path: Path, files: dict[str, str], classic: list[ClassicParam] | None = None):
    root = tmp_path / "ln"
    root.mkdir(parents=True)
    for name, text in files.items():
        (root / name).write_text(text)
    schema = px4params.load_schema(
        [root], include_dronecan=False, use_env=False, cache_dir=tmp_path / "cache"
    )
    return px4params.Store(schema, classic=classic or [])


def _wide(instances: int | None, field: str) -> dict[str, str]:
    """``WIDE`` with one uint8 leaf named ``field``: instanced (``instances``) or shared."""
    head = f"# @max_instances {instances}\n" if instances else "# @param WIDE\n"
    return {"Wide.1.0.dsdl": f"{head}uint4 p_version\nuint8 {field}\n@sealed\n"}


def test_getsets_name_holds_92_characters() -> None:
    assert MAX_LONG_NAME_LEN == 92


def test_a_name_of_92_characters_is_carried_and_93_refused(tmp_path: Path) -> None:
    # WIDE_9_ is 7 characters: an 85-letter field makes WIDE#9's name 92, WIDE#10's 93.
    field = "f" * 85
    names = LongNames(_store(tmp_path / "ten", _wide(10, field)))
    store = names._store
    store.add("WIDE#9")
    (row,) = names.table()
    assert (row.name, len(row.name), str(row.target)) == (
        f"WIDE_9_{field.upper()}",
        92,
        f"WIDE#9.{field}",
    )
    with pytest.raises(FlatError) as info:
        LongNames(_store(tmp_path / "eleven", _wide(11, field)))
    assert str(info.value) == (
        f"WIDE: DroneCAN name WIDE_10_{field.upper()} (WIDE#10.{field}) has 93 characters "
        "(at most 92)"
    )


@pytest.mark.parametrize(
    ("instances", "widest"), [(1, 0), (10, 0), (11, 10), (100, 10), (101, 100), (256, 100)]
)
def test_the_widest_instance_number_is_the_one_checked(
    tmp_path: Path, instances: int, widest: int
) -> None:
    """Every instance from 0 to max_instances - 1 (at most 255) has a name: those with the most
    digits are the longest. A field that makes them 93 characters is refused, naming the first
    (instances are checked in order); one letter less, every name fits."""
    prefix = f"WIDE_{widest}_"
    field = "f" * (MAX_LONG_NAME_LEN + 1 - len(prefix))
    with pytest.raises(FlatError) as info:
        LongNames(_store(tmp_path, _wide(instances, field)))
    assert str(info.value) == (
        f"WIDE: DroneCAN name {prefix}{field.upper()} (WIDE#{widest}.{field}) has 93 "
        "characters (at most 92)"
    )
    # one letter less: every instance's name fits
    LongNames(_store(tmp_path / "less", _wide(instances, field[1:])))


def test_a_shared_parameters_name_has_no_number(tmp_path: Path) -> None:
    field = "f" * (MAX_LONG_NAME_LEN - len("WIDE_"))
    names = LongNames(_store(tmp_path / "fits", _wide(None, field)))
    assert [(row.name, str(row.leaf)) for row in names.table()] == [
        (f"WIDE_{field.upper()}", "WIDE[1]")
    ]
    with pytest.raises(FlatError) as info:
        LongNames(_store(tmp_path / "over", _wide(None, field + "f")))
    assert str(info.value) == (
        f"WIDE: DroneCAN name WIDE_{field.upper()}F (WIDE.{field}f) has 93 characters (at most 92)"
    )


def test_a_parameter_named_like_another_parameters_long_names(tmp_path: Path) -> None:
    """``BAT_0`` beside the instanced ``BAT``: its leaf ``volts`` would be ``BAT_0_VOLTS``,
    which is ``BAT#0.volts``'s name; its leaf ``amps`` names nothing of ``BAT``'s."""
    bat = "# @max_instances 2\nuint4 p_version\nuint8 volts\n@sealed\n"
    for field, clash in (("amps", False), ("volts", True)):
        files = {
            "Bat.1.0.dsdl": bat,
            "Bat0.1.0.dsdl": f"# @param BAT_0\nuint4 p_version\nuint8 {field}\n@sealed\n",
        }
        store = _store(tmp_path / field, files)
        if not clash:  # BAT_0_AMPS is BAT_0's (BAT has no leaf amps): so is a classic's name
            classic = [ClassicParam("BAT_0_AMPS", "Int32", 0)]
            with pytest.raises(FlatError) as info:
                LongNames(_store(tmp_path / "classic", files, classic))
            assert str(info.value) == (
                "BAT_0: DroneCAN name BAT_0_AMPS (BAT_0.amps) is the name of another parameter"
            )
        if not clash:
            store.add("BAT#0")
            names = [row.name for row in LongNames(store).table()]
            assert names == ["BAT_0_VOLTS", "BAT_0_AMPS"]
            continue
        with pytest.raises(FlatError) as info:
            LongNames(store)
        assert str(info.value) == (
            "BAT_0: DroneCAN name BAT_0_VOLTS (BAT_0.volts) is the name of another parameter"
        )


def test_a_long_name_that_is_an_instance_masks_name_is_refused(tmp_path: Path) -> None:
    """``AB_CD``'s instance mask is ``AB_CD_INST``; the shared ``AB``'s leaf ``cd_inst`` would be
    named so too."""
    files = {
        "AbCd.1.0.dsdl": "# @max_instances 2\nuint4 p_version\nuint8 x\n@sealed\n",
        "Ab.1.0.dsdl": "# @param AB\nuint4 p_version\nuint8 cd_inst\n@sealed\n",
    }
    store = _store(tmp_path, files)
    with pytest.raises(FlatError) as info:
        LongNames(store)
    assert str(info.value) == (
        "AB: DroneCAN name AB_CD_INST (AB.cd_inst) is the name of another parameter"
    )


def test_two_leaves_of_one_instance_under_one_name_are_refused(tmp_path: Path) -> None:
    """A leaf ``a_b`` and a leaf ``b`` of a struct ``a`` would both be ``CL_0_A_B``: a GetSet of
    that name could not say which it means."""
    files = {
        "Inner.1.0.dsdl": "uint8 b\n@sealed\n",
        "Cl.1.0.dsdl": "# @max_instances 2\nuint4 p_version\nuint8 a_b\nInner.1.0 a\n@sealed\n",
    }
    with pytest.raises(FlatError) as info:
        LongNames(_store(tmp_path, files))
    message = "CL: DroneCAN name CL_0_A_B is the name of two of its leaves, CL#0.a_b and CL#0.a.b"
    assert str(info.value) == message


@pytest.mark.parametrize(
    ("classic", "message"),
    [
        # Q#1's leaf v: a one-letter parameter's name is read like any other
        ("Q_1_V", "Q: DroneCAN name Q_1_V (Q#1.v) is the name of another parameter"),
        # a shared parameter's leaf; then Q_X's, read past Q (X is no instance number)
        ("QX_X_W", "QX: DroneCAN name QX_X_W (QX.x_w) is the name of another parameter"),
        ("Q_X_W", "Q_X: DroneCAN name Q_X_W (Q_X.w) is the name of another parameter"),
        ("Q_5_V", None),  # Q has instances 0 and 1 only: no leaf of Q is named so
    ],
)
def test_a_classic_parameter_named_like_a_leaf_is_refused(
    tmp_path: Path, classic: str, message: str | None
) -> None:
    files = {
        "Q.1.0.dsdl": "# @max_instances 2\nuint4 p_version\nuint8 v\n@sealed\n",
        "Qx.1.0.dsdl": "# @param QX\nuint4 p_version\nuint8 x_w\n@sealed\n",
        "QxW.1.0.dsdl": "# @param Q_X\nuint4 p_version\nuint8 w\n@sealed\n",
    }
    store = _store(tmp_path, files, [ClassicParam(classic, "Int32", 0)])
    if message is None:
        LongNames(store)
        return
    with pytest.raises(FlatError) as info:
        LongNames(store)
    assert str(info.value) == message


def test_a_parameter_whose_type_is_a_union_names_its_variants(tmp_path: Path) -> None:
    """The tag of a parameter that is itself a union is ``<NAME>_<N>_TYPE``; its variant's
    leaves are named by the variant."""
    files = {"Pick.1.0.dsdl": "# @max_instances 1\n@union\nuint8 low\nuint16 high\n@sealed\n"}
    store = _store(tmp_path, files)
    store.add("PICK#0")
    store.set("PICK#0", {"high": 7})
    assert [(row.name, str(row.target)) for row in LongNames(store).table()] == [
        ("PICK_0_TYPE", "PICK#0._tag"),
        ("PICK_0_HIGH", "PICK#0.high"),
    ]


def test_a_variant_stands_for_its_union_field_at_any_depth(tmp_path: Path) -> None:
    """``s.u.low`` of a union ``u`` inside a struct ``s`` is ``S_LOW``; its tag ``S_U_TYPE``."""
    files = {
        "Choice.1.0.dsdl": "@union\nuint8 low\nuint8 high\n@sealed\n",
        "Holder.1.0.dsdl": "Choice.1.0 u\n@sealed\n",
        "Deep.1.0.dsdl": "# @max_instances 1\nuint4 p_version\nHolder.1.0 s\n@sealed\n",
    }
    store = _store(tmp_path, files)
    store.add("DEEP#0")
    assert [(row.name, str(row.target)) for row in LongNames(store).table()] == [
        ("DEEP_0_S_U_TYPE", "DEEP#0.s.u._tag"),
        ("DEEP_0_S_LOW", "DEEP#0.s.u.low"),
    ]


@pytest.mark.parametrize("instanced_q", [False, True])
def test_a_name_with_two_underscores_in_a_row_is_read(tmp_path: Path, instanced_q: bool) -> None:
    """``Q_``'s leaf ``v`` is ``Q__V`` (a parameter name may end in ``_``), also beside an
    instanced ``Q`` (whose names are ``Q_<N>_...``): a classic of that name clashes."""
    files = {"Qu.1.0.dsdl": "# @param Q_\nuint4 p_version\nuint8 v\n@sealed\n"}
    if instanced_q:
        files["Q.1.0.dsdl"] = "# @max_instances 2\nuint4 p_version\nuint8 v\n@sealed\n"
    store = _store(tmp_path, files, [ClassicParam("Q__V", "Int32", 0)])
    with pytest.raises(FlatError) as info:
        LongNames(store)
    assert str(info.value) == "Q_: DroneCAN name Q__V (Q_.v) is the name of another parameter"
