//! `Store::set_translated` against its documentation (issue 40): a stored value of an older
//! minor version of a parameter's type is written as a value of the current version, fields
//! carried over by name, the fields the new version added taken from the instance's default
//! (for a value) or from the type's default (for a default), `p_version` the new version; a
//! default written this way carries a value that equalled the old default (PX4's
//! `param set-default`); with `check_only` nothing is written. The bytes are DroneCAN's bit
//! packing worked out by hand (fields back to back, most significant bit first).

mod common;

use common::VecStore;
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::NodeId;
use px4params_core::store::{ParamDef, Slot, StoreError, Which};

const SENSOR: u32 = 0;
/// Sensor 1.1's type default: p_version 1, address 0x45, enabled, offset -3:
/// `0001 1000101 1 11101`.
const TYPE_DEFAULT: [u8; 3] = [0x18, 0xBE, 0x80];
/// An instance's own default: p_version 1, address 0x45, disabled, offset 5:
/// `0001 1000101 0 00101`.
const OWN_DEFAULT: [u8; 3] = [0x18, 0xA2, 0x80];
/// Sensor 1.0's value: p_version 0, address 0x22, gain 9: `0000 0100010 00001001`.
const OLD: [u8; 3] = [0x04, 0x41, 0x20];
/// OLD as a 1.1 value over OWN_DEFAULT: address 0x22 carried, disabled and offset 5 new
/// (from the base), gain dropped: `0001 0100010 0 00101`.
const OLD_OVER_OWN: [u8; 3] = [0x14, 0x42, 0x80];
/// OLD as a 1.1 value over TYPE_DEFAULT: `0001 0100010 1 11101`.
const OLD_OVER_TYPE: [u8; 3] = [0x14, 0x5E, 0x80];

struct Fixture {
    layout: OwnedLayout,
    store: VecStore,
    old: NodeId,
}

/// Sensor 1.1 (p_version uint4, address uint7, enabled bool, offset int5) in three instances;
/// Sensor 1.0 (p_version uint4, address uint7, gain uint8) in the same layout, not stored.
fn fixture() -> Fixture {
    let mut l = OwnedLayout::default();
    let (sensor, old) = common::sensor_versions(&mut l);
    let view = l.as_layout();
    let mut store = common::vec_store(&view, vec![ParamDef::instanced(sensor, 3)]);
    store
        .set_type_default(&view, SENSOR, &TYPE_DEFAULT)
        .unwrap();
    Fixture {
        layout: l,
        store,
        old,
    }
}

impl Fixture {
    fn translated(&mut self, instance: u16, which: Which, data: &[u8], check_only: bool) -> bool {
        let layout = self.layout.as_layout();
        self.store
            .set_translated(&layout, SENSOR, instance, which, self.old, data, check_only)
            .is_ok()
    }

    /// Adds `instance` with its own `default`, then `value` as its value when given.
    fn add(&mut self, instance: u16, default: &[u8], value: Option<&[u8]>) {
        let layout = self.layout.as_layout();
        let s = &mut self.store;
        s.add(SENSOR, Some(instance)).unwrap();
        s.set_encoded(&layout, SENSOR, instance, Which::Default, default)
            .unwrap();
        if let Some(value) = value {
            s.set_encoded(&layout, SENSOR, instance, Which::Value, value)
                .unwrap();
        }
    }

    fn held(&self, instance: u16) -> (Vec<u8>, Vec<u8>, bool) {
        let s = &self.store;
        (
            s.get(SENSOR, instance, Which::Value).unwrap().to_vec(),
            s.get(SENSOR, instance, Which::Default).unwrap().to_vec(),
            s.slot(SENSOR, instance).unwrap().unsaved(),
        )
    }
}

#[test]
fn a_translated_value_takes_the_new_fields_from_the_instance_s_default() {
    let mut f = fixture();
    f.add(1, &OWN_DEFAULT, None);
    f.store.mark_saved();
    assert!(f.translated(1, Which::Value, &OLD, false));
    assert_eq!(
        f.held(1),
        (OLD_OVER_OWN.to_vec(), OWN_DEFAULT.to_vec(), true)
    );
}

#[test]
fn a_translated_default_takes_the_new_fields_from_the_type_s_default() {
    let mut f = fixture();
    // Instance 0: its value changed from its own default (it keeps its value).
    f.add(0, &OWN_DEFAULT, Some(&OLD_OVER_OWN));
    // Instance 2: at its own default (its value follows the new default).
    f.add(2, &OWN_DEFAULT, Some(&OWN_DEFAULT));
    f.store.mark_saved();
    assert!(f.translated(0, Which::Default, &OLD, false));
    assert_eq!(
        f.held(0),
        (OLD_OVER_OWN.to_vec(), OLD_OVER_TYPE.to_vec(), true)
    );
    assert!(f.translated(2, Which::Default, &OLD, false));
    assert_eq!(
        f.held(2),
        (OLD_OVER_TYPE.to_vec(), OLD_OVER_TYPE.to_vec(), true)
    );
}

#[test]
fn check_only_translates_and_writes_nothing() {
    let mut f = fixture();
    f.add(1, &OWN_DEFAULT, None);
    f.store.mark_saved();
    let before = f.held(1);
    assert_eq!(before, (OWN_DEFAULT.to_vec(), OWN_DEFAULT.to_vec(), false));
    for which in [Which::Value, Which::Default] {
        assert!(f.translated(1, which, &OLD, true));
        assert_eq!(f.held(1), before);
    }
    // An instance not there yet is checked (before a file adds it), not written.
    assert!(f.translated(0, Which::Value, &OLD, true));
    assert!(f.translated(0, Which::Default, &OLD, true));
    assert_eq!(
        f.store.slot(SENSOR, 0).unwrap(),
        Slot::default(),
        "absent, saved"
    );
    // A value the old type cannot be read from is refused, checked or written.
    assert!(!f.translated(0, Which::Value, &OLD[..1], true));
    assert!(!f.translated(1, Which::Value, &OLD[..1], false));
    assert_eq!(f.held(1), before);
}

#[test]
fn a_translation_into_an_instance_that_is_not_there_is_refused() {
    let mut f = fixture();
    let layout = f.layout.as_layout();
    let old = f.old;
    let mut write = |param, instance, check_only| {
        f.store.set_translated(
            &layout,
            param,
            instance,
            Which::Value,
            old,
            &OLD,
            check_only,
        )
    };
    assert!(matches!(
        write(SENSOR, 0, false),
        Err(StoreError::NotPresent { instance: 0 })
    ));
    for check_only in [false, true] {
        assert!(matches!(
            write(SENSOR, 3, check_only),
            Err(StoreError::InstanceOutOfRange {
                instance: 3,
                max_instances: 3
            })
        ));
        assert!(matches!(
            write(1, 0, check_only),
            Err(StoreError::NoSuchParam { param: 1 })
        ));
    }
    assert_eq!(f.store.instances(SENSOR).unwrap().count(), 0);
}
