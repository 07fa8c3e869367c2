//! Leaf tables (`px4params_core::table`) answer exactly as the walk does: the same leaves,
//! paths, values and errors, for random types and random data, and for tables cut short by
//! small storage; the store answers the same with and without its tables.

mod common;

use common::{any_type, same_scalar};

use proptest::prelude::*;
use px4params_core::codec::{decode, DecodeOptions};
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{NodeId, Role};
use px4params_core::leaf::{get_leaf, locate, seek, Leaf, LeafAccessError, Target};
use px4params_core::store::{plan, table_slots, ParamDef, Slot, Store, Which};
use px4params_core::table::{self, LeafSlot, LeafTable};
use px4params_core::value::{LeafSink, LeafSource};
use px4params_core::{Cast, Scalar};

type Got = Result<(Leaf, Scalar), LeafAccessError>;

fn same(a: &Got, b: &Got) -> bool {
    match (a, b) {
        (Ok((la, va)), Ok((lb, vb))) => la == lb && same_scalar(*va, *vb),
        (Err(x), Err(y)) => x == y,
        _ => false,
    }
}

/// Every leaf number up to a few beyond the value's leaves, read through `table` and walked.
fn check_all(
    layout: &px4params_core::Layout<'_>,
    root: NodeId,
    table: &LeafTable<'_>,
    data: &[u8],
) -> Result<(), TestCaseError> {
    for tao in [false, true] {
        for k in 0..48 {
            let target = Target::Index(k);
            let walked = get_leaf(layout, root, data, target, tao);
            let tabled = table.get_leaf(layout, data, target, tao);
            prop_assert!(
                same(&walked, &tabled),
                "[{}] tao {}: walk {:?}, table {:?}",
                k,
                tao,
                walked,
                tabled
            );
            prop_assert_eq!(
                locate(layout, root, data, target, tao),
                table.locate(layout, data, target, tao)
            );
        }
    }
    for k in 0..48 {
        prop_assert_eq!(
            seek(layout, root, data, k),
            table.seek(layout, data, k),
            "seek [{}]",
            k
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// On random types, with random bytes and with valid values, the table gives what the
    /// walk gives, complete and cut short.
    #[test]
    fn tables_answer_as_the_walk(ty in any_type(), data in proptest::collection::vec(any::<u8>(), 0..48), cut in any::<prop::sample::Index>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let needed = LeafTable::slots_needed(&layout, root);
        let mut storage = vec![LeafSlot::default(); needed];
        let table = LeafTable::build(&layout, root, &mut storage).unwrap();
        prop_assert_eq!(table.len(), needed);
        prop_assert!(!table.is_cut_short());
        prop_assert_eq!(table.root(), root);
        // Random bytes: tags and lengths that are out of range, data that ends early.
        check_all(&layout, root, &table, &data)?;
        // A valid value (the longest prefix that decodes), exactly and with bytes after it.
        let mut leaves = [Scalar::Uint(0); 512];
        let mut sink = LeafSink::new(&mut leaves);
        let opts = DecodeOptions { tao: false, allow_trailing: true };
        if let Ok(bits) = decode(&layout, root, &data[..], &mut sink, opts) {
            let value = &data[..bits.div_ceil(8)];
            check_all(&layout, root, &table, value)?;
            // Without dynamic arrays, the table alone finds every leaf of a valid value.
            if !ty.has_dyn() {
                for k in 0..sink.leaves().len() {
                    prop_assert!(table.covers(value, k), "[{}] not covered", k);
                }
            }
        }
        // A table cut short by its storage answers the same.
        let size = table::MIN_SLOTS + cut.index(needed.max(table::MIN_SLOTS) - 1);
        let mut small = vec![LeafSlot::default(); size];
        let short = LeafTable::build(&layout, root, &mut small).unwrap();
        prop_assert!(short.len() <= size);
        prop_assert_eq!(short.is_cut_short(), size < needed);
        check_all(&layout, root, &short, &data)?;
    }
}

#[test]
fn ina238_is_covered_through_its_union() {
    let mut l = OwnedLayout::default();
    let root = common::ina238(&mut l);
    let layout = l.as_layout();
    let mut storage = vec![LeafSlot::default(); LeafTable::slots_needed(&layout, root)];
    let table = LeafTable::build(&layout, root, &mut storage).unwrap();
    // The talk's value: I2C bus 1, address 0x45, 200 mA, 0.0003 ohm.
    let mut talk: Vec<Scalar> = [0, 0, 0, 1, 0x45, 200].map(Scalar::Uint).to_vec();
    talk.push(Scalar::Float(0.0003));
    let mut data = [0u8; 16];
    let opts = px4params_core::EncodeOptions::default();
    let len = px4params_core::encode(&layout, root, &mut LeafSource::new(&talk), &mut data, opts);
    let data = &data[..len.unwrap()];
    let (leaf, value) = table
        .get_leaf(&layout, data, Target::Index(4), false)
        .unwrap();
    assert_eq!(leaf.path.display(&layout).to_string(), "bus.i2c.address");
    assert_eq!(leaf.bit_offset, 15);
    assert_eq!(value, Scalar::Uint(0x45));
    assert!(seek(&layout, root, data, 4).is_some());
    assert!((0..7).all(|k| table.covers(data, k)));
    assert!(!table.covers(data, 7));
    // Storage for none of it: every leaf is walked.
    let mut two = [LeafSlot::default(); 2];
    let bare = LeafTable::build(&layout, root, &mut two).unwrap();
    assert!(bare.is_cut_short());
    assert_eq!(
        bare.get_leaf(&layout, data, Target::Index(4), false),
        get_leaf(&layout, root, data, Target::Index(4), false)
    );
    assert!(LeafTable::build(&layout, root, &mut two[..1]).is_err());
}

/// Two stores over the same parameters, one with its tables: every read and write agrees.
#[test]
fn stores_with_and_without_tables_agree() {
    let mut l = OwnedLayout::default();
    let roots = [
        common::ina238(&mut l),
        common::battery_info(&mut l),
        common::kitchen_sink(&mut l),
        common::golden(&mut l),
    ];
    let layout = l.as_layout();
    let mut defs: Vec<ParamDef> = roots.iter().map(|&r| ParamDef::instanced(r, 2)).collect();
    defs.push(ParamDef::shared(roots[0]));
    let capacity = plan(&layout, &mut defs).unwrap();
    let n = table_slots(&layout, &defs);
    let mut plain = Store::new(
        &layout,
        defs.clone(),
        vec![Slot::default(); capacity.slots],
        vec![0u8; capacity.bytes],
    )
    .unwrap();
    // Complete tables, and tables cut short (down to none at all).
    for slots in [n, n / 2, defs.len() + 3, defs.len(), 3] {
        let mut tabled = Store::with_tables(
            &layout,
            defs.clone(),
            vec![Slot::default(); capacity.slots],
            vec![0u8; capacity.bytes],
            vec![LeafSlot::default(); slots],
        )
        .unwrap();
        let mut plain = plain.clone();
        for param in 0..4 {
            plain.add(param, Some(1)).unwrap();
            tabled.add(param, Some(1)).unwrap();
        }
        for round in 0..3u64 {
            for param in 0..5u32 {
                let instance = if param == 4 { 0 } else { 1 };
                for k in 0..40 {
                    let target = Target::Index(k);
                    let a = plain.get_leaf(&layout, param, instance, Which::Value, target);
                    let b = tabled.get_leaf(&layout, param, instance, Which::Value, target);
                    assert_eq!(a, b, "param {param} [{k}]");
                    let a = plain.read(&layout, param, instance, Which::Default, k);
                    let b = tabled.read(&layout, param, instance, Which::Default, k);
                    assert_eq!(a, b, "param {param} [{k}]");
                    let value = Scalar::Uint(round * 7 + k as u64);
                    let a =
                        plain.set_leaf(&layout, param, instance, Which::Value, target, value, true);
                    let b = tabled.set_leaf(
                        &layout,
                        param,
                        instance,
                        Which::Value,
                        target,
                        value,
                        true,
                    );
                    assert_eq!(a, b, "set param {param} [{k}]");
                    assert_eq!(
                        plain.get(param, instance, Which::Value),
                        tabled.get(param, instance, Which::Value)
                    );
                }
            }
        }
    }
    plain.clear();
}

/// A store operation, for [`stores_agree_after_any_operations`].
#[derive(Clone, Debug)]
enum Op {
    Add(u16),
    Remove(u16),
    /// Parameter, instance, the default (else the value), leaf, value.
    SetLeaf(u32, u16, bool, usize, u64),
    /// Leaves `[0]` to `[15]` set to values from a seed (so that data read from the wrong
    /// place shows).
    Scramble(u32, u16, bool, u64),
    /// Parameter, instance, the default, bytes (mostly refused: random).
    SetEncoded(u32, u16, bool, Vec<u8>),
    /// An instance's value set to another's: always a valid value.
    Copy(u16, u16),
    Reset(u32, u16),
    /// The type default set to an instance's value (the shared parameter's default follows).
    TypeDefault(u32, u16),
    Clear,
}

fn any_op() -> impl Strategy<Value = Op> {
    // Few instances and leaves, so that operations meet on the same ones.
    let inst = 0u16..2;
    prop_oneof![
        2 => inst.clone().prop_map(Op::Add),
        1 => inst.clone().prop_map(Op::Remove),
        // Small values keep tags and lengths valid; others fill the bits.
        6 => (0u32..2, inst.clone(), any::<bool>(), 0usize..8, prop_oneof![0u64..4, any::<u64>()])
            .prop_map(|(p, i, d, k, v)| Op::SetLeaf(p, i, d, k, v)),
        1 => (0u32..2, inst.clone(), any::<bool>(), proptest::collection::vec(any::<u8>(), 0..12))
            .prop_map(|(p, i, d, b)| Op::SetEncoded(p, i, d, b)),
        2 => (0u32..2, inst.clone(), any::<bool>(), any::<u64>())
            .prop_map(|(p, i, d, seed)| Op::Scramble(p, i, d, seed)),
        2 => (inst.clone(), inst.clone()).prop_map(|(a, b)| Op::Copy(a, b)),
        1 => (0u32..2, inst.clone()).prop_map(|(p, i)| Op::Reset(p, i)),
        1 => (0u32..2, inst).prop_map(|(p, i)| Op::TypeDefault(p, i)),
        1 => Just(Op::Clear),
    ]
}

type AnyStore = Store<Vec<ParamDef>, Vec<Slot>, Vec<u8>, Vec<LeafSlot>>;

/// Applies `op`; what it returned, in a form all stores can be compared by.
fn apply(store: &mut AnyStore, layout: &px4params_core::Layout<'_>, op: &Op) -> String {
    let which = |default: bool| {
        if default {
            Which::Default
        } else {
            Which::Value
        }
    };
    let result = match op {
        Op::Add(i) => store.add(0, Some(*i)).map(|_| ()),
        Op::Remove(i) => store.remove(0, *i),
        Op::SetLeaf(p, i, d, k, v) => store.set_leaf(
            layout,
            *p,
            *i,
            which(*d),
            Target::Index(*k),
            Scalar::Uint(*v),
            true,
        ),
        Op::Scramble(p, i, d, seed) => {
            let results: Vec<_> = (0..16u64)
                .map(|k| {
                    let value = seed.rotate_left(k as u32 * 7) >> (k % 5 * 12);
                    let target = Target::Index(k as usize);
                    store.set_leaf(layout, *p, *i, which(*d), target, Scalar::Uint(value), true)
                })
                .collect();
            return format!("{results:?}");
        }
        Op::SetEncoded(p, i, d, bytes) => store.set_encoded(layout, *p, *i, which(*d), bytes),
        Op::Copy(to, from) => match store.get(0, *from, Which::Value) {
            Ok(value) => {
                let value = value.to_vec();
                store.set_encoded(layout, 0, *to, Which::Value, &value)
            }
            Err(e) => Err(e),
        },
        Op::Reset(p, i) => store.reset(*p, *i),
        Op::TypeDefault(p, i) => match store.get(*p, *i, Which::Value) {
            Ok(value) => {
                let value = value.to_vec();
                store.set_type_default(layout, *p, &value)
            }
            Err(e) => Err(e),
        },
        Op::Clear => {
            store.clear();
            Ok(())
        }
    };
    format!("{result:?}")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// A store with complete tables (each instance's leaves resolved whenever its value
    /// changes), one with room for only some of that, and one without tables read every leaf
    /// alike after any sequence of operations.
    #[test]
    fn stores_agree_after_any_operations(ty in any_type(), ops in proptest::collection::vec(any_op(), 1..40), cut in any::<prop::sample::Index>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let mut defs = vec![ParamDef::instanced(root, 4), ParamDef::shared(root)];
        let Ok(capacity) = plan(&layout, &mut defs) else {
            return Ok(());
        };
        let full = table_slots(&layout, &defs);
        let new = |tables: usize| {
            Store::with_tables(
                &layout,
                defs.clone(),
                vec![Slot::default(); capacity.slots],
                vec![0u8; capacity.bytes],
                vec![LeafSlot::default(); tables],
            )
            .unwrap()
        };
        let mut stores = [new(0), new(full), new(defs.len() + cut.index(full - defs.len() + 1))];
        for op in &ops {
            let results: Vec<String> = stores.iter_mut().map(|s| apply(s, &layout, op)).collect();
            prop_assert!(results.iter().all(|r| *r == results[0]), "{:?}: {:?}", op, results);
            for (param, instances) in [(0u32, 0u16..4), (1, 0..1)] {
                for instance in instances {
                    for which in [Which::Value, Which::Default] {
                        let plain = &stores[0];
                        for (s, tabled) in stores.iter().enumerate().skip(1) {
                            prop_assert_eq!(plain.get(param, instance, which), tabled.get(param, instance, which));
                            for k in 0..40 {
                                let target = Target::Index(k);
                                let a = plain.get_leaf(&layout, param, instance, which, target);
                                let b = tabled.get_leaf(&layout, param, instance, which, target);
                                let agree = match (&a, &b) {
                                    (Ok(x), Ok(y)) => same(&Ok(*x), &Ok(*y)),
                                    _ => a == b,
                                };
                                prop_assert!(agree, "store {} #{} {:?} [{}] after {:?}: {:?} / {:?}", s, instance, which, k, op, a, b);
                                let a = plain.read(&layout, param, instance, which, k);
                                let b = tabled.read(&layout, param, instance, which, k);
                                let agree = match (a, b) {
                                    (Ok(x), Ok(y)) => same_scalar(x, y),
                                    _ => a == b,
                                };
                                prop_assert!(agree, "read: store {} #{} {:?} [{}] after {:?}: {:?} / {:?}", s, instance, which, k, op, a, b);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// An INA238 whose value moved to another bus and back to its default by `reset` reads the
/// default's leaves again (where its leaves are is worked out anew on every change).
#[test]
fn reset_reads_the_default_leaves() {
    let mut l = OwnedLayout::default();
    let root = common::ina238(&mut l);
    let layout = l.as_layout();
    let mut defs = vec![ParamDef::instanced(root, 2)];
    let capacity = plan(&layout, &mut defs).unwrap();
    let mut store = Store::with_tables(
        &layout,
        defs.clone(),
        vec![Slot::default(); capacity.slots],
        vec![0u8; capacity.bytes],
        vec![LeafSlot::default(); table_slots(&layout, &defs)],
    )
    .unwrap();
    store.add(0, Some(1)).unwrap();
    let set = |store: &mut AnyStore, which, k, value| {
        let target = Target::Index(k);
        store
            .set_leaf(&layout, 0, 1, which, target, Scalar::Uint(value), false)
            .unwrap()
    };
    // The default (and the value, which follows it): I2C address 0x45, current 300.
    set(&mut store, Which::Default, 4, 0x45);
    set(&mut store, Which::Default, 5, 300);
    // The value on SPI: leaf [4] is now the SPI device.
    set(&mut store, Which::Value, 1, 1);
    set(&mut store, Which::Value, 4, 7);
    assert_eq!(
        store.read(&layout, 0, 1, Which::Value, 4),
        Ok(Scalar::Uint(7))
    );
    store.reset(0, 1).unwrap();
    let read = |k| store.read(&layout, 0, 1, Which::Value, k);
    assert_eq!(read(1), Ok(Scalar::Uint(0)));
    assert_eq!(read(4), Ok(Scalar::Uint(0x45)));
    assert_eq!(read(5), Ok(Scalar::Uint(300)));
}

/// Deeply nested leaves keep their whole field paths (as many steps as a path holds, and the
/// depth beyond): every step of every depth comes back from the table as the walk gives it.
#[test]
fn deep_paths_come_back_whole() {
    for depth in [1, 2, 3, 4, 5, 6, 11, 12, 13, 14, 20] {
        let mut l = OwnedLayout::default();
        let u3 = l.uint(3, Cast::Saturated).unwrap();
        let mut node = l.uint(5, Cast::Saturated).unwrap();
        for level in 0..depth {
            let names = [format!("a{level}"), format!("b{level}")];
            node = l
                .structure(&[
                    (names[0].as_str(), u3, Role::Data),
                    (names[1].as_str(), node, Role::Data),
                ])
                .unwrap();
        }
        let layout = l.as_layout();
        let mut storage = vec![LeafSlot::default(); LeafTable::slots_needed(&layout, node)];
        let table = LeafTable::build(&layout, node, &mut storage).unwrap();
        let data = [0xA5u8; 16];
        for k in 0..=depth {
            let walked = get_leaf(&layout, node, &data[..], Target::Index(k), false);
            let tabled = table.get_leaf(&layout, &data[..], Target::Index(k), false);
            assert!(walked.is_ok(), "depth {depth} [{k}]: {walked:?}");
            assert_eq!(tabled, walked, "depth {depth} [{k}]");
            let (leaf, _) = tabled.unwrap();
            let (expected, _) = walked.unwrap();
            assert_eq!(format!("{:?}", leaf.path), format!("{:?}", expected.path));
        }
    }
}
