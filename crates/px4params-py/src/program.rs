//! Python objects for the core's value programs ([`px4params_core::program`]): plain values
//! read for encoding ([`PyValues`]: exact dicts, lists, tuples, ints, floats, bools, bytes and
//! str) and dicts or struct values built by decoding ([`Built`]).
//!
//! Whatever a program's source does not take exactly as the general path ([`crate::values`])
//! would (a subclass, an integer beyond 64 bits, a look-up that raised) makes it decline; the
//! general path then encodes the value or words the error.

use std::marker::PhantomData;
use std::sync::Arc;

use px4params_core::layout::{Kind, NodeId};
use px4params_core::program::{ValueSink, ValueSource};
use px4params_core::Scalar;
use pyo3::ffi;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString, PyTuple};

use crate::plain::{item_at, scalar as plain_scalar, Entries};
use crate::structs::StructValue;
use crate::values::scalar_to_py;
use crate::Compiled;

/// What decoding makes of each struct: a dict (`decode`) or a struct value (`decode_struct`).
pub(crate) trait Form<'py>: Sized {
    /// An empty value of struct `node`.
    fn begin(py: Python<'py>, compiled: &Arc<Compiled>, node: NodeId) -> PyResult<Self>;
    /// Adds field `name` (its index in the layout), the fields coming in order.
    fn put(
        &mut self,
        py: Python<'py>,
        compiled: &Arc<Compiled>,
        name: u32,
        item: Bound<'py, PyAny>,
    ) -> PyResult<()>;
    /// The value, every field added.
    fn end(
        self,
        py: Python<'py>,
        compiled: &Arc<Compiled>,
        node: NodeId,
    ) -> PyResult<Bound<'py, PyAny>>;
}

impl<'py> Form<'py> for Bound<'py, PyDict> {
    #[inline(always)]
    fn begin(py: Python<'py>, compiled: &Arc<Compiled>, node: NodeId) -> PyResult<Self> {
        compiled.new_dict(py, node)
    }

    #[inline(always)]
    fn put(
        &mut self,
        py: Python<'py>,
        compiled: &Arc<Compiled>,
        name: u32,
        item: Bound<'py, PyAny>,
    ) -> PyResult<()> {
        self.set_item(compiled.names[name as usize].bind(py), item)
    }

    fn end(self, _: Python<'py>, _: &Arc<Compiled>, _: NodeId) -> PyResult<Bound<'py, PyAny>> {
        Ok(self.into_any())
    }
}

/// A struct value's field values, filled in order.
pub(crate) struct Fields<'py> {
    values: Bound<'py, PyTuple>,
    filled: usize,
}

impl<'py> Form<'py> for Fields<'py> {
    #[inline(always)]
    fn begin(py: Python<'py>, compiled: &Arc<Compiled>, node: NodeId) -> PyResult<Self> {
        let count = compiled.named_count(node) as ffi::Py_ssize_t;
        // SAFETY: a new tuple of empty slots, each filled below before the tuple is shared
        // (one dropped half-filled frees only what it holds).
        let values = unsafe {
            Bound::from_owned_ptr_or_err(py, ffi::PyTuple_New(count))?.cast_into_unchecked()
        };
        Ok(Self { values, filled: 0 })
    }

    #[inline(always)]
    fn put(
        &mut self,
        _: Python<'py>,
        _: &Arc<Compiled>,
        _: u32,
        item: Bound<'py, PyAny>,
    ) -> PyResult<()> {
        // SAFETY: the program has one item per named field, the tuple's length; the slot is
        // empty and takes the reference.
        let status = unsafe {
            ffi::PyTuple_SetItem(
                self.values.as_ptr(),
                self.filled as ffi::Py_ssize_t,
                item.into_ptr(),
            )
        };
        self.filled += 1;
        if status == 0 {
            Ok(())
        } else {
            Err(PyErr::fetch(self.values.py()))
        }
    }

    fn end(
        self,
        py: Python<'py>,
        compiled: &Arc<Compiled>,
        node: NodeId,
    ) -> PyResult<Bound<'py, PyAny>> {
        let value = StructValue::new(compiled, node, self.values.unbind());
        Ok(Bound::new(py, value)?.into_any())
    }
}

/// Builds the Python value a program decodes: structs as `F` (dicts or struct values), arrays
/// as lists, primitives as int, float and bool.
pub(crate) struct Built<'py, 'c, F> {
    py: Python<'py>,
    compiled: &'c Arc<Compiled>,
    form: PhantomData<F>,
}

impl<'py, 'c, F> Built<'py, 'c, F> {
    pub(crate) fn new(py: Python<'py>, compiled: &'c Arc<Compiled>) -> Self {
        Self {
            py,
            compiled,
            form: PhantomData,
        }
    }
}

impl<'py, F: Form<'py>> ValueSink for Built<'py, '_, F> {
    type Value = Bound<'py, PyAny>;
    type Struct = F;
    type Error = PyErr;

    #[inline(always)]
    fn begin_struct(&mut self, node: NodeId) -> PyResult<F> {
        F::begin(self.py, self.compiled, node)
    }

    #[inline(always)]
    fn put(&mut self, fields: &mut F, field: u32, value: Bound<'py, PyAny>) -> PyResult<()> {
        fields.put(self.py, self.compiled, field, value)
    }

    #[inline(always)]
    fn end_struct(&mut self, fields: F, node: NodeId) -> PyResult<Bound<'py, PyAny>> {
        fields.end(self.py, self.compiled, node)
    }

    #[inline(always)]
    fn scalar(&mut self, value: Scalar) -> PyResult<Bound<'py, PyAny>> {
        scalar_to_py(self.py, value)
    }

    fn list(
        &mut self,
        len: usize,
        items: impl Iterator<Item = Scalar>,
    ) -> PyResult<Bound<'py, PyAny>> {
        // SAFETY: a new list of `len` empty slots, each filled below before it is read (a
        // list dropped half-filled frees only what it holds).
        let list = unsafe {
            Bound::from_owned_ptr_or_err(self.py, ffi::PyList_New(len as ffi::Py_ssize_t))?
        };
        for (i, value) in items.take(len).enumerate() {
            let item = scalar_to_py(self.py, value)?;
            // SAFETY: `i` is within the list; the slot is empty and takes the reference.
            unsafe { ffi::PyList_SetItem(list.as_ptr(), i as ffi::Py_ssize_t, item.into_ptr()) };
        }
        Ok(list)
    }
}

/// Plain Python values read for a program. Containers are held (`Bound`) while they are read;
/// their items are borrowed pointers, read at once, with no Python code run in between.
pub(crate) struct PyValues<'py, 'n> {
    py: Python<'py>,
    /// Every field name of the layout as an interned Python string, by field index.
    names: &'n [Py<PyString>],
}

impl<'py, 'n> PyValues<'py, 'n> {
    pub(crate) fn new(py: Python<'py>, names: &'n [Py<PyString>]) -> Self {
        Self { py, names }
    }
}

/// An array being read: an exact list or tuple, or the bytes of an exact bytes or str.
pub(crate) enum PyArray<'py> {
    Seq { seq: Bound<'py, PyAny>, list: bool },
    Bytes(Bound<'py, PyBytes>),
    Str(Bound<'py, PyString>),
}

impl PyArray<'_> {
    /// The bytes of a bytes or str array.
    fn bytes(&self) -> Option<&[u8]> {
        match self {
            PyArray::Bytes(b) => Some(b.as_bytes()),
            PyArray::Str(s) => s.to_str().ok().map(str::as_bytes),
            PyArray::Seq { .. } => None,
        }
    }
}

impl<'py> ValueSource for PyValues<'py, '_> {
    type Item = *mut ffi::PyObject;
    type Struct = Entries<'py>;
    type Array = PyArray<'py>;

    #[inline]
    fn begin_struct(&mut self, item: *mut ffi::PyObject) -> Option<Entries<'py>> {
        // SAFETY: a live object (the root, or an item of a held container), held from here on.
        let held = unsafe { Bound::from_borrowed_ptr(self.py, item) };
        Some(Entries::new(held.cast_into_exact::<PyDict>().ok()?))
    }

    #[inline(always)]
    fn field(&mut self, fields: &mut Entries<'py>, field: u32) -> Option<Option<Self::Item>> {
        let item = fields.get(&self.names[field as usize])?;
        Some((!item.is_null()).then_some(item))
    }

    #[inline]
    fn end_struct(&mut self, fields: Entries<'py>, used: usize) -> Option<()> {
        // More keys than fields: an unknown one.
        (fields.len() == used).then_some(())
    }

    #[inline(always)]
    fn scalar(&mut self, item: *mut ffi::PyObject, kind: Kind) -> Option<Scalar> {
        plain_scalar(kind, item)
    }

    fn begin_array(
        &mut self,
        item: *mut ffi::PyObject,
        elem: Kind,
    ) -> Option<(PyArray<'py>, usize)> {
        // SAFETY: a live item of a held container, held from here on.
        let held = unsafe { Bound::from_borrowed_ptr(self.py, item) };
        let list = held.is_exact_instance_of::<PyList>();
        if list || held.is_exact_instance_of::<PyTuple>() {
            let n = held.len().ok()?;
            return Some((PyArray::Seq { seq: held, list }, n));
        }
        // Byte strings, for integer elements only.
        if !matches!(elem, Kind::Uint { .. } | Kind::Int { .. }) {
            return None;
        }
        let array = match held.cast_into_exact::<PyBytes>() {
            Ok(bytes) => PyArray::Bytes(bytes),
            Err(e) => PyArray::Str(e.into_inner().cast_into_exact::<PyString>().ok()?),
        };
        let n = array.bytes()?.len();
        Some((array, n))
    }

    #[inline(always)]
    fn element(&mut self, array: &PyArray<'py>, index: usize, elem: Kind) -> Option<Scalar> {
        match array {
            PyArray::Seq { seq, list } => plain_scalar(
                elem,
                item_at(seq.as_ptr(), *list, index as ffi::Py_ssize_t)?,
            ),
            _ => Some(Scalar::Uint(array.bytes()?.get(index).copied()?.into())),
        }
    }
}
