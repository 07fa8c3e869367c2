//! The fast path of `encode` and `decode` for types without a program ([`crate::program`]: those
//! with unions or arrays of composites) and for data in pieces: plain values (dicts, lists,
//! tuples, ints, floats, bools, bytes and str of the exact built-in types) converted straight to
//! and from the core's flat leaf lists, walking the compiled layout once, so that the core's
//! flat fast paths do the bits. Programs share its readers of plain values.
//!
//! It never decides anything the general path ([`crate::values`]) would decide differently:
//! whatever it does not recognise (a subclass, a missing or unknown field, an integer beyond
//! 64 bits, a wrong length) makes it give up, and the general path then encodes the value or
//! words the error. Giving up costs only the work done so far.

use std::cell::RefCell;

use px4params_core::layout::{Kind, Layout, NodeId, Role};
use px4params_core::Scalar;
use pyo3::ffi;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString, PyTuple};

use crate::values::scalar_to_py;
use crate::Compiled;

thread_local! {
    /// The leaf list of the call in progress, kept between calls (most values fit the last
    /// one's room, and allocating is a good part of a small value's cost).
    static LEAVES: RefCell<Vec<Scalar>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` with this thread's leaf list (a new one if a call is already using it: Python
/// code run by a look-up may encode too).
pub fn with_leaves<R>(f: impl FnOnce(&mut Vec<Scalar>) -> R) -> R {
    LEAVES.with(|cell| match cell.try_borrow_mut() {
        Ok(mut leaves) => {
            let result = f(&mut leaves);
            // The room a rare big value needed is not kept.
            if leaves.capacity() > 4096 {
                *leaves = Vec::new();
            }
            result
        }
        Err(_) => f(&mut Vec::new()),
    })
}

/// A value's leaves in `[k]` order, as [`px4params_core::value::LeafSource`] reads them:
/// `None` when the value is not plain (the general path takes it; a look-up may have raised,
/// which the caller clears).
pub fn leaves_of(
    layout: &Layout<'_>,
    names: &[Py<PyString>],
    root: NodeId,
    value: &Bound<'_, PyAny>,
    leaves: &mut Vec<Scalar>,
) -> Option<()> {
    Flatten {
        py: value.py(),
        layout,
        names,
        leaves,
    }
    .node(root, value)
}

struct Flatten<'a, 'l, 'py> {
    py: Python<'py>,
    layout: &'a Layout<'l>,
    names: &'a [Py<PyString>],
    leaves: &'a mut Vec<Scalar>,
}

// Containers are held as owned references (`Bound`) while they are read; their primitive items
// are read through borrowed pointers at once, with no Python code running in between.
impl Flatten<'_, '_, '_> {
    fn node(&mut self, id: NodeId, obj: &Bound<'_, PyAny>) -> Option<()> {
        let layout = self.layout;
        match layout.node(id).kind {
            kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool) => {
                self.leaves.push(scalar(kind, obj.as_ptr())?);
            }
            Kind::Void { .. } => {}
            Kind::Struct { first, count } => {
                let dict = obj.cast_exact::<PyDict>().ok()?;
                let mut entries = Entries::new(dict.clone());
                let mut used = 0;
                for index in first..first + count {
                    let field = layout.fields[index as usize];
                    if field.role == Role::Padding {
                        continue;
                    }
                    let item = entries.get(&self.names[index as usize])?;
                    if item.is_null() {
                        // Left out, it is written with the type's version, as the walk does.
                        let Role::Version(version) = field.role else {
                            return None;
                        };
                        self.leaves.push(Scalar::Uint(version.into()));
                        continue;
                    }
                    used += 1;
                    self.item(field.node, item)?;
                }
                // More keys than fields: an unknown one, which the general path names.
                if dict.len() != used {
                    return None;
                }
            }
            Kind::Union { first, count, .. } => {
                let dict = obj.cast_exact::<PyDict>().ok()?;
                if dict.len() != 1 {
                    return None;
                }
                let (key, item) = dict.iter().next()?;
                let key = key.cast_exact::<PyString>().ok()?;
                let tag = (first..first + count).find(|&i| {
                    // Keys written in source code are the interned names themselves.
                    key.as_ptr() == self.names[i as usize].as_ptr()
                        || key.to_str().ok() == Some(layout.name(&layout.fields[i as usize]))
                })?;
                self.leaves.push(Scalar::Uint((tag - first).into()));
                self.node(layout.fields[tag as usize].node, &item)?;
            }
            Kind::Array { elem, len } => self.array(elem, obj, |n| n == len as usize, false)?,
            Kind::DynArray { elem, max, .. } => {
                self.array(elem, obj, |n| n <= max as usize, true)?
            }
        }
        Some(())
    }

    /// An item borrowed from a live container: a primitive is read at once, a container is
    /// held while it is read.
    #[inline]
    fn item(&mut self, id: NodeId, item: *mut ffi::PyObject) -> Option<()> {
        match self.layout.node(id).kind {
            kind if is_primitive(kind) => {
                self.leaves.push(scalar(kind, item)?);
                Some(())
            }
            _ => {
                // SAFETY: `item` is a borrowed reference from a container that is alive.
                let held = unsafe { Bound::from_borrowed_ptr(self.py, item) };
                self.node(id, &held)
            }
        }
    }

    fn array(
        &mut self,
        elem: NodeId,
        obj: &Bound<'_, PyAny>,
        fits: impl Fn(usize) -> bool,
        counted: bool,
    ) -> Option<()> {
        let count = |leaves: &mut Vec<Scalar>, n: usize| {
            if !fits(n) {
                return None;
            }
            if counted {
                leaves.push(Scalar::Uint(n as u64));
            }
            Some(())
        };
        let ptr = obj.as_ptr();
        if obj.is_exact_instance_of::<PyList>() || obj.is_exact_instance_of::<PyTuple>() {
            let list = obj.is_exact_instance_of::<PyList>();
            let n = obj.len().ok()?;
            count(self.leaves, n)?;
            let kind = self.layout.node(elem).kind;
            let primitive = is_primitive(kind);
            for i in 0..n as ffi::Py_ssize_t {
                let item = item_at(ptr, list, i)?;
                if primitive {
                    self.leaves.push(scalar(kind, item)?);
                } else {
                    self.item(elem, item)?;
                }
            }
        } else {
            // Byte strings, for integer elements only (the general path takes the rest).
            if !matches!(
                self.layout.node(elem).kind,
                Kind::Uint { .. } | Kind::Int { .. }
            ) {
                return None;
            }
            let bytes = if let Ok(b) = obj.cast_exact::<PyBytes>() {
                b.as_bytes()
            } else {
                obj.cast_exact::<PyString>().ok()?.to_str().ok()?.as_bytes()
            };
            count(self.leaves, bytes.len())?;
            self.leaves
                .extend(bytes.iter().map(|&b| Scalar::Uint(b.into())));
        }
        Some(())
    }
}

/// Item `i` of `seq`, an exact list (`list`) or tuple that the caller holds, borrowed; `None`
/// when out of range (the list shrank), with an error set that the caller clears.
#[inline(always)]
pub(crate) fn item_at(
    seq: *mut ffi::PyObject,
    list: bool,
    i: ffi::Py_ssize_t,
) -> Option<*mut ffi::PyObject> {
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
    pub(crate) fn new(dict: Bound<'py, PyDict>) -> Self {
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
    pub(crate) fn get(&mut self, name: &Py<PyString>) -> Option<*mut ffi::PyObject> {
        if let Some((key, value)) = self.next {
            if key == name.as_ptr() {
                self.advance();
                return Some(value);
            }
        }
        self.look_up(name)
    }

    /// How many entries the dict has.
    pub(crate) fn len(&self) -> usize {
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
pub(crate) fn scalar(kind: Kind, obj: *mut ffi::PyObject) -> Option<Scalar> {
    // SAFETY (all calls): `obj` is a live object, checked for its exact type before each
    // call that expects one; failures are reported (and left for `leaves_of` to clear).
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

/// An exact int of up to 64 bits: `Uint` when not negative (the core's fast case), else `Int`.
///
/// SAFETY: `obj` is a live object.
#[inline]
pub(crate) unsafe fn integer(obj: *mut ffi::PyObject) -> Option<Scalar> {
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

/// The Python value of `root` from its decoded leaves, as the general path builds it.
pub fn value_of<'py>(
    py: Python<'py>,
    compiled: &Compiled,
    root: NodeId,
    leaves: &[Scalar],
) -> PyResult<Bound<'py, PyAny>> {
    Build {
        py,
        layout: &compiled.layout.as_layout(),
        compiled,
        leaves: leaves.iter(),
    }
    .node(root)
}

struct Build<'a, 'l, 'py> {
    py: Python<'py>,
    layout: &'a Layout<'l>,
    compiled: &'a Compiled,
    leaves: core::slice::Iter<'a, Scalar>,
}

impl<'py> Build<'_, '_, 'py> {
    /// The next leaf; the decoder produced exactly the layout's leaves, so one is always there.
    fn take(&mut self) -> Scalar {
        *self
            .leaves
            .next()
            .expect("the decoded leaves follow the layout")
    }

    fn count(&mut self) -> usize {
        match self.take() {
            Scalar::Uint(n) => n as usize,
            _ => unreachable!("tags and lengths are decoded as unsigned"),
        }
    }

    fn name(&self, index: u32) -> &Bound<'py, PyString> {
        self.compiled.names[index as usize].bind(self.py)
    }

    fn node(&mut self, id: NodeId) -> PyResult<Bound<'py, PyAny>> {
        let layout = self.layout;
        Ok(match layout.node(id).kind {
            Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool => {
                let leaf = self.take();
                scalar_to_py(self.py, leaf)?
            }
            Kind::Struct { first, count } => {
                let fields = first..first + count;
                let dict = self.compiled.new_dict(self.py, id)?;
                for index in fields {
                    let field = layout.fields[index as usize];
                    if field.role != Role::Padding {
                        let item = self.node(field.node)?;
                        dict.set_item(self.name(index), item)?;
                    }
                }
                dict.into_any()
            }
            Kind::Union { first, .. } => {
                let index = first + self.count() as u32;
                let item = self.node(layout.fields[index as usize].node)?;
                let dict = PyDict::new(self.py);
                dict.set_item(self.name(index), item)?;
                dict.into_any()
            }
            Kind::Array { elem, len } => self.list(elem, len as usize)?,
            Kind::DynArray { elem, .. } => {
                let n = self.count();
                self.list(elem, n)?
            }
            Kind::Void { .. } => unreachable!("padding is no value"),
        })
    }

    fn list(&mut self, elem: NodeId, n: usize) -> PyResult<Bound<'py, PyAny>> {
        let mut items = Vec::with_capacity(n);
        if is_primitive(self.layout.node(elem).kind) {
            for leaf in self.leaves.by_ref().take(n) {
                items.push(scalar_to_py(self.py, *leaf)?);
            }
        } else {
            for _ in 0..n {
                items.push(self.node(elem)?);
            }
        }
        Ok(PyList::new(self.py, items)?.into_any())
    }
}

pub(crate) fn is_primitive(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool
    )
}
