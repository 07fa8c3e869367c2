//! `Store::set_leaf` honours its `saturate` flag (issue 40), in every build: hosts write a
//! primitive leaf in place, firmware builds (`--features compact`: no leaf tables) through
//! the value copied into the scratch area. DroneCAN's `saturated` cast mode clamps a number
//! outside the field's range to the nearest bound when asked to (docs/codec.md, "Cast modes");
//! otherwise the write is refused, naming the field and its range, and the memory is left as
//! it was.
//!
//! The parameter: 2 instances of tests/common's Sensor 1.1 (uint4 p_version of minor 1, uint7
//! address, bool enabled, int5 offset, all saturated). Its default, p_version 1, address 0x45,
//! enabled, offset -3, is `0001 1000101 1 11101` = `18 BE 80` (each byte filled from its most
//! significant bit, docs/codec.md); the bytes below are worked out the same way by hand.

mod common;

use px4params_core::compile::OwnedLayout;
use px4params_core::leaf::Target;
use px4params_core::store::{ParamDef, StoreError, Which};
use px4params_core::Scalar;

const SENSOR: u32 = 0;
const DEFAULT: [u8; 3] = [0x18, 0xBE, 0x80];

fn fixture() -> (OwnedLayout, common::VecStore) {
    let mut l = OwnedLayout::default();
    let (sensor, _) = common::sensor_versions(&mut l);
    let view = l.as_layout();
    let mut store = common::vec_store(&view, vec![ParamDef::instanced(sensor, 2)]);
    store.set_type_default(&view, SENSOR, &DEFAULT).unwrap();
    store.add(SENSOR, Some(1)).unwrap();
    (l, store)
}

fn set(
    l: &OwnedLayout,
    store: &mut common::VecStore,
    which: Which,
    field: &str,
    value: Scalar,
    saturate: bool,
) -> Result<(), String> {
    let view = l.as_layout();
    store
        .set_leaf(
            &view,
            SENSOR,
            1,
            which,
            Target::Path(field),
            value,
            saturate,
        )
        .map_err(|e| e.display(&view).to_string())
}

#[test]
fn a_leaf_out_of_range_is_refused_unless_saturated() {
    let (l, mut store) = fixture();
    for (field, value, message) in [
        (
            "address",
            Scalar::Uint(200),
            "address: value 200 is out of range (expected 0 to 127)",
        ),
        (
            "offset",
            Scalar::Int(-20),
            "offset: value -20 is out of range (expected -16 to 15)",
        ),
        (
            "offset",
            Scalar::Int(16),
            "offset: value 16 is out of range (expected -16 to 15)",
        ),
    ] {
        for which in [Which::Value, Which::Default] {
            assert_eq!(
                set(&l, &mut store, which, field, value, false),
                Err(message.to_string())
            );
            assert_eq!(store.get(SENSOR, 1, which).unwrap(), DEFAULT);
        }
    }
}

#[test]
fn a_saturated_leaf_is_clamped_to_its_fields_bound() {
    // (written to, field, value, saturate, the bytes by hand); the other one stays the default.
    for (which, field, value, saturate, bytes) in [
        // address 200 -> 127: 0001 1111111 1 11101 = 1F FE 80.
        (
            Which::Value,
            "address",
            Scalar::Uint(200),
            true,
            [0x1F, 0xFE, 0x80],
        ),
        // offset -20 -> -16: 0001 1000101 1 10000 = 18 B8 00, in the default too.
        (
            Which::Default,
            "offset",
            Scalar::Int(-20),
            true,
            [0x18, 0xB8, 0x00],
        ),
        // offset 40 -> 15: 0001 1000101 1 01111 = 18 B7 80.
        (
            Which::Value,
            "offset",
            Scalar::Int(40),
            true,
            [0x18, 0xB7, 0x80],
        ),
        // A value in range is written as it is, saturated or not: address 0x22 is 14 5E 80.
        (
            Which::Value,
            "address",
            Scalar::Uint(0x22),
            false,
            [0x14, 0x5E, 0x80],
        ),
        (
            Which::Value,
            "address",
            Scalar::Uint(0x22),
            true,
            [0x14, 0x5E, 0x80],
        ),
    ] {
        let (l, mut store) = fixture();
        set(&l, &mut store, which, field, value, saturate).unwrap();
        assert_eq!(
            store.get(SENSOR, 1, which).unwrap(),
            bytes,
            "{field} {value:?}"
        );
        let other = match which {
            Which::Value => Which::Default,
            _ => Which::Value,
        };
        let kept = match other {
            // A value follows its default until written itself.
            Which::Value => bytes,
            _ => DEFAULT,
        };
        assert_eq!(
            store.get(SENSOR, 1, other).unwrap(),
            kept,
            "{field} {value:?}"
        );
    }
}

#[test]
fn the_version_leaf_is_never_written() {
    // p_version is the type's own: refused whatever the flag, the value left as it was.
    let (l, mut store) = fixture();
    let view = l.as_layout();
    for saturate in [false, true] {
        let e = store
            .set_leaf(
                &view,
                SENSOR,
                1,
                Which::Value,
                Target::Path("p_version"),
                Scalar::Uint(1),
                saturate,
            )
            .unwrap_err();
        assert!(matches!(e, StoreError::VersionLeaf { .. }), "{e:?}");
        assert_eq!(store.get(SENSOR, 1, Which::Value).unwrap(), DEFAULT);
    }
}
