//! The store file, read and written by the core (`px4params_core::file`): the same bytes as
//! firmware reads and writes through the C ABI. Python keeps the file system side (atomic
//! replace, backups, locking) and version translation.

use px4params_core::file::{self, ClassicType, FileName, Key, SaveError, WriteError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList, PyString};

use crate::errors;
use crate::store::CoreStore;

/// A checked record: `(offset, kind, key, instance, default, value, raw, classic type)`.
type RecordTuple<'py> = (
    usize,
    u8,
    Bound<'py, PyAny>,
    u16,
    Option<Bound<'py, PyBytes>>,
    Option<Bound<'py, PyBytes>>,
    Bound<'py, PyBytes>,
    u8,
);

/// A classic parameter's type as a number, as the C ABI's `px4p_param.classic` says it: 1
/// int32, 2 float32 (0 for a record that does not say, or a structured parameter).
fn classic_code(ty: Option<ClassicType>) -> u8 {
    match ty {
        None => 0,
        Some(ClassicType::Int32) => 1,
        Some(ClassicType::Float32) => 2,
    }
}

/// A checked file: `(version, fingerprint, table lines or None, records)`.
type CheckedTuple<'py> = (u8, u32, Option<Vec<String>>, Bound<'py, PyList>);

/// Checks a whole store file; returns `(version, fingerprint, table lines or None, records)`
/// or raises `StoreFileError(message, where, offset)`.
#[pyfunction]
pub fn check_store_file<'py>(
    py: Python<'py>,
    data: &[u8],
    r#where: &Bound<'py, PyString>,
) -> PyResult<CheckedTuple<'py>> {
    let checked = file::check(data).map_err(|e| errors::store_file(e, r#where))?;
    let table = checked
        .has_table()
        .then(|| checked.table().map(str::to_owned).collect());
    let records = PyList::empty(py);
    let bytes = |b: &[u8]| PyBytes::new(py, b);
    for r in checked.records() {
        let (kind, key, ty) = match r.key {
            Key::Structured(index) => (
                file::KIND_STRUCTURED,
                index.into_pyobject(py)?.into_any(),
                None,
            ),
            // (The core checked the name: upper-case ASCII letters, digits and '_'.)
            Key::Classic(name, ty) => (
                file::KIND_CLASSIC,
                PyString::new(py, &String::from_utf8_lossy(name)).into_any(),
                ty,
            ),
        };
        let record: RecordTuple<'py> = (
            r.offset,
            kind,
            key,
            r.instance,
            r.default.map(bytes),
            r.value.map(bytes),
            bytes(r.raw),
            classic_code(ty),
        );
        records.append(record)?;
    }
    Ok((checked.version, checked.fingerprint, table, records))
}

/// The store's file (see `Store.file_bytes`).
pub(crate) fn store_file_bytes(
    store: &CoreStore,
    names: &[(String, u8)],
    order: &[u32],
    foreign: &[Vec<u8>],
) -> PyResult<Vec<u8>> {
    let names: Vec<FileName<'_>> = names
        .iter()
        .map(|(name, classic)| match classic {
            0 => FileName::Structured(name),
            1 => FileName::Classic(name, ClassicType::Int32),
            _ => FileName::Classic(name, ClassicType::Float32),
        })
        .collect();
    let mut buf = vec![0u8; 4096];
    loop {
        let foreign = foreign.iter().map(Vec::as_slice);
        match file::write_store(store, names.as_slice(), order, foreign, &mut buf) {
            Ok(len) => {
                buf.truncate(len);
                return Ok(buf);
            }
            Err(SaveError::Write(WriteError::BufferFull { needed })) => {
                buf.resize(needed.max(buf.len() * 2), 0);
            }
            Err(e) => return Err(errors::save(e)),
        }
    }
}
