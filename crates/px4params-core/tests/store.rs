//! The instance store: operations, their errors, and random operation sequences against a model.

mod common;

use proptest::prelude::*;
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::NodeId;
use px4params_core::leaf::{self, Target};
use px4params_core::store::{plan, ParamDef, Slot, Store, StoreError, Which};
use px4params_core::value::LeafSource;
use px4params_core::{EncodeOptions, Scalar};

type VecStore = Store<Vec<ParamDef>, Vec<Slot>, Vec<u8>>;

const INA: u32 = 0;
const BATTERY: u32 = 1;
const CLASSIC: u32 = 2;

struct Fixture {
    layout: OwnedLayout,
    store: VecStore,
}

fn fixture() -> Fixture {
    let mut layout = OwnedLayout::default();
    let mut defs = common::store_params(&mut layout);
    let view = layout.as_layout();
    let capacity = plan(&view, &mut defs).unwrap();
    let store = Store::new(
        &view,
        defs,
        vec![Slot::default(); capacity.slots],
        vec![0u8; capacity.bytes],
    )
    .unwrap();
    Fixture { layout, store }
}

fn message<E: core::fmt::Display>(f: &Fixture, e: &StoreError<E>) -> String {
    e.display(&f.layout.as_layout()).to_string()
}

#[test]
fn instances_are_added_in_order_and_keep_their_numbers() {
    let mut f = fixture();
    assert_eq!(f.store.add(INA, None), Ok(0));
    assert_eq!(f.store.add(INA, Some(2)), Ok(2));
    assert_eq!(f.store.add(INA, None), Ok(1));
    f.store.remove(INA, 1).unwrap();
    assert_eq!(f.store.instances(INA).unwrap().collect::<Vec<_>>(), [0, 2]);
    assert_eq!(f.store.add(INA, None), Ok(1));
    assert_eq!(f.store.add(INA, None), Ok(3));
    let full = f.store.add(INA, None).unwrap_err();
    assert_eq!(full, StoreError::Full { max_instances: 4 });
    assert_eq!(
        message(&f, &full),
        "all 4 instances are in use (max_instances is 4)"
    );
}

#[test]
fn instance_errors_name_the_problem() {
    let mut f = fixture();
    let cases: Vec<(StoreError, &str)> = vec![
        (
            f.store.add(INA, Some(4)).unwrap_err(),
            "instance 4 is out of range (max_instances is 4: instances 0..3)",
        ),
        (
            f.store.remove(INA, 0).unwrap_err(),
            "instance does not exist (add it first: param add)",
        ),
        (
            f.store.add(BATTERY, None).unwrap_err(),
            "a shared parameter has no instances to add or remove",
        ),
        (f.store.add(9, None).unwrap_err(), "no parameter #9"),
    ];
    f.store.add(INA, Some(0)).unwrap();
    let again = f.store.add(INA, Some(0)).unwrap_err();
    assert_eq!(message(&f, &again), "instance exists already");
    for (e, text) in cases {
        assert_eq!(message(&f, &e), text);
    }
}

#[test]
fn p_version_is_written_by_the_store_only() {
    let mut f = fixture();
    let layout = f.layout.as_layout();
    f.store.add(INA, Some(0)).unwrap();
    for (k, path) in [(0, "p_version"), (2, "bus.i2c.p_version")] {
        let e = f
            .store
            .set_leaf(
                &layout,
                INA,
                0,
                Which::Value,
                Target::Index(k),
                Scalar::Uint(0),
                false,
            )
            .unwrap_err();
        assert_eq!(
            e.display(&layout).to_string(),
            format!("{path} is set automatically to the type's version and cannot be written")
        );
    }
    // A whole encoded value with another version is refused too.
    let mut data = f.store.get(INA, 0, Which::Value).unwrap().to_vec();
    data[0] |= 0x30;
    let e = f
        .store
        .set_encoded(&layout, INA, 0, Which::Value, &data)
        .unwrap_err();
    assert_eq!(
        e.display(&layout).to_string(),
        "p_version: p_version is set automatically; got 3, the type's version is 0"
    );
}

#[test]
fn leaves_are_written_in_place_and_defaults_carry_unchanged_values() {
    let mut f = fixture();
    let layout = f.layout.as_layout();
    f.store.add(INA, Some(1)).unwrap();
    let set = |s: &mut VecStore, which, k, v| {
        s.set_leaf(&layout, INA, 1, which, Target::Index(k), v, false)
    };
    set(&mut f.store, Which::Default, 3, Scalar::Uint(1)).unwrap();
    set(&mut f.store, Which::Default, 4, Scalar::Uint(0x45)).unwrap();
    set(&mut f.store, Which::Default, 5, Scalar::Uint(200)).unwrap();
    set(&mut f.store, Which::Default, 6, Scalar::Float(0.0003)).unwrap();
    assert_eq!(
        f.store.get(INA, 1, Which::Value).unwrap(),
        [0x00, 0x03, 0x17, 0x20, 0xea, 0x0c]
    );
    assert!(!f.store.changed(INA, 1).unwrap());
    set(&mut f.store, Which::Value, 5, Scalar::Uint(100)).unwrap();
    set(&mut f.store, Which::Default, 5, Scalar::Uint(300)).unwrap();
    let current = |s: &VecStore, which| {
        s.get_leaf(&layout, INA, 1, which, Target::Path("current"))
            .unwrap()
            .1
    };
    assert_eq!(current(&f.store, Which::Value), Scalar::Uint(100));
    assert_eq!(current(&f.store, Which::Default), Scalar::Uint(300));
    f.store.reset(INA, 1).unwrap();
    assert_eq!(current(&f.store, Which::Value), Scalar::Uint(300));
    // Out of range: refused, nothing written.
    let before = f.store.get(INA, 1, Which::Value).unwrap().to_vec();
    let e = set(&mut f.store, Which::Value, 5, Scalar::Uint(5000)).unwrap_err();
    assert_eq!(
        e.display(&layout).to_string(),
        "current: value 5000 is out of range (expected 0 to 1023)"
    );
    assert_eq!(f.store.get(INA, 1, Which::Value).unwrap(), before);
}

#[test]
fn union_tags_and_whole_values() {
    let mut f = fixture();
    let layout = f.layout.as_layout();
    f.store.add(INA, Some(0)).unwrap();
    f.store
        .set_leaf(
            &layout,
            INA,
            0,
            Which::Value,
            Target::Path("bus._tag"),
            Scalar::Uint(1),
            false,
        )
        .unwrap();
    let (found, _) = f
        .store
        .get_leaf(
            &layout,
            INA,
            0,
            Which::Value,
            Target::Path("bus.spi.device"),
        )
        .unwrap();
    assert_eq!(found.index, 4);
    // A whole value from a leaf list (as firmware would give one).
    let leaves = [
        Scalar::Uint(0),
        Scalar::Uint(0),
        Scalar::Uint(0),
        Scalar::Uint(1),
        Scalar::Uint(0x45),
        Scalar::Uint(200),
        Scalar::Float(0.0003),
    ];
    f.store
        .set_from(
            &layout,
            INA,
            0,
            Which::Value,
            &mut LeafSource::new(&leaves),
            false,
        )
        .unwrap();
    assert_eq!(
        f.store.get(INA, 0, Which::Value).unwrap(),
        [0x00, 0x03, 0x17, 0x20, 0xea, 0x0c]
    );
    // A leaf list that ends early is refused and changes nothing.
    let e = f
        .store
        .set_from(
            &layout,
            INA,
            0,
            Which::Value,
            &mut LeafSource::new(&leaves[..5]),
            false,
        )
        .unwrap_err();
    assert!(matches!(e, StoreError::Codec(_)));
    assert_eq!(
        f.store.get(INA, 0, Which::Value).unwrap(),
        [0x00, 0x03, 0x17, 0x20, 0xea, 0x0c]
    );
}

#[test]
fn shared_and_classic_parameters_always_exist() {
    let mut f = fixture();
    let layout = f.layout.as_layout();
    assert_eq!(f.store.instances(CLASSIC).unwrap().collect::<Vec<_>>(), [0]);
    f.store
        .set_leaf(
            &layout,
            CLASSIC,
            0,
            Which::Value,
            Target::Index(0),
            Scalar::Int(-5),
            false,
        )
        .unwrap();
    assert_eq!(
        f.store.get(CLASSIC, 0, Which::Value).unwrap(),
        (-5i32).to_le_bytes()
    );
    assert!(f.store.changed(CLASSIC, 0).unwrap());
    assert_eq!(
        f.store.remove(CLASSIC, 0),
        Err(StoreError::Shared),
        "shared parameters cannot be removed"
    );
    // The type default can be given (from metadata) and a shared value follows it.
    f.store
        .set_type_default(&layout, CLASSIC, &7i32.to_le_bytes())
        .unwrap();
    assert_eq!(
        f.store.get(CLASSIC, 0, Which::Default).unwrap(),
        7i32.to_le_bytes()
    );
    assert_eq!(
        f.store.get(CLASSIC, 0, Which::Value).unwrap(),
        (-5i32).to_le_bytes()
    );
}

#[test]
fn memory_that_does_not_match_the_plan_is_refused() {
    let mut layout = OwnedLayout::default();
    let ina = common::ina238(&mut layout);
    let view = layout.as_layout();
    let mut defs = vec![ParamDef::instanced(ina, 2)];
    let capacity = plan(&view, &mut defs).unwrap();
    let small = Store::new(
        &view,
        defs.clone(),
        vec![Slot::default(); capacity.slots],
        vec![0u8; capacity.bytes - 1],
    );
    let e = small.unwrap_err();
    assert_eq!(
        e.display(&view).to_string(),
        format!(
            "store memory does not match its plan ({} slots and {} bytes needed)",
            capacity.slots, capacity.bytes
        )
    );
    defs[0].first_byte = 3;
    let moved = Store::new(&view, defs, vec![Slot::default(); 9], vec![0u8; 999]);
    assert_eq!(moved.unwrap_err(), StoreError::NotPlanned { param: 0 });
}

// -- random operation sequences against a model ----------------------------------------------

#[derive(Clone, Debug)]
enum Op {
    Add(Option<u16>),
    Remove(u16),
    SetLeaf {
        instance: u16,
        default: bool,
        leaf: usize,
        value: Scalar,
    },
    Reset(u16),
}

fn op() -> impl Strategy<Value = Op> {
    let value = prop_oneof![
        (0u64..2000).prop_map(Scalar::Uint),
        (-3i64..3).prop_map(Scalar::Int),
        (-2.0f64..2.0).prop_map(Scalar::Float),
    ];
    prop_oneof![
        proptest::option::of(0u16..6).prop_map(Op::Add),
        (0u16..6).prop_map(Op::Remove),
        (0u16..6, any::<bool>(), 0usize..9, value).prop_map(|(instance, default, leaf, value)| {
            Op::SetLeaf {
                instance,
                default,
                leaf,
                value,
            }
        }),
        (0u16..6).prop_map(Op::Reset),
    ]
}

/// What the store should hold: per instance slot, its value and default (or absent).
type Model = Vec<Option<(Vec<u8>, Vec<u8>)>>;

fn snapshot(s: &VecStore) -> Model {
    (0..4)
        .map(|i| {
            s.get(INA, i, Which::Value)
                .ok()
                .map(|v| (v.to_vec(), s.get(INA, i, Which::Default).unwrap().to_vec()))
        })
        .collect()
}

fn model_set(
    layout: &OwnedLayout,
    root: NodeId,
    data: &[u8],
    k: usize,
    v: Scalar,
) -> Option<Vec<u8>> {
    let view = layout.as_layout();
    let found = leaf::locate(&view, root, data, Target::Index(k), false).ok()?;
    if found.path.steps().last().is_some_and(|step| {
        matches!(step, px4params_core::error::Step::Field(f)
            if matches!(view.fields[f as usize].role, px4params_core::layout::Role::Version(_)))
    }) {
        return None;
    }
    let mut out = vec![0u8; view.max_bytes(root)];
    let options = EncodeOptions {
        tao: false,
        saturate: false,
        keep_versions: true,
    };
    let n = leaf::set_leaf(&view, root, data, Target::Index(k), v, &mut out, options).ok()?;
    out.truncate(n);
    Some(out)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn store_follows_the_model(ops in proptest::collection::vec(op(), 1..40)) {
        let mut f = fixture();
        let root = f.store.def(INA).unwrap().root;
        let empty = f.store.type_default(INA).unwrap().to_vec();
        let mut model: Model = vec![None; 4];
        for op in ops {
            let before = snapshot(&f.store);
            let layout = f.layout.as_layout();
            let ok = match op {
                Op::Add(which) => {
                    let slot = which.or_else(|| model.iter().position(Option::is_none).map(|i| i as u16));
                    let accepted = f.store.add(INA, which).is_ok();
                    match slot {
                        Some(i) if (i as usize) < 4 && model[i as usize].is_none() => {
                            prop_assert!(accepted);
                            model[i as usize] = Some((empty.clone(), empty.clone()));
                        }
                        _ => prop_assert!(!accepted),
                    }
                    accepted
                }
                Op::Remove(i) => {
                    let accepted = f.store.remove(INA, i).is_ok();
                    let present = model.get(i as usize).is_some_and(Option::is_some);
                    prop_assert_eq!(accepted, present);
                    if present {
                        model[i as usize] = None;
                    }
                    accepted
                }
                Op::Reset(i) => {
                    let accepted = f.store.reset(INA, i).is_ok();
                    if let Some(Some((value, default))) = model.get_mut(i as usize) {
                        *value = default.clone();
                    }
                    accepted
                }
                Op::SetLeaf { instance, default, leaf, value } => {
                    let which = if default { Which::Default } else { Which::Value };
                    let accepted = f
                        .store
                        .set_leaf(&layout, INA, instance, which, Target::Index(leaf), value, false)
                        .is_ok();
                    let expected = model.get(instance as usize).cloned().flatten().and_then(|(v, d)| {
                        let target = if default { &d } else { &v };
                        model_set(&f.layout, root, target, leaf, value).map(|new| {
                            if !default {
                                (new, d.clone())
                            } else if v == d {
                                (new.clone(), new)
                            } else {
                                (v.clone(), new)
                            }
                        })
                    });
                    prop_assert_eq!(accepted, expected.is_some());
                    if let Some(next) = expected {
                        model[instance as usize] = Some(next);
                    }
                    accepted
                }
            };
            if !ok {
                prop_assert_eq!(snapshot(&f.store), before, "a refused operation changed the store");
            }
            prop_assert_eq!(snapshot(&f.store), model.clone());
            // The fast leaf reader agrees with the full one, for every leaf and past the end.
            let layout = f.layout.as_layout();
            for i in f.store.instances(INA).unwrap().collect::<Vec<_>>() {
                for k in 0..9 {
                    let fast = f.store.read(&layout, INA, i, Which::Value, k);
                    let full = f.store.get_leaf(&layout, INA, i, Which::Value, Target::Index(k));
                    prop_assert_eq!(fast, full.map(|(_, v)| v));
                }
            }
        }
    }
}

// -- values in fixed-size pages, read in place ------------------------------------------------

proptest! {
    #[test]
    fn values_read_from_pages_equal_the_store(page in 1usize..24, currents in proptest::collection::vec(0u64..1024, 1..4)) {
        use px4params_core::pages::{read_paged_leaf, write_pages, PagedValue};
        use px4params_core::scatter::Scattered;

        let mut f = fixture();
        let layout = f.layout.as_layout();
        for (i, &c) in currents.iter().enumerate() {
            f.store.add(INA, Some(i as u16)).unwrap();
            f.store
                .set_leaf(&layout, INA, i as u16, Which::Value, Target::Path("current"), Scalar::Uint(c), false)
                .unwrap();
        }
        f.store
            .set_leaf(&layout, BATTERY, 0, Which::Value, Target::Path("voltage"), Scalar::Float(12.5), false)
            .unwrap();
        let mut memory = vec![0u8; page * 64];
        let mut pages: Vec<&mut [u8]> = memory.chunks_mut(page).collect();
        let mut index = [PagedValue::default(); 16];
        let n = write_pages(&f.store, Which::Value, &mut pages, &mut index).unwrap();
        prop_assert_eq!(n, currents.len() + 2); // the instances, the battery and the classic value
        let pages: Vec<&[u8]> = memory.chunks(page).collect();
        for value in &index[..n] {
            let def = f.store.def(value.param).unwrap();
            let stored = f.store.get(value.param, value.instance, Which::Value).unwrap();
            let pieces = value.pieces(&pages);
            let scattered = Scattered::new(&pieces);
            prop_assert_eq!(scattered.len(), stored.len());
            for k in 0..8 {
                let paged = read_paged_leaf(&layout, &def, &pages, value, k);
                let direct = f.store.read(&layout, value.param, value.instance, Which::Value, k);
                prop_assert_eq!(paged, direct);
            }
        }
    }
}

#[test]
fn pages_that_are_too_small_are_refused() {
    use px4params_core::pages::{write_pages, PagedValue};

    let mut f = fixture();
    f.store.add(INA, None).unwrap();
    let mut memory = [0u8; 8];
    let mut pages: Vec<&mut [u8]> = memory.chunks_mut(4).collect();
    let mut index = [PagedValue::default(); 4];
    let e = write_pages(&f.store, Which::Value, &mut pages, &mut index).unwrap_err();
    assert!(matches!(e, StoreError::PagesFull { .. }));
    assert_eq!(
        message(&f, &e),
        "the pages or their index are too small (3 values of 34 bytes)"
    );
}

/// A caller that knows parameters by name gives the names as data ([`StoreError::display_named`]):
/// the three errors about a parameter say it where the plain display says its number, and
/// every other error reads as before (issue 39: the binding no longer edits the text).
#[test]
fn errors_name_a_parameter_by_the_name_given_or_by_its_number() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let names = ["INA238", "BATTERY", "SYS_AUTOSTART"];
    let cases: [(StoreError, &str, &str); 5] = [
        (
            StoreError::Unsupported { param: 1 },
            "parameter #1 cannot be stored (no slot, or a value over 65535 bytes)",
            "parameter BATTERY cannot be stored (no slot, or a value over 65535 bytes)",
        ),
        (
            StoreError::NotPlanned { param: 2 },
            "parameter #2 is not laid out as plan() lays it out",
            "parameter SYS_AUTOSTART is not laid out as plan() lays it out",
        ),
        (
            StoreError::NoSuchParam { param: 0 },
            "no parameter #0",
            "no parameter INA238",
        ),
        // A number the names lack: by its number.
        (
            StoreError::NoSuchParam { param: 3 },
            "no parameter #3",
            "no parameter #3",
        ),
        (
            StoreError::Full { max_instances: 4 },
            "all 4 instances are in use (max_instances is 4)",
            "all 4 instances are in use (max_instances is 4)",
        ),
    ];
    for (error, by_number, by_name) in cases {
        assert_eq!(error.display(&layout).to_string(), by_number);
        assert_eq!(error.display_named(&layout, &names).to_string(), by_name);
    }
}

/// A store keeps finite numbers only, as the Python store and its file loader do: a NaN or an
/// infinity is refused by every write (a leaf, a whole value, encoded bytes, a type default),
/// naming the leaf, and nothing is written. (Firmware's writes go through the same calls: the
/// C ABI's `px4p_store_set`, `px4p_store_set_leaf` and load.)
#[test]
fn a_nan_or_an_infinity_is_refused_by_every_write_and_nothing_is_written() {
    let mut f = fixture();
    let layout = f.layout.as_layout();
    f.store.add(INA, Some(0)).unwrap();
    let before = |s: &VecStore| {
        let get = |which| s.get(INA, 0, which).unwrap().to_vec();
        (
            get(Which::Value),
            get(Which::Default),
            s.type_default(INA).unwrap().to_vec(),
        )
    };
    let stored = before(&f.store);
    let refused = |shown: &str| {
        format!("shunt: value {shown} is not a finite number (a store keeps no NaN or infinity)")
    };
    let cases = [
        (f64::NAN, "NaN", [0x00, 0x7e]),
        (f64::INFINITY, "inf", [0x00, 0x7c]),
        (-f64::INFINITY, "-inf", [0x00, 0xfc]),
    ];
    for (v, shown, bytes) in cases {
        for which in [Which::Value, Which::Default] {
            // Saturation asked or not: a cast never makes a NaN finite.
            for saturate in [false, true] {
                let shunt = Target::Path("shunt");
                let e = f
                    .store
                    .set_leaf(&layout, INA, 0, which, shunt, Scalar::Float(v), saturate)
                    .unwrap_err();
                assert_eq!(message(&f, &e), refused(shown));
            }
            let mut leaves = [0, 0, 0, 1, 0x45, 200].map(Scalar::Uint).to_vec();
            leaves.push(Scalar::Float(v));
            let source = &mut LeafSource::new(&leaves);
            let e = f.store.set_from(&layout, INA, 0, which, source, false);
            assert_eq!(message(&f, &e.unwrap_err()), refused(shown));
            // INA238 with the shunt (float16, its last two bytes, low byte first) as `v`.
            let encoded = [0x00, 0x03, 0x17, 0x20, bytes[0], bytes[1]];
            let e = f.store.set_encoded(&layout, INA, 0, which, &encoded);
            assert_eq!(message(&f, &e.unwrap_err()), refused(shown));
            let e = f.store.check_value(&layout, INA, &encoded);
            assert_eq!(message(&f, &e.unwrap_err()), refused(shown));
        }
        let encoded = [0x00, 0x03, 0x17, 0x20, bytes[0], bytes[1]];
        let e = f.store.set_type_default(&layout, INA, &encoded);
        assert_eq!(message(&f, &e.unwrap_err()), refused(shown));
        // A float16's largest finite value is kept.
        let largest = [0x00, 0x03, 0x17, 0x20, 0xff, 0x7b];
        f.store.check_value(&layout, INA, &largest).unwrap();
    }
    assert_eq!(before(&f.store), stored);
}

/// A truncated float field turns a finite number beyond its range into an infinity (the
/// DroneCAN rule the codec keeps): a store refuses what it would keep as one, and takes the
/// largest finite number.
#[test]
fn a_finite_number_a_truncated_float_makes_infinite_is_refused() {
    let mut layout = OwnedLayout::default();
    let f32_ = layout.float(32, px4params_core::Cast::Truncated).unwrap();
    let f16 = layout.float(16, px4params_core::Cast::Truncated).unwrap();
    let root = layout
        .structure(&[
            ("gain", f32_, px4params_core::layout::Role::Data),
            ("trim", f16, px4params_core::layout::Role::Data),
        ])
        .unwrap();
    let view = layout.as_layout();
    let mut s = common::vec_store(&view, vec![ParamDef::shared(root)]);
    let set = |s: &mut VecStore, path, v| {
        let target = Target::Path(path);
        let r = s.set_leaf(&view, 0, 0, Which::Value, target, Scalar::Float(v), false);
        r.map_err(|e| e.display(&view).to_string())
    };
    let refused = |path: &str, shown: &str| {
        format!(
            "{path}: value {shown} becomes an infinity in this field (a store keeps no NaN or \
             infinity)"
        )
    };
    // (Shown with an exponent: 40 digits said nothing more.)
    assert_eq!(set(&mut s, "gain", 1e39), Err(refused("gain", "1e39")));
    assert_eq!(set(&mut s, "trim", 65505.0), Err(refused("trim", "65505")));
    assert_eq!(s.get(0, 0, Which::Value).unwrap(), [0; 6]);
    // The largest finite numbers are kept.
    assert_eq!(set(&mut s, "gain", f64::from(f32::MAX)), Ok(()));
    assert_eq!(set(&mut s, "trim", 65504.0), Ok(()));
    assert_eq!(
        s.get(0, 0, Which::Value).unwrap(),
        [0xff, 0xff, 0x7f, 0x7f, 0xff, 0x7b]
    );
}
