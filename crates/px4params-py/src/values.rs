//! Python objects as codec values: dicts for structs, one-key dicts for unions, sequences for
//! arrays (bytes and str too), int/float/bool for primitives, "nan"/"inf"/"-inf" for floats,
//! read by the core's general encoder ([`PySource`]: values of any type the programs decline;
//! what does not fit is a [`ValueError`], worded in [`crate::errors`]); decoded scalars as
//! Python objects; leaf listings.

use px4params_core::codec::{ArrayLen, At, LeafKind, Sink, Source};
use px4params_core::error::Path;
use px4params_core::layout::{Field, Kind, Layout};
use px4params_core::leaf::Leaf;
use px4params_core::Scalar;
use pyo3::prelude::*;
use pyo3::types::{
    PyBool, PyByteArray, PyBytes, PyDict, PyFloat, PyInt, PyList, PySequence, PyString, PyTuple,
};

use crate::errors::{names_of, Expected, ValueError};
use crate::structs::StructValue;

/// `numbers.Integral` and `numbers.Real`: numbers of other types (numpy's `int64`, `float32`)
/// are taken by what they declare themselves to be, as Python's own `operator.index` and
/// `float` take them (a numpy `bool`, which declares neither, is no number here either).
static NUMBER_ABCS: pyo3::sync::PyOnceLock<(Py<PyAny>, Py<PyAny>)> = pyo3::sync::PyOnceLock::new();

fn is_number_kind(obj: &Bound<'_, PyAny>, integral: bool) -> PyResult<bool> {
    let py = obj.py();
    let (integral_abc, real_abc) = NUMBER_ABCS.get_or_try_init(py, || -> PyResult<_> {
        let numbers = py.import("numbers")?;
        Ok((
            numbers.getattr("Integral")?.unbind(),
            numbers.getattr("Real")?.unbind(),
        ))
    })?;
    obj.is_instance(if integral { integral_abc } else { real_abc }.bind(py))
}

fn wrong<'py>(expected: Expected, value: &Bound<'py, PyAny>) -> ValueError<'py> {
    // A new reference to the value: the error outlives the borrow it was found through.
    ValueError::WrongType {
        expected,
        value: value.clone(),
    }
}

enum Frame<'py> {
    Obj(Bound<'py, PyAny>),
    Bytes(Vec<u8>),
}

/// Reads a Python value for the encoder.
pub(crate) struct PySource<'py, 'n> {
    py: Python<'py>,
    names: &'n [Py<PyString>],
    stack: Vec<Frame<'py>>,
    saturate: bool,
}

impl<'py, 'n> PySource<'py, 'n> {
    /// `names` holds every field name of the layout as a Python string, by field index, so
    /// that dict look-ups use interned keys with cached hashes.
    pub(crate) fn new(value: Bound<'py, PyAny>, names: &'n [Py<PyString>], saturate: bool) -> Self {
        Self {
            py: value.py(),
            names,
            stack: vec![Frame::Obj(value)],
            saturate,
        }
    }

    fn current(&self) -> &Bound<'py, PyAny> {
        match self.stack.last() {
            Some(Frame::Obj(o)) => o,
            // Bytes frames only ever sit under their element's Obj frame.
            _ => unreachable!("a value is always on top of the stack"),
        }
    }

    fn integer(&self, given: &Bound<'py, PyAny>, kind: Kind) -> Result<Scalar, ValueError<'py>> {
        if given.is_instance_of::<PyBool>() {
            return Err(wrong(Expected::Integer, given));
        }
        let index;
        let obj = if given.is_instance_of::<PyInt>() {
            given
        } else if is_number_kind(given, true)? {
            // numpy's integers: their value as an int (`__index__`), errors named by the
            // value as given
            index = given.call_method0("__index__")?;
            &index
        } else {
            return Err(wrong(Expected::Integer, given));
        };
        if let Ok(v) = obj.extract::<i64>() {
            return Ok(Scalar::Int(v));
        }
        if let Ok(v) = obj.extract::<u64>() {
            return Ok(Scalar::Uint(v));
        }
        // Beyond 64 bits: clamp when saturating, else report the value as given.
        let negative = obj.lt(0)?;
        if self.saturate {
            return Ok(if negative {
                Scalar::Int(i64::MIN)
            } else {
                Scalar::Uint(u64::MAX)
            });
        }
        // The field's range (only integer kinds, of at most 64 bits, come here).
        let (min, max) = match kind {
            Kind::Int { bits, .. } => {
                let max = i64::MAX >> (64 - u32::from(bits));
                (Scalar::Int(-max - 1), Scalar::Int(max))
            }
            Kind::Uint { bits, .. } => (
                Scalar::Uint(0),
                Scalar::Uint(u64::MAX >> (64 - u32::from(bits))),
            ),
            _ => (Scalar::Uint(0), Scalar::Uint(u64::MAX)),
        };
        Err(ValueError::OutOfRange {
            value: given.clone(),
            min,
            max,
        })
    }
}

fn float_of<'py>(obj: &Bound<'py, PyAny>) -> Result<f64, ValueError<'py>> {
    if obj.is_instance_of::<PyBool>() {
        return Err(wrong(Expected::Number, obj));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(obj.extract::<f64>()?);
    }
    if obj.is_instance_of::<PyInt>() {
        // An int beyond every double is refused as out of range (as the CLI refuses 1e400),
        // not raised as Python's OverflowError.
        return obj
            .extract::<f64>()
            .map_err(|_| ValueError::BeyondFloat64 { value: obj.clone() });
    }
    if is_number_kind(obj, false)? {
        // numpy's floats and integers, fractions: `float()` of them (beyond every double:
        // out of range, as above)
        return obj
            .call_method0("__float__")
            .and_then(|f| f.extract::<f64>())
            .map_err(|_| ValueError::BeyondFloat64 { value: obj.clone() });
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return match s.to_str()?.trim().to_ascii_lowercase().as_str() {
            "nan" => Ok(f64::NAN),
            "inf" | "+inf" | "infinity" => Ok(f64::INFINITY),
            "-inf" | "-infinity" => Ok(f64::NEG_INFINITY),
            other => Err(ValueError::NotANumber { text: other.into() }),
        };
    }
    Err(wrong(Expected::Number, obj))
}

impl<'py> Source for PySource<'py, '_> {
    type Error = ValueError<'py>;

    fn scalar(&mut self, kind: Kind) -> Result<Scalar, ValueError<'py>> {
        let obj = self.current().clone();
        match kind {
            Kind::Uint { .. } | Kind::Int { .. } => self.integer(&obj, kind),
            Kind::Float { .. } => Ok(Scalar::Float(float_of(&obj)?)),
            _ => {
                if let Ok(b) = obj.cast::<PyBool>() {
                    Ok(Scalar::Bool(b.is_true()))
                } else if obj.is_instance_of::<PyInt>() {
                    match obj.extract::<i64>() {
                        Ok(v @ (0 | 1)) => Ok(Scalar::Bool(v == 1)),
                        _ => Err(ValueError::NotABoolean { value: obj }),
                    }
                } else {
                    Err(wrong(Expected::Boolean, &obj))
                }
            }
        }
    }

    fn begin_struct(&mut self) -> Result<(), ValueError<'py>> {
        let obj = self.current();
        if obj.is_instance_of::<PyDict>() {
            Ok(())
        } else if let Ok(value) = obj.cast_exact::<StructValue>() {
            // Taken as its dict, which replaces it on the stack.
            let plain = value.get().as_dict(self.py)?.into_any();
            self.stack.pop();
            self.stack.push(Frame::Obj(plain));
            Ok(())
        } else {
            Err(wrong(Expected::Struct, obj))
        }
    }

    fn field(&mut self, index: u32, _name: &str) -> Result<bool, ValueError<'py>> {
        let dict = self.current().cast::<PyDict>().map_err(PyErr::from)?;
        match dict.get_item(self.names[index as usize].bind(self.py))? {
            Some(v) => {
                self.stack.push(Frame::Obj(v));
                Ok(true)
            }
            None => Ok(false),
        }
    }

    fn end_field(&mut self) {
        self.stack.pop();
    }

    fn end_struct(
        &mut self,
        layout: &Layout<'_>,
        fields: &[Field],
        used: usize,
    ) -> Result<(), ValueError<'py>> {
        let dict = self.current().cast::<PyDict>().map_err(PyErr::from)?;
        if dict.len() == used {
            return Ok(());
        }
        let names = names_of(layout, fields);
        for key in dict.keys() {
            let known = key
                .cast::<PyString>()
                .ok()
                .and_then(|k| k.to_str().ok().map(|k| names.iter().any(|n| n == k)))
                .unwrap_or(false);
            if !known {
                return Err(ValueError::UnknownField { key, fields: names });
            }
        }
        Ok(())
    }

    fn begin_union(
        &mut self,
        layout: &Layout<'_>,
        variants: &[Field],
    ) -> Result<u32, ValueError<'py>> {
        let obj = self.current();
        let Ok(dict) = obj.cast::<PyDict>() else {
            return Err(ValueError::NotAUnion {
                value: obj.clone(),
                variants: names_of(layout, variants),
            });
        };
        if dict.len() != 1 {
            return Err(ValueError::UnionKeys {
                keys: dict.len(),
                variants: names_of(layout, variants),
            });
        }
        let (key, value) = dict.iter().next().expect("one item");
        let key_str = key
            .cast::<PyString>()
            .ok()
            .and_then(|k| k.to_str().ok().map(str::to_owned));
        let Some(index) = key_str
            .as_deref()
            .and_then(|k| variants.iter().position(|f| layout.name(f) == k))
        else {
            return Err(ValueError::UnknownVariant {
                key,
                variants: names_of(layout, variants),
            });
        };
        self.stack.push(Frame::Obj(value));
        Ok(index as u32)
    }

    fn end_union(&mut self) {
        self.stack.pop();
    }

    fn begin_array(&mut self, _fixed: Option<u32>) -> Result<usize, ValueError<'py>> {
        let obj = self.current().clone();
        if let Ok(b) = obj.cast::<PyBytes>() {
            let bytes = b.as_bytes().to_vec();
            let n = bytes.len();
            self.stack.push(Frame::Bytes(bytes));
            return Ok(n);
        }
        if let Ok(b) = obj.cast::<PyByteArray>() {
            let bytes = b.to_vec();
            let n = bytes.len();
            self.stack.push(Frame::Bytes(bytes));
            return Ok(n);
        }
        if let Ok(s) = obj.cast::<PyString>() {
            // A str that is not valid Unicode (lone surrogates) cannot become UTF-8 bytes.
            let text = s.to_str().map_err(|_| ValueError::NotUtf8)?;
            let bytes = text.as_bytes().to_vec();
            let n = bytes.len();
            self.stack.push(Frame::Bytes(bytes));
            return Ok(n);
        }
        if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
            let n = obj.len()?;
            self.stack.push(Frame::Obj(obj));
            return Ok(n);
        }
        if obj.is_instance_of::<PyDict>() {
            return Err(wrong(Expected::Array, &obj));
        }
        match obj.cast::<PySequence>() {
            Ok(seq) => {
                let n = seq.len()?;
                self.stack.push(Frame::Obj(obj));
                Ok(n)
            }
            Err(_) => Err(wrong(Expected::Array, &obj)),
        }
    }

    fn element(&mut self, index: usize) -> Result<(), ValueError<'py>> {
        let item = match self.stack.last() {
            Some(Frame::Bytes(b)) => PyInt::new(self.py, b[index]).into_any(),
            Some(Frame::Obj(o)) => {
                if let Ok(list) = o.cast::<PyList>() {
                    list.get_item(index)?
                } else {
                    o.get_item(index)?
                }
            }
            None => unreachable!("an array frame is on the stack"),
        };
        self.stack.push(Frame::Obj(item));
        Ok(())
    }

    fn end_element(&mut self) {
        self.stack.pop();
    }

    fn end_array(&mut self) {
        self.stack.pop();
    }
}

/// A scalar as a Python object.
#[inline]
pub fn scalar_to_py<'py>(py: Python<'py>, value: Scalar) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Scalar::Uint(v) => match crate::program::small_int_object(py, v) {
            Some(int) => int,
            None => v.into_pyobject(py)?.into_any(),
        },
        Scalar::Int(v) => v.into_pyobject(py)?.into_any(),
        Scalar::Float(v) => v.into_pyobject(py)?.into_any(),
        Scalar::Bool(v) => PyBool::new(py, v).to_owned().into_any(),
    })
}

/// One leaf of a decoded value, for listings.
pub struct LeafRow {
    pub index: usize,
    pub path: String,
    pub type_name: String,
    pub value: Scalar,
}

/// Collects every leaf with its path and type.
pub struct LeafRows<'l> {
    pub layout: &'l Layout<'l>,
    pub rows: Vec<LeafRow>,
    depth: usize,
    // A tail-optimized array is the last thing in a value: one pending length row suffices.
    tail: Option<(usize, usize)>,
}

impl<'l> LeafRows<'l> {
    pub fn new(layout: &'l Layout<'l>) -> Self {
        Self {
            layout,
            rows: Vec::new(),
            depth: 0,
            tail: None,
        }
    }

    /// A row for the leaf at `at` (`tail`: a tail array's length, which has no bits).
    fn push(&mut self, at: &At<'_>, tail: bool, value: Scalar) {
        let (path, type_name) = leaf_name(self.layout, at.path, at.kind, tail);
        self.rows.push(LeafRow {
            index: self.rows.len(),
            path,
            type_name,
            value,
        });
    }
}

/// A leaf's path and type as listings show them: the field path, then `_tag` or `_len` for a
/// union's tag or an array's length; the DSDL type (`uint8`), or `tail` for the length of a
/// tail array (`tail`: no bits of its own).
pub(crate) fn leaf_name(
    layout: &Layout<'_>,
    path: &Path,
    kind: LeafKind,
    tail: bool,
) -> (String, String) {
    let mut text = path.display(layout).to_string();
    let (suffix, type_name) = match kind {
        LeafKind::Scalar(kind) => ("", kind_name(kind)),
        LeafKind::Tag { bits, .. } => ("_tag", format!("uint{bits}")),
        LeafKind::Len { .. } if tail => ("_len", "tail".to_owned()),
        LeafKind::Len { bits, .. } => ("_len", format!("uint{bits}")),
    };
    if !suffix.is_empty() {
        if !text.is_empty() {
            text.push('.');
        }
        text.push_str(suffix);
    }
    (text, type_name)
}

/// A located leaf's path and type name (see [`leaf_name`]).
pub(crate) fn describe(layout: &Layout<'_>, leaf: &Leaf) -> (String, String) {
    let tail = matches!(leaf.kind, LeafKind::Len { bits: 0, .. });
    leaf_name(layout, &leaf.path, leaf.kind, tail)
}

/// A located leaf and its value as Python gets it: `(index, path, type, value)`.
pub(crate) fn leaf_tuple<'py>(
    py: Python<'py>,
    layout: &Layout<'_>,
    leaf: &Leaf,
    value: Scalar,
) -> PyResult<Bound<'py, PyTuple>> {
    let (path, type_name) = describe(layout, leaf);
    (leaf.index, path, type_name, scalar_to_py(py, value)?).into_pyobject(py)
}

/// The DSDL spelling of a scalar kind.
fn kind_name(kind: Kind) -> String {
    match kind {
        Kind::Uint { bits, .. } => format!("uint{bits}"),
        Kind::Int { bits, .. } => format!("int{bits}"),
        Kind::Float { bits, .. } => format!("float{bits}"),
        Kind::Bool => "bool".into(),
        Kind::Void { bits } => format!("void{bits}"),
        _ => "composite".into(),
    }
}

impl Sink for LeafRows<'_> {
    type Error = std::convert::Infallible;

    fn scalar(&mut self, value: Scalar, at: At<'_>) -> Result<(), Self::Error> {
        if let LeafKind::Scalar(_) = at.kind {
            self.push(&at, false, value);
        }
        Ok(())
    }
    fn begin_struct(&mut self, _: usize) -> Result<(), Self::Error> {
        Ok(())
    }
    fn field(&mut self, _: u32, _: &str) -> Result<(), Self::Error> {
        Ok(())
    }
    fn end_struct(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
    fn begin_union(&mut self, tag: u32, _: u32, _: &str, at: At<'_>) -> Result<(), Self::Error> {
        if let LeafKind::Tag { .. } = at.kind {
            self.push(&at, false, Scalar::Uint(tag.into()));
        }
        Ok(())
    }
    fn end_union(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
    fn begin_array(&mut self, len: ArrayLen, at: At<'_>) -> Result<(), Self::Error> {
        self.depth += 1;
        if !matches!(at.kind, LeafKind::Len { .. }) {
            return Ok(());
        }
        match len {
            ArrayLen::Fixed(_) => {}
            ArrayLen::Prefixed(n) => self.push(&at, false, Scalar::Uint(n as u64)),
            ArrayLen::Tail => {
                self.tail = Some((self.rows.len(), self.depth));
                self.push(&at, true, Scalar::Uint(0));
            }
        }
        Ok(())
    }
    fn end_array(&mut self, len: usize) -> Result<(), Self::Error> {
        if let Some((row, depth)) = self.tail {
            if depth == self.depth {
                self.rows[row].value = Scalar::Uint(len as u64);
                self.tail = None;
            }
        }
        self.depth -= 1;
        Ok(())
    }
}
