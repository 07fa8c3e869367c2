//! Layouts for the tests and benchmarks, built by hand as the Python loader would build them.
#![allow(dead_code)]

use proptest::prelude::*;
use px4params_core::compile::OwnedLayout;
use px4params_core::error::Error;
use px4params_core::layout::{Layout, NodeId, Role};
use px4params_core::store::{plan, ParamDef, Slot, Store};
use px4params_core::Cast::{Saturated, Truncated};
use px4params_core::{Cast, ErrorKind, Scalar};

/// A store over growable memory, as a host keeps one.
pub type VecStore = Store<Vec<ParamDef>, Vec<Slot>, Vec<u8>>;

/// A store of `defs` over memory of the size [`plan`] asks for.
pub fn vec_store(layout: &Layout<'_>, mut defs: Vec<ParamDef>) -> VecStore {
    let capacity = plan(layout, &mut defs).unwrap();
    let slots = vec![Slot::default(); capacity.slots];
    Store::new(layout, defs, slots, vec![0u8; capacity.bytes]).unwrap()
}

/// A `Sensor` type in two minor versions, for the translation tests: 1.1 (p_version uint4,
/// address uint7, enabled bool, offset int5) and 1.0 (p_version uint4, address uint7, gain
/// uint8), returned in that order.
pub fn sensor_versions(l: &mut OwnedLayout) -> (NodeId, NodeId) {
    let u4 = l.uint(4, Saturated).unwrap();
    let u7 = l.uint(7, Saturated).unwrap();
    let u8_ = l.uint(8, Saturated).unwrap();
    let i5 = l.int(5, Saturated).unwrap();
    let flag = l.boolean();
    let sensor = l
        .structure(&[
            ("p_version", u4, Role::Version(1)),
            ("address", u7, Role::Data),
            ("enabled", flag, Role::Data),
            ("offset", i5, Role::Data),
        ])
        .unwrap();
    let sensor_1_0 = l
        .structure(&[
            ("p_version", u4, Role::Version(0)),
            ("address", u7, Role::Data),
            ("gain", u8_, Role::Data),
        ])
        .unwrap();
    (sensor, sensor_1_0)
}

/// The talk's INA238 type (`px.Ina238.1.0`) and its `Bus` union.
/// The store the store tests share: INA238 in four instances (index 0), a shared BatteryInfo
/// (1) and a classic int32 parameter (2).
pub fn store_params(l: &mut OwnedLayout) -> Vec<ParamDef> {
    let ina = ina238(l);
    let battery = battery_info(l);
    let int32 = l.int(32, Saturated).unwrap();
    vec![
        ParamDef::instanced(ina, 4),
        ParamDef::shared(battery),
        ParamDef::shared(int32),
    ]
}

pub fn ina238(l: &mut OwnedLayout) -> NodeId {
    let u4 = l.uint(4, Saturated).unwrap();
    let u7 = l.uint(7, Saturated).unwrap();
    let u8_ = l.uint(8, Saturated).unwrap();
    let u10 = l.uint(10, Saturated).unwrap();
    let f16 = l.float(16, Saturated).unwrap();
    let i2c = l
        .structure(&[
            ("p_version", u4, Role::Version(0)),
            ("bus_id", u4, Role::Data),
            ("address", u7, Role::Data),
        ])
        .unwrap();
    let spi = l
        .structure(&[
            ("p_version", u4, Role::Version(0)),
            ("bus_id", u4, Role::Data),
            ("device", u8_, Role::Data),
        ])
        .unwrap();
    let serial = l
        .structure(&[
            ("p_version", u4, Role::Version(0)),
            ("port", u8_, Role::Data),
        ])
        .unwrap();
    let bus = l
        .union(&[
            ("i2c", i2c),
            ("spi", spi),
            ("serial", serial),
            ("sim", serial),
            ("dronecan", serial),
        ])
        .unwrap();
    l.structure(&[
        ("p_version", u4, Role::Version(0)),
        ("bus", bus, Role::Data),
        ("current", u10, Role::Data),
        ("shunt", f16, Role::Data),
    ])
    .unwrap()
}

/// `uavcan.equipment.power.BatteryInfo`.
pub fn battery_info(l: &mut OwnedLayout) -> NodeId {
    let f16 = l.float(16, Saturated).unwrap();
    let u11 = l.uint(11, Saturated).unwrap();
    let u7 = l.uint(7, Saturated).unwrap();
    let u8_ = l.uint(8, Saturated).unwrap();
    let u32_ = l.uint(32, Saturated).unwrap();
    let name = l.dyn_array(u8_, 31).unwrap();
    let mut fields = vec![];
    for n in [
        "temperature",
        "voltage",
        "current",
        "average_power_10sec",
        "remaining_capacity_wh",
        "full_charge_capacity_wh",
        "hours_to_full_charge",
    ] {
        fields.push((n, f16, Role::Data));
    }
    fields.extend([
        ("status_flags", u11, Role::Data),
        ("state_of_health_pct", u7, Role::Data),
        ("state_of_charge_pct", u7, Role::Data),
        ("state_of_charge_pct_stdev", u7, Role::Data),
        ("battery_id", u8_, Role::Data),
        ("model_instance_id", u32_, Role::Data),
        ("model_name", name, Role::Data),
    ]);
    l.structure(&fields).unwrap()
}

/// `uavcan.protocol.NodeStatus`: uint32 uptime_sec, uint2 health, uint3 mode, uint3 sub_mode,
/// uint16 vendor_specific_status_code.
pub fn node_status(l: &mut OwnedLayout) -> NodeId {
    let u32_ = l.uint(32, Saturated).unwrap();
    let u2 = l.uint(2, Saturated).unwrap();
    let u3 = l.uint(3, Saturated).unwrap();
    let u16_ = l.uint(16, Saturated).unwrap();
    l.structure(&[
        ("uptime_sec", u32_, Role::Data),
        ("health", u2, Role::Data),
        ("mode", u3, Role::Data),
        ("sub_mode", u3, Role::Data),
        ("vendor_specific_status_code", u16_, Role::Data),
    ])
    .unwrap()
}

/// `uavcan.protocol.file.Read.Response`: an `Error` struct (int16 value) and uint8[<=256] data.
pub fn file_read_response(l: &mut OwnedLayout) -> NodeId {
    let i16_ = l.int(16, Saturated).unwrap();
    let u8_ = l.uint(8, Saturated).unwrap();
    let error = l.structure(&[("value", i16_, Role::Data)]).unwrap();
    let data = l.dyn_array(u8_, 256).unwrap();
    l.structure(&[("error", error, Role::Data), ("data", data, Role::Data)])
        .unwrap()
}

/// The golden vector's fields: uint12, int3, int4, int2, uint4 (the first and last truncated).
pub fn golden(l: &mut OwnedLayout) -> NodeId {
    let a = l.uint(12, Truncated).unwrap();
    let b = l.int(3, Saturated).unwrap();
    let c = l.int(4, Saturated).unwrap();
    let d = l.int(2, Saturated).unwrap();
    let e = l.uint(4, Truncated).unwrap();
    l.structure(&[
        ("a", a, Role::Data),
        ("b", b, Role::Data),
        ("c", c, Role::Data),
        ("d", d, Role::Data),
        ("e", e, Role::Data),
    ])
    .unwrap()
}

/// A type exercising everything: nested unions, static and dynamic arrays, void, bool,
/// every float, signed values and a tail array of structs.
pub fn kitchen_sink(l: &mut OwnedLayout) -> NodeId {
    let b = l.boolean();
    let i5 = l.int(5, Saturated).unwrap();
    let u3 = l.uint(3, Truncated).unwrap();
    let i64_ = l.int(64, Saturated).unwrap();
    let u64_ = l.uint(64, Saturated).unwrap();
    let f16 = l.float(16, Saturated).unwrap();
    let f32_ = l.float(32, Truncated).unwrap();
    let f64_ = l.float(64, Saturated).unwrap();
    let v3 = l.void(3).unwrap();
    let pair = l
        .structure(&[("x", i5, Role::Data), ("flag", b, Role::Data)])
        .unwrap();
    let small = l.dyn_array(u3, 5).unwrap();
    let choice = l
        .union(&[("pair", pair), ("small", small), ("wide", f64_)])
        .unwrap();
    let elem = l
        .structure(&[
            ("a", u64_, Role::Data),
            ("b", f16, Role::Data),
            ("pad", v3, Role::Padding),
        ])
        .unwrap();
    let fixed = l.array(f32_, 3).unwrap();
    let tail = l.dyn_array(elem, 4).unwrap();
    l.structure(&[
        ("flag", b, Role::Data),
        ("gap", v3, Role::Padding),
        ("choice", choice, Role::Data),
        ("fixed", fixed, Role::Data),
        ("big", i64_, Role::Data),
        ("tail", tail, Role::Data),
    ])
    .unwrap()
}

/// A random type, built into a layout by [`Ty::build`].
#[derive(Clone, Debug)]
pub enum Ty {
    Uint(u32),
    Int(u32),
    Float(u32),
    Bool,
    Void(u32),
    /// Fields; `true` makes a `uint` field a `p_version`.
    Struct(Vec<(Ty, bool)>),
    Union(Vec<Ty>),
    Array(Box<Ty>, u32),
    Dyn(Box<Ty>, u32),
}

impl Ty {
    pub fn has_dyn(&self) -> bool {
        match self {
            Ty::Dyn(..) => true,
            Ty::Struct(fields) => fields.iter().any(|(t, _)| t.has_dyn()),
            Ty::Union(variants) => variants.iter().any(Ty::has_dyn),
            Ty::Array(t, _) => t.has_dyn(),
            _ => false,
        }
    }

    pub fn build(&self, l: &mut OwnedLayout) -> NodeId {
        match self {
            Ty::Uint(b) => l.uint(*b, Cast::Saturated).unwrap(),
            Ty::Int(b) => l.int(*b, Cast::Truncated).unwrap(),
            Ty::Float(b) => l.float(*b, Cast::Saturated).unwrap(),
            Ty::Bool => l.boolean(),
            Ty::Void(b) => l.void(*b).unwrap(),
            Ty::Struct(fields) => {
                let built: Vec<(String, NodeId, Role)> = fields
                    .iter()
                    .enumerate()
                    .map(|(i, (t, version))| {
                        let role = match t {
                            Ty::Void(_) => Role::Padding,
                            Ty::Uint(_) if *version => Role::Version(1),
                            _ => Role::Data,
                        };
                        (format!("f{i}"), t.build(l), role)
                    })
                    .collect();
                let refs: Vec<(&str, NodeId, Role)> = built
                    .iter()
                    .map(|(n, id, r)| (n.as_str(), *id, *r))
                    .collect();
                l.structure(&refs).unwrap()
            }
            Ty::Union(variants) => {
                let built: Vec<(String, NodeId)> = variants
                    .iter()
                    .enumerate()
                    .map(|(i, t)| (format!("v{i}"), t.build(l)))
                    .collect();
                let refs: Vec<(&str, NodeId)> =
                    built.iter().map(|(n, id)| (n.as_str(), *id)).collect();
                l.union(&refs).unwrap()
            }
            Ty::Array(t, n) => {
                let e = t.build(l);
                l.array(e, *n).unwrap()
            }
            Ty::Dyn(t, n) => {
                let e = t.build(l);
                l.dyn_array(e, *n).unwrap()
            }
        }
    }
}

pub fn primitive() -> impl Strategy<Value = Ty> {
    prop_oneof![
        (1u32..=64).prop_map(Ty::Uint),
        (1u32..=12).prop_map(Ty::Uint),
        (2u32..=64).prop_map(Ty::Int),
        prop_oneof![Just(16u32), Just(32), Just(64)].prop_map(Ty::Float),
        Just(Ty::Bool),
    ]
}

pub fn any_type() -> impl Strategy<Value = Ty> {
    primitive().prop_recursive(4, 40, 5, |inner| {
        let field = prop_oneof![
            4 => (inner.clone(), any::<bool>()),
            1 => (1u32..=9).prop_map(|b| (Ty::Void(b), false)),
        ];
        prop_oneof![
            3 => proptest::collection::vec(field, 0..5).prop_map(Ty::Struct),
            2 => proptest::collection::vec(inner.clone(), 2..5).prop_map(Ty::Union),
            1 => (inner.clone(), 1u32..4).prop_map(|(t, n)| Ty::Array(Box::new(t), n)),
            1 => (inner, 1u32..4).prop_map(|(t, n)| Ty::Dyn(Box::new(t), n)),
        ]
    })
}

pub fn same_scalar(a: Scalar, b: Scalar) -> bool {
    match (a, b) {
        (Scalar::Float(x), Scalar::Float(y)) => x.to_bits() == y.to_bits(),
        _ => a == b,
    }
}

pub fn same_leaves(a: &[Scalar], b: &[Scalar]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same_scalar(*x, *y))
}

/// The errors the walk and the host's plans must report alike. A tail array longer than its
/// maximum is found by the host's decoder at the element past the maximum, by the walk
/// (which counts a tail array's elements before it reads them) at the array: same error,
/// another place.
pub fn same_error<E: PartialEq + core::fmt::Debug>(ours: &Error<E>, theirs: &Error<E>) -> bool {
    match (&ours.kind, &theirs.kind) {
        (ErrorKind::ArrayTooLong { max: a, .. }, ErrorKind::ArrayTooLong { max: b, .. }) => a == b,
        // NaNs (in a wrong p_version, say) are equal when written out.
        _ => ours == theirs || format!("{ours:?}") == format!("{theirs:?}"),
    }
}

/// Spoils a valid leaf list as the encoder's tests need: each `(at, raw, kind)` replaces one
/// leaf by a value of another kind (an out-of-range or wrong-kind leaf), and `cut` 1 drops
/// the last leaf, 2 adds one too many.
pub fn tweak_leaves(
    leaves: &mut Vec<Scalar>,
    tweaks: &[(prop::sample::Index, u64, u8)],
    cut: usize,
) {
    for (at, raw, kind) in tweaks {
        if leaves.is_empty() {
            break;
        }
        let i = at.index(leaves.len());
        leaves[i] = match kind {
            0 => Scalar::Uint(*raw % 8),
            1 => Scalar::Int(*raw as i64),
            2 => Scalar::Float(f64::from_bits(*raw)),
            _ => Scalar::Bool(raw % 2 == 1),
        };
    }
    match cut {
        1 => {
            leaves.pop();
        }
        2 => leaves.push(Scalar::Uint(1)),
        _ => {}
    }
}
