//! The instance store (`px4params_core::store`) against what its documentation promises
//! (issue 40): the memory `plan` asks for (per parameter its type default, then each
//! instance's value and default, each the type's largest encoding long, and one scratch area of
//! the largest), the states of a slot (present, used, unsaved) through every operation, PX4's
//! `param set-default` (a value equal to the old default follows it), `clear` back to a new
//! store, and each error with the memory left as it was.

mod common;

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::NodeId;
use px4params_core::leaf::Target;
use px4params_core::store::{plan, Capacity, ParamDef, Slot, Store, StoreError, Which};
use px4params_core::{Cast, Scalar};

type VecStore = Store<Vec<ParamDef>, Vec<Slot>, Vec<u8>>;

const INA: u32 = 0;
const BATTERY: u32 = 1;
const CLASSIC: u32 = 2;

/// Largest encodings, counted by hand from the types (tests/common):
/// INA238: p_version 4, the bus union's tag 3 (five variants) and its largest variant (spi:
/// 4 + 4 + 8), current 10, shunt 16: 49 bits, 7 bytes.
const INA_BYTES: u32 = 7;
/// BatteryInfo: seven float16 (112), status_flags 11, three uint7 (21), battery_id 8,
/// model_instance_id 32, model_name's 5-bit length and 31 bytes (253): 437 bits, 55 bytes.
const BATTERY_BYTES: u32 = 55;
/// A classic int32 parameter: 4 bytes.
const CLASSIC_BYTES: u32 = 4;

struct Fixture {
    layout: OwnedLayout,
    defs: Vec<ParamDef>,
    capacity: Capacity,
}

fn fixture() -> Fixture {
    let mut layout = OwnedLayout::default();
    let mut defs = common::store_params(&mut layout);
    let capacity = plan(&layout.as_layout(), &mut defs).unwrap();
    Fixture {
        layout,
        defs,
        capacity,
    }
}

impl Fixture {
    fn store(&self) -> VecStore {
        Store::new(
            &self.layout.as_layout(),
            self.defs.clone(),
            vec![Slot::default(); self.capacity.slots],
            vec![0u8; self.capacity.bytes],
        )
        .unwrap()
    }

    fn set(&self, s: &mut VecStore, param: u32, i: u16, which: Which, leaf: &str, v: Scalar) {
        let layout = self.layout.as_layout();
        s.set_leaf(&layout, param, i, which, Target::Path(leaf), v, false)
            .unwrap();
    }

    /// The classic parameter's value (its one leaf).
    fn set_classic(&self, s: &mut VecStore, which: Which, v: i64) {
        let layout = self.layout.as_layout();
        s.set_leaf(
            &layout,
            CLASSIC,
            0,
            which,
            Target::Index(0),
            Scalar::Int(v),
            false,
        )
        .unwrap();
    }

    fn leaf(&self, s: &VecStore, param: u32, i: u16, which: Which, leaf: &str) -> Scalar {
        let layout = self.layout.as_layout();
        s.get_leaf(&layout, param, i, which, Target::Path(leaf))
            .unwrap()
            .1
    }
}

fn state(s: &VecStore, param: u32, instance: u16) -> (bool, bool, bool) {
    let slot = s.slot(param, instance).unwrap();
    (slot.present(), slot.used(), slot.unsaved())
}

#[test]
fn plan_lays_parameters_out_one_after_the_other() {
    let f = fixture();
    let placed = |root: NodeId, instances, shared, first_slot, first_byte, slot_bytes| ParamDef {
        root,
        instances,
        shared,
        first_slot,
        first_byte,
        slot_bytes,
    };
    let [ina, battery, classic] = [0, 1, 2].map(|i| f.defs[i].root);
    // Each: 1 + instances slots; (1 + 2 * instances) * slot_bytes bytes.
    assert_eq!(
        f.defs,
        [
            placed(ina, 4, false, 0, 0, INA_BYTES),
            placed(battery, 1, true, 5, 9 * INA_BYTES, BATTERY_BYTES),
            placed(
                classic,
                1,
                true,
                7,
                9 * INA_BYTES + 3 * BATTERY_BYTES,
                CLASSIC_BYTES
            ),
        ]
    );
    let values = 9 * INA_BYTES + 3 * BATTERY_BYTES + 3 * CLASSIC_BYTES;
    assert_eq!(
        f.capacity,
        Capacity {
            slots: 9,
            bytes: (values + BATTERY_BYTES) as usize // and the scratch area: the largest
        }
    );
    // Planning again gives the same (a plan does not depend on what was set before).
    let mut again = f.defs.clone();
    assert_eq!(plan(&f.layout.as_layout(), &mut again), Ok(f.capacity));
    assert_eq!(again, f.defs);
    // The scratch area is the largest encoding, wherever that parameter is.
    let mut reordered = vec![f.defs[2], f.defs[1], f.defs[0]];
    let c = plan(&f.layout.as_layout(), &mut reordered).unwrap();
    assert_eq!(c.bytes, (values + BATTERY_BYTES) as usize);
    let mut small = vec![f.defs[2], f.defs[0]];
    let c = plan(&f.layout.as_layout(), &mut small).unwrap();
    assert_eq!(
        c,
        Capacity {
            slots: 2 + 5,
            bytes: (3 * CLASSIC_BYTES + 9 * INA_BYTES + INA_BYTES) as usize
        }
    );
    assert_eq!((small[1].first_slot, small[1].first_byte), (2, 12));
}

#[test]
fn parameters_the_store_cannot_hold_are_refused_by_number() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let root = f.defs[0].root;
    let message = |e: &StoreError| e.display(&layout).to_string();
    let mut none = vec![ParamDef::shared(root), ParamDef::instanced(root, 0)];
    let e = plan(&layout, &mut none).unwrap_err();
    assert_eq!(e, StoreError::Unsupported { param: 1 });
    assert_eq!(
        message(&e),
        "parameter #1 cannot be stored (no slot, or a value over 65535 bytes)"
    );
    let mut two_shared = vec![ParamDef {
        instances: 2,
        ..ParamDef::shared(root)
    }];
    assert_eq!(
        plan(&layout, &mut two_shared),
        Err(StoreError::Unsupported { param: 0 })
    );
    let mut unknown = vec![ParamDef::shared(root), ParamDef::instanced(9999, 2)];
    let e = plan(&layout, &mut unknown).unwrap_err();
    assert_eq!(e, StoreError::NoSuchParam { param: 1 });
    assert_eq!(message(&e), "no parameter #1");
    // A value of exactly 65535 bytes can be stored; one byte more cannot.
    let mut big = OwnedLayout::default();
    let byte = big.uint(8, Cast::Saturated).unwrap();
    let largest = big.array(byte, 65535).unwrap();
    let over = big.array(byte, 65536).unwrap();
    let view = big.as_layout();
    let mut fits = vec![ParamDef::shared(largest)];
    let c = plan(&view, &mut fits).unwrap();
    assert_eq!(c.bytes, 4 * 65535);
    let mut too_big = vec![ParamDef::shared(largest), ParamDef::shared(over)];
    assert_eq!(
        plan(&view, &mut too_big),
        Err(StoreError::Unsupported { param: 1 })
    );
}

#[test]
fn memory_other_than_the_plan_is_refused_and_more_is_accepted() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let (slots, bytes) = (f.capacity.slots, f.capacity.bytes);
    let new = |defs: Vec<ParamDef>, s: usize, b: usize| {
        Store::new(&layout, defs, vec![Slot::default(); s], vec![0u8; b]).map(|_| ())
    };
    let memory = StoreError::Memory { needed: f.capacity };
    assert_eq!(new(f.defs.clone(), slots - 1, bytes), Err(memory));
    assert_eq!(new(f.defs.clone(), slots, bytes - 1), Err(memory));
    assert_eq!(new(f.defs.clone(), slots, bytes), Ok(()));
    assert_eq!(new(f.defs.clone(), slots + 3, bytes + 100), Ok(()));
    assert_eq!(
        memory.display(&layout).to_string(),
        "store memory does not match its plan (9 slots and 295 bytes needed)"
    );
    // Any field other than plan's is refused, naming the parameter.
    for change in 0..4 {
        let mut defs = f.defs.clone();
        let d = &mut defs[2];
        match change {
            0 => d.first_slot += 1,
            1 => d.first_byte -= 1,
            2 => d.slot_bytes += 1,
            _ => d.root = f.defs[0].root,
        }
        let e = new(defs, slots + 99, bytes + 999).unwrap_err();
        assert_eq!(e, StoreError::NotPlanned { param: 2 }, "change {change}");
        assert_eq!(
            e.display(&layout).to_string(),
            "parameter #2 is not laid out as plan() lays it out"
        );
    }
}

#[test]
fn a_new_store_has_shared_values_only_and_nothing_unsaved() {
    let f = fixture();
    let s = f.store();
    for param in [BATTERY, CLASSIC] {
        assert_eq!(state(&s, param, 0), (true, false, false));
        assert_eq!(s.instances(param).unwrap().collect::<Vec<_>>(), [0]);
        // Value and default are the type default: the zero value.
        let zero = s.type_default(param).unwrap();
        assert_eq!(s.get(param, 0, Which::Value).unwrap(), zero);
        assert_eq!(s.get(param, 0, Which::Default).unwrap(), zero);
        assert!(!s.changed(param, 0).unwrap());
    }
    assert_eq!(s.type_default(CLASSIC).unwrap(), [0; 4]);
    for i in 0..4 {
        assert_eq!(state(&s, INA, i), (false, false, false));
        assert_eq!(
            s.get(INA, i, Which::Value),
            Err(StoreError::NotPresent { instance: i })
        );
    }
    assert_eq!(s.instances(INA).unwrap().count(), 0);
    assert_eq!(s.defs(), &f.defs[..]);
    assert_eq!(s.def(INA), Ok(f.defs[0]));
    assert_eq!(s.def(3), Err(StoreError::NoSuchParam { param: 3 }));
    assert_eq!(
        s.slot(INA, 4),
        Err(StoreError::InstanceOutOfRange {
            instance: 4,
            max_instances: 4
        })
    );
    assert_eq!(s.slot(7, 0), Err(StoreError::NoSuchParam { param: 7 }));
    assert_eq!(s.type_default(3), Err(StoreError::NoSuchParam { param: 3 }));
}

#[test]
fn each_operation_leaves_the_states_it_promises() {
    let f = fixture();
    let mut s = f.store();
    // Added: present and unsaved, not yet used.
    assert_eq!(s.add(INA, Some(2)), Ok(2));
    assert_eq!(state(&s, INA, 2), (true, false, true));
    s.mark_saved();
    assert_eq!(state(&s, INA, 2), (true, false, false));
    // A driver read it: used; saving does not forget that.
    s.mark_used(INA, 2).unwrap();
    assert_eq!(state(&s, INA, 2), (true, true, false));
    s.mark_saved();
    assert_eq!(state(&s, INA, 2), (true, true, false));
    // Written: unsaved again, still used.
    f.set(&mut s, INA, 2, Which::Value, "current", Scalar::Uint(9));
    assert_eq!(state(&s, INA, 2), (true, true, true));
    s.mark_saved();
    f.set(&mut s, INA, 2, Which::Default, "current", Scalar::Uint(4));
    assert_eq!(state(&s, INA, 2), (true, true, true));
    s.mark_saved();
    s.reset(INA, 2).unwrap();
    assert_eq!(state(&s, INA, 2), (true, true, true));
    assert_eq!(f.leaf(&s, INA, 2, Which::Value, "current"), Scalar::Uint(4));
    s.mark_saved();
    // Removed: not present, and unsaved (the removal is to be saved); nothing else held.
    s.remove(INA, 2).unwrap();
    assert_eq!(state(&s, INA, 2), (false, false, true));
    // Added again: the type default, not what the removed instance held.
    s.add(INA, Some(2)).unwrap();
    assert_eq!(state(&s, INA, 2), (true, false, true));
    let zero = s.type_default(INA).unwrap().to_vec();
    assert_eq!(s.get(INA, 2, Which::Value).unwrap(), zero);
    assert_eq!(s.get(INA, 2, Which::Default).unwrap(), zero);
    // The other slots saw none of it.
    for i in [0, 1, 3] {
        assert_eq!(state(&s, INA, i), (false, false, false));
    }
    assert_eq!(state(&s, BATTERY, 0), (true, false, false));
    // Operations on an absent instance are refused and change nothing.
    let absent = StoreError::NotPresent { instance: 1 };
    assert_eq!(s.mark_used(INA, 1), Err(absent));
    assert_eq!(s.reset(INA, 1), Err(absent));
    assert_eq!(s.remove(INA, 1), Err(absent));
    assert_eq!(s.get(INA, 1, Which::Default), Err(absent));
    assert_eq!(s.changed(INA, 1), Err(absent));
    assert_eq!(state(&s, INA, 1), (false, false, false));
    assert_eq!(
        s.mark_used(INA, 4),
        Err(StoreError::InstanceOutOfRange {
            instance: 4,
            max_instances: 4
        })
    );
    assert_eq!(s.mark_used(5, 0), Err(StoreError::NoSuchParam { param: 5 }));
    assert_eq!(s.remove(BATTERY, 0), Err(StoreError::Shared));
    assert_eq!(s.add(CLASSIC, Some(0)), Err(StoreError::Shared));
    // A shared value is used and saved like any other.
    s.mark_used(CLASSIC, 0).unwrap();
    assert_eq!(state(&s, CLASSIC, 0), (true, true, false));
}

#[test]
fn the_lowest_free_instance_is_taken() {
    let f = fixture();
    let mut s = f.store();
    for expected in 0..4 {
        assert_eq!(s.add(INA, None), Ok(expected));
    }
    assert_eq!(s.add(INA, None), Err(StoreError::Full { max_instances: 4 }));
    s.remove(INA, 2).unwrap();
    s.remove(INA, 0).unwrap();
    assert_eq!(s.add(INA, None), Ok(0));
    assert_eq!(s.add(INA, None), Ok(2));
    assert_eq!(
        s.add(INA, Some(3)),
        Err(StoreError::AlreadyPresent { instance: 3 })
    );
}

#[test]
fn clear_gives_back_a_new_store_with_every_change_unsaved() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let mut s = f.store();
    s.set_type_default(&layout, CLASSIC, &7i32.to_le_bytes())
        .unwrap();
    f.set_classic(&mut s, Which::Value, -3);
    f.set(
        &mut s,
        BATTERY,
        0,
        Which::Default,
        "voltage",
        Scalar::Float(11.5),
    );
    f.set(
        &mut s,
        BATTERY,
        0,
        Which::Value,
        "voltage",
        Scalar::Float(12.5),
    );
    s.add(INA, Some(1)).unwrap();
    s.add(INA, Some(3)).unwrap();
    s.mark_used(INA, 3).unwrap();
    s.mark_saved();
    s.clear();
    for i in 0..4 {
        // Every instance gone; the removals are to be saved.
        assert_eq!(state(&s, INA, i), (false, false, true));
    }
    for param in [BATTERY, CLASSIC] {
        assert_eq!(state(&s, param, 0), (true, false, true));
        let default = s.type_default(param).unwrap();
        assert_eq!(s.get(param, 0, Which::Value).unwrap(), default);
        assert_eq!(s.get(param, 0, Which::Default).unwrap(), default);
    }
    // The type defaults stay: they come from the types' metadata, not from the user.
    assert_eq!(s.get(CLASSIC, 0, Which::Value).unwrap(), 7i32.to_le_bytes());
    assert_eq!(
        f.leaf(&s, BATTERY, 0, Which::Value, "voltage"),
        Scalar::Float(0.0)
    );
}

#[test]
fn a_type_default_is_where_new_instances_start() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let mut s = f.store();
    s.add(INA, Some(0)).unwrap();
    let before = s.get(INA, 0, Which::Value).unwrap().to_vec();
    // An INA238 on SPI bus 2, device 5, current 300, from a value set on instance 0.
    f.set(&mut s, INA, 0, Which::Value, "bus._tag", Scalar::Uint(1));
    f.set(
        &mut s,
        INA,
        0,
        Which::Value,
        "bus.spi.bus_id",
        Scalar::Uint(2),
    );
    f.set(
        &mut s,
        INA,
        0,
        Which::Value,
        "bus.spi.device",
        Scalar::Uint(5),
    );
    f.set(&mut s, INA, 0, Which::Value, "current", Scalar::Uint(300));
    let spi = s.get(INA, 0, Which::Value).unwrap().to_vec();
    s.reset(INA, 0).unwrap();
    assert_eq!(s.get(INA, 0, Which::Value).unwrap(), before);
    s.mark_saved();
    s.set_type_default(&layout, INA, &spi).unwrap();
    assert_eq!(s.type_default(INA).unwrap(), spi);
    // The existing instance keeps its value and default, and nothing is unsaved.
    assert_eq!(s.get(INA, 0, Which::Value).unwrap(), before);
    assert_eq!(s.get(INA, 0, Which::Default).unwrap(), before);
    assert_eq!(state(&s, INA, 0), (true, false, false));
    s.add(INA, Some(2)).unwrap();
    assert_eq!(s.get(INA, 2, Which::Value).unwrap(), spi);
    assert_eq!(s.get(INA, 2, Which::Default).unwrap(), spi);
    assert_eq!(
        f.leaf(&s, INA, 2, Which::Value, "bus.spi.device"),
        Scalar::Uint(5)
    );
    // Bad data is refused with the codec's reason; nothing changes.
    let e = s
        .set_type_default(&layout, INA, &spi[..spi.len() - 1])
        .unwrap_err();
    assert!(matches!(e, StoreError::Codec(_)), "{e:?}");
    assert_eq!(s.type_default(INA).unwrap(), spi);
    assert_eq!(
        s.set_type_default(&layout, 8, &spi),
        Err(StoreError::NoSuchParam { param: 8 })
    );
}

#[test]
fn a_shared_value_follows_its_new_default_unless_it_was_changed() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let mut s = f.store();
    s.set_type_default(&layout, CLASSIC, &7i32.to_le_bytes())
        .unwrap();
    assert_eq!(s.get(CLASSIC, 0, Which::Value).unwrap(), 7i32.to_le_bytes());
    assert_eq!(
        s.get(CLASSIC, 0, Which::Default).unwrap(),
        7i32.to_le_bytes()
    );
    assert_eq!(state(&s, CLASSIC, 0), (true, false, true));
    f.set_classic(&mut s, Which::Value, -1);
    s.set_type_default(&layout, CLASSIC, &9i32.to_le_bytes())
        .unwrap();
    assert_eq!(
        s.get(CLASSIC, 0, Which::Value).unwrap(),
        (-1i32).to_le_bytes()
    );
    assert_eq!(
        s.get(CLASSIC, 0, Which::Default).unwrap(),
        9i32.to_le_bytes()
    );
}

#[test]
fn a_default_written_whole_carries_a_value_that_equalled_the_old_one() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let mut s = f.store();
    s.add(INA, Some(1)).unwrap();
    s.add(INA, Some(2)).unwrap();
    f.set(&mut s, INA, 2, Which::Value, "current", Scalar::Uint(10));
    let mut other = f.store();
    other.add(INA, Some(0)).unwrap();
    f.set(
        &mut other,
        INA,
        0,
        Which::Value,
        "current",
        Scalar::Uint(77),
    );
    let data = other.get(INA, 0, Which::Value).unwrap().to_vec();
    s.mark_saved();
    for i in [1, 2] {
        s.set_encoded(&layout, INA, i, Which::Default, &data)
            .unwrap();
        assert_eq!(s.get(INA, i, Which::Default).unwrap(), data);
        assert_eq!(state(&s, INA, i), (true, false, true));
    }
    // Instance 1 was at its default: it follows. Instance 2 was changed: it keeps its value.
    assert_eq!(
        f.leaf(&s, INA, 1, Which::Value, "current"),
        Scalar::Uint(77)
    );
    assert_eq!(
        f.leaf(&s, INA, 2, Which::Value, "current"),
        Scalar::Uint(10)
    );
    assert!(!s.changed(INA, 1).unwrap());
    assert!(s.changed(INA, 2).unwrap());
    // A value written whole never touches the default.
    let zero = s.type_default(INA).unwrap().to_vec();
    s.set_encoded(&layout, INA, 1, Which::Value, &zero).unwrap();
    assert_eq!(s.get(INA, 1, Which::Default).unwrap(), data);
    assert_eq!(s.get(INA, 1, Which::Value).unwrap(), zero);
    // A leaf of a default: the same rule.
    f.set(&mut s, INA, 1, Which::Default, "current", Scalar::Uint(5));
    assert_eq!(f.leaf(&s, INA, 1, Which::Value, "current"), Scalar::Uint(0));
    s.reset(INA, 1).unwrap();
    f.set(&mut s, INA, 1, Which::Default, "current", Scalar::Uint(6));
    assert_eq!(f.leaf(&s, INA, 1, Which::Value, "current"), Scalar::Uint(6));
    // Refused data changes nothing; the check alone says the same.
    let before = (
        s.get(INA, 1, Which::Value).unwrap().to_vec(),
        s.get(INA, 1, Which::Default).unwrap().to_vec(),
    );
    let short = &data[..data.len() - 1];
    let e = s.set_encoded(&layout, INA, 1, Which::Default, short);
    assert!(matches!(e, Err(StoreError::Codec(_))), "{e:?}");
    assert_eq!(s.check_value(&layout, INA, short), e);
    assert_eq!(s.check_value(&layout, INA, &data), Ok(()));
    assert_eq!(
        s.check_value(&layout, 9, &data),
        Err(StoreError::NoSuchParam { param: 9 })
    );
    let after = (
        s.get(INA, 1, Which::Value).unwrap().to_vec(),
        s.get(INA, 1, Which::Default).unwrap().to_vec(),
    );
    assert_eq!(after, before);
    assert_eq!(
        s.set_encoded(&layout, INA, 0, Which::Value, &data),
        Err(StoreError::NotPresent { instance: 0 })
    );
}

#[test]
fn every_error_keeps_its_fields_when_widened() {
    let errors: Vec<StoreError> = vec![
        StoreError::NoSuchParam { param: 3 },
        StoreError::Unsupported { param: 4 },
        StoreError::NotPlanned { param: 5 },
        StoreError::InstanceOutOfRange {
            instance: 7,
            max_instances: 6,
        },
        StoreError::NotPresent { instance: 8 },
        StoreError::AlreadyPresent { instance: 9 },
        StoreError::Full { max_instances: 10 },
        StoreError::Shared,
        StoreError::Memory {
            needed: Capacity { slots: 1, bytes: 2 },
        },
        StoreError::PagesFull {
            needed: 11,
            values: 12,
        },
        StoreError::UnequalPages,
    ];
    let f = fixture();
    let layout = f.layout.as_layout();
    for e in errors {
        let wide: StoreError<core::fmt::Error> = e.widen();
        // The same variant and fields: the same message.
        assert_eq!(
            wide.display(&layout).to_string(),
            e.display(&layout).to_string()
        );
        assert_eq!(format!("{wide:?}"), format!("{e:?}"));
    }
    // A codec error keeps its kind, offset and path.
    let mut s = f.store();
    s.add(INA, Some(0)).unwrap();
    let e = s
        .set_leaf(
            &layout,
            INA,
            0,
            Which::Value,
            Target::Path("current"),
            Scalar::Uint(5000),
            false,
        )
        .unwrap_err();
    let wide: StoreError<core::fmt::Error> = e.widen();
    assert_eq!(format!("{wide:?}"), format!("{e:?}"));
    assert_eq!(
        wide.display(&layout).to_string(),
        "current: value 5000 is out of range (expected 0 to 1023)"
    );
}

#[test]
fn the_values_must_lie_within_four_gibibytes() {
    // ParamDef::first_byte is a u32: the parameters' values end at byte u32::MAX at most.
    // plan() only counts; nothing of that size is allocated here.
    let mut big = OwnedLayout::default();
    let byte = big.uint(8, Cast::Saturated).unwrap();
    let largest = big.array(byte, 65535).unwrap();
    let view = big.as_layout();
    // (1 + 2 * 32768) * 65535 = 65537 * 65535 = u32::MAX.
    let mut fits = vec![ParamDef::instanced(largest, 32768)];
    let c = plan(&view, &mut fits).unwrap();
    assert_eq!(c.bytes, u32::MAX as usize + 65535);
    let mut over = vec![ParamDef::instanced(largest, 32769)];
    assert_eq!(
        plan(&view, &mut over),
        Err(StoreError::Unsupported { param: 0 })
    );
    let mut second = vec![ParamDef::instanced(largest, 32768), ParamDef::shared(byte)];
    assert_eq!(
        plan(&view, &mut second),
        Err(StoreError::Unsupported { param: 1 })
    );
}
