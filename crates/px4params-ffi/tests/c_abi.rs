//! The C ABI called as C calls it: tables of raw pointers and counts, caller memory, byte
//! buffers with lengths, and status codes (docs/firmware.md, "The C ABI"). Store files are
//! built here byte by byte from docs/store-format.md, with this file's own CRCs (checked
//! against the CRC catalogue's check values), and values are encoded by hand with the
//! DroneCAN rules (docs/codec.md: fields back to back, each byte filled from its most
//! significant bit, wider scalars little-endian).
//!
//! The parameters, in ID order (file order is by name: BAT_N_CELLS, LAST, SENS, TRIM):
//! - 0 `SENS=test.Sensor.1`, 3 instances: uint4 p_version (minor 1), uint7 address, bool
//!   enabled, int5 offset; its type default p_version 1, address 0x45, enabled, offset -3 is
//!   `0001 1000101 1 11101` = `18 BE 80`. The tables also carry its minor version 0: uint4
//!   p_version, uint7 address, uint8 gain.
//! - 1 `BAT_N_CELLS`, classic: an int32, default 4.
//! - 2 `TRIM=test.Last.1`, shared; 3 `LAST=test.Last.1`, 2 instances: uint4 p_version
//!   (minor 1), uint3 mode, uint8 level, float16 gain (minor 0 had no gain). TRIM's default
//!   (mode 5, level 200, gain 0.5 = 0x3800) is `0001 101 11001000 00000000 00111000` =
//!   `1B 90 00 70`; LAST's (mode 2, level 7, gain -2.0 = 0xC000) is `14 0E 01 80`.
//!
//! LAST is the table's last parameter: issue 40 planted the table bound in store open as
//! `param_count - 1`, and nothing in Rust or C noticed.

use std::ffi::CStr;
use std::ptr;

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::Role;
use px4params_core::store::{plan, ParamDef, Slot};
use px4params_core::Cast::Saturated;
use px4params_ffi::*;

const SENS: u32 = 0;
const BAT_N_CELLS: u32 = 1;
const TRIM: u32 = 2;
const LAST: u32 = 3;
const BEYOND: u32 = 4;

const SENS_DEFAULT: [u8; 3] = [0x18, 0xBE, 0x80];
const BAT_DEFAULT: [u8; 4] = 4i32.to_le_bytes();
const TRIM_DEFAULT: [u8; 4] = [0x1B, 0x90, 0x00, 0x70];
const LAST_DEFAULT: [u8; 4] = [0x14, 0x0E, 0x01, 0x80];
/// SENS with address 0x22: `0001 0100010 1 11101`.
const SENS_ADDRESS_22: [u8; 3] = [0x14, 0x5E, 0x80];

const VALUE: u8 = 0;
const DEFAULT: u8 = 1;

// -- the tables, as `metadata --firmware` lays them out ----------------------------------------

struct Tables {
    tables: &'static px4p_tables,
}

fn leak<T>(items: Vec<T>) -> &'static [T] {
    Vec::leak(items)
}

fn tables() -> Tables {
    let mut l = OwnedLayout::default();
    let u3 = l.uint(3, Saturated).unwrap();
    let u4 = l.uint(4, Saturated).unwrap();
    let u7 = l.uint(7, Saturated).unwrap();
    let u8_ = l.uint(8, Saturated).unwrap();
    let i5 = l.int(5, Saturated).unwrap();
    let i32_ = l.int(32, Saturated).unwrap();
    let f16 = l.float(16, Saturated).unwrap();
    let flag = l.boolean();
    let sensor_1_0 = l
        .structure(&[
            ("p_version", u4, Role::Version(0)),
            ("address", u7, Role::Data),
            ("gain", u8_, Role::Data),
        ])
        .unwrap();
    let sensor = l
        .structure(&[
            ("p_version", u4, Role::Version(1)),
            ("address", u7, Role::Data),
            ("enabled", flag, Role::Data),
            ("offset", i5, Role::Data),
        ])
        .unwrap();
    let last_1_0 = l
        .structure(&[
            ("p_version", u4, Role::Version(0)),
            ("mode", u3, Role::Data),
            ("level", u8_, Role::Data),
        ])
        .unwrap();
    let last = l
        .structure(&[
            ("p_version", u4, Role::Version(1)),
            ("mode", u3, Role::Data),
            ("level", u8_, Role::Data),
            ("gain", f16, Role::Data),
        ])
        .unwrap();
    let owned: &'static OwnedLayout = Box::leak(Box::new(l));
    let view = owned.as_layout();
    let mut defs = vec![
        ParamDef::instanced(sensor, 3),
        ParamDef::shared(i32_),
        ParamDef::shared(last),
        ParamDef::instanced(last, 2),
    ];
    let capacity = plan(&view, &mut defs).unwrap();
    let param = |name: &'static CStr, classic: u8, default: &'static [u8]| px4p_param {
        file_name: name.as_ptr(),
        classic,
        type_default: default.as_ptr(),
        type_default_len: default.len() as u32,
    };
    let params = leak(vec![
        param(c"SENS=test.Sensor.1", 0, &SENS_DEFAULT),
        param(c"BAT_N_CELLS", PX4P_CLASSIC_INT32, &BAT_DEFAULT),
        param(c"TRIM=test.Last.1", 0, &TRIM_DEFAULT),
        param(c"LAST=test.Last.1", 0, &LAST_DEFAULT),
    ]);
    // SENS's older version last: a lookup by minor version alone, or by parameter alone,
    // finds Last 1.0 instead.
    let versions = leak(vec![
        px4p_version {
            param: TRIM,
            minor: 0,
            root: last_1_0,
        },
        px4p_version {
            param: LAST,
            minor: 0,
            root: last_1_0,
        },
        px4p_version {
            param: SENS,
            minor: 0,
            root: sensor_1_0,
        },
    ]);
    let defs = leak(defs);
    let order = leak(vec![BAT_N_CELLS, LAST, SENS, TRIM]);
    let tables = Box::leak(Box::new(px4p_tables {
        layout: px4p_layout {
            nodes: view.nodes.as_ptr(),
            node_count: view.nodes.len() as u32,
            fields: view.fields.as_ptr(),
            field_count: view.fields.len() as u32,
            names: view.names.as_ptr().cast(),
            names_len: view.names.len() as u32,
            segments: view.segments.as_ptr(),
            segment_count: view.segments.len() as u32,
            flat: view.flat.as_ptr(),
            flat_count: view.flat.len() as u32,
        },
        defs: defs.as_ptr(),
        params: params.as_ptr(),
        order: order.as_ptr(),
        param_count: defs.len() as u32,
        versions: versions.as_ptr(),
        version_count: versions.len() as u32,
        slot_count: capacity.slots as u32,
        byte_count: capacity.bytes as u32,
    }));
    Tables { tables }
}

/// A store's room and memory, as C keeps them in `static`s.
struct Memory {
    store: *mut px4p_store,
    slots: &'static mut [Slot],
    bytes: &'static mut [u8],
}

fn memory(slot_count: usize, byte_count: usize) -> Memory {
    Memory {
        store: Box::leak(Box::new(px4p_store { opaque: [0; 12] })),
        slots: Vec::leak(vec![Slot::default(); slot_count]),
        bytes: Vec::leak(vec![0xA5; byte_count]),
    }
}

fn open_with(tables: &px4p_tables, m: &mut Memory) -> i32 {
    unsafe {
        px4p_store_open(
            m.store,
            tables,
            m.slots.as_mut_ptr(),
            m.slots.len(),
            m.bytes.as_mut_ptr(),
            m.bytes.len(),
        )
    }
}

/// A store opened over exactly the memory the tables ask for.
fn opened() -> *mut px4p_store {
    let t = tables();
    let mut m = memory(t.tables.slot_count as usize, t.tables.byte_count as usize);
    assert_eq!(open_with(t.tables, &mut m), 0);
    m.store
}

// -- calls, as C makes them --------------------------------------------------------------------

fn get(s: *mut px4p_store, param: u32, instance: u16, which: u8) -> Result<Vec<u8>, i32> {
    let mut out = [0u8; 16];
    match unsafe { px4p_get(s, param, instance, which, out.as_mut_ptr(), out.len()) } {
        n @ 0.. => Ok(out[..n as usize].to_vec()),
        code => Err(code),
    }
}

fn set(s: *mut px4p_store, param: u32, instance: u16, which: u8, data: &[u8]) -> i32 {
    unsafe { px4p_set(s, param, instance, which, data.as_ptr(), data.len()) }
}

fn leaf(
    s: *mut px4p_store,
    param: u32,
    instance: u16,
    which: u8,
    k: u32,
) -> Result<px4p_value, i32> {
    let mut out = px4p_value {
        kind: 0,
        u: 0,
        i: 0,
        f: 0.0,
    };
    match unsafe { px4p_get_leaf(s, param, instance, which, k, &mut out) } {
        0 => Ok(out),
        code => Err(code),
    }
}

fn uint(u: u64) -> px4p_value {
    px4p_value {
        kind: PX4P_VALUE_UINT,
        u,
        i: 0,
        f: 0.0,
    }
}

fn int(i: i64) -> px4p_value {
    px4p_value {
        kind: PX4P_VALUE_INT,
        u: 0,
        i,
        f: 0.0,
    }
}

fn float(f: f64) -> px4p_value {
    px4p_value {
        kind: PX4P_VALUE_FLOAT,
        u: 0,
        i: 0,
        f,
    }
}

fn boolean(u: u64) -> px4p_value {
    px4p_value {
        kind: PX4P_VALUE_BOOL,
        u,
        i: 0,
        f: 0.0,
    }
}

/// The leaf's kind and its value as text: `u 69`, `i -3`, `f 0.5`, `b 1`.
fn shown(v: Result<px4p_value, i32>) -> String {
    match v {
        Ok(v) => match v.kind {
            PX4P_VALUE_UINT => format!("u {}", v.u),
            PX4P_VALUE_INT => format!("i {}", v.i),
            PX4P_VALUE_FLOAT => format!("f {}", v.f),
            PX4P_VALUE_BOOL => format!("b {}", v.u),
            kind => format!("kind {kind}"),
        },
        Err(code) => name(code).to_string(),
    }
}

#[allow(clippy::too_many_arguments)]
fn set_leaf(
    s: *mut px4p_store,
    param: u32,
    instance: u16,
    which: u8,
    k: u32,
    value: px4p_value,
    saturate: u8,
) -> i32 {
    unsafe { px4p_set_leaf(s, param, instance, which, k, &value, saturate) }
}

fn add(s: *mut px4p_store, param: u32, instance: i32) -> i32 {
    unsafe { px4p_add(s, param, instance) }
}

fn remove(s: *mut px4p_store, param: u32, instance: u16) -> i32 {
    unsafe { px4p_remove(s, param, instance) }
}

/// Every present instance, by `px4p_next_instance` from -1 until `PX4P_ERR_END`.
fn instances(s: *mut px4p_store, param: u32) -> Result<Vec<i32>, i32> {
    let mut found = vec![];
    let mut after = -1;
    loop {
        match unsafe { px4p_next_instance(s, param, after) } {
            PX4P_ERR_END => return Ok(found),
            code if code < 0 => return Err(code),
            i => {
                found.push(i);
                after = i;
            }
        }
    }
}

fn save(s: *mut px4p_store) -> Result<Vec<u8>, i32> {
    let mut buf = [0u8; 256];
    match unsafe { px4p_store_save(s, buf.as_mut_ptr(), buf.len()) } {
        n @ 0.. => Ok(buf[..n as usize].to_vec()),
        code => Err(code),
    }
}

fn load(s: *mut px4p_store, file: &[u8]) -> i32 {
    unsafe { px4p_store_load(s, file.as_ptr(), file.len()) }
}

fn name(code: i32) -> &'static str {
    unsafe { CStr::from_ptr(px4p_error_name(code)) }
        .to_str()
        .unwrap()
}

// -- store files, by hand from docs/store-format.md ---------------------------------------------

#[path = "../../px4params-core/tests/support/store_file.rs"]
mod store_file;
use store_file::{classic_record, store_file};

#[test]
fn the_test_crcs_give_the_catalogue_check_values() {
    store_file::assert_catalogue_check_values();
}

/// A structured record with a value or nothing.
fn structured_record(index: u8, instance: u8, value: Option<&[u8]>) -> Vec<u8> {
    store_file::structured_record(index, instance, None, value)
}

// -- the tests -----------------------------------------------------------------------------------

#[test]
fn every_code_has_its_documented_number_and_name() {
    // docs/firmware.md's table of codes.
    let documented = [
        (PX4P_ERR_ARGUMENT, -1, "PX4P_ERR_ARGUMENT"),
        (PX4P_ERR_TABLES, -2, "PX4P_ERR_TABLES"),
        (PX4P_ERR_NO_SUCH_PARAM, -3, "PX4P_ERR_NO_SUCH_PARAM"),
        (PX4P_ERR_INSTANCE_RANGE, -4, "PX4P_ERR_INSTANCE_RANGE"),
        (PX4P_ERR_NOT_PRESENT, -5, "PX4P_ERR_NOT_PRESENT"),
        (PX4P_ERR_ALREADY_PRESENT, -6, "PX4P_ERR_ALREADY_PRESENT"),
        (PX4P_ERR_FULL, -7, "PX4P_ERR_FULL"),
        (PX4P_ERR_SHARED, -8, "PX4P_ERR_SHARED"),
        (PX4P_ERR_VALUE, -9, "PX4P_ERR_VALUE"),
        (PX4P_ERR_NO_SUCH_LEAF, -10, "PX4P_ERR_NO_SUCH_LEAF"),
        (PX4P_ERR_VERSION_LEAF, -11, "PX4P_ERR_VERSION_LEAF"),
        (PX4P_ERR_VERSION, -12, "PX4P_ERR_VERSION"),
        (PX4P_ERR_BUFFER, -13, "PX4P_ERR_BUFFER"),
        (PX4P_ERR_FILE, -14, "PX4P_ERR_FILE"),
        (PX4P_ERR_FILE_PARAM, -15, "PX4P_ERR_FILE_PARAM"),
        (PX4P_ERR_FILE_FORMAT_1, -16, "PX4P_ERR_FILE_FORMAT_1"),
        (PX4P_ERR_END, -17, "PX4P_ERR_END"),
    ];
    for (constant, number, text) in documented {
        assert_eq!(constant, number, "{text}");
        assert_eq!(name(number), text);
    }
    for result in [0, 1, 3, i32::MAX] {
        assert_eq!(name(result), "PX4P_OK");
    }
    for unknown in [-18, -100, i32::MIN] {
        assert_eq!(name(unknown), "PX4P_ERR_UNKNOWN");
    }
    let kinds = [
        PX4P_VALUE_UINT,
        PX4P_VALUE_INT,
        PX4P_VALUE_FLOAT,
        PX4P_VALUE_BOOL,
    ];
    assert_eq!(kinds, [1, 2, 3, 4]);
}

#[test]
fn the_store_holds_the_last_parameter_of_the_table_and_refuses_one_beyond_it() {
    let s = opened();
    // The last parameter is a parameter like any other: it has its type default, a new
    // instance starts from it, and it is saved.
    assert_eq!(get(s, LAST, 0, VALUE), Err(PX4P_ERR_NOT_PRESENT));
    assert_eq!(add(s, LAST, -1), 0);
    assert_eq!(get(s, LAST, 0, VALUE), Ok(LAST_DEFAULT.to_vec()));
    assert_eq!(get(s, LAST, 0, DEFAULT), Ok(LAST_DEFAULT.to_vec()));
    let leaves: Vec<_> = (0..4).map(|k| shown(leaf(s, LAST, 0, VALUE, k))).collect();
    assert_eq!(leaves, ["u 1", "u 2", "u 7", "f -2"]);
    assert_eq!(add(s, LAST, -1), 1);
    assert_eq!(add(s, LAST, -1), PX4P_ERR_FULL);
    assert_eq!(instances(s, LAST), Ok(vec![0, 1]));
    assert_eq!(set_leaf(s, LAST, 1, VALUE, 2, uint(9), 0), 0);
    let saved = save(s).unwrap();
    let expected = store_file(
        3,
        &["LAST=test.Last.1"],
        &[
            &structured_record(0, 0, None),
            &structured_record(0, 1, Some(&[0x14, 0x12, 0x01, 0x80])),
        ],
    );
    assert_eq!(saved, expected);
    // One beyond the table is no parameter, whatever the call.
    let mut out = [0u8; 8];
    let mut v = uint(0);
    unsafe {
        assert_eq!(px4p_add(s, BEYOND, -1), PX4P_ERR_NO_SUCH_PARAM);
        assert_eq!(px4p_add(s, BEYOND, 0), PX4P_ERR_NO_SUCH_PARAM);
        assert_eq!(px4p_remove(s, BEYOND, 0), PX4P_ERR_NO_SUCH_PARAM);
        let get = px4p_get(s, BEYOND, 0, VALUE, out.as_mut_ptr(), out.len());
        assert_eq!(get, PX4P_ERR_NO_SUCH_PARAM);
        let set = px4p_set(s, BEYOND, 0, VALUE, LAST_DEFAULT.as_ptr(), 4);
        assert_eq!(set, PX4P_ERR_NO_SUCH_PARAM);
        assert_eq!(
            px4p_get_leaf(s, BEYOND, 0, VALUE, 0, &mut v),
            PX4P_ERR_NO_SUCH_PARAM
        );
        let set_leaf = px4p_set_leaf(s, BEYOND, 0, VALUE, 1, &uint(1), 0);
        assert_eq!(set_leaf, PX4P_ERR_NO_SUCH_PARAM);
        assert_eq!(px4p_next_instance(s, BEYOND, -1), PX4P_ERR_NO_SUCH_PARAM);
    }
    // And a file naming it is loaded into it.
    let fresh = opened();
    assert_eq!(load(fresh, &expected), 2);
    assert_eq!(instances(fresh, LAST), Ok(vec![0, 1]));
    assert_eq!(shown(leaf(fresh, LAST, 1, VALUE, 2)), "u 9");
}

#[test]
fn open_refuses_null_pointers_bad_tables_and_too_little_memory() {
    let t = tables();
    let (slots, bytes) = (t.tables.slot_count as usize, t.tables.byte_count as usize);
    let mut m = memory(slots, bytes);
    let call = |store: *mut px4p_store, tables: *const px4p_tables, m: &mut Memory| unsafe {
        px4p_store_open(
            store,
            tables,
            m.slots.as_mut_ptr(),
            m.slots.len(),
            m.bytes.as_mut_ptr(),
            m.bytes.len(),
        )
    };
    assert_eq!(call(ptr::null_mut(), t.tables, &mut m), PX4P_ERR_ARGUMENT);
    assert_eq!(call(m.store, ptr::null(), &mut m), PX4P_ERR_ARGUMENT);
    let (store, tables) = (m.store, t.tables as *const px4p_tables);
    unsafe {
        let no_slots = px4p_store_open(
            store,
            tables,
            ptr::null_mut(),
            slots,
            m.bytes.as_mut_ptr(),
            bytes,
        );
        assert_eq!(no_slots, PX4P_ERR_ARGUMENT);
        let no_bytes = px4p_store_open(
            store,
            tables,
            m.slots.as_mut_ptr(),
            slots,
            ptr::null_mut(),
            bytes,
        );
        assert_eq!(no_bytes, PX4P_ERR_ARGUMENT);
    }
    // The store was not opened by any of these: every other call refuses it.
    assert_eq!(add(m.store, SENS, -1), PX4P_ERR_ARGUMENT);
    // One slot or one byte less than the tables say is refused; exactly that much opens.
    let mut short = memory(slots - 1, bytes);
    assert_eq!(open_with(t.tables, &mut short), PX4P_ERR_TABLES);
    let mut short = memory(slots, bytes - 1);
    assert_eq!(open_with(t.tables, &mut short), PX4P_ERR_TABLES);
    assert_eq!(open_with(t.tables, &mut m), 0);
    // Tables with a null pointer under a count, or names that are not UTF-8.
    let broken = |edit: fn(&mut px4p_tables)| {
        let mut copy = *t.tables;
        edit(&mut copy);
        let copy: &'static px4p_tables = Box::leak(Box::new(copy));
        open_with(copy, &mut memory(slots, bytes))
    };
    assert_eq!(broken(|t| t.defs = ptr::null()), PX4P_ERR_TABLES);
    assert_eq!(broken(|t| t.params = ptr::null()), PX4P_ERR_TABLES);
    assert_eq!(broken(|t| t.layout.nodes = ptr::null()), PX4P_ERR_TABLES);
    assert_eq!(
        broken(|t| t.layout.names = c"\xff".as_ptr()),
        PX4P_ERR_TABLES
    );
    let bad_param = |param: px4p_param| {
        let mut copy = *t.tables;
        let mut params = unsafe { std::slice::from_raw_parts(copy.params, 4) }.to_vec();
        params[LAST as usize] = param;
        copy.params = leak(params).as_ptr();
        let copy: &'static px4p_tables = Box::leak(Box::new(copy));
        open_with(copy, &mut memory(slots, bytes))
    };
    let last = unsafe { *t.tables.params.add(LAST as usize) };
    let no_default = px4p_param {
        type_default: ptr::null(),
        ..last
    };
    assert_eq!(bad_param(no_default), PX4P_ERR_TABLES);
    // A classic parameter is an int32 or a float32: a third kind is a table's mistake.
    let third = px4p_param {
        classic: PX4P_CLASSIC_FLOAT + 1,
        ..last
    };
    assert_eq!(bad_param(third), PX4P_ERR_TABLES);
    // A type default that does not decode as the type (two of its four bytes).
    let short_default = px4p_param {
        type_default_len: 2,
        ..last
    };
    assert_eq!(bad_param(short_default), PX4P_ERR_VALUE);
}

#[test]
fn a_store_never_opened_or_a_null_pointer_is_refused_by_every_call() {
    let never = Box::leak(Box::new(px4p_store { opaque: [0; 12] })) as *mut px4p_store;
    let s = opened();
    let mut out = [0u8; 8];
    let mut v = uint(0);
    for store in [never, ptr::null_mut()] {
        unsafe {
            assert_eq!(px4p_store_load(store, out.as_ptr(), 0), PX4P_ERR_ARGUMENT);
            assert_eq!(
                px4p_store_save(store, out.as_mut_ptr(), 8),
                PX4P_ERR_ARGUMENT
            );
            assert_eq!(
                px4p_get(store, SENS, 0, VALUE, out.as_mut_ptr(), 8),
                PX4P_ERR_ARGUMENT
            );
            assert_eq!(
                px4p_set(store, SENS, 0, VALUE, out.as_ptr(), 3),
                PX4P_ERR_ARGUMENT
            );
            assert_eq!(
                px4p_get_leaf(store, SENS, 0, VALUE, 1, &mut v),
                PX4P_ERR_ARGUMENT
            );
            assert_eq!(
                px4p_set_leaf(store, SENS, 0, VALUE, 1, &v, 0),
                PX4P_ERR_ARGUMENT
            );
            assert_eq!(px4p_add(store, SENS, -1), PX4P_ERR_ARGUMENT);
            assert_eq!(px4p_remove(store, SENS, 0), PX4P_ERR_ARGUMENT);
            assert_eq!(px4p_next_instance(store, SENS, -1), PX4P_ERR_ARGUMENT);
        }
    }
    assert_eq!(add(s, SENS, 0), 0);
    unsafe {
        // Null buffers with a length, on an open store.
        assert_eq!(px4p_store_load(s, ptr::null(), 10), PX4P_ERR_ARGUMENT);
        assert_eq!(px4p_store_save(s, ptr::null_mut(), 10), PX4P_ERR_ARGUMENT);
        assert_eq!(
            px4p_get(s, SENS, 0, VALUE, ptr::null_mut(), 3),
            PX4P_ERR_ARGUMENT
        );
        assert_eq!(
            px4p_set(s, SENS, 0, VALUE, ptr::null(), 3),
            PX4P_ERR_ARGUMENT
        );
        assert_eq!(
            px4p_get_leaf(s, SENS, 0, VALUE, 1, ptr::null_mut()),
            PX4P_ERR_ARGUMENT
        );
        assert_eq!(
            px4p_set_leaf(s, SENS, 0, VALUE, 1, ptr::null(), 0),
            PX4P_ERR_ARGUMENT
        );
        // A length of 0 needs no pointer: an empty buffer is too small, an empty file none.
        assert_eq!(
            px4p_get(s, SENS, 0, VALUE, ptr::null_mut(), 0),
            PX4P_ERR_BUFFER
        );
        assert_eq!(px4p_store_save(s, ptr::null_mut(), 0), PX4P_ERR_BUFFER);
        assert_eq!(px4p_store_load(s, ptr::null(), 0), PX4P_ERR_FILE);
    }
    // A value kind that is none of the four.
    for kind in [0, 5, 255] {
        let odd = px4p_value { kind, ..uint(1) };
        assert_eq!(set_leaf(s, SENS, 0, VALUE, 1, odd, 0), PX4P_ERR_ARGUMENT);
    }
    assert_eq!(get(s, SENS, 0, VALUE), Ok(SENS_DEFAULT.to_vec()));
}

#[test]
fn instances_are_added_removed_and_listed_with_their_errors() {
    let s = opened();
    assert_eq!(instances(s, SENS), Ok(vec![]));
    assert_eq!(add(s, SENS, 1), 1);
    assert_eq!(add(s, SENS, -1), 0);
    assert_eq!(add(s, SENS, -7), 2, "any negative number: the lowest free");
    assert_eq!(add(s, SENS, -1), PX4P_ERR_FULL);
    assert_eq!(add(s, SENS, 1), PX4P_ERR_ALREADY_PRESENT);
    assert_eq!(add(s, SENS, 3), PX4P_ERR_INSTANCE_RANGE);
    assert_eq!(add(s, SENS, 70_000), PX4P_ERR_INSTANCE_RANGE);
    assert_eq!(instances(s, SENS), Ok(vec![0, 1, 2]));
    assert_eq!(remove(s, SENS, 1), 0);
    assert_eq!(remove(s, SENS, 1), PX4P_ERR_NOT_PRESENT);
    assert_eq!(instances(s, SENS), Ok(vec![0, 2]));
    assert_eq!(unsafe { px4p_next_instance(s, SENS, 0) }, 2);
    assert_eq!(unsafe { px4p_next_instance(s, SENS, 2) }, PX4P_ERR_END);
    assert_eq!(unsafe { px4p_next_instance(s, SENS, 99) }, PX4P_ERR_END);
    assert_eq!(get(s, SENS, 1, VALUE), Err(PX4P_ERR_NOT_PRESENT));
    assert_eq!(get(s, SENS, 3, VALUE), Err(PX4P_ERR_INSTANCE_RANGE));
    // A shared parameter is always there, as instance 0, and has nothing to add or remove.
    assert_eq!(instances(s, TRIM), Ok(vec![0]));
    assert_eq!(add(s, TRIM, -1), PX4P_ERR_SHARED);
    assert_eq!(remove(s, TRIM, 0), PX4P_ERR_SHARED);
    assert_eq!(get(s, TRIM, 0, VALUE), Ok(TRIM_DEFAULT.to_vec()));
    assert_eq!(get(s, BAT_N_CELLS, 0, VALUE), Ok(BAT_DEFAULT.to_vec()));
}

#[test]
fn values_and_defaults_are_read_and_written_as_encoded_bytes() {
    let s = opened();
    assert_eq!(add(s, SENS, 0), 0);
    assert_eq!(get(s, SENS, 0, VALUE), Ok(SENS_DEFAULT.to_vec()));
    assert_eq!(set(s, SENS, 0, VALUE, &SENS_ADDRESS_22), 0);
    assert_eq!(get(s, SENS, 0, VALUE), Ok(SENS_ADDRESS_22.to_vec()));
    assert_eq!(get(s, SENS, 0, DEFAULT), Ok(SENS_DEFAULT.to_vec()));
    // Any nonzero which_default is the default.
    assert_eq!(get(s, SENS, 0, 7), Ok(SENS_DEFAULT.to_vec()));
    // The returned length, and a buffer one byte short.
    let mut out = [0u8; 3];
    let n = unsafe { px4p_get(s, SENS, 0, VALUE, out.as_mut_ptr(), 3) };
    assert_eq!((n, out), (3, SENS_ADDRESS_22));
    let short = unsafe { px4p_get(s, SENS, 0, VALUE, out.as_mut_ptr(), 2) };
    assert_eq!(short, PX4P_ERR_BUFFER);
    // The instance's default, apart from its value.
    let default_off = [0x18, 0xA0, 0x00]; // 0001 1000101 0 00000
    assert_eq!(set(s, SENS, 0, DEFAULT, &default_off), 0);
    assert_eq!(get(s, SENS, 0, DEFAULT), Ok(default_off.to_vec()));
    assert_eq!(get(s, SENS, 0, VALUE), Ok(SENS_ADDRESS_22.to_vec()));
    // Bytes that do not decode: too few, or another minor version in p_version.
    assert_eq!(set(s, SENS, 0, VALUE, &[0x18]), PX4P_ERR_VALUE);
    assert_eq!(
        set(s, SENS, 0, VALUE, &[0x28, 0xBE, 0x80]),
        PX4P_ERR_VERSION
    );
    assert_eq!(get(s, SENS, 0, VALUE), Ok(SENS_ADDRESS_22.to_vec()));
    assert_eq!(set(s, SENS, 1, VALUE, &SENS_DEFAULT), PX4P_ERR_NOT_PRESENT);
}

#[test]
fn leaves_are_read_and_written_by_index_with_their_kinds() {
    let s = opened();
    assert_eq!(add(s, SENS, 0), 0);
    let leaves =
        |which| -> Vec<String> { (0..4).map(|k| shown(leaf(s, SENS, 0, which, k))).collect() };
    assert_eq!(leaves(VALUE), ["u 1", "u 69", "b 1", "i -3"]);
    assert_eq!(shown(leaf(s, TRIM, 0, VALUE, 3)), "f 0.5");
    assert_eq!(shown(leaf(s, BAT_N_CELLS, 0, VALUE, 0)), "i 4");
    assert_eq!(shown(leaf(s, SENS, 0, VALUE, 4)), "PX4P_ERR_NO_SUCH_LEAF");
    assert_eq!(shown(leaf(s, SENS, 1, VALUE, 1)), "PX4P_ERR_NOT_PRESENT");
    // One of each kind written.
    assert_eq!(set_leaf(s, SENS, 0, VALUE, 1, uint(0x22), 0), 0);
    assert_eq!(set_leaf(s, SENS, 0, VALUE, 2, boolean(0), 0), 0);
    assert_eq!(set_leaf(s, SENS, 0, VALUE, 3, int(5), 0), 0);
    assert_eq!(set_leaf(s, TRIM, 0, VALUE, 3, float(1.5), 0), 0);
    assert_eq!(leaves(VALUE), ["u 1", "u 34", "b 0", "i 5"]);
    assert_eq!(leaves(DEFAULT), ["u 1", "u 69", "b 1", "i -3"]);
    assert_eq!(shown(leaf(s, TRIM, 0, VALUE, 3)), "f 1.5");
    // 0001 0100010 0 00101: the bytes say the same.
    assert_eq!(get(s, SENS, 0, VALUE), Ok(vec![0x14, 0x42, 0x80]));
    // A bool is any nonzero number.
    assert_eq!(set_leaf(s, SENS, 0, VALUE, 2, boolean(2), 0), 0);
    assert_eq!(shown(leaf(s, SENS, 0, VALUE, 2)), "b 1");
    // int5 holds -16..15: refused unless saturated, then clamped.
    assert_eq!(set_leaf(s, SENS, 0, VALUE, 3, int(-20), 0), PX4P_ERR_VALUE);
    assert_eq!(shown(leaf(s, SENS, 0, VALUE, 3)), "i 5");
    assert_eq!(set_leaf(s, SENS, 0, VALUE, 3, int(-20), 1), 0);
    assert_eq!(shown(leaf(s, SENS, 0, VALUE, 3)), "i -16");
    // p_version is the store's; a leaf past the last is none.
    assert_eq!(
        set_leaf(s, SENS, 0, VALUE, 0, uint(1), 0),
        PX4P_ERR_VERSION_LEAF
    );
    assert_eq!(
        set_leaf(s, SENS, 0, VALUE, 4, uint(1), 0),
        PX4P_ERR_NO_SUCH_LEAF
    );
    // The default's leaves, apart from the value's.
    assert_eq!(set_leaf(s, SENS, 0, DEFAULT, 1, uint(0x10), 0), 0);
    assert_eq!(shown(leaf(s, SENS, 0, DEFAULT, 1)), "u 16");
    assert_eq!(shown(leaf(s, SENS, 0, VALUE, 1)), "u 34");
}

/// SENS#0 = address 0x22, SENS#2 at its defaults, BAT_N_CELLS = 6, in file order.
fn saved_file() -> Vec<u8> {
    store_file(
        3,
        &["SENS=test.Sensor.1"],
        &[
            &classic_record("BAT_N_CELLS", 6),
            &structured_record(0, 0, Some(&SENS_ADDRESS_22)),
            &structured_record(0, 2, None),
        ],
    )
}

#[test]
fn a_store_is_saved_as_the_store_file_format_says() {
    let s = opened();
    // Nothing differs from a default: a header, an empty table and the trailer.
    let empty = store_file(3, &[], &[]);
    assert_eq!(save(s), Ok(empty.clone()));
    assert_eq!(add(s, SENS, 0), 0);
    assert_eq!(add(s, SENS, 2), 2);
    assert_eq!(set(s, SENS, 0, VALUE, &SENS_ADDRESS_22), 0);
    assert_eq!(set(s, BAT_N_CELLS, 0, VALUE, &6i32.to_le_bytes()), 0);
    let expected = saved_file();
    assert_eq!(save(s), Ok(expected.clone()));
    // The returned length, and a buffer one byte short.
    let mut buf = vec![0u8; expected.len()];
    let n = unsafe { px4p_store_save(s, buf.as_mut_ptr(), buf.len()) };
    assert_eq!(n as usize, expected.len());
    let short = unsafe { px4p_store_save(s, buf.as_mut_ptr(), expected.len() - 1) };
    assert_eq!(short, PX4P_ERR_BUFFER);
    // An instance's own default is saved with flag 0x10; its value, equal to its default
    // before, follows it (PX4's set-default) and is not saved.
    assert_eq!(set(s, SENS, 2, DEFAULT, &SENS_ADDRESS_22), 0);
    assert_eq!(get(s, SENS, 2, VALUE), Ok(SENS_ADDRESS_22.to_vec()));
    let with_default = store_file::structured_record(0, 2, Some(&SENS_ADDRESS_22), None);
    assert_eq!(with_default[..4], [0x11, 0, 2, 3]);
    let expected = store_file(
        3,
        &["SENS=test.Sensor.1"],
        &[
            &classic_record("BAT_N_CELLS", 6),
            &structured_record(0, 0, Some(&SENS_ADDRESS_22)),
            &with_default,
        ],
    );
    assert_eq!(save(s), Ok(expected));
}

#[test]
fn a_store_file_is_loaded_in_place_of_the_content_and_saved_back_byte_identical() {
    let s = opened();
    assert_eq!(add(s, LAST, 1), 1);
    let file = saved_file();
    assert_eq!(load(s, &file), 3, "three records applied");
    assert_eq!(
        instances(s, LAST),
        Ok(vec![]),
        "a load replaces, not merges"
    );
    assert_eq!(instances(s, SENS), Ok(vec![0, 2]));
    assert_eq!(get(s, SENS, 0, VALUE), Ok(SENS_ADDRESS_22.to_vec()));
    assert_eq!(get(s, SENS, 2, VALUE), Ok(SENS_DEFAULT.to_vec()));
    assert_eq!(
        get(s, BAT_N_CELLS, 0, VALUE),
        Ok(6i32.to_le_bytes().to_vec())
    );
    assert_eq!(save(s), Ok(file));
    // A classic record of a parameter the tables lack is skipped (PX4 keeps those), not
    // counted.
    let foreign = store_file(
        2,
        &["SENS=test.Sensor.1"],
        &[
            &classic_record("NOT_HERE", 1),
            &structured_record(0, 1, None),
        ],
    );
    assert_eq!(load(s, &foreign), 1);
    assert_eq!(instances(s, SENS), Ok(vec![1]));
    // So is one of another type: 6.0's float bits are not six cells.
    let float = store_file(3, &[], &[&store_file::float_record("BAT_N_CELLS", 6.0)]);
    assert_eq!(load(s, &float), 0);
    assert_eq!(get(s, BAT_N_CELLS, 0, VALUE), Ok(BAT_DEFAULT.to_vec()));
    // A format 2 file did not say: the record is the tables' type.
    let untyped = store_file(2, &[], &[&classic_record("BAT_N_CELLS", 6)]);
    assert_eq!(load(s, &untyped), 1);
    assert_eq!(
        get(s, BAT_N_CELLS, 0, VALUE),
        Ok(6i32.to_le_bytes().to_vec())
    );
}

#[test]
fn a_bad_store_file_is_refused_with_its_code_and_the_store_left_as_it_was() {
    let s = opened();
    assert_eq!(add(s, SENS, 1), 1);
    assert_eq!(set_leaf(s, SENS, 1, VALUE, 1, uint(0x30), 0), 0);
    let good = saved_file();
    let mut flipped = good.clone();
    flipped[16] ^= 0x01;
    let mut not_a_store = good.clone();
    not_a_store[0] = b'Q';
    let format_4 = store_file(4, &[], &[]);
    let cases: Vec<(&str, Vec<u8>, i32)> = vec![
        ("a flipped bit", flipped, PX4P_ERR_FILE),
        ("truncated", good[..good.len() - 1].to_vec(), PX4P_ERR_FILE),
        ("no magic", not_a_store, PX4P_ERR_FILE),
        ("format 4", format_4, PX4P_ERR_FILE),
        (
            "format 1",
            store_file(1, &[], &[&structured_record(0, 0, None)]),
            PX4P_ERR_FILE_FORMAT_1,
        ),
        (
            "a parameter the tables lack",
            store_file(2, &["GONE=test.Gone.1"], &[&structured_record(0, 0, None)]),
            PX4P_ERR_FILE_PARAM,
        ),
        (
            "another major version",
            store_file(
                2,
                &["SENS=test.Sensor.2"],
                &[&structured_record(0, 0, None)],
            ),
            PX4P_ERR_FILE_PARAM,
        ),
        (
            "an instance out of range",
            store_file(
                2,
                &["SENS=test.Sensor.1"],
                &[&structured_record(0, 3, None)],
            ),
            PX4P_ERR_INSTANCE_RANGE,
        ),
        (
            // The firmware took the last of the two (the host refused the file).
            "two records of one instance",
            store_file(
                2,
                &["SENS=test.Sensor.1"],
                &[
                    &structured_record(0, 2, Some(&SENS_ADDRESS_22)),
                    &structured_record(0, 2, None),
                ],
            ),
            PX4P_ERR_FILE,
        ),
        (
            "a table naming one parameter twice",
            store_file(
                2,
                &["SENS=test.Sensor.1", "SENS=test.Sensor.1"],
                &[
                    &structured_record(0, 0, None),
                    &structured_record(1, 0, None),
                ],
            ),
            PX4P_ERR_FILE,
        ),
        (
            "an instance of a shared parameter",
            store_file(2, &["TRIM=test.Last.1"], &[&structured_record(0, 1, None)]),
            PX4P_ERR_NOT_PRESENT,
        ),
        (
            "a value that does not decode, after a good record",
            store_file(
                2,
                &["SENS=test.Sensor.1"],
                &[
                    &structured_record(0, 0, None),
                    &structured_record(0, 2, Some(&[0x18])),
                ],
            ),
            PX4P_ERR_VALUE,
        ),
        (
            "a minor version the tables do not carry",
            store_file(
                2,
                &["SENS=test.Sensor.1"],
                &[&structured_record(0, 0, Some(&[0x28, 0xBE, 0x80]))],
            ),
            PX4P_ERR_VERSION,
        ),
    ];
    for (what, file, code) in cases {
        assert_eq!(name(load(s, &file)), name(code), "{what}");
        assert_eq!(instances(s, SENS), Ok(vec![1]), "{what}");
        assert_eq!(shown(leaf(s, SENS, 1, VALUE, 1)), "u 48", "{what}");
    }
}

#[test]
fn a_value_of_an_older_minor_version_is_translated_on_load() {
    let s = opened();
    // Sensor 1.0: p_version 0, address 0x22, gain 9 = 0000 0100010 00001001.
    let sensor_1_0 = [0x04, 0x41, 0x20];
    // Last 1.0: p_version 0, mode 3, level 9 = 0000 011 00001001.
    let last_1_0 = [0x06, 0x12];
    let file = store_file(
        2,
        &["LAST=test.Last.1", "SENS=test.Sensor.1"],
        &[
            &structured_record(0, 1, Some(&last_1_0)),
            &structured_record(1, 2, Some(&sensor_1_0)),
        ],
    );
    assert_eq!(load(s, &file), 2);
    // Fields carried over by name; what 1.1 added takes the default; gain of 1.0 dropped.
    let sens: Vec<_> = (0..4).map(|k| shown(leaf(s, SENS, 2, VALUE, k))).collect();
    assert_eq!(sens, ["u 1", "u 34", "b 1", "i -3"]);
    let last: Vec<_> = (0..4).map(|k| shown(leaf(s, LAST, 1, VALUE, k))).collect();
    assert_eq!(last, ["u 1", "u 3", "u 9", "f -2"]);
    assert_eq!(get(s, SENS, 2, VALUE), Ok(SENS_ADDRESS_22.to_vec()));
}

/// A store keeps no NaN or infinity (the host's loader refuses a file with one): firmware's
/// writes refuse them as the host's do, and so does load, leaving the store as it was. TRIM
/// with gain NaN (float16 0x7E00) is `1B 90 00 FC`, with gain infinity (0x7C00) `1B 90 00 F8`.
#[test]
fn a_nan_or_an_infinity_is_refused_by_set_set_leaf_and_load() {
    let s = opened();
    let (nan_gain, infinite_gain) = ([0x1B, 0x90, 0x00, 0xFC], [0x1B, 0x90, 0x00, 0xF8]);
    assert_eq!(set(s, TRIM, 0, VALUE, &nan_gain), PX4P_ERR_VALUE);
    assert_eq!(set(s, TRIM, 0, DEFAULT, &infinite_gain), PX4P_ERR_VALUE);
    assert_eq!(
        set_leaf(s, TRIM, 0, VALUE, 3, float(f64::NAN), 0),
        PX4P_ERR_VALUE
    );
    assert_eq!(
        set_leaf(s, TRIM, 0, DEFAULT, 3, float(-f64::INFINITY), 1),
        PX4P_ERR_VALUE
    );
    let file = store_file(
        2,
        &["TRIM=test.Last.1"],
        &[&structured_record(0, 0, Some(&nan_gain))],
    );
    assert_eq!(name(load(s, &file)), name(PX4P_ERR_VALUE));
    assert_eq!(get(s, TRIM, 0, VALUE), Ok(TRIM_DEFAULT.to_vec()));
    assert_eq!(get(s, TRIM, 0, DEFAULT), Ok(TRIM_DEFAULT.to_vec()));
    // The largest finite float16 is kept.
    assert_eq!(set_leaf(s, TRIM, 0, VALUE, 3, float(65504.0), 0), 0);
    assert_eq!(shown(leaf(s, TRIM, 0, VALUE, 3)), "f 65504");
}
