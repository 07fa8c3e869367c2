//! Batch calls (`DataType.encode_many` / `decode_many`): one call runs a type's encode or
//! decode over many items, so that the cost of a Python call (argument parsing, the result
//! buffer, about a third of a small message's time) is paid once per batch.
//!
//! A batch is all or nothing: the first item that fails raises what the single call raises,
//! told which item it was (`item N:` and an `index` attribute on px4params' own errors, a
//! note on anything else).

use pyo3::ffi;
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};

use crate::errors::at_item;

/// `each` of every item of `items` (any iterable), as a new list.
pub(crate) fn map_items<'py>(
    items: &Bound<'py, PyAny>,
    mut each: impl FnMut(&Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let py = items.py();
    // A list is read from a snapshot: encoding may run Python code (a key's `__eq__`) that
    // changes it.
    let snapshot;
    let tuple = if let Ok(tuple) = items.cast_exact::<PyTuple>() {
        tuple
    } else if let Ok(list) = items.cast_exact::<PyList>() {
        snapshot = list.to_tuple();
        &snapshot
    } else {
        let mut out = Vec::new();
        for (i, item) in items.try_iter()?.enumerate() {
            out.push(each(&item?).map_err(|e| at_item(py, e, i))?);
        }
        return PyList::new(py, out);
    };
    let n = tuple.len();
    // SAFETY: a new list of `n` empty slots, each filled below before the list is returned
    // (a list dropped half-filled frees only what it holds).
    let list = unsafe {
        Bound::from_owned_ptr_or_err(py, ffi::PyList_New(n as ffi::Py_ssize_t))?
            .cast_into_unchecked::<PyList>()
    };
    for (i, item) in tuple.iter().enumerate() {
        let value = each(&item).map_err(|e| at_item(py, e, i))?;
        // SAFETY: `i` is within the list; the slot is empty and takes the reference.
        unsafe { ffi::PyList_SetItem(list.as_ptr(), i as ffi::Py_ssize_t, value.into_ptr()) };
    }
    Ok(list)
}
