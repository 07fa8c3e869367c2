//! `StructValue`: a decoded struct whose fields are attributes, the typed form of a value
//! beside the plain dict (`DataType.decode_struct`).
//!
//! A struct value is one object holding its field values in field order: building it costs
//! an allocation where a dict costs a hash insertion per field, and `value.voltage` reads as
//! pydronecan's decoded objects do. Nested structs are struct values too; arrays stay lists
//! and unions one-key dicts, as `decode` gives them. Like a named tuple, its own attributes
//! start with an underscore (`_asdict`, `_fields`, `_type`), so that no DSDL field name is
//! hidden by them. `encode` takes a struct value as its `_asdict()`.

use std::sync::Arc;

use px4params_core::layout::NodeId;
use pyo3::prelude::*;
use pyo3::pyclass::CompareOp;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};
use pyo3::{PyTraverseError, PyVisit};

use crate::errors::Refusal;
use crate::Compiled;

/// A decoded struct: its fields are attributes (`value.uptime_sec`).
#[pyclass(frozen, module = "px4params._native")]
pub(crate) struct StructValue {
    compiled: Arc<Compiled>,
    node: NodeId,
    /// The values of the struct's named fields (padding has none), in field order. A tuple:
    /// CPython keeps small ones ready to reuse, where a Rust allocation costs a `malloc`.
    values: Py<PyTuple>,
}

impl StructValue {
    /// A struct value of struct `node` from its named fields' values, in field order.
    pub(crate) fn new(compiled: &Arc<Compiled>, node: NodeId, values: Py<PyTuple>) -> Self {
        Self {
            compiled: Arc::clone(compiled),
            node,
            values,
        }
    }

    fn values<'py>(&self, py: Python<'py>) -> &Bound<'py, PyTuple> {
        self.values.bind(py)
    }

    /// The struct's field names, in the order of [`StructValue::values`].
    fn names(&self) -> impl Iterator<Item = &Py<PyString>> {
        self.compiled
            .named_fields(self.node)
            .map(|index| &self.compiled.names[index as usize])
    }

    fn key(&self) -> &str {
        self.compiled.type_key(self.node)
    }

    /// The plain value (a dict, nested structs dicts too), as `decode` gives it.
    pub(crate) fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (name, value) in self.names().zip(self.values(py).iter()) {
            dict.set_item(name.bind(py), to_plain(&value)?)?;
        }
        Ok(dict)
    }
}

/// `value` with every struct value inside it made a dict; lists and dicts holding one are
/// copied, anything else is itself.
fn to_plain<'py>(value: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let py = value.py();
    if let Ok(inner) = value.cast_exact::<StructValue>() {
        return Ok(inner.get().as_dict(py)?.into_any());
    }
    if let Ok(list) = value.cast_exact::<PyList>() {
        if list
            .iter()
            .any(|item| item.is_exact_instance_of::<StructValue>())
        {
            let items = list.iter().map(|item| to_plain(&item));
            return Ok(PyList::new(py, items.collect::<PyResult<Vec<_>>>()?)?.into_any());
        }
    } else if let Ok(dict) = value.cast_exact::<PyDict>() {
        // A union: its one variant's value may be a struct.
        let copy = PyDict::new(py);
        for (name, item) in dict.iter() {
            copy.set_item(name, to_plain(&item)?)?;
        }
        return Ok(copy.into_any());
    }
    Ok(value.clone())
}

#[pymethods]
impl StructValue {
    /// The value of field `name`.
    fn __getattr__(&self, py: Python<'_>, name: &Bound<'_, PyString>) -> PyResult<Py<PyAny>> {
        // Field names are interned, as are attribute names in code: most match by identity.
        let found = self.names().position(|field| field.is(name)).or_else(|| {
            self.names()
                .position(|field| field.bind(py).as_any().eq(name).unwrap_or(false))
        });
        match found {
            Some(i) => Ok(self.values(py).get_item(i)?.unbind()),
            None => Err(Refusal::NoField {
                key: self.key(),
                name,
                fields: self.names().map(|n| n.to_string()).collect(),
            }
            .into()),
        }
    }

    /// The value as a dict (nested structs dicts too): what `decode` gives.
    fn _asdict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.as_dict(py)
    }

    /// The struct's field names, in order (padding has none).
    #[getter]
    fn _fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, self.names().map(|n| n.bind(py)).collect::<Vec<_>>())
    }

    /// The key of the struct's type, as `DataType.key` names it.
    #[getter]
    fn _type(&self) -> &str {
        self.key()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let mut text = format!("{}(", self.key());
        for (i, (name, value)) in self.names().zip(self.values(py).iter()).enumerate() {
            if i > 0 {
                text.push_str(", ");
            }
            text.push_str(&format!("{name}={}", value.repr()?));
        }
        text.push(')');
        Ok(text)
    }

    /// Equal to a struct value of the same type with equal fields.
    fn __richcmp__(&self, other: &Bound<'_, PyAny>, op: CompareOp) -> PyResult<Py<PyAny>> {
        let py = other.py();
        let Ok(other) = other.cast_exact::<StructValue>() else {
            return Ok(py.NotImplemented());
        };
        let equal = || -> PyResult<bool> {
            let other = other.get();
            Ok(self.key() == other.key() && self.values(py).eq(other.values(py))?)
        };
        Ok(match op {
            CompareOp::Eq => equal()?.into_pyobject(py)?.to_owned().into_any().unbind(),
            CompareOp::Ne => (!equal()?)
                .into_pyobject(py)?
                .to_owned()
                .into_any()
                .unbind(),
            _ => py.NotImplemented(),
        })
    }

    /// Field names first, for completion in a REPL.
    fn __dir__(&self) -> Vec<String> {
        let mut names: Vec<String> = self.names().map(|n| n.to_string()).collect();
        names.extend(["_asdict", "_fields", "_type"].map(String::from));
        names
    }

    // Lists inside may come to hold the value itself: the collector must see its fields.
    fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
        visit.call(&self.values)
    }
}
