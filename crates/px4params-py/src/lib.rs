//! `px4params._native`: the Rust core, compiled once per schema, as frozen Python objects.
//!
//! Core errors become the exception classes of `px4params.errors` in [`errors`], and only there.

mod batch;
mod compile;
mod errors;
mod fastcall;
mod file;
mod program;
mod store;
mod structs;
mod tables;
mod transfer;
mod values;

use std::collections::HashMap;
use std::sync::Arc;

use px4params_core::codec::{decode, encode, DecodeOptions, EncodeOptions, LeafKind};
use px4params_core::compile::OwnedLayout;
use px4params_core::error::Error;
use px4params_core::layout::{Kind, Layout, NodeId, Role};
use px4params_core::leaf::{encode_default, get_leaf, locate, set_leaf, Target};
use px4params_core::program::Program;
use px4params_core::Scalar;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyInt, PyList, PyString, PyTuple};

use errors::{Op, Refusal, SourceError};
use structs::StructValue;
use values::{leaf_tuple, scalar_to_py, LeafRows, PySource};

pub(crate) struct Compiled {
    layout: OwnedLayout,
    roots: HashMap<String, NodeId>,
    /// `int32` and `float32` nodes: classic PX4 parameters are stored as values of these.
    classic_roots: [NodeId; 2],
    /// Every field name as an interned Python string, by field index (decoding builds dicts).
    names: Vec<Py<PyString>>,
    /// Per struct node of more fields than a new dict holds without growing, made on first
    /// use: a dict of its field names (values None) that decoding copies and fills, cheaper
    /// than growing a new dict key by key (see [`Compiled::new_dict`]).
    templates: Vec<std::sync::OnceLock<Py<PyDict>>>,
    /// Per node, made on first use: the struct's program, when it has one.
    programs: Vec<std::sync::OnceLock<Option<Program>>>,
    /// Per node: the key of the type it is (empty for nodes that are no type of the model).
    type_keys: Vec<String>,
    /// Per node: how many named fields it has (structs; 0 for other nodes).
    named_counts: Vec<u32>,
}

/// The most keys a new dict holds without growing (CPython's smallest table, 8 slots, is
/// filled to two thirds).
const SMALL_DICT: usize = 5;

/// The named fields of node `id` of `layout` when it is a struct (padding is not named), as
/// indices into [`Layout::fields`]; none for other nodes.
fn named_fields<'a>(layout: Layout<'a>, id: NodeId) -> impl Iterator<Item = u32> + Clone + 'a {
    let fields = match layout.node(id).kind {
        Kind::Struct { first, count } => first..first + count,
        _ => 0..0,
    };
    fields.filter(move |&index| layout.fields[index as usize].role != Role::Padding)
}

impl Compiled {
    /// The named fields of struct `id` (see [`named_fields`]).
    fn named_fields(&self, id: NodeId) -> impl Iterator<Item = u32> + Clone + '_ {
        named_fields(self.layout.as_layout(), id)
    }

    /// How many named fields struct `id` has.
    fn named_count(&self, id: NodeId) -> u32 {
        self.named_counts[id as usize]
    }

    /// The key of the type node `id` is, e.g. `uavcan.protocol.NodeStatus.1.0`.
    fn type_key(&self, id: NodeId) -> &str {
        self.type_keys.get(id as usize).map_or("", String::as_str)
    }

    /// A new dict for a value of struct `id`, to be filled in field order. A struct of more
    /// fields than a new dict holds without growing gets a copy of its template (its field
    /// names, values None, made on first use): replacing values costs less than growing.
    fn new_dict<'py>(&self, py: Python<'py>, id: NodeId) -> PyResult<Bound<'py, PyDict>> {
        // A plain count first: small structs (most messages) skip the template's lock.
        if self.named_count(id) as usize <= SMALL_DICT {
            return Ok(PyDict::new(py));
        }
        let template = self.templates[id as usize].get_or_init(|| {
            let dict = PyDict::new(py);
            for index in self.named_fields(id) {
                // Inserting into a new dict fails only without memory: the copy below would
                // fail the same way and raise.
                let _ = dict.set_item(self.names[index as usize].bind(py), py.None());
            }
            dict.unbind()
        });
        template.bind(py).copy()
    }

    /// The root node of the type with this exact key.
    fn root(&self, key: &str) -> PyResult<NodeId> {
        let root = self.roots.get(key).copied();
        root.ok_or_else(|| Refusal::NoType { key }.into())
    }

    /// The program of type `root`, compiled on first use.
    fn program(&self, root: NodeId) -> Option<&Program> {
        self.programs[root as usize]
            .get_or_init(|| Program::compile(&self.layout.as_layout(), root))
            .as_ref()
    }
}

/// A translated value and each field's fate (`Schema.translate`).
type Translated<'py> = (Bound<'py, PyBytes>, Vec<(&'static str, String)>);

/// A schema compiled into one flat layout; hands out [`DataType`]s by key.
#[pyclass(frozen, module = "px4params._native")]
pub(crate) struct Schema {
    compiled: Arc<Compiled>,
}

#[pymethods]
impl Schema {
    /// Compiles the model's `types` dict (see `px4params.dsdl_loader`).
    #[new]
    fn new(py: Python<'_>, types: &Bound<'_, PyDict>) -> PyResult<Self> {
        let (mut layout, roots) = compile::compile_model(types)?;
        let saturated = px4params_core::Cast::Saturated;
        let classic_roots = [
            layout.int(32, saturated).expect("int32 is valid"),
            layout.float(32, saturated).expect("float32 is valid"),
        ];
        let view = layout.as_layout();
        let names = view
            .fields
            .iter()
            .map(|f| PyString::intern(py, view.name(f)).unbind())
            .collect();
        let templates = (0..view.nodes.len()).map(|_| Default::default()).collect();
        let programs = (0..view.nodes.len()).map(|_| Default::default()).collect();
        let mut type_keys = vec![String::new(); view.nodes.len()];
        for (key, &id) in &roots {
            type_keys[id as usize].clone_from(key);
        }
        let named_counts = (0..view.nodes.len() as NodeId)
            .map(|id| named_fields(view, id).count() as u32)
            .collect();
        Ok(Self {
            compiled: Arc::new(Compiled {
                layout,
                roots,
                classic_roots,
                names,
                templates,
                programs,
                type_keys,
                named_counts,
            }),
        })
    }

    /// Keys of all compiled types, sorted.
    fn keys(&self) -> Vec<String> {
        let mut keys: Vec<String> = self.compiled.roots.keys().cloned().collect();
        keys.sort();
        keys
    }

    /// The compiled type with this exact key.
    fn get(&self, key: &str) -> PyResult<DataType> {
        let root = self.compiled.root(key)?;
        Ok(DataType {
            max_bytes: self.compiled.layout.as_layout().max_bytes(root),
            compiled: Arc::clone(&self.compiled),
            root,
            key: key.to_owned(),
        })
    }

    /// `data`, a stored value of type `old`, as a value of type `new` (see
    /// `px4params_core::translate`), with the fields `new` added taken from `base`: the bytes
    /// and each field's fate as `("kept" | "new" | "dropped", path)`. Raises `StoreError`.
    fn translate<'py>(
        &self,
        py: Python<'py>,
        old: &str,
        data: &[u8],
        new: &str,
        base: &[u8],
    ) -> PyResult<Translated<'py>> {
        let (old_root, new_root) = (self.compiled.root(old)?, self.compiled.root(new)?);
        let layout = self.compiled.layout.as_layout();
        let mut out = vec![0u8; layout.max_bytes(new_root)];
        let mut changes = Vec::new();
        let mut record = |c: px4params_core::translate::Change<'_>| {
            use px4params_core::translate::Change;
            changes.push(match c {
                Change::Kept(p) => ("kept", p.to_owned()),
                Change::New(p) => ("new", p.to_owned()),
                Change::Dropped(p) => ("dropped", p.to_owned()),
            });
        };
        let translated = px4params_core::translate::translate(
            &layout,
            old_root,
            data,
            new_root,
            base,
            &mut out,
            &mut record,
        );
        match translated {
            Ok(len) => Ok((PyBytes::new(py, &out[..len]), changes)),
            Err(e) => Err(errors::translate(&layout, e)),
        }
    }

    /// Number of nodes in the compiled layout (shared nested types count once).
    #[getter]
    fn node_count(&self) -> usize {
        self.compiled.layout.as_layout().nodes.len()
    }
}

/// One compiled type: encode, decode and leaf access with the DroneCAN rules.
///
/// `px4params.dsdl.schema.DataType` subclasses it, so that its users call `encode` and `decode`
/// here directly, with no Python call in between.
#[pyclass(frozen, subclass, module = "px4params._native")]
struct DataType {
    compiled: Arc<Compiled>,
    root: NodeId,
    /// The length of the type's largest value in bytes.
    max_bytes: usize,
    /// The type's key, e.g. `px.Ina238.1.1`.
    #[pyo3(get)]
    key: String,
}

/// Bytes given as `bytes` (read in place) or as anything `bytes()` takes a buffer from.
fn bytes_of<'py>(data: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyBytes>> {
    if let Ok(b) = data.cast::<PyBytes>() {
        return Ok(b.clone());
    }
    // SAFETY: a live object; the result is a new reference or null with an exception set.
    unsafe { Bound::from_owned_ptr_or_err(data.py(), pyo3::ffi::PyBytes_FromObject(data.as_ptr())) }
        .map(|b| {
            b.cast_into::<PyBytes>()
                .expect("PyBytes_FromObject returns bytes")
        })
}

pub(crate) fn target_of<'a>(target: &'a Bound<'_, PyAny>) -> PyResult<Target<'a>> {
    // Paths first: a failed int extraction builds an exception, a tenth of a microsecond.
    if let Ok(s) = target.cast::<PyString>() {
        // A borrowed &str lives as long as the Python string, which outlives the call.
        return Ok(Target::Path(s.to_str()?));
    }
    if let Ok(k) = target.extract::<usize>() {
        return Ok(Target::Index(k));
    }
    if target.is_instance_of::<PyInt>() && !target.is_instance_of::<PyBool>() {
        // Negative, or beyond any value's leaves: no such leaf, as for any index too high.
        return Err(Refusal::NoLeaf { index: target }.into());
    }
    Err(Refusal::LeafTarget { target }.into())
}

impl DataType {
    fn layout(&self) -> Layout<'_> {
        self.compiled.layout.as_layout()
    }

    fn err<E: SourceError>(&self, py: Python<'_>, err: Error<E>, op: Op) -> PyErr {
        errors::codec(py, &self.key, &self.layout(), err, op)
    }

    /// Data the type's program declined (or a type without one, nested deeper than the codec
    /// walks): the codec decodes it again and words the error.
    fn declined<'py>(&self, py: Python<'py>, data: &[u8], options: DecodeOptions) -> PyErr {
        let layout = self.layout();
        let mut rows = LeafRows::new(&layout);
        match decode(&layout, self.root, data, &mut rows, options) {
            Err(e) => self.err(py, e, Op::Decode),
            Ok(_) => Refusal::TooDeep { key: &self.key }.into(),
        }
    }

    /// Runs `f` with room for the type's largest value: on the stack up to 256 bytes.
    #[inline]
    fn with_out<R>(&self, f: impl FnOnce(&mut [u8]) -> R) -> R {
        let max = self.max_bytes;
        // Small messages (NodeStatus: 7 bytes, BatteryInfo: 55) zero a small buffer.
        if max <= 32 {
            f(&mut [0u8; 32])
        } else if max <= 64 {
            f(&mut [0u8; 64])
        } else if max <= 256 {
            f(&mut [0u8; 256])
        } else {
            f(&mut vec![0u8; max])
        }
    }

    /// Encodes `value` using `out` (room for the type's largest value; what it holds before
    /// does not matter: every byte of the result is written).
    fn encode_into<'py>(
        &self,
        value: &Bound<'py, PyAny>,
        out: &mut [u8],
        tao: bool,
        saturate: bool,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let py = value.py();
        let options = EncodeOptions {
            tao,
            saturate,
            keep_versions: false,
        };
        let encoded = self.compiled.program(self.root).and_then(|program| {
            let mut source = program::PyValues::new(py, &self.compiled.names);
            program.encode(&mut source, value.as_ptr(), out, options)
        });
        match encoded {
            Some(n) => Ok(PyBytes::new(py, &out[..n])),
            None => self.encode_declined(value, out, options),
        }
    }

    /// A value the type's program declined (or a type without one): a struct value as its
    /// dict, anything else by the general path, which encodes it or words the error.
    #[cold]
    #[inline(never)]
    fn encode_declined<'py>(
        &self,
        value: &Bound<'py, PyAny>,
        out: &mut [u8],
        options: EncodeOptions,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let py = value.py();
        let (tao, saturate) = (options.tao, options.saturate);
        let names = &self.compiled.names;
        let layout = self.layout();
        // A look-up may have raised: the general path meets it again and reports it.
        drop(PyErr::take(py));
        if let Ok(value) = value.cast_exact::<StructValue>() {
            let plain = value.get().as_dict(py)?;
            return self.encode_into(&plain, out, tao, saturate);
        }
        // Not plain, or refused: the general path encodes it or words the error.
        let mut source = PySource::new(value.clone(), names, saturate);
        match encode(&layout, self.root, &mut source, out, options) {
            Ok(n) => Ok(PyBytes::new(py, &out[..n])),
            Err(e) => Err(self.err(py, e, Op::Encode)),
        }
    }

    /// Decodes whole bytes by the type's program, structs as `F`; what it declines, the codec
    /// words.
    #[inline(always)]
    fn decode_as<'py, F: program::Form<'py>>(
        &self,
        py: Python<'py>,
        data: &[u8],
        tao: bool,
        allow_trailing: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let options = DecodeOptions {
            tao,
            allow_trailing,
        };
        if let Some(program) = self.compiled.program(self.root) {
            let mut built = program::Built::<F>::new(py, &self.compiled);
            let decoded = program.decode(&mut built, data, options)?;
            if let Some(value) = decoded {
                return Ok(value);
            }
        }
        Err(self.declined(py, data, options))
    }

    /// Decodes whole bytes into dicts.
    fn decode_bytes<'py>(
        &self,
        py: Python<'py>,
        data: &[u8],
        tao: bool,
        allow_trailing: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.decode_as::<Bound<PyDict>>(py, data, tao, allow_trailing)
    }

    /// [`DataType::decode_bytes`] into a [`StructValue`].
    fn decode_struct_bytes<'py>(
        &self,
        py: Python<'py>,
        data: &[u8],
        tao: bool,
        allow_trailing: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        if !matches!(self.layout().node(self.root).kind, Kind::Struct { .. }) {
            return Err(Refusal::UnionStruct { key: &self.key }.into());
        }
        self.decode_as::<program::Fields>(py, data, tao, allow_trailing)
    }
}

#[pymethods]
impl DataType {
    /// The same compiled type (for subclasses made from one `Schema.get` gave).
    #[new]
    fn new(compiled: PyRef<'_, DataType>) -> Self {
        Self {
            max_bytes: compiled.max_bytes,
            compiled: Arc::clone(&compiled.compiled),
            root: compiled.root,
            key: compiled.key.clone(),
        }
    }

    /// Encodes ``value`` (a dict; see the class) to bytes. Out-of-range numbers are refused
    /// unless ``saturate`` is set, which applies the fields' cast modes (clamping
    /// ``saturated`` fields).
    #[pyo3(signature = (value, *, tao = true, saturate = false))]
    fn encode<'py>(
        &self,
        value: &Bound<'py, PyAny>,
        tao: bool,
        saturate: bool,
    ) -> PyResult<Bound<'py, PyBytes>> {
        self.with_out(|out| self.encode_into(value, out, tao, saturate))
    }

    /// Decodes ``data`` (bytes, or anything ``bytes()`` takes) to a value; whole bytes after
    /// the value are refused unless ``allow_trailing``.
    #[pyo3(signature = (data, *, tao = true, allow_trailing = false))]
    fn decode<'py>(
        &self,
        data: &Bound<'py, PyAny>,
        tao: bool,
        allow_trailing: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let data = bytes_of(data)?;
        self.decode_bytes(data.py(), data.as_bytes(), tao, allow_trailing)
    }

    /// ``decode``, into a ``StructValue`` (fields as attributes, nested structs struct values
    /// too) instead of a dict. The type must be a struct.
    #[pyo3(signature = (data, *, tao = true, allow_trailing = false))]
    fn decode_struct<'py>(
        &self,
        data: &Bound<'py, PyAny>,
        tao: bool,
        allow_trailing: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let data = bytes_of(data)?;
        self.decode_struct_bytes(data.py(), data.as_bytes(), tao, allow_trailing)
    }

    /// ``encode`` of each value of ``values`` (any iterable), in one call: a list of bytes.
    /// The first value that cannot be encoded raises what ``encode`` raises, its message
    /// starting ``item N:`` and its ``index`` attribute N.
    #[pyo3(signature = (values, *, tao = true, saturate = false))]
    fn encode_many<'py>(
        &self,
        values: &Bound<'py, PyAny>,
        tao: bool,
        saturate: bool,
    ) -> PyResult<Bound<'py, PyList>> {
        self.with_out(|out| {
            batch::map_items(values, |value| {
                Ok(self.encode_into(value, out, tao, saturate)?.into_any())
            })
        })
    }

    /// ``decode`` of each item of ``items`` (any iterable of bytes-like objects), in one
    /// call: a list of values. The first item that cannot be decoded raises what ``decode``
    /// raises, its message starting ``item N:`` and its ``index`` attribute N.
    #[pyo3(signature = (items, *, tao = true, allow_trailing = false))]
    fn decode_many<'py>(
        &self,
        items: &Bound<'py, PyAny>,
        tao: bool,
        allow_trailing: bool,
    ) -> PyResult<Bound<'py, PyList>> {
        batch::map_items(items, |item| {
            let data = bytes_of(item)?;
            self.decode_bytes(item.py(), data.as_bytes(), tao, allow_trailing)
        })
    }

    /// Decodes a value whose bytes arrive in pieces.
    #[pyo3(signature = (fragments, *, tao = true, allow_trailing = false))]
    fn decode_fragments<'py>(
        &self,
        py: Python<'py>,
        fragments: Vec<Vec<u8>>,
        tao: bool,
        allow_trailing: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        // Joined: the program reads one run of bytes (the pieces are copies already).
        self.decode_bytes(py, &fragments.concat(), tao, allow_trailing)
    }

    /// Every leaf of an encoded value as `(index, path, type, value)`.
    #[pyo3(signature = (data, *, tao = true))]
    fn leaves<'py>(&self, py: Python<'py>, data: &[u8], tao: bool) -> PyResult<Bound<'py, PyList>> {
        let layout = self.layout();
        let mut rows = LeafRows::new(&layout);
        let options = DecodeOptions {
            tao,
            allow_trailing: false,
        };
        decode(&layout, self.root, data, &mut rows, options)
            .map_err(|e| self.err(py, e, Op::Decode))?;
        let list = PyList::empty(py);
        for row in rows.rows {
            let value = scalar_to_py(py, row.value)?;
            let item = (row.index, row.path, row.type_name, value).into_pyobject(py)?;
            list.append(item)?;
        }
        Ok(list)
    }

    /// Reads one leaf (`[k]` index or path) of an encoded value: `(index, path, type, value)`.
    #[pyo3(signature = (data, target, *, tao = true))]
    fn get_leaf<'py>(
        &self,
        py: Python<'py>,
        data: &[u8],
        target: &Bound<'py, PyAny>,
        tao: bool,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let layout = self.layout();
        let t = target_of(target)?;
        let (leaf, value) =
            get_leaf(&layout, self.root, data, t, tao).map_err(|e| self.err(py, e, Op::Leaf))?;
        leaf_tuple(py, &layout, &leaf, value)
    }

    /// Writes one leaf; returns the new encoding. Changing a union tag selects that variant
    /// with its default value; changing an array length truncates or appends defaults.
    #[pyo3(signature = (data, target, value, *, tao = true, saturate = false))]
    fn set_leaf<'py>(
        &self,
        py: Python<'py>,
        data: &[u8],
        target: &Bound<'py, PyAny>,
        value: Bound<'py, PyAny>,
        tao: bool,
        saturate: bool,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let layout = self.layout();
        let t = target_of(target)?;
        let leaf =
            locate(&layout, self.root, data, t, tao).map_err(|e| self.err(py, e, Op::Leaf))?;
        let scalar = leaf_value(py, &self.compiled, &self.key, &leaf, value, saturate)?;
        let mut out = vec![0u8; layout.max_bytes(self.root).max(data.len())];
        let options = EncodeOptions {
            tao,
            saturate,
            keep_versions: true,
        };
        let n = set_leaf(
            &layout,
            self.root,
            data,
            Target::Index(leaf.index),
            scalar,
            &mut out,
            options,
        )
        .map_err(|e| self.err(py, e, Op::Encode))?;
        Ok(PyBytes::new(py, &out[..n]))
    }

    /// The default encoding: zeros, `p_version` filled in, first union variants, empty arrays.
    #[pyo3(signature = (*, tao = true))]
    fn default<'py>(&self, py: Python<'py>, tao: bool) -> PyResult<Bound<'py, PyBytes>> {
        let layout = self.layout();
        let mut out = vec![0u8; layout.max_bytes(self.root)];
        let n = encode_default(&layout, self.root, &mut out, tao)
            .map_err(|e| self.err(py, e, Op::Encode))?;
        Ok(PyBytes::new(py, &out[..n]))
    }

    /// Smallest encoded length in bits (without tail array optimization).
    #[getter]
    fn min_bits(&self) -> u64 {
        self.layout().node(self.root).min_bits
    }

    /// Largest encoded length in bits (without tail array optimization).
    #[getter]
    fn max_bits(&self) -> u64 {
        self.layout().node(self.root).max_bits
    }

    fn __repr__(&self) -> String {
        format!("<DataType {}>", self.key)
    }
}

/// A Python value given for a located leaf, as the leaf's kind of scalar.
pub(crate) fn leaf_value(
    py: Python<'_>,
    compiled: &Compiled,
    type_name: &str,
    leaf: &px4params_core::leaf::Leaf,
    value: Bound<'_, PyAny>,
    saturate: bool,
) -> PyResult<Scalar> {
    let kind = match leaf.kind {
        LeafKind::Scalar(kind) => kind,
        // Tags and lengths are unsigned counts.
        LeafKind::Tag { .. } | LeafKind::Len { .. } => px4params_core::Kind::Uint {
            bits: 32,
            cast: px4params_core::Cast::Saturated,
        },
    };
    let mut source = PySource::new(value, &compiled.names, saturate);
    use px4params_core::codec::Source;
    source.scalar(kind).map_err(|e| {
        let (path, _) = values::describe(&compiled.layout.as_layout(), leaf);
        errors::value(py, type_name, path, e)
    })
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Schema>()?;
    m.add_class::<DataType>()?;
    m.add_class::<StructValue>()?;
    fastcall::install(&m.py().get_type::<DataType>())?;
    program::find_small_ints(m.py());
    m.add_class::<store::Store>()?;
    m.add_function(wrap_pyfunction!(file::check_store_file, m)?)?;
    m.add_function(wrap_pyfunction!(transfer::dsdl_signature, m)?)?;
    m.add_function(wrap_pyfunction!(transfer::data_type_signature, m)?)?;
    m.add_function(wrap_pyfunction!(transfer::transfer_crc_seed, m)?)?;
    m.add_function(wrap_pyfunction!(transfer::can_frames, m)?)?;
    m.add_function(wrap_pyfunction!(transfer::reassemble, m)?)?;
    // The compiled core's own version and store file format, which a wheel may pair with
    // another Python package version only by mistake (`px4params --version` shows both).
    m.add("CORE_VERSION", px4params_core::VERSION)?;
    m.add("STORE_FORMAT_VERSION", px4params_core::file::FORMAT_VERSION)?;
    Ok(())
}
