//! The store's leaf tables (`Store::with_tables`, `table_slots`) against what their
//! documentation promises (issue 40): `table_slots` counts one slot per parameter, each
//! distinct type's table once (`LeafTable::slots_needed`), and for each instance's value and
//! default one slot per leaf the table answers for, at most 32; a parameter whose type is not
//! in the layout counts its one slot only.

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{NodeId, Role};
use px4params_core::store::{table_slots, ParamDef};
use px4params_core::table::LeafTable;
use px4params_core::Cast;

/// A struct of three primitive leaves (no union, no dynamic array: its table has all three),
/// and a fixed array of 40 bytes (40 leaves: more than the 32 resolved per value).
fn types() -> (OwnedLayout, NodeId, NodeId) {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let i16_ = l.int(16, Cast::Saturated).unwrap();
    let f32_ = l.float(32, Cast::Saturated).unwrap();
    let three = l
        .structure(&[
            ("a", u8_, Role::Data),
            ("b", i16_, Role::Data),
            ("c", f32_, Role::Data),
        ])
        .unwrap();
    let forty = l.array(u8_, 40).unwrap();
    (l, three, forty)
}

#[test]
fn table_slots_counts_each_parameter_each_type_once_and_each_value_s_leaves() {
    let (l, three, forty) = types();
    let layout = l.as_layout();
    let t3 = LeafTable::slots_needed(&layout, three);
    let t40 = LeafTable::slots_needed(&layout, forty);
    assert!(t3 > 0 && t40 > 0);
    let slots = |defs: &[ParamDef]| table_slots(&layout, defs);
    // One parameter, its type's table, 3 leaves for the value and 3 for the default.
    assert_eq!(slots(&[ParamDef::shared(three)]), 1 + t3 + 3 * 2);
    // Four instances: 4 values and 4 defaults.
    assert_eq!(slots(&[ParamDef::instanced(three, 4)]), 1 + t3 + 3 * 2 * 4);
    // The same type twice: its table once, each parameter's instances their own.
    assert_eq!(
        slots(&[ParamDef::instanced(three, 4), ParamDef::shared(three)]),
        2 + t3 + 3 * 2 * 4 + 3 * 2
    );
    assert_eq!(
        slots(&[
            ParamDef::shared(three),
            ParamDef::instanced(forty, 2),
            ParamDef::instanced(three, 2),
        ]),
        3 + t3 + t40 + 3 * 2 + 32 * 2 * 2 + 3 * 2 * 2
    );
    // 40 leaves: 32 of them resolved per value.
    assert_eq!(slots(&[ParamDef::shared(forty)]), 1 + t40 + 32 * 2);
    // A type the layout does not have: the parameter's own slot only.
    let unknown = layout.nodes.len() as NodeId;
    assert_eq!(slots(&[ParamDef::instanced(unknown, 2)]), 1);
    assert_eq!(
        slots(&[ParamDef::instanced(unknown, 2), ParamDef::shared(three)]),
        2 + t3 + 3 * 2
    );
    assert_eq!(slots(&[]), 0);
}
