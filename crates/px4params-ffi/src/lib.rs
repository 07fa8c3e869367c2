//! The C ABI of px4params-core: the instance parameter store over memory and layout tables the
//! firmware keeps in `static`/`const` storage, loaded from and saved to the store file format
//! that the `px4params` tools read and write.
//!
//! The tables come from `px4params metadata --firmware`; the header is `include/px4params.h`
//! (generated with cbindgen from this crate, see `cbindgen.toml`). Every function returns a
//! non-negative result or a negative `PX4P_ERR_*` code; [`px4p_error_name`] names a code.
//! No function allocates, and none panics on any input the C side can give.
//!
//! With the `firmware` feature the crate is `no_std` and brings a panic handler (build it with
//! `panic = "abort"`); without it, host builds (tests, the example) link std's.
#![cfg_attr(feature = "firmware", no_std)]
#![deny(missing_docs)]
// The C ABI is raw pointers from C; each function checks them before it makes references.
#![allow(clippy::missing_safety_doc)]

use core::ffi::c_char;
use core::mem::{align_of, size_of, MaybeUninit};
use core::slice;

use px4params_core::file::{self, ApplyError, ClassicType, FileName, SaveError, WriteError};
use px4params_core::layout::{Field, FlatItem, Layout, Node, Segment};
use px4params_core::store::{ParamDef, Slot, Store, StoreError, Which};
use px4params_core::{ErrorKind, Scalar};

#[cfg(feature = "firmware")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {}
}

/// A compiled layout in C tables: the core's [`Layout`] as pointers and lengths.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct px4p_layout {
    /// All nodes.
    pub nodes: *const Node,
    /// Number of nodes.
    pub node_count: u32,
    /// All struct fields and union variants.
    pub fields: *const Field,
    /// Number of fields.
    pub field_count: u32,
    /// All field names, concatenated (not NUL-terminated; may be empty).
    pub names: *const c_char,
    /// Length of `names` in bytes.
    pub names_len: u32,
    /// Struct segments.
    pub segments: *const Segment,
    /// Number of segments.
    pub segment_count: u32,
    /// Flattened items of fixed-shape runs.
    pub flat: *const FlatItem,
    /// Number of flat items.
    pub flat_count: u32,
}

/// One parameter of the firmware's store, as its file names it.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct px4p_param {
    /// `NAME=TYPE.MAJOR` of a structured parameter (`INA238=px.Ina238.1`), or a classic
    /// parameter's name; NUL-terminated ASCII.
    pub file_name: *const c_char,
    /// 0 for a structured parameter; for a classic one (4-byte values) its type, as its
    /// records say it: [`PX4P_CLASSIC_INT32`] or [`PX4P_CLASSIC_FLOAT`].
    pub classic: u8,
    /// The type's default, encoded without tail array optimization.
    pub type_default: *const u8,
    /// Length of `type_default` in bytes.
    pub type_default_len: u32,
}

/// An older minor version of a parameter's type that the tables carry, so that values it
/// stored are translated on load.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct px4p_version {
    /// The parameter.
    pub param: u32,
    /// The minor version.
    pub minor: u32,
    /// The root node of that version of the type.
    pub root: u32,
}

/// Everything generated for a firmware's store: the layout, each parameter's definition as
/// the core's `plan` laid it out, its file name and type default, and the memory it needs.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct px4p_tables {
    /// The compiled types.
    pub layout: px4p_layout,
    /// The parameters' definitions, in parameter ID order.
    pub defs: *const ParamDef,
    /// The parameters' names and defaults, in the same order.
    pub params: *const px4p_param,
    /// Parameter IDs in file order (sorted by name, as `px4params` saves).
    pub order: *const u32,
    /// Number of parameters.
    pub param_count: u32,
    /// Older versions of the parameters' types.
    pub versions: *const px4p_version,
    /// Number of older versions.
    pub version_count: u32,
    /// Slots the store needs.
    pub slot_count: u32,
    /// Bytes the store needs.
    pub byte_count: u32,
}

/// Room for a store, in the caller's memory (`static px4p_store store;`). Opened by
/// [`px4p_store_open`]; the tables and memory given there must outlive it. Every other
/// function refuses a store that was not opened (`PX4P_ERR_ARGUMENT`).
#[repr(C)]
pub struct px4p_store {
    /// Private (`u64`s: 8-byte aligned).
    pub opaque: [u64; 12],
}

/// A leaf's value: `kind` says which member holds it.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct px4p_value {
    /// One of `PX4P_VALUE_*`.
    pub kind: u8,
    /// An unsigned integer (also union tags and array lengths).
    pub u: u64,
    /// A signed integer.
    pub i: i64,
    /// A floating-point number.
    pub f: f64,
}

/// [`px4p_value::kind`]: an unsigned integer in `u`.
pub const PX4P_VALUE_UINT: u8 = 1;
/// [`px4p_value::kind`]: a signed integer in `i`.
pub const PX4P_VALUE_INT: u8 = 2;
/// [`px4p_value::kind`]: a float in `f`.
pub const PX4P_VALUE_FLOAT: u8 = 3;
/// [`px4p_value::kind`]: a boolean in `u` (0 or 1).
pub const PX4P_VALUE_BOOL: u8 = 4;
/// [`px4p_param::classic`]: a classic parameter holding an int32.
pub const PX4P_CLASSIC_INT32: u8 = 1;
/// [`px4p_param::classic`]: a classic parameter holding a float32.
pub const PX4P_CLASSIC_FLOAT: u8 = 2;

/// A null pointer, or a length that does not fit.
pub const PX4P_ERR_ARGUMENT: i32 = -1;
/// Tables that do not match their plan, or memory smaller than they need.
pub const PX4P_ERR_TABLES: i32 = -2;
/// No parameter with this ID.
pub const PX4P_ERR_NO_SUCH_PARAM: i32 = -3;
/// An instance number at or above the parameter's maximum.
pub const PX4P_ERR_INSTANCE_RANGE: i32 = -4;
/// The instance does not exist.
pub const PX4P_ERR_NOT_PRESENT: i32 = -5;
/// The instance exists already.
pub const PX4P_ERR_ALREADY_PRESENT: i32 = -6;
/// Every instance slot is taken.
pub const PX4P_ERR_FULL: i32 = -7;
/// A shared parameter has no instances to add or remove.
pub const PX4P_ERR_SHARED: i32 = -8;
/// A value that does not decode as the parameter's type, a leaf value out of range, or a
/// NaN or an infinity (a store keeps none).
pub const PX4P_ERR_VALUE: i32 = -9;
/// No leaf with this index.
pub const PX4P_ERR_NO_SUCH_LEAF: i32 = -10;
/// `p_version` leaves are written by the store, never by the caller.
pub const PX4P_ERR_VERSION_LEAF: i32 = -11;
/// A value stored by another minor version of its type that the tables do not carry.
pub const PX4P_ERR_VERSION: i32 = -12;
/// The output buffer is too small.
pub const PX4P_ERR_BUFFER: i32 = -13;
/// Not a store file, another format version, truncated or corrupted (a CRC mismatch), or
/// malformed (a parameter table naming one parameter twice, two records of one instance).
pub const PX4P_ERR_FILE: i32 = -14;
/// A store file record of a structured parameter this store does not have.
pub const PX4P_ERR_FILE_PARAM: i32 = -15;
/// A format 1 store file: `px4params param load` on the host upgrades it.
pub const PX4P_ERR_FILE_FORMAT_1: i32 = -16;
/// No more instances ([`px4p_next_instance`]).
pub const PX4P_ERR_END: i32 = -17;

type CStore = Store<&'static [ParamDef], &'static mut [Slot], &'static mut [u8]>;

/// What [`px4p_store`] holds once opened; `magic` first, so that a store never opened (or
/// memory that is not a store) is refused rather than used.
#[repr(C)]
struct Open {
    magic: u64,
    tables: &'static px4p_tables,
    store: CStore,
}

const OPEN: u64 = u64::from_le_bytes(*b"px4p-ok!");

const _: () = assert!(size_of::<Open>() <= size_of::<px4p_store>());
const _: () = assert!(align_of::<Open>() <= align_of::<px4p_store>());

/// Builds a slice from a C pointer and count (empty for a count of 0, whatever the pointer).
unsafe fn table<'a, T>(ptr: *const T, count: u32) -> Option<&'a [T]> {
    match (ptr.is_null(), count) {
        (_, 0) => Some(&[]),
        (true, _) => None,
        (false, n) => Some(slice::from_raw_parts(ptr, n as usize)),
    }
}

unsafe fn layout_of(t: &px4p_layout) -> Option<Layout<'static>> {
    let names = table(t.names.cast::<u8>(), t.names_len)?;
    Some(Layout {
        nodes: table(t.nodes, t.node_count)?,
        fields: table(t.fields, t.field_count)?,
        names: core::str::from_utf8(names).ok()?,
        segments: table(t.segments, t.segment_count)?,
        flat: table(t.flat, t.flat_count)?,
        // Firmware runs no straight-line plan (`NoPlans`).
        straight: &[],
    })
}

unsafe fn open<'a>(store: *const px4p_store) -> Option<&'a Open> {
    // SAFETY: the magic word is only there where px4p_store_open wrote an `Open`.
    match store.as_ref() {
        Some(s) if s.opaque[0] == OPEN => store.cast::<Open>().as_ref(),
        _ => None,
    }
}

unsafe fn open_mut<'a>(store: *mut px4p_store) -> Option<&'a mut Open> {
    match store.as_ref() {
        Some(s) if s.opaque[0] == OPEN => store.cast::<Open>().as_mut(),
        _ => None,
    }
}

impl Open {
    fn layout(&self) -> Layout<'static> {
        // Checked by px4p_store_open.
        unsafe { layout_of(&self.tables.layout) }.unwrap_or(Layout {
            nodes: &[],
            fields: &[],
            names: "",
            segments: &[],
            flat: &[],
            straight: &[],
        })
    }

    fn params(&self) -> &'static [px4p_param] {
        unsafe { table(self.tables.params, self.tables.param_count) }.unwrap_or(&[])
    }

    fn versions(&self) -> &'static [px4p_version] {
        unsafe { table(self.tables.versions, self.tables.version_count) }.unwrap_or(&[])
    }
}

fn store_code<E>(e: StoreError<E>) -> i32 {
    match e {
        StoreError::NoSuchParam { .. } => PX4P_ERR_NO_SUCH_PARAM,
        StoreError::InstanceOutOfRange { .. } => PX4P_ERR_INSTANCE_RANGE,
        StoreError::NotPresent { .. } => PX4P_ERR_NOT_PRESENT,
        StoreError::AlreadyPresent { .. } => PX4P_ERR_ALREADY_PRESENT,
        StoreError::Full { .. } => PX4P_ERR_FULL,
        StoreError::Shared => PX4P_ERR_SHARED,
        StoreError::VersionLeaf { .. } => PX4P_ERR_VERSION_LEAF,
        StoreError::Unsupported { .. }
        | StoreError::NotPlanned { .. }
        | StoreError::Memory { .. }
        | StoreError::PagesFull { .. }
        | StoreError::UnequalPages => PX4P_ERR_TABLES,
        StoreError::Codec(e) => match e.kind {
            ErrorKind::VersionMismatch { .. } => PX4P_ERR_VERSION,
            ErrorKind::NoSuchLeaf { .. } => PX4P_ERR_NO_SUCH_LEAF,
            _ => PX4P_ERR_VALUE,
        },
        // The core's errors are open to new kinds: one this ABI does not know is a refusal.
        _ => PX4P_ERR_VALUE,
    }
}

/// Opens a store over `tables` and the caller's memory (`slot_count` slots, `byte_count`
/// bytes, at least what `tables` says): every instance absent, shared and classic parameters
/// at their type defaults.
#[no_mangle]
pub unsafe extern "C" fn px4p_store_open(
    store: *mut px4p_store,
    tables: *const px4p_tables,
    slots: *mut Slot,
    slot_count: usize,
    bytes: *mut u8,
    byte_count: usize,
) -> i32 {
    let (Some(tables), false, false, false) = (
        tables.as_ref(),
        store.is_null(),
        slots.is_null(),
        bytes.is_null(),
    ) else {
        return PX4P_ERR_ARGUMENT;
    };
    let (Some(layout), Some(defs), Some(params)) = (
        layout_of(&tables.layout),
        table(tables.defs, tables.param_count),
        table(tables.params, tables.param_count),
    ) else {
        return PX4P_ERR_TABLES;
    };
    let slots = slice::from_raw_parts_mut(slots, slot_count);
    let bytes = slice::from_raw_parts_mut(bytes, byte_count);
    let mut core = match CStore::new(&layout, defs, slots, bytes) {
        Ok(s) => s,
        Err(e) => return store_code(e),
    };
    for (param, p) in params.iter().enumerate() {
        let Some(default) = table(p.type_default, p.type_default_len) else {
            return PX4P_ERR_TABLES;
        };
        if p.classic > PX4P_CLASSIC_FLOAT {
            return PX4P_ERR_TABLES;
        }
        if let Err(e) = core.set_type_default(&layout, param as u32, default) {
            return store_code(e);
        }
    }
    core.mark_saved();
    let open = Open {
        magic: OPEN,
        tables,
        store: core,
    };
    store
        .cast::<MaybeUninit<Open>>()
        .write(MaybeUninit::new(open));
    0
}

/// The parameters' file names and older type versions, read from the C tables.
struct CNames(&'static [px4p_param], &'static [px4p_version]);

impl file::FileNames for CNames {
    fn name(&self, param: u32) -> Option<FileName<'_>> {
        let p = self.0.get(param as usize)?;
        if p.file_name.is_null() {
            return None;
        }
        // SAFETY: the tables hold NUL-terminated strings (checked non-null above).
        let text = unsafe { core::ffi::CStr::from_ptr(p.file_name) }
            .to_str()
            .ok()?;
        Some(match p.classic {
            0 => FileName::Structured(text),
            PX4P_CLASSIC_FLOAT => FileName::Classic(text, ClassicType::Float32),
            _ => FileName::Classic(text, ClassicType::Int32),
        })
    }

    fn older(&self, param: u32, minor: u32) -> Option<u32> {
        let v = self
            .1
            .iter()
            .find(|v| v.param == param && v.minor == minor)?;
        Some(v.root)
    }
}

/// Replaces the store's content with a store file's (written by `px4params param save` or by
/// [`px4p_store_save`]). The file and every record are checked before anything changes: on any
/// error the store is as it was. Values stored by an older minor version of their type are
/// checked whole as that version, then translated when the tables carry it. A classic record
/// the tables lack, or hold as the other type, is skipped, not counted (PX4 keeps classic
/// parameters in its own storage). Returns the number of records applied.
#[no_mangle]
pub unsafe extern "C" fn px4p_store_load(
    store: *mut px4p_store,
    data: *const u8,
    len: usize,
) -> i32 {
    let Some(open) = open_mut(store) else {
        return PX4P_ERR_ARGUMENT;
    };
    let Some(data) = bytes_in(data, len) else {
        return PX4P_ERR_ARGUMENT;
    };
    let Ok(checked) = file::check(data) else {
        return PX4P_ERR_FILE;
    };
    let layout = open.layout();
    let names = CNames(open.params(), open.versions());
    match file::apply(&mut open.store, &layout, &names, &checked, true) {
        Ok(applied) => clamp(applied.records),
        Err(ApplyError::Format1) => PX4P_ERR_FILE_FORMAT_1,
        Err(ApplyError::UnknownParameter { .. }) => PX4P_ERR_FILE_PARAM,
        Err(ApplyError::Refused { error, .. }) => store_code(error),
        Err(_) => PX4P_ERR_FILE, // (a second record of one instance too)
    }
}

/// Writes the store's file into `buf` (the bytes `px4params param load` reads); returns its
/// length, or `PX4P_ERR_BUFFER` when `buf` is too small. Parameters are written in name order,
/// as `px4params` writes them, so a file loaded and saved again is byte-identical, but for the
/// classic records the load skipped: only the tables' parameters are written.
#[no_mangle]
pub unsafe extern "C" fn px4p_store_save(store: *mut px4p_store, buf: *mut u8, cap: usize) -> i32 {
    let Some(open) = open_mut(store) else {
        return PX4P_ERR_ARGUMENT;
    };
    let Some(buf) = bytes_in_mut(buf, cap) else {
        return PX4P_ERR_ARGUMENT;
    };
    let names = CNames(open.params(), open.versions());
    let order = open.tables.order;
    let Some(order) = table(order, open.tables.param_count) else {
        return PX4P_ERR_TABLES;
    };
    match file::write_store(&open.store, &names, order, [], buf) {
        Ok(len) => {
            open.store.mark_saved();
            clamp(len)
        }
        Err(SaveError::Write(WriteError::BufferFull { .. })) => PX4P_ERR_BUFFER,
        Err(_) => PX4P_ERR_TABLES,
    }
}

/// Copies an instance's value (or with `which_default` its default) into `out`; returns its
/// length in bytes (encoded without tail array optimization).
#[no_mangle]
pub unsafe extern "C" fn px4p_get(
    store: *const px4p_store,
    param: u32,
    instance: u16,
    which_default: u8,
    out: *mut u8,
    cap: usize,
) -> i32 {
    let (Some(open), Some(out)) = (open(store), bytes_in_mut(out, cap)) else {
        return PX4P_ERR_ARGUMENT;
    };
    match open.store.get(param, instance, which(which_default)) {
        Ok(value) => match out.get_mut(..value.len()) {
            Some(to) => {
                to.copy_from_slice(value);
                clamp(value.len())
            }
            None => PX4P_ERR_BUFFER,
        },
        Err(e) => store_code(e),
    }
}

/// Sets an instance's value (or default) from encoded bytes, checked first: they must decode
/// as the parameter's type, `p_version` included.
#[no_mangle]
pub unsafe extern "C" fn px4p_set(
    store: *mut px4p_store,
    param: u32,
    instance: u16,
    which_default: u8,
    data: *const u8,
    len: usize,
) -> i32 {
    let (Some(open), Some(data)) = (open_mut(store), bytes_in(data, len)) else {
        return PX4P_ERR_ARGUMENT;
    };
    let layout = open.layout();
    let result = open
        .store
        .set_encoded(&layout, param, instance, which(which_default), data);
    result.map_or_else(store_code, |()| 0)
}

/// Reads leaf `leaf` (its index in depth-first order, `[k]` in `px4params`) of an instance's
/// value (or default) into `out`.
#[no_mangle]
pub unsafe extern "C" fn px4p_get_leaf(
    store: *const px4p_store,
    param: u32,
    instance: u16,
    which_default: u8,
    leaf: u32,
    out: *mut px4p_value,
) -> i32 {
    let (Some(open), Some(out)) = (open(store), out.as_mut()) else {
        return PX4P_ERR_ARGUMENT;
    };
    let layout = open.layout();
    let k = leaf as usize;
    match open
        .store
        .read(&layout, param, instance, which(which_default), k)
    {
        Ok(scalar) => {
            *out = value_of(scalar);
            0
        }
        Err(e) => store_code(e),
    }
}

/// Writes leaf `leaf` of an instance's value (or default); out-of-range values are refused
/// unless `saturate`.
#[no_mangle]
pub unsafe extern "C" fn px4p_set_leaf(
    store: *mut px4p_store,
    param: u32,
    instance: u16,
    which_default: u8,
    leaf: u32,
    value: *const px4p_value,
    saturate: u8,
) -> i32 {
    let (Some(open), Some(value)) = (open_mut(store), value.as_ref()) else {
        return PX4P_ERR_ARGUMENT;
    };
    let Some(scalar) = scalar_of(value) else {
        return PX4P_ERR_ARGUMENT;
    };
    let layout = open.layout();
    let (k, w) = (leaf as usize, which(which_default));
    let result = open
        .store
        .set_leaf_at(&layout, param, instance, w, k, scalar, saturate != 0);
    result.map_or_else(store_code, |()| 0)
}

/// Adds instance `instance` of a parameter, or with a negative `instance` the lowest free
/// one; returns the instance's number. It starts from the type's default.
#[no_mangle]
pub unsafe extern "C" fn px4p_add(store: *mut px4p_store, param: u32, instance: i32) -> i32 {
    let Some(open) = open_mut(store) else {
        return PX4P_ERR_ARGUMENT;
    };
    let wanted = match instance {
        i if i < 0 => None,
        i => match u16::try_from(i) {
            Ok(i) => Some(i),
            Err(_) => return PX4P_ERR_INSTANCE_RANGE,
        },
    };
    open.store
        .add(param, wanted)
        .map_or_else(store_code, i32::from)
}

/// Removes an instance.
#[no_mangle]
pub unsafe extern "C" fn px4p_remove(store: *mut px4p_store, param: u32, instance: u16) -> i32 {
    let Some(open) = open_mut(store) else {
        return PX4P_ERR_ARGUMENT;
    };
    open.store
        .remove(param, instance)
        .map_or_else(store_code, |()| 0)
}

/// The first present instance of a parameter above `after` (-1 to start): the loop of the
/// talk's `param_find_instances`. Returns `PX4P_ERR_END` after the last.
#[no_mangle]
pub unsafe extern "C" fn px4p_next_instance(
    store: *const px4p_store,
    param: u32,
    after: i32,
) -> i32 {
    let Some(open) = open(store) else {
        return PX4P_ERR_ARGUMENT;
    };
    match open.store.instances(param) {
        Ok(mut present) => present
            .find(|&i| i32::from(i) > after)
            .map_or(PX4P_ERR_END, i32::from),
        Err(e) => store_code(e),
    }
}

/// The name of a `PX4P_ERR_*` code (`"PX4P_ERR_FULL"`), or `"PX4P_OK"` for 0 and above;
/// NUL-terminated, static.
#[no_mangle]
pub extern "C" fn px4p_error_name(code: i32) -> *const c_char {
    let name: &'static [u8] = match code {
        0.. => b"PX4P_OK\0",
        PX4P_ERR_ARGUMENT => b"PX4P_ERR_ARGUMENT\0",
        PX4P_ERR_TABLES => b"PX4P_ERR_TABLES\0",
        PX4P_ERR_NO_SUCH_PARAM => b"PX4P_ERR_NO_SUCH_PARAM\0",
        PX4P_ERR_INSTANCE_RANGE => b"PX4P_ERR_INSTANCE_RANGE\0",
        PX4P_ERR_NOT_PRESENT => b"PX4P_ERR_NOT_PRESENT\0",
        PX4P_ERR_ALREADY_PRESENT => b"PX4P_ERR_ALREADY_PRESENT\0",
        PX4P_ERR_FULL => b"PX4P_ERR_FULL\0",
        PX4P_ERR_SHARED => b"PX4P_ERR_SHARED\0",
        PX4P_ERR_VALUE => b"PX4P_ERR_VALUE\0",
        PX4P_ERR_NO_SUCH_LEAF => b"PX4P_ERR_NO_SUCH_LEAF\0",
        PX4P_ERR_VERSION_LEAF => b"PX4P_ERR_VERSION_LEAF\0",
        PX4P_ERR_VERSION => b"PX4P_ERR_VERSION\0",
        PX4P_ERR_BUFFER => b"PX4P_ERR_BUFFER\0",
        PX4P_ERR_FILE => b"PX4P_ERR_FILE\0",
        PX4P_ERR_FILE_PARAM => b"PX4P_ERR_FILE_PARAM\0",
        PX4P_ERR_FILE_FORMAT_1 => b"PX4P_ERR_FILE_FORMAT_1\0",
        PX4P_ERR_END => b"PX4P_ERR_END\0",
        _ => b"PX4P_ERR_UNKNOWN\0",
    };
    name.as_ptr().cast()
}

fn which(default: u8) -> Which {
    match default {
        0 => Which::Value,
        _ => Which::Default,
    }
}

fn clamp(n: usize) -> i32 {
    i32::try_from(n).unwrap_or(i32::MAX)
}

unsafe fn bytes_in<'a>(data: *const u8, len: usize) -> Option<&'a [u8]> {
    match (data.is_null(), len) {
        (_, 0) => Some(&[]),
        (true, _) => None,
        (false, n) => Some(slice::from_raw_parts(data, n)),
    }
}

unsafe fn bytes_in_mut<'a>(data: *mut u8, len: usize) -> Option<&'a mut [u8]> {
    match (data.is_null(), len) {
        (_, 0) => Some(&mut []),
        (true, _) => None,
        (false, n) => Some(slice::from_raw_parts_mut(data, n)),
    }
}

fn value_of(scalar: Scalar) -> px4p_value {
    let mut v = px4p_value {
        kind: 0,
        u: 0,
        i: 0,
        f: 0.0,
    };
    match scalar {
        Scalar::Uint(u) => (v.kind, v.u) = (PX4P_VALUE_UINT, u),
        Scalar::Int(i) => (v.kind, v.i) = (PX4P_VALUE_INT, i),
        Scalar::Float(f) => (v.kind, v.f) = (PX4P_VALUE_FLOAT, f),
        Scalar::Bool(b) => (v.kind, v.u) = (PX4P_VALUE_BOOL, u64::from(b)),
    }
    v
}

fn scalar_of(v: &px4p_value) -> Option<Scalar> {
    Some(match v.kind {
        PX4P_VALUE_UINT => Scalar::Uint(v.u),
        PX4P_VALUE_INT => Scalar::Int(v.i),
        PX4P_VALUE_FLOAT => Scalar::Float(v.f),
        PX4P_VALUE_BOOL => Scalar::Bool(v.u != 0),
        _ => return None,
    })
}
