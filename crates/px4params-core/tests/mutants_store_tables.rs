//! The store's leaf tables (`Store::with_tables`, `table_slots`) against what their
//! documentation promises (issue 40): `table_slots` counts one slot per parameter, each
//! distinct type's table once (`LeafTable::slots_needed`), and for each instance's value and
//! default one slot per leaf the table answers for, at most 32; a parameter whose type is not
//! in the layout counts its one slot only; the tables are built over whatever the memory
//! given for them held.

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{NodeId, Role};
use px4params_core::leaf::Target;
use px4params_core::store::{plan, table_slots, ParamDef, Slot, Store, Which};
use px4params_core::table::{LeafSlot, LeafTable};
use px4params_core::{Cast, Scalar};

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

type TabledStore<'t> = Store<Vec<ParamDef>, Vec<Slot>, Vec<u8>, &'t mut [LeafSlot]>;

/// A store of `defs` with its tables in `tables` (enough for all of them).
fn store_over<'t>(
    layout: &px4params_core::Layout<'_>,
    defs: &[ParamDef],
    tables: &'t mut [LeafSlot],
) -> TabledStore<'t> {
    let mut defs = defs.to_vec();
    let capacity = plan(layout, &mut defs).unwrap();
    assert!(table_slots(layout, &defs) <= tables.len());
    Store::with_tables(
        layout,
        defs,
        vec![Slot::default(); capacity.slots],
        vec![0u8; capacity.bytes],
        tables,
    )
    .unwrap()
}

/// The tables a store builds replace whatever the memory given for them held: here first a
/// leaf table of another type, then another store's tables of other parameters (firmware
/// makes its store again over the same static memory after a reset). Values written by hand
/// (DroneCAN: byte-aligned fields little-endian): `three` a = 7, b = -2, c = 1.5 is
/// 07 FE FF 00 00 C0 3F; `forty` holds 100..140.
#[test]
fn tables_are_built_anew_over_memory_that_held_other_tables() {
    let (l, three, forty) = types();
    let layout = l.as_layout();
    let three_value = [0x07, 0xFE, 0xFF, 0x00, 0x00, 0xC0, 0x3F];
    let forty_value: Vec<u8> = (100..140).collect();
    let first = [ParamDef::instanced(forty, 2), ParamDef::shared(three)];
    let second = [ParamDef::shared(three), ParamDef::instanced(forty, 2)];
    let mut memory = vec![LeafSlot::default(); 400];
    // What the memory holds first: `forty`'s leaf table, written at a few places.
    for start in [0, 1, 2, 200] {
        LeafTable::build(&layout, forty, &mut memory[start..]).unwrap();
    }
    // `three`'s b, its zero default, read through the store's own tables.
    let over_a_table =
        store_over(&layout, &second, &mut memory).read(&layout, 0, 0, Which::Value, 1);
    assert_eq!(over_a_table, Ok(Scalar::Int(0)));
    {
        let mut s = store_over(&layout, &first, &mut memory);
        s.add(0, Some(1)).unwrap();
        s.set_encoded(&layout, 0, 1, Which::Value, &forty_value)
            .unwrap();
        s.set_encoded(&layout, 1, 0, Which::Value, &three_value)
            .unwrap();
        assert_eq!(
            s.read(&layout, 0, 1, Which::Value, 5),
            Ok(Scalar::Uint(105))
        );
    }
    let mut s = store_over(&layout, &second, &mut memory);
    s.set_encoded(&layout, 0, 0, Which::Value, &three_value)
        .unwrap();
    s.add(1, Some(0)).unwrap();
    s.set_encoded(&layout, 1, 0, Which::Value, &forty_value)
        .unwrap();
    let three_leaves = [Scalar::Uint(7), Scalar::Int(-2), Scalar::Float(1.5)];
    for (k, leaf) in three_leaves.into_iter().enumerate() {
        assert_eq!(s.read(&layout, 0, 0, Which::Value, k), Ok(leaf), "[{k}]");
        let got = s.get_leaf(&layout, 0, 0, Which::Value, Target::Index(k));
        assert_eq!(got.map(|(_, v)| v), Ok(leaf), "[{k}]");
    }
    for k in 0..40 {
        let leaf = Scalar::Uint(100 + k as u64);
        assert_eq!(s.read(&layout, 1, 0, Which::Value, k), Ok(leaf), "[{k}]");
        let got = s.get_leaf(&layout, 1, 0, Which::Value, Target::Index(k));
        assert_eq!(got.map(|(_, v)| v), Ok(leaf), "[{k}]");
    }
}

/// Tables past 65536 slots: five parameters of 256 instances (PX4's most) with 32 resolved
/// leaves per value and default take 5 * 16384 slots; the last parameter's area starts past
/// slot 65536 and its leaves read as written (`three` a = 7, b = -2, c = 1.5 as above).
#[test]
fn leaves_resolved_past_slot_65536_read_as_written() {
    let (l, three, forty) = types();
    let layout = l.as_layout();
    let mut defs = vec![ParamDef::instanced(forty, 256); 4];
    defs.push(ParamDef::instanced(three, 256));
    let n = table_slots(&layout, &defs);
    // The first four areas alone: 4 * 32 * 2 * 256 = 65536 slots.
    assert!(n > 4 * 32 * 2 * 256);
    let mut memory = vec![LeafSlot::default(); n];
    let mut s = store_over(&layout, &defs, &mut memory);
    let three_value = [0x07, 0xFE, 0xFF, 0x00, 0x00, 0xC0, 0x3F];
    let forty_value: Vec<u8> = (100..140).collect();
    for instance in [0, 255] {
        s.add(3, Some(instance)).unwrap();
        s.set_encoded(&layout, 3, instance, Which::Value, &forty_value)
            .unwrap();
        s.add(4, Some(instance)).unwrap();
        s.set_encoded(&layout, 4, instance, Which::Value, &three_value)
            .unwrap();
    }
    let three_leaves = [Scalar::Uint(7), Scalar::Int(-2), Scalar::Float(1.5)];
    for instance in [0, 255] {
        for (k, leaf) in three_leaves.into_iter().enumerate() {
            assert_eq!(s.read(&layout, 4, instance, Which::Value, k), Ok(leaf));
            assert_eq!(s.read(&layout, 4, instance, Which::Default, k), Ok(zero(k)));
        }
        for k in [0, 31, 39] {
            let leaf = Scalar::Uint(100 + k as u64);
            assert_eq!(s.read(&layout, 3, instance, Which::Value, k), Ok(leaf));
        }
    }
}

/// `three`'s zero value, leaf by leaf.
fn zero(k: usize) -> Scalar {
    [Scalar::Uint(0), Scalar::Int(0), Scalar::Float(0.0)][k]
}

/// Each instance's resolved leaves are its own, also where the tables are given more room
/// than [`table_slots`] asks for (firmware's static memory sized for a larger manifest): the
/// tables take what they need, and every leaf of every instance, value and default, reads
/// as written. Three parameters after one another (`three` shared, `forty` and `three` with
/// four instances each), written in that order; values by hand as above: `forty` instance i
/// holds 50 i + k at [k] and 255 - k - i in its default, `three` instance i a = i + 1,
/// b = -2 - i, c = 1.5 + i, and its default a = 9, b = 300, c = -0.5.
#[test]
fn every_instance_reads_its_own_leaves_with_more_table_memory_than_needed() {
    let (l, three, forty) = types();
    let layout = l.as_layout();
    let three_bytes = |a: u8, b: i16, c: f32| {
        let mut v = vec![a];
        v.extend(b.to_le_bytes());
        v.extend(c.to_le_bytes());
        v
    };
    let forty_value = |i: u16| (0..40).map(|k| (50 * i + k) as u8).collect::<Vec<_>>();
    let forty_default = |i: u16| (0..40).map(|k| (255 - k - i) as u8).collect::<Vec<_>>();
    let three_value = |i: u16| three_bytes(i as u8 + 1, -2 - i as i16, 1.5 + f32::from(i));
    let defs = [
        ParamDef::shared(three),
        ParamDef::instanced(forty, 4),
        ParamDef::instanced(three, 4),
    ];
    let needed = {
        let mut planned = defs.to_vec();
        plan(&layout, &mut planned).unwrap();
        table_slots(&layout, &planned)
    };
    for room in [needed, 2 * needed, 4 * needed] {
        let mut memory = vec![LeafSlot::default(); room];
        let mut s = store_over(&layout, &defs, &mut memory);
        s.set_encoded(&layout, 0, 0, Which::Value, &three_bytes(5, -7, 2.25))
            .unwrap();
        for i in 0..4 {
            s.add(1, Some(i)).unwrap();
            s.set_encoded(&layout, 1, i, Which::Value, &forty_value(i))
                .unwrap();
            s.set_encoded(&layout, 1, i, Which::Default, &forty_default(i))
                .unwrap();
        }
        for i in 0..4 {
            s.add(2, Some(i)).unwrap();
            s.set_encoded(&layout, 2, i, Which::Value, &three_value(i))
                .unwrap();
            s.set_encoded(&layout, 2, i, Which::Default, &three_bytes(9, 300, -0.5))
                .unwrap();
        }
        let shared = [Scalar::Uint(5), Scalar::Int(-7), Scalar::Float(2.25)];
        for (k, leaf) in shared.into_iter().enumerate() {
            assert_eq!(
                s.read(&layout, 0, 0, Which::Value, k),
                Ok(leaf),
                "room {room}"
            );
        }
        for i in 0..4u16 {
            for k in 0..40 {
                let value = Scalar::Uint(u64::from(50 * i) + k as u64);
                let default = Scalar::Uint(255 - k as u64 - u64::from(i));
                let at = format!("room {room}: forty#{i}[{k}]");
                assert_eq!(s.read(&layout, 1, i, Which::Value, k), Ok(value), "{at}");
                assert_eq!(
                    s.read(&layout, 1, i, Which::Default, k),
                    Ok(default),
                    "{at}"
                );
            }
            let value = [
                Scalar::Uint(u64::from(i) + 1),
                Scalar::Int(-2 - i64::from(i)),
                Scalar::Float(1.5 + f64::from(i)),
            ];
            let default = [Scalar::Uint(9), Scalar::Int(300), Scalar::Float(-0.5)];
            for k in 0..3 {
                let at = format!("room {room}: three#{i}[{k}]");
                assert_eq!(s.read(&layout, 2, i, Which::Value, k), Ok(value[k]), "{at}");
                assert_eq!(
                    s.read(&layout, 2, i, Which::Default, k),
                    Ok(default[k]),
                    "{at}"
                );
            }
        }
    }
}
