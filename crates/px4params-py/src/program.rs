//! Programs: a struct type compiled once into a flat list of steps over its interned field
//! names, so that `encode` reads a plain dict and writes the bits, and `decode` reads the bits
//! and builds the dict, each in one pass, with no leaf list and no layout walk in between.
//!
//! Programs cover the common shapes of parameters and messages: structs of primitives, nested
//! structs, padding, versions and arrays of primitives. A type with a union or an array of
//! composites inside has none (the leaf-list path of [`crate::plain`] takes it).
//!
//! A program never decides anything the general path ([`crate::values`]) would decide
//! differently: the bits come from the core's own conversions ([`scalar_stream`],
//! [`read_scalar`]), and whatever a program does not take exactly as the walk would (a
//! subclass, a missing or unknown field, a number out of range, short data, trailing bytes)
//! makes it give up; the general path then does the work or words the error.

use std::mem::MaybeUninit;
use std::sync::Arc;
use std::{ptr, slice};

use px4params_core::bits::{read_bits, BitWriter};
use px4params_core::codec::{read_scalar, scalar_bits, scalar_stream};
use px4params_core::layout::{Kind, Layout, NodeId, Role};
use px4params_core::scalar;
use px4params_core::Scalar;
use pyo3::ffi;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyString, PyTuple};

use crate::plain::{integer, is_primitive, item_at, scalar as plain_scalar, Entries};
use crate::structs::StructValue;
use crate::values::scalar_to_py;
use crate::Compiled;

/// Nesting beyond this has no program (the walk's own limit is far above; no real type
/// comes near either).
const MAX_NESTING: usize = 16;

/// One step of a program, in the order of the bits. `name` is a field's index in the layout
/// (and in [`crate::Compiled`]'s interned names).
#[derive(Clone, Copy, Debug)]
enum Step {
    /// A primitive field of the current struct.
    Leaf { name: u32, kind: Kind },
    /// The `p_version` field: the type's version, which the value may leave out.
    Version { name: u32, kind: Kind, version: u32 },
    /// Padding bits.
    Pad { bits: u8 },
    /// A struct field (of type `node`): the current struct until the matching [`Step::End`].
    Begin { name: u32, node: NodeId },
    /// The current struct ends.
    End,
    /// An array of primitives.
    Array { name: u32, elem: Kind, len: Len },
    /// The next `len` steps are primitives and padding, which the encoder writes in one run.
    Run { len: u32 },
}

/// An array's length rule.
#[derive(Clone, Copy, Debug)]
enum Len {
    /// `T[N]`.
    Fixed(u32),
    /// `T[<=max]` with a `len_bits` prefix; `tail` when the array ends the value and its
    /// elements have 8 bits or more, so the tail-array optimization drops the prefix.
    Dynamic { max: u32, len_bits: u8, tail: bool },
}

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

/// A struct type's program.
#[derive(Debug)]
pub(crate) struct Program {
    root: NodeId,
    steps: Box<[Step]>,
    /// For a type of primitives and padding alone (NodeStatus, most small messages): each
    /// field at its bit offset, which is fixed, so that decoding interprets no steps.
    fixed: Option<Fixed>,
}

/// The fields of a type of primitives and padding alone, and its length in bits.
#[derive(Debug)]
struct Fixed {
    fields: Box<[FixedField]>,
    bits: usize,
}

/// A primitive field at a fixed bit offset.
#[derive(Clone, Copy, Debug)]
struct FixedField {
    name: u32,
    kind: Kind,
    offset: u32,
}

impl Fixed {
    /// The fields of `steps` (a root struct's, without runs) when all are primitives and
    /// padding.
    fn of(steps: &[Step]) -> Option<Self> {
        let mut fields = Vec::with_capacity(steps.len());
        let mut bits = 0u32;
        for &step in steps {
            match step {
                Step::Leaf { name, kind } | Step::Version { name, kind, .. } => {
                    fields.push(FixedField {
                        name,
                        kind,
                        offset: bits,
                    });
                    bits += scalar_bits(kind);
                }
                Step::Pad { bits: pad } => bits += u32::from(pad),
                Step::End => {}
                Step::Begin { .. } | Step::Array { .. } | Step::Run { .. } => return None,
            }
        }
        Some(Self {
            fields: fields.into(),
            bits: bits as usize,
        })
    }
}

impl Program {
    /// The program of type `root`, or `None` for shapes programs do not cover.
    pub(crate) fn compile(layout: &Layout<'_>, root: NodeId) -> Option<Self> {
        let Kind::Struct { first, count } = layout.node(root).kind else {
            return None;
        };
        let mut steps = Vec::new();
        compile_struct(layout, first, count, true, 0, &mut steps)?;
        steps.push(Step::End);
        Some(Self {
            root,
            fixed: Fixed::of(&steps),
            steps: with_runs(&steps).into(),
        })
    }

    /// Encodes a plain `value` into `out` (room for the type's largest value); the length in
    /// bytes, or `None` to give up.
    pub(crate) fn encode(
        &self,
        names: &[Py<PyString>],
        value: &Bound<'_, PyAny>,
        out: &mut [u8],
        tao: bool,
        saturate: bool,
    ) -> Option<usize> {
        let dict = value.cast_exact::<PyDict>().ok()?;
        let mut encoder = Encoder {
            py: value.py(),
            names,
            out: BitWriter::new(out),
            tao,
            saturate,
        };
        let done = encoder.fields(&mut self.steps.iter(), dict);
        if done.is_none() {
            // A look-up may have raised: the general path meets it again and reports it.
            drop(PyErr::take(value.py()));
            return None;
        }
        encoder.out.finish().ok()
    }

    /// Decodes `data` into a new dict (`F` a dict) or struct value (`F` [`Fields`]), as the
    /// general path builds it; `Ok(None)` to give up.
    pub(crate) fn decode<'py, F: Form<'py>>(
        &self,
        py: Python<'py>,
        compiled: &Arc<Compiled>,
        data: &[u8],
        tao: bool,
        allow_trailing: bool,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        // Short data is read from a copy with 8 zero bytes after it, so that every read takes
        // the bit reader's fast path (a whole 8-byte window; the bounds are checked on
        // `bit_len`). Only those bytes are written: zeroing the whole buffer would cost as
        // much as decoding a small message's field.
        let mut padded = [MaybeUninit::<u8>::uninit(); 256];
        let len = data.len();
        let window = if len + 8 <= padded.len() {
            // SAFETY: `len` bytes from `data` and 8 zeros fit the buffer; the slice made
            // covers exactly the bytes written.
            unsafe {
                let to = padded.as_mut_ptr().cast::<u8>();
                ptr::copy_nonoverlapping(data.as_ptr(), to, len);
                ptr::write_bytes(to.add(len), 0, 8);
                slice::from_raw_parts(to.cast_const(), len + 8)
            }
        } else {
            data
        };
        let mut decoder = Decoder {
            py,
            compiled,
            data: window,
            bit_len: data.len() * 8,
            pos: 0,
            tao,
        };
        if let Some(fixed) = &self.fixed {
            // Short data, or trailing bytes not allowed: the general path words the error.
            let fits = data.len() * 8 >= fixed.bits
                && (allow_trailing || data.len() == fixed.bits.div_ceil(8));
            if !fits {
                return Ok(None);
            }
            return decoder.fixed::<F>(&fixed.fields, self.root).map(Some);
        }
        let Some(value) = decoder.fields::<F>(&mut self.steps.iter(), self.root)? else {
            return Ok(None);
        };
        if !allow_trailing && data.len() > decoder.pos.div_ceil(8) {
            return Ok(None);
        }
        Ok(Some(value))
    }
}

/// Appends the steps of a struct's fields; `tail` when the struct ends the value.
fn compile_struct(
    layout: &Layout<'_>,
    first: u32,
    count: u32,
    tail: bool,
    depth: usize,
    steps: &mut Vec<Step>,
) -> Option<()> {
    if depth > MAX_NESTING {
        return None;
    }
    for name in first..first + count {
        let field = layout.fields[name as usize];
        let last = tail && name + 1 == first + count;
        let kind = layout.node(field.node).kind;
        let step = match (field.role, kind) {
            (Role::Padding, Kind::Void { bits }) => Step::Pad { bits },
            (Role::Version(version), kind) if is_primitive(kind) => Step::Version {
                name,
                kind,
                version,
            },
            (Role::Data, kind) if is_primitive(kind) => Step::Leaf { name, kind },
            (Role::Data, Kind::Struct { first, count }) => {
                steps.push(Step::Begin {
                    name,
                    node: field.node,
                });
                compile_struct(layout, first, count, last, depth + 1, steps)?;
                Step::End
            }
            (Role::Data, Kind::Array { elem, len }) => Step::Array {
                name,
                elem: primitive(layout, elem)?,
                len: Len::Fixed(len),
            },
            (
                Role::Data,
                Kind::DynArray {
                    elem,
                    max,
                    len_bits,
                },
            ) if len_bits > 0 => Step::Array {
                name,
                elem: primitive(layout, elem)?,
                len: Len::Dynamic {
                    max,
                    len_bits,
                    tail: last && layout.node(elem).min_bits >= 8,
                },
            },
            _ => return None,
        };
        steps.push(step);
    }
    Some(())
}

/// `steps` with a [`Step::Run`] before each run of primitives and padding.
fn with_runs(steps: &[Step]) -> Vec<Step> {
    let mut marked = Vec::with_capacity(steps.len() * 2);
    let mut run = None;
    for &step in steps {
        if matches!(
            step,
            Step::Leaf { .. } | Step::Version { .. } | Step::Pad { .. }
        ) {
            let start = *run.get_or_insert(marked.len());
            if start == marked.len() {
                marked.push(Step::Run { len: 0 });
            }
            if let Step::Run { len } = &mut marked[start] {
                *len += 1;
            }
        } else {
            run = None;
        }
        marked.push(step);
    }
    marked
}

/// The kind of node `id` when it is a primitive.
fn primitive(layout: &Layout<'_>, id: NodeId) -> Option<Kind> {
    let kind = layout.node(id).kind;
    is_primitive(kind).then_some(kind)
}

struct Encoder<'a, 'o, 'py> {
    py: Python<'py>,
    names: &'a [Py<PyString>],
    out: BitWriter<'o>,
    tao: bool,
    saturate: bool,
}

// Containers are held as owned references (`Bound`) while they are read; their primitive items
// are read through borrowed pointers at once, with no Python code running in between.
impl Encoder<'_, '_, '_> {
    /// The steps of one struct, up to its [`Step::End`], from its dict.
    fn fields(
        &mut self,
        steps: &mut slice::Iter<'_, Step>,
        dict: &Bound<'_, PyDict>,
    ) -> Option<()> {
        let mut entries = Entries::new(dict);
        let mut used = 0;
        while let Some(&step) = steps.next() {
            match step {
                Step::Run { len } => {
                    let run = steps.as_slice().get(..len as usize)?.iter();
                    self.run(run, &mut entries, &mut used)?;
                    steps.nth(len as usize - 1);
                }
                Step::Begin { name, .. } => {
                    let item = present(entries.get(&self.names[name as usize])?)?;
                    used += 1;
                    // SAFETY: a live item of the dict, held from here on.
                    let held = unsafe { Bound::from_borrowed_ptr(self.py, item) };
                    self.fields(steps, held.cast_exact::<PyDict>().ok()?)?;
                }
                Step::End => break,
                Step::Array { name, elem, len } => {
                    let item = present(entries.get(&self.names[name as usize])?)?;
                    used += 1;
                    // SAFETY: as for a struct.
                    let held = unsafe { Bound::from_borrowed_ptr(self.py, item) };
                    self.array(elem, len, &held)?;
                }
                // Only ever inside runs.
                Step::Leaf { .. } | Step::Version { .. } | Step::Pad { .. } => return None,
            }
        }
        // More keys than fields: an unknown one.
        (dict.len() == used).then_some(())
    }

    /// A run of primitives and padding, written in one go (the writer's state stays in
    /// registers); `used` counts the fields found.
    fn run(
        &mut self,
        mut run: slice::Iter<'_, Step>,
        entries: &mut Entries<'_, '_>,
        used: &mut usize,
    ) -> Option<()> {
        let (names, saturate) = (self.names, self.saturate);
        let mut bits_of = |step: Step| -> Option<(u64, u32)> {
            let (kind, value) = match step {
                Step::Leaf { name, kind } => {
                    let item = present(entries.get(&names[name as usize])?)?;
                    *used += 1;
                    (kind, plain_scalar(kind, item)?)
                }
                Step::Version {
                    name,
                    kind,
                    version,
                } => {
                    let item = entries.get(&names[name as usize])?;
                    if !item.is_null() {
                        *used += 1;
                        // SAFETY: a live item of the dict, read at once.
                        let given = unsafe { integer(item) }?;
                        if given != Scalar::Uint(version.into()) {
                            return None;
                        }
                    }
                    (kind, Scalar::Uint(version.into()))
                }
                Step::Pad { bits } => return Some((0, bits.into())),
                _ => return None,
            };
            scalar_stream(kind, value, saturate).ok()
        };
        let count = run.len();
        let written = self
            .out
            .write_run(count, |_| bits_of(*run.next().ok_or(())?).ok_or(()));
        written.ok()
    }

    fn array(&mut self, elem: Kind, len: Len, obj: &Bound<'_, PyAny>) -> Option<()> {
        let list = obj.is_exact_instance_of::<PyList>();
        if list || obj.is_exact_instance_of::<PyTuple>() {
            let n = obj.len().ok()?;
            self.length(len, n)?;
            let ptr = obj.as_ptr();
            if let Kind::Uint { bits: 8, .. } = elem {
                // Byte strings on a byte boundary (most names): the bytes themselves.
                if let Some(bytes) = self.out.aligned_bytes(n) {
                    for (i, byte) in bytes.iter_mut().enumerate() {
                        *byte = byte_at(ptr, list, i as ffi::Py_ssize_t)?;
                    }
                    return Some(());
                }
            }
            for i in 0..n as ffi::Py_ssize_t {
                let value = plain_scalar(elem, item_at(ptr, list, i)?)?;
                self.scalar(elem, value)?;
            }
            return Some(());
        }
        // Byte strings, for integer elements only.
        if !matches!(elem, Kind::Uint { .. } | Kind::Int { .. }) {
            return None;
        }
        let bytes = if let Ok(b) = obj.cast_exact::<PyBytes>() {
            b.as_bytes()
        } else {
            obj.cast_exact::<PyString>().ok()?.to_str().ok()?.as_bytes()
        };
        self.length(len, bytes.len())?;
        for &b in bytes {
            self.scalar(elem, Scalar::Uint(b.into()))?;
        }
        Some(())
    }

    /// Checks an array's length and writes its prefix.
    fn length(&mut self, len: Len, n: usize) -> Option<()> {
        match len {
            Len::Fixed(len) => (n == len as usize).then_some(()),
            Len::Dynamic { max, .. } if n > max as usize => None,
            Len::Dynamic { tail: true, .. } if self.tao => Some(()),
            Len::Dynamic { len_bits, .. } => self.raw(n as u64, len_bits.into()),
        }
    }

    #[inline(always)]
    fn scalar(&mut self, kind: Kind, value: Scalar) -> Option<()> {
        let (stream, bits) = scalar_stream(kind, value, self.saturate).ok()?;
        self.out.write(stream, bits).ok()
    }

    /// Padding and length prefixes.
    fn raw(&mut self, raw: u64, bits: u32) -> Option<()> {
        self.out.write(scalar::to_stream(raw, bits), bits).ok()
    }
}

/// Item `i` of an exact list (or tuple) of ints, when it fits a byte.
#[inline]
fn byte_at(seq: *mut ffi::PyObject, list: bool, i: ffi::Py_ssize_t) -> Option<u8> {
    let item = item_at(seq, list, i)?;
    // SAFETY: a live item, read at once.
    match unsafe { integer(item) }? {
        Scalar::Uint(v) => u8::try_from(v).ok(),
        _ => None,
    }
}

/// An item found (not null).
#[inline]
fn present(item: *mut ffi::PyObject) -> Option<*mut ffi::PyObject> {
    (!item.is_null()).then_some(item)
}

struct Decoder<'a, 'py> {
    py: Python<'py>,
    compiled: &'a Arc<Compiled>,
    /// The data, perhaps with zeros after it.
    data: &'a [u8],
    /// The data's own length in bits.
    bit_len: usize,
    /// The bit offset of the next read.
    pos: usize,
    tao: bool,
}

impl<'py> Decoder<'_, 'py> {
    fn bits_left(&self) -> usize {
        self.bit_len - self.pos
    }

    /// The primitive of `kind` at bit `offset` as a Python object; the data holds its bits.
    #[inline(always)]
    fn primitive_at(&self, kind: Kind, offset: usize) -> PyResult<Bound<'py, PyAny>> {
        match kind {
            // Unsigned fields, the most common, go straight to a Python int.
            Kind::Uint { bits, .. } => {
                let raw = read_bits(self.data, offset, bits.into());
                let value = scalar::from_stream(raw, bits.into());
                Ok(value.into_pyobject(self.py)?.into_any())
            }
            _ => scalar_to_py(self.py, read_scalar(self.data, offset, kind)),
        }
    }

    /// A struct (of type `node`) of primitives and padding alone, into a new `F`; the data
    /// holds all of its bits.
    fn fixed<F: Form<'py>>(
        &self,
        fields: &[FixedField],
        node: NodeId,
    ) -> PyResult<Bound<'py, PyAny>> {
        let mut built = F::begin(self.py, self.compiled, node)?;
        for field in fields {
            let item = self.primitive_at(field.kind, field.offset as usize)?;
            built.put(self.py, self.compiled, field.name, item)?;
        }
        built.end(self.py, self.compiled, node)
    }

    /// The steps of one struct (of type `node`), up to its [`Step::End`], into a new `F`.
    fn fields<F: Form<'py>>(
        &mut self,
        steps: &mut slice::Iter<'_, Step>,
        node: NodeId,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        let mut built = F::begin(self.py, self.compiled, node)?;
        while let Some(&step) = steps.next() {
            let (name, item) = match step {
                Step::Leaf { name, kind } | Step::Version { name, kind, .. } => {
                    let bits = scalar_bits(kind) as usize;
                    if bits > self.bits_left() {
                        return Ok(None);
                    }
                    let item = self.primitive_at(kind, self.pos)?;
                    self.pos += bits;
                    (name, item)
                }
                Step::Run { .. } => continue,
                Step::Pad { bits } => {
                    if usize::from(bits) > self.bits_left() {
                        return Ok(None);
                    }
                    self.pos += usize::from(bits);
                    continue;
                }
                Step::Begin { name, node } => match self.fields::<F>(steps, node)? {
                    Some(inner) => (name, inner),
                    None => return Ok(None),
                },
                Step::End => break,
                Step::Array { name, elem, len } => match self.array(elem, len)? {
                    Some(list) => (name, list),
                    None => return Ok(None),
                },
            };
            built.put(self.py, self.compiled, name, item)?;
        }
        built.end(self.py, self.compiled, node).map(Some)
    }

    fn array(&mut self, elem: Kind, len: Len) -> PyResult<Option<Bound<'py, PyAny>>> {
        let bits = scalar_bits(elem) as usize;
        let (n, tail) = match len {
            Len::Fixed(len) => (len as usize, false),
            // Every remaining whole byte.
            Len::Dynamic { tail: true, .. } if self.tao => (self.bits_left() / 8 * 8 / bits, true),
            Len::Dynamic { len_bits, .. } => {
                if usize::from(len_bits) > self.bits_left() {
                    return Ok(None);
                }
                let n = scalar::from_stream(
                    read_bits(self.data, self.pos, len_bits.into()),
                    len_bits.into(),
                );
                self.pos += usize::from(len_bits);
                (n as usize, false)
            }
        };
        let too_long = matches!(len, Len::Dynamic { max, .. } if n > max as usize);
        if too_long || n * bits > self.bits_left() {
            return Ok(None);
        }
        // A tail array that leaves a whole byte unread: the walk reads on and reports it.
        if tail && self.bits_left() - n * bits >= 8 {
            return Ok(None);
        }
        // SAFETY: a new list of `n` empty slots, each filled below before it is read (a
        // list dropped half-filled frees only what it holds).
        let list = unsafe {
            Bound::from_owned_ptr_or_err(self.py, ffi::PyList_New(n as ffi::Py_ssize_t))?
        };
        for i in 0..n {
            let value = read_scalar(self.data, self.pos, elem);
            self.pos += bits;
            let item = scalar_to_py(self.py, value)?;
            // SAFETY: `i` is within the list; the slot is empty and takes the reference.
            unsafe { ffi::PyList_SetItem(list.as_ptr(), i as ffi::Py_ssize_t, item.into_ptr()) };
        }
        Ok(Some(list))
    }
}
