//! `Store::set_from` honours its `saturate` flag (issue 40): DroneCAN's `saturated` cast mode
//! clamps a value outside the field's range to the nearest bound when asked to, and otherwise
//! the write is refused with the memory left as it was. The classic parameter of tests/common
//! is a saturated int32, shared (instance 0), stored little-endian in 4 bytes.

mod common;

use px4params_core::compile::OwnedLayout;
use px4params_core::store::{plan, ParamDef, Slot, Store, StoreError, Which};
use px4params_core::value::LeafSource;
use px4params_core::Scalar;

const CLASSIC: u32 = 2;

#[test]
fn a_whole_value_out_of_range_is_clamped_only_when_asked() {
    let mut layout = OwnedLayout::default();
    let mut defs = common::store_params(&mut layout);
    let layout_ref = layout.as_layout();
    let capacity = plan(&layout_ref, &mut defs).unwrap();
    let mut store: Store<Vec<ParamDef>, Vec<Slot>, Vec<u8>> = Store::new(
        &layout_ref,
        defs,
        vec![Slot::default(); capacity.slots],
        vec![0u8; capacity.bytes],
    )
    .unwrap();
    // A shared (not instanced) parameter: its one instance, 0, is always present.
    let instance = 0;
    let too_big = [Scalar::Int(1 << 40)];
    let e = store
        .set_from(
            &layout_ref,
            CLASSIC,
            instance,
            Which::Value,
            &mut LeafSource::new(&too_big),
            false,
        )
        .unwrap_err();
    assert!(matches!(e, StoreError::Codec(_)), "{e:?}");
    assert_eq!(store.get(CLASSIC, instance, Which::Value).unwrap(), [0; 4]);
    store
        .set_from(
            &layout_ref,
            CLASSIC,
            instance,
            Which::Value,
            &mut LeafSource::new(&too_big),
            true,
        )
        .unwrap();
    // i32::MAX, little-endian.
    assert_eq!(
        store.get(CLASSIC, instance, Which::Value).unwrap(),
        [0xFF, 0xFF, 0xFF, 0x7F]
    );
    let too_small = [Scalar::Int(-(1 << 40))];
    store
        .set_from(
            &layout_ref,
            CLASSIC,
            instance,
            Which::Value,
            &mut LeafSource::new(&too_small),
            true,
        )
        .unwrap();
    assert_eq!(
        store.get(CLASSIC, instance, Which::Value).unwrap(),
        [0x00, 0x00, 0x00, 0x80]
    );
}
