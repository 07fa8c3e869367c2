//! `DataType.encode`, `decode` and `decode_struct` as CPython's own fast-call methods.
//!
//! A call with the value alone (`t.encode(value)`, `t.decode(data)`), by far the most common,
//! goes straight to the codec: pyo3's argument parsing and call wrapper cost about a tenth of
//! a small message's call. Any other call (keywords, a wrong number of arguments) is passed
//! to the pyo3 method it replaces, which parses it and words its errors as before. Errors and
//! panics are handled as pyo3 handles them: an exception, never an abort. One difference: the
//! fast path does not raise pyo3's own count of attached calls, so a `Py` dropped inside it
//! (none is, on the paths measured) would be released at pyo3's next call rather than at once.

use std::ffi::{CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr;

use pyo3::ffi;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyBytes, PyDict, PyTuple, PyType};

use crate::DataType;

/// The pyo3 methods replaced, for the calls the fast path does not take.
static ENCODE: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
static DECODE: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
static DECODE_STRUCT: PyOnceLock<Py<PyAny>> = PyOnceLock::new();

/// Replaces `encode`, `decode` and `decode_struct` of `DataType` (the class `ty`) with
/// fast-call methods.
pub(crate) fn install(ty: &Bound<'_, PyType>) -> PyResult<()> {
    replace(ty, c"encode", encode, &ENCODE)?;
    replace(ty, c"decode", decode::<false>, &DECODE)?;
    replace(ty, c"decode_struct", decode::<true>, &DECODE_STRUCT)
}

fn replace(
    ty: &Bound<'_, PyType>,
    name: &'static CStr,
    method: ffi::PyCFunctionFastWithKeywords,
    full: &'static PyOnceLock<Py<PyAny>>,
) -> PyResult<()> {
    let py = ty.py();
    let name_str = name.to_str().expect("an ASCII method name");
    let original = ty.getattr(name_str)?;
    // The docstring as CPython reads it: the signature line first, for `inspect.signature`.
    let signature: String = original.getattr("__text_signature__")?.extract()?;
    let doc: String = original.getattr("__doc__")?.extract()?;
    let doc = CString::new(format!("{name_str}{signature}\n--\n\n{doc}"))?;
    // Method definitions must outlive the class: made once per interpreter, kept for good.
    let def = Box::leak(Box::new(ffi::PyMethodDef {
        ml_name: name.as_ptr(),
        ml_meth: ffi::PyMethodDefPointer {
            PyCFunctionFastWithKeywords: method,
        },
        ml_flags: ffi::METH_FASTCALL | ffi::METH_KEYWORDS,
        ml_doc: doc.into_raw().cast_const(),
    }));
    // SAFETY: `ty` is a live type object and `def` is never freed.
    let descriptor =
        unsafe { Bound::from_owned_ptr_or_err(py, ffi::PyDescr_NewMethod(ty.as_type_ptr(), def))? };
    let _ = full.set(py, original.unbind());
    ty.setattr(name_str, descriptor)
}

unsafe extern "C" fn encode(
    slf: *mut ffi::PyObject,
    args: *const *mut ffi::PyObject,
    nargs: ffi::Py_ssize_t,
    kwnames: *mut ffi::PyObject,
) -> *mut ffi::PyObject {
    // SAFETY: called by CPython as a METH_FASTCALL | METH_KEYWORDS method of `DataType`.
    unsafe {
        fast_call(slf, args, nargs, kwnames, &ENCODE, |t, value| {
            t.with_out(|out| t.encode_into(value, out, true, false))
                .map(Bound::into_any)
        })
    }
}

/// `decode`, or `decode_struct` when `STRUCT`.
unsafe extern "C" fn decode<const STRUCT: bool>(
    slf: *mut ffi::PyObject,
    args: *const *mut ffi::PyObject,
    nargs: ffi::Py_ssize_t,
    kwnames: *mut ffi::PyObject,
) -> *mut ffi::PyObject {
    let full = if STRUCT { &DECODE_STRUCT } else { &DECODE };
    // SAFETY: as for `encode`.
    unsafe {
        fast_call(slf, args, nargs, kwnames, full, |t, data| {
            let py = data.py();
            let decode = |bytes: &[u8]| match STRUCT {
                true => t.decode_struct_bytes(py, bytes, true, false),
                false => t.decode_bytes(py, bytes, true, false),
            };
            // `bytes` itself is read in place, with no new reference.
            if let Ok(bytes) = data.cast_exact::<PyBytes>() {
                return decode(bytes.as_bytes());
            }
            decode(crate::bytes_of(data)?.as_bytes())
        })
    }
}

/// Runs `call` on the one positional argument, or passes the call on to `full`.
///
/// # Safety
/// As for a METH_FASTCALL | METH_KEYWORDS method of `DataType`: called by CPython with the
/// thread attached, `slf` an instance, `args` holding `nargs` arguments and then one per
/// name in `kwnames` (a tuple, or null).
unsafe fn fast_call(
    slf: *mut ffi::PyObject,
    args: *const *mut ffi::PyObject,
    nargs: ffi::Py_ssize_t,
    kwnames: *mut ffi::PyObject,
    full: &PyOnceLock<Py<PyAny>>,
    call: impl for<'py> FnOnce(&DataType, &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>>,
) -> *mut ffi::PyObject {
    // SAFETY: CPython calls methods with the thread attached.
    let py = unsafe { Python::assume_attached() };
    let result = catch_unwind(AssertUnwindSafe(|| {
        if nargs != 1 || !kwnames.is_null() {
            // SAFETY: the caller's arguments, passed on as they came.
            return unsafe { pass_on(py, full, slf, args, nargs, kwnames) };
        }
        // SAFETY: live objects borrowed from the caller for the call.
        let (slf, value) = unsafe {
            (
                Bound::from_borrowed_ptr(py, slf),
                Bound::from_borrowed_ptr(py, *args),
            )
        };
        // SAFETY: CPython calls a method descriptor only on instances of its class (it raised
        // `TypeError` for anything else).
        let t = unsafe { slf.cast_unchecked::<DataType>() };
        call(t.get(), &value).map(Bound::into_ptr)
    }));
    let err = match result {
        Ok(Ok(object)) => return object,
        Ok(Err(err)) => err,
        Err(payload) => crate::errors::panic(payload),
    };
    err.restore(py);
    ptr::null_mut()
}

/// Calls the pyo3 method with `slf` and the caller's arguments.
///
/// # Safety
/// As for [`fast_call`].
unsafe fn pass_on(
    py: Python<'_>,
    full: &PyOnceLock<Py<PyAny>>,
    slf: *mut ffi::PyObject,
    args: *const *mut ffi::PyObject,
    nargs: ffi::Py_ssize_t,
    kwnames: *mut ffi::PyObject,
) -> PyResult<*mut ffi::PyObject> {
    let method = full.get(py).ok_or_else(crate::errors::not_installed)?;
    // SAFETY: live objects, borrowed from the caller for the call.
    let borrowed = |p: *mut ffi::PyObject| unsafe { Bound::from_borrowed_ptr(py, p) };
    let names = (!kwnames.is_null()).then(|| borrowed(kwnames));
    let keywords = match &names {
        Some(names) => names.cast::<PyTuple>()?.len(),
        None => 0,
    };
    let nargs = nargs as usize;
    // SAFETY: `args` holds the positional and then the keyword arguments.
    let given = unsafe { std::slice::from_raw_parts(args, nargs + keywords) };
    let mut positional = vec![borrowed(slf)];
    positional.extend(given[..nargs].iter().map(|&p| borrowed(p)));
    let positional = PyTuple::new(py, positional)?;
    let kwargs = match &names {
        Some(names) => {
            let kwargs = PyDict::new(py);
            for (name, &value) in names.cast::<PyTuple>()?.iter().zip(&given[nargs..]) {
                kwargs.set_item(name, borrowed(value))?;
            }
            Some(kwargs)
        }
        None => None,
    };
    method
        .bind(py)
        .call(positional, kwargs.as_ref())
        .map(Bound::into_ptr)
}
