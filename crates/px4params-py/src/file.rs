//! The store file, read and written by the core (`px4params_core::file`): the same bytes as
//! firmware reads and writes through the C ABI. Python keeps the file system side (atomic
//! replace, backups, locking) and version translation.

use px4params_core::file::{self, FileName, Key, SaveError, WriteError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList, PyString};

use crate::errors;
use crate::store::CoreStore;

/// A checked record: `(offset, kind, key, instance, default, value, raw)`.
type RecordTuple<'py> = (
    usize,
    u8,
    Bound<'py, PyAny>,
    u16,
    Option<Bound<'py, PyBytes>>,
    Option<Bound<'py, PyBytes>>,
    Bound<'py, PyBytes>,
);

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
        let (kind, key) = match r.key {
            Key::Structured(index) => (file::KIND_STRUCTURED, index.into_pyobject(py)?.into_any()),
            // Non-ASCII bytes become U+FFFD, one each (the name is only shown).
            Key::Classic(name) => {
                let text: String = name
                    .iter()
                    .map(|&b| if b.is_ascii() { b as char } else { '\u{FFFD}' })
                    .collect();
                (file::KIND_CLASSIC, text.into_pyobject(py)?.into_any())
            }
        };
        let record: RecordTuple<'py> = (
            r.offset,
            kind,
            key,
            r.instance,
            r.default.map(bytes),
            r.value.map(bytes),
            bytes(r.raw),
        );
        records.append(record)?;
    }
    Ok((checked.version, checked.fingerprint, table, records))
}

/// The store's file (see `Store.file_bytes`).
pub(crate) fn store_file_bytes(
    store: &CoreStore,
    names: &[(String, bool)],
    order: &[u32],
    foreign: &[Vec<u8>],
) -> PyResult<Vec<u8>> {
    let names: Vec<FileName<'_>> = names
        .iter()
        .map(|(name, classic)| match classic {
            true => FileName::Classic(name),
            false => FileName::Structured(name),
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
