//! `_native.Store`: the core's instance parameter store over memory reserved at construction.
//!
//! Parameters are addressed by index (the Python wrapper resolves names); errors name the
//! instance (`INA238#5`) and become `px4params.errors` classes here.

use std::sync::Arc;

use px4params_core::layout::Layout;
use px4params_core::leaf::{Leaf, Target};
use px4params_core::store::{self, Capacity, ParamDef, Slot, StoreError as CoreError, Which};
use px4params_core::table::LeafSlot;
use px4params_core::Scalar;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};

use crate::errors::{self, Op, Refusal, SourceError};
use crate::values::{leaf_tuple, scalar_to_py, PySource};
use crate::{leaf_value, target_of, Compiled, Schema};

// With a leaf table per type and each instance's first leaves resolved when its value changes:
// reading leaf [k] is a lookup and a bit read (`px4params_core::table`, `store::table_slots`).
pub(crate) type CoreStore = store::Store<Vec<ParamDef>, Vec<Slot>, Vec<u8>, Vec<LeafSlot>>;

/// Key of the `int32` root in the parameter list (a classic integer parameter).
const CLASSIC_INT: &str = "@int32";
/// Key of the `float32` root (a classic float parameter).
const CLASSIC_FLOAT: &str = "@float32";

/// Instance parameters and classic parameters, in memory reserved once.
#[pyclass(module = "px4params._native")]
pub struct Store {
    compiled: Arc<Compiled>,
    inner: CoreStore,
    names: Vec<String>,
    capacity: Capacity,
}

fn which(default: bool) -> Which {
    if default {
        Which::Default
    } else {
        Which::Value
    }
}

impl Store {
    pub(crate) fn layout(&self) -> Layout<'_> {
        self.compiled.layout.as_layout()
    }

    pub(crate) fn core(&self) -> &CoreStore {
        &self.inner
    }

    pub(crate) fn capacity_of(&self) -> Capacity {
        self.capacity
    }

    pub(crate) fn root_of(&self, key: &str) -> PyResult<u32> {
        self.compiled.root(key)
    }

    /// Leaf `target` of an instance's value (or default), located and read.
    fn read_leaf(
        &self,
        py: Python<'_>,
        param: u32,
        instance: u16,
        target: &Bound<'_, PyAny>,
        default: bool,
    ) -> PyResult<(Leaf, Scalar)> {
        let layout = self.layout();
        let t = target_of(target)?;
        self.inner
            .get_leaf(&layout, param, instance, which(default), t)
            .map_err(|e| self.err(py, param, Some(instance), e, Op::Leaf))
    }

    /// `INA238#2`, or `INA238` for a shared parameter.
    fn instance_name(&self, param: u32, instance: Option<u16>) -> String {
        let name = self.names.get(param as usize).map_or("?", String::as_str);
        match (instance, self.inner.defs().get(param as usize)) {
            (Some(i), Some(def)) if !def.shared => format!("{name}#{i}"),
            _ => name.to_owned(),
        }
    }

    /// A store error of the instance (or parameter) as a Python exception.
    fn err<E: SourceError>(
        &self,
        py: Python<'_>,
        param: u32,
        instance: Option<u16>,
        err: CoreError<E>,
        op: Op,
    ) -> PyErr {
        let name = self.instance_name(param, instance);
        let param_name = self.instance_name(param, None);
        errors::store(py, &name, &param_name, &self.layout(), err, op)
    }
}

#[pymethods]
impl Store {
    /// A store for `params`, a list of `(name, type key, max_instances or None)`; the type key
    /// `"@int32"` or `"@float32"` makes a classic parameter. Every instance starts absent;
    /// shared and classic parameters exist from the start.
    #[new]
    fn new(
        schema: PyRef<'_, Schema>,
        params: Vec<(String, String, Option<u16>)>,
    ) -> PyResult<Self> {
        let compiled = Arc::clone(&schema.compiled);
        let mut defs = Vec::with_capacity(params.len());
        let mut names = Vec::with_capacity(params.len());
        for (name, key, max_instances) in params {
            let root = match key.as_str() {
                CLASSIC_INT => compiled.classic_roots[0],
                CLASSIC_FLOAT => compiled.classic_roots[1],
                _ => *compiled.roots.get(&key).ok_or_else(|| Refusal::ParamType {
                    name: &name,
                    key: &key,
                })?,
            };
            defs.push(match max_instances {
                Some(0) => return Err(Refusal::NoInstances { name: &name }.into()),
                Some(n) => ParamDef::instanced(root, n),
                None => ParamDef::shared(root),
            });
            names.push(name);
        }
        let layout = compiled.layout.as_layout();
        let named = |e: CoreError| errors::store_plan(&layout, e, &names);
        let capacity = store::plan(&layout, &mut defs).map_err(named)?;
        let slots = vec![Slot::default(); capacity.slots];
        let bytes = vec![0u8; capacity.bytes];
        let tables = vec![LeafSlot::default(); store::table_slots(&layout, &defs)];
        let inner = CoreStore::with_tables(&layout, defs, slots, bytes, tables).map_err(named)?;
        Ok(Self {
            compiled: Arc::clone(&compiled),
            inner,
            names,
            capacity,
        })
    }

    /// `(slots, bytes)` reserved.
    #[getter]
    fn capacity(&self) -> (usize, usize) {
        (self.capacity.slots, self.capacity.bytes)
    }

    /// An independent copy (for all-or-nothing batches: work on a copy, then `restore`).
    fn copy(&self) -> Self {
        Self {
            compiled: Arc::clone(&self.compiled),
            inner: self.inner.clone(),
            names: self.names.clone(),
            capacity: self.capacity,
        }
    }

    /// Takes over the whole state of `other`, a copy of this store (same schema and
    /// parameters); any other store is refused.
    fn restore(&mut self, other: PyRef<'_, Store>) -> PyResult<()> {
        if !Arc::ptr_eq(&self.compiled, &other.compiled)
            || self.names != other.names
            || self.inner.defs() != other.inner.defs()
        {
            return Err(Refusal::NotACopy.into());
        }
        self.inner = other.inner.clone();
        Ok(())
    }

    /// The layout and the plan as tuples, for C tables (`px4params metadata --firmware`), with
    /// the root nodes of the types `roots` names (older versions the tables carry).
    fn tables<'py>(
        &self,
        py: Python<'py>,
        roots: Vec<String>,
    ) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        crate::tables::tables(py, self, &roots)
    }

    /// The store's file: `names` per parameter index, `(table line, 0)` for a structured
    /// parameter (`NAME=TYPE.MAJOR`) or `(name, 1)` for a classic int32, `(name, 2)` for a
    /// classic float32; `order` the parameters in file order; `foreign` records kept from a
    /// loaded file, written back.
    fn file_bytes<'py>(
        &self,
        py: Python<'py>,
        names: Vec<(String, u8)>,
        order: Vec<u32>,
        foreign: Vec<Vec<u8>>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = crate::file::store_file_bytes(&self.inner, &names, &order, &foreign)?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// Sets the type default of parameter `param` (encoded without tail array optimization).
    fn set_type_default(&mut self, py: Python<'_>, param: u32, data: &[u8]) -> PyResult<()> {
        let layout = self.compiled.layout.as_layout();
        let result = self.inner.set_type_default(&layout, param, data);
        result.map_err(|e| self.err(py, param, None, e, Op::Decode))
    }

    /// The type default of parameter `param`.
    fn type_default<'py>(&self, py: Python<'py>, param: u32) -> PyResult<Bound<'py, PyBytes>> {
        let data = self
            .inner
            .type_default(param)
            .map_err(|e| self.err(py, param, None, e, Op::Leaf))?;
        Ok(PyBytes::new(py, data))
    }

    /// `(present, used, unsaved)` of an instance.
    fn slot(&self, py: Python<'_>, param: u32, instance: u16) -> PyResult<(bool, bool, bool)> {
        let slot = self
            .inner
            .slot(param, instance)
            .map_err(|e| self.err(py, param, Some(instance), e, Op::Leaf))?;
        Ok((slot.present(), slot.used(), slot.unsaved()))
    }

    /// The numbers of the instances that exist, in order.
    fn instances(&self, py: Python<'_>, param: u32) -> PyResult<Vec<u16>> {
        match self.inner.instances(param) {
            Ok(it) => Ok(it.collect()),
            Err(e) => Err(self.err(py, param, None, e, Op::Leaf)),
        }
    }

    /// Adds an instance (the lowest free one when `instance` is None); returns its number.
    #[pyo3(signature = (param, instance = None))]
    fn add(&mut self, py: Python<'_>, param: u32, instance: Option<u16>) -> PyResult<u16> {
        let result = self.inner.add(param, instance);
        result.map_err(|e| self.err(py, param, instance, e, Op::Leaf))
    }

    /// Removes an instance; the others keep their numbers.
    fn remove(&mut self, py: Python<'_>, param: u32, instance: u16) -> PyResult<()> {
        let result = self.inner.remove(param, instance);
        result.map_err(|e| self.err(py, param, Some(instance), e, Op::Leaf))
    }

    /// The encoded value (or default) of an instance.
    #[pyo3(signature = (param, instance, *, default = false))]
    fn get<'py>(
        &self,
        py: Python<'py>,
        param: u32,
        instance: u16,
        default: bool,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let data = self
            .inner
            .get(param, instance, which(default))
            .map_err(|e| self.err(py, param, Some(instance), e, Op::Leaf))?;
        Ok(PyBytes::new(py, data))
    }

    /// Whether an instance's value differs from its default.
    fn changed(&self, py: Python<'_>, param: u32, instance: u16) -> PyResult<bool> {
        let result = self.inner.changed(param, instance);
        result.map_err(|e| self.err(py, param, Some(instance), e, Op::Leaf))
    }

    /// Reads one leaf: `(index, path, type, value)`.
    #[pyo3(signature = (param, instance, target, *, default = false))]
    fn get_leaf<'py>(
        &self,
        py: Python<'py>,
        param: u32,
        instance: u16,
        target: &Bound<'py, PyAny>,
        default: bool,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let (leaf, value) = self.read_leaf(py, param, instance, target, default)?;
        leaf_tuple(py, &self.layout(), &leaf, value)
    }

    /// Reads one leaf's value only (`Store.get` of a leaf: no path or type text is built).
    /// `default` may be given by position: keywords cost a call a tenth of its time.
    #[pyo3(signature = (param, instance, target, default = false))]
    fn get_leaf_value<'py>(
        &self,
        py: Python<'py>,
        param: u32,
        instance: u16,
        target: &Bound<'py, PyAny>,
        default: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (_, value) = self.read_leaf(py, param, instance, target, default)?;
        scalar_to_py(py, value)
    }

    /// Writes one leaf of an instance's value (or default).
    #[pyo3(signature = (param, instance, target, value, *, default = false, saturate = false))]
    #[allow(clippy::too_many_arguments)] // mirrors the Python call's arguments one to one
    fn set_leaf(
        &mut self,
        py: Python<'_>,
        param: u32,
        instance: u16,
        target: &Bound<'_, PyAny>,
        value: Bound<'_, PyAny>,
        default: bool,
        saturate: bool,
    ) -> PyResult<()> {
        let (leaf, _) = self.read_leaf(py, param, instance, target, default)?;
        let compiled = Arc::clone(&self.compiled);
        let layout = compiled.layout.as_layout();
        let w = which(default);
        let name = self.instance_name(param, Some(instance));
        let scalar = leaf_value(py, &compiled, &name, &leaf, value, saturate)?;
        let target = Target::Index(leaf.index);
        let result = self
            .inner
            .set_leaf(&layout, param, instance, w, target, scalar, saturate);
        result.map_err(|e| self.err(py, param, Some(instance), e, Op::Encode))
    }

    /// Writes a whole value (or default) given as Python data; `p_version` may be left out.
    #[pyo3(signature = (param, instance, value, *, default = false, saturate = false))]
    fn set_value(
        &mut self,
        py: Python<'_>,
        param: u32,
        instance: u16,
        value: Bound<'_, PyAny>,
        default: bool,
        saturate: bool,
    ) -> PyResult<()> {
        let compiled = Arc::clone(&self.compiled);
        let layout = compiled.layout.as_layout();
        let mut source = PySource::new(value, &compiled.names, saturate);
        let result = self.inner.set_from(
            &layout,
            param,
            instance,
            which(default),
            &mut source,
            saturate,
        );
        result.map_err(|e| self.err(py, param, Some(instance), e, Op::Encode))
    }

    /// Writes a whole encoded value (or default), checked before it is taken.
    #[pyo3(signature = (param, instance, data, *, default = false))]
    fn set_encoded(
        &mut self,
        py: Python<'_>,
        param: u32,
        instance: u16,
        data: &[u8],
        default: bool,
    ) -> PyResult<()> {
        let compiled = Arc::clone(&self.compiled);
        let layout = compiled.layout.as_layout();
        let result = self
            .inner
            .set_encoded(&layout, param, instance, which(default), data);
        result.map_err(|e| self.err(py, param, Some(instance), e, Op::Decode))
    }

    /// Sets an instance's value back to its default.
    fn reset(&mut self, py: Python<'_>, param: u32, instance: u16) -> PyResult<()> {
        let result = self.inner.reset(param, instance);
        result.map_err(|e| self.err(py, param, Some(instance), e, Op::Leaf))
    }

    /// Marks an instance as used by a driver.
    fn mark_used(&mut self, py: Python<'_>, param: u32, instance: u16) -> PyResult<()> {
        let result = self.inner.mark_used(param, instance);
        result.map_err(|e| self.err(py, param, Some(instance), e, Op::Leaf))
    }

    /// Marks everything as saved.
    fn mark_saved(&mut self) {
        self.inner.mark_saved();
    }
}
