//! Python objects for the core's value programs ([`px4params_core::program`]), which encode and
//! decode every type: plain values read for encoding ([`PyValues`]: exact dicts, lists, tuples,
//! ints, floats, bools, bytes and str; a union a one-key dict) and dicts or struct values built
//! by decoding ([`Built`]). Conversion only: the programs hold the DroneCAN rules.
//!
//! Whatever a program's source does not take exactly as the general path ([`crate::values`])
//! would (a subclass, an integer beyond 64 bits, a look-up that raised) makes it decline; the
//! general path then encodes the value or words the error.

use std::marker::PhantomData;
use std::sync::atomic::{AtomicU32, AtomicUsize, Ordering};
use std::sync::Arc;

use px4params_core::layout::{Kind, NodeId};
use px4params_core::program::{ValueSink, ValueSource};
use px4params_core::Scalar;
use pyo3::ffi;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString, PyTuple};

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

/// Builds the Python value a program decodes: structs as `F` (dicts or struct values), unions
/// as one-key dicts, arrays as lists, primitives as int, float and bool.
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
    type Items = Bound<'py, PyList>;
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

    fn union(&mut self, _: NodeId, field: u32, value: Bound<'py, PyAny>) -> PyResult<Self::Value> {
        let dict = PyDict::new(self.py);
        dict.set_item(self.compiled.names[field as usize].bind(self.py), value)?;
        Ok(dict.into_any())
    }

    #[inline(always)]
    fn scalar(&mut self, value: Scalar) -> PyResult<Bound<'py, PyAny>> {
        scalar_to_py(self.py, value)
    }

    fn begin_items(&mut self, _len: usize) -> PyResult<Bound<'py, PyList>> {
        // Appended to: a tail array's length is known when it ends.
        Ok(PyList::empty(self.py))
    }

    fn push(&mut self, items: &mut Bound<'py, PyList>, value: Bound<'py, PyAny>) -> PyResult<()> {
        items.append(value)
    }

    fn end_items(&mut self, items: Bound<'py, PyList>) -> PyResult<Bound<'py, PyAny>> {
        Ok(items.into_any())
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

    fn union(
        &mut self,
        item: *mut ffi::PyObject,
        first: u32,
        count: u32,
    ) -> Option<(u32, *mut ffi::PyObject)> {
        // SAFETY: a live item of a held container, held from here on (its one entry is
        // borrowed from it, and no Python code runs while it is read).
        let held = unsafe { Bound::from_borrowed_ptr(self.py, item) };
        let dict = held.cast_exact::<PyDict>().ok()?;
        if dict.len() != 1 {
            return None;
        }
        let (mut pos, mut key, mut value) = (0, std::ptr::null_mut(), std::ptr::null_mut());
        // SAFETY: a live dict of one entry, read once.
        if unsafe { ffi::PyDict_Next(dict.as_ptr(), &mut pos, &mut key, &mut value) } == 0 {
            return None;
        }
        // SAFETY: `key` is a live object; exact str keys compare without running Python code.
        if unsafe { ffi::PyUnicode_CheckExact(key) } == 0 {
            return None;
        }
        let names = &self.names[first as usize..(first + count) as usize];
        let variant = names.iter().position(|name| {
            // SAFETY: both are live exact str objects.
            name.as_ptr() == key || unsafe { ffi::PyUnicode_Compare(name.as_ptr(), key) } == 0
        })?;
        Some((variant as u32, value))
    }

    fn begin_items(&mut self, item: *mut ffi::PyObject) -> Option<(PyArray<'py>, usize)> {
        // SAFETY: a live item of a held container, held from here on.
        let held = unsafe { Bound::from_borrowed_ptr(self.py, item) };
        let list = held.is_exact_instance_of::<PyList>();
        if !list && !held.is_exact_instance_of::<PyTuple>() {
            return None;
        }
        let n = held.len().ok()?;
        Some((PyArray::Seq { seq: held, list }, n))
    }

    #[inline(always)]
    fn item(&mut self, array: &PyArray<'py>, index: usize) -> Option<*mut ffi::PyObject> {
        match array {
            PyArray::Seq { seq, list } => item_at(seq.as_ptr(), *list, index as ffi::Py_ssize_t),
            _ => None,
        }
    }
}

/// Item `i` of `seq`, an exact list (`list`) or tuple that the caller holds, borrowed; `None`
/// when out of range (the list shrank), with an error set that the caller clears.
#[inline(always)]
fn item_at(seq: *mut ffi::PyObject, list: bool, i: ffi::Py_ssize_t) -> Option<*mut ffi::PyObject> {
    // SAFETY: `seq` is a live exact list or tuple (checked by the caller).
    let item = unsafe {
        if list {
            ffi::PyList_GetItem(seq, i)
        } else {
            ffi::PyTuple_GetItem(seq, i)
        }
    };
    (!item.is_null()).then_some(item)
}

/// A struct's dict read in field order: the entries are taken in the dict's own order while it
/// matches the fields' (as for values written in source code, or decoded), by the key's
/// identity with the field's interned name; any other key is looked up.
pub(crate) struct Entries<'py> {
    dict: Bound<'py, PyDict>,
    pos: ffi::Py_ssize_t,
    next: Option<(*mut ffi::PyObject, *mut ffi::PyObject)>,
}

impl<'py> Entries<'py> {
    /// The entries of `dict`, which they hold.
    fn new(dict: Bound<'py, PyDict>) -> Self {
        let mut entries = Self {
            dict,
            pos: 0,
            next: None,
        };
        entries.advance();
        entries
    }

    #[inline(always)]
    fn advance(&mut self) {
        let (mut key, mut value) = (std::ptr::null_mut(), std::ptr::null_mut());
        // SAFETY: the dict is alive (held); `pos` is only ever advanced by this call.
        let more =
            unsafe { ffi::PyDict_Next(self.dict.as_ptr(), &mut self.pos, &mut key, &mut value) };
        self.next = (more != 0).then_some((key, value));
    }

    /// The value of the field named `name`, borrowed from the dict: null when absent, `None`
    /// when the look-up raised.
    #[inline(always)]
    fn get(&mut self, name: &Py<PyString>) -> Option<*mut ffi::PyObject> {
        if let Some((key, value)) = self.next {
            if key == name.as_ptr() {
                self.advance();
                return Some(value);
            }
        }
        self.look_up(name)
    }

    /// How many entries the dict has.
    fn len(&self) -> usize {
        self.dict.len()
    }

    /// A key out of the fields' order, or not the interned name: looked up.
    #[inline(never)]
    fn look_up(&mut self, name: &Py<PyString>) -> Option<*mut ffi::PyObject> {
        // SAFETY: both objects are alive; a borrowed result or null (raised or absent).
        let value = unsafe { ffi::PyDict_GetItemWithError(self.dict.as_ptr(), name.as_ptr()) };
        // SAFETY: called with the GIL held.
        if value.is_null() && unsafe { !ffi::PyErr_Occurred().is_null() } {
            return None;
        }
        Some(value)
    }
}

/// A primitive as the general path reads it, for the exact built-in types only.
#[inline(always)]
fn plain_scalar(kind: Kind, obj: *mut ffi::PyObject) -> Option<Scalar> {
    // SAFETY (all calls): `obj` is a live object, checked for its exact type before each
    // call that expects one; failures are reported (and left for the caller to clear).
    unsafe {
        match kind {
            Kind::Uint { .. } | Kind::Int { .. } => integer(obj),
            Kind::Float { .. } => {
                if ffi::PyFloat_CheckExact(obj) != 0 {
                    Some(Scalar::Float(ffi::PyFloat_AsDouble(obj)))
                } else if ffi::PyLong_CheckExact(obj) != 0 {
                    let v = ffi::PyLong_AsDouble(obj);
                    (v != -1.0 || ffi::PyErr_Occurred().is_null()).then_some(Scalar::Float(v))
                } else {
                    None
                }
            }
            _ => {
                if obj == ffi::Py_True() || obj == ffi::Py_False() {
                    Some(Scalar::Bool(obj == ffi::Py_True()))
                } else {
                    match integer(obj)? {
                        Scalar::Uint(v @ (0 | 1)) => Some(Scalar::Bool(v == 1)),
                        _ => None,
                    }
                }
            }
        }
    }
}

/// Where CPython's ints 0 to 255 are: each is one object (every `0` is the same object),
/// and they lie one after the other, `1 << SMALL_SHIFT` bytes apart, from `SMALL_BASE` (0:
/// not laid out so; every int is then read by a call). Found by [`find_small_ints`].
static SMALL_BASE: AtomicUsize = AtomicUsize::new(0);
static SMALL_SHIFT: AtomicU32 = AtomicU32::new(0);

/// Finds CPython's small ints ([`SMALL_BASE`]), checking every one of them, once.
pub(crate) fn find_small_ints(_py: Python<'_>) {
    // SAFETY: attached to the interpreter (`_py`); each result is a new reference (or null),
    // given back at once: a small int lives as long as the interpreter.
    let at = |v: std::ffi::c_long| unsafe {
        let int = ffi::PyLong_FromLong(v);
        if int.is_null() {
            ffi::PyErr_Clear();
            return 0;
        }
        ffi::Py_DECREF(int);
        int as usize
    };
    let base = at(0);
    let stride = at(1).wrapping_sub(base);
    let laid_out = base != 0
        && stride.is_power_of_two()
        && (0..256).all(|v| at(v) == base + v as usize * stride);
    if laid_out {
        SMALL_SHIFT.store(stride.trailing_zeros(), Ordering::Relaxed);
        SMALL_BASE.store(base, Ordering::Relaxed);
    }
}

/// The number `obj` is when it is one of CPython's ints 0 to 255, told by its address alone.
#[inline(always)]
fn small_int(obj: *mut ffi::PyObject) -> Option<u64> {
    let base = SMALL_BASE.load(Ordering::Relaxed);
    let shift = SMALL_SHIFT.load(Ordering::Relaxed);
    let offset = (obj as usize).wrapping_sub(base);
    let at_one = offset & ((1 << shift) - 1) == 0 && offset >> shift < 256;
    (base != 0 && at_one).then_some((offset >> shift) as u64)
}

/// CPython's own object for `v` when it is 0 to 255 (a new reference, made with no call).
#[inline(always)]
pub(crate) fn small_int_object(py: Python<'_>, v: u64) -> Option<Bound<'_, PyAny>> {
    let base = SMALL_BASE.load(Ordering::Relaxed);
    if base == 0 || v >= 256 {
        return None;
    }
    let int = base + ((v as usize) << SMALL_SHIFT.load(Ordering::Relaxed));
    // SAFETY: the small int `v` (checked by `find_small_ints`), alive as long as the
    // interpreter: a new reference to it.
    Some(unsafe { Bound::from_borrowed_ptr(py, int as *mut ffi::PyObject) })
}

/// An exact int of up to 64 bits: `Uint` when not negative (the core's fast case), else `Int`.
///
/// SAFETY: `obj` is a live object.
#[inline]
unsafe fn integer(obj: *mut ffi::PyObject) -> Option<Scalar> {
    if let Some(v) = small_int(obj) {
        return Some(Scalar::Uint(v));
    }
    if ffi::PyLong_CheckExact(obj) == 0 {
        return None;
    }
    let mut overflow = 0;
    let v = ffi::PyLong_AsLongLongAndOverflow(obj, &mut overflow);
    match overflow {
        0 if v >= 0 => Some(Scalar::Uint(v as u64)),
        0 => Some(Scalar::Int(v)),
        // Beyond i64: u64 may still hold it.
        _ => {
            let v = ffi::PyLong_AsUnsignedLongLong(obj);
            (v != u64::MAX || ffi::PyErr_Occurred().is_null()).then_some(Scalar::Uint(v))
        }
    }
}
