//! The one boundary where errors become Python exceptions, and the only place they are worded:
//! the core's errors (codec, store, file, transfer, translation), the binding's own findings
//! about a Python value ([`ValueError`]: kind, the value, what was expected, as data; the
//! path comes from the core's walk), a schema model it cannot compile ([`ModelError`]) and
//! its other refusals ([`Refusal`]). The classes are those of `px4params.errors`, which Python
//! owns. Every message is one line and names the type, instance or file, the path, the value
//! and what was expected.

use std::any::Any;
use std::fmt;

use px4params_core::codec::MAX_DEPTH;
use px4params_core::compile::BuildError;
use px4params_core::error::{Error, ErrorKind};
use px4params_core::file::{FileError, SaveError};
use px4params_core::layout::{Field, Layout};
use px4params_core::store::StoreError as CoreStoreError;
use px4params_core::transfer::TransferError as CoreTransferError;
use px4params_core::translate::TranslateError;
use px4params_core::Scalar;
use pyo3::exceptions::{PyAttributeError, PyKeyError, PyTypeError, PyValueError};
use pyo3::panic::PanicException;
use pyo3::prelude::*;
use pyo3::types::PyString;

pyo3::import_exception!(px4params.errors, CodecError);
pyo3::import_exception!(px4params.errors, EncodeError);
pyo3::import_exception!(px4params.errors, DecodeError);
pyo3::import_exception!(px4params.errors, ValueShapeError);
pyo3::import_exception!(px4params.errors, LeafError);
pyo3::import_exception!(px4params.errors, StoreError);
pyo3::import_exception!(px4params.errors, InstanceError);
pyo3::import_exception!(px4params.errors, StoreFileError);
pyo3::import_exception!(px4params.errors, TransferError);

/// Which operation failed, to pick the exception class.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum Op {
    Encode,
    Decode,
    Leaf,
}

/// What a field takes, for a Python value of another kind.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Expected {
    Integer,
    Number,
    Boolean,
    Struct,
    Array,
}

/// What the binding finds wrong with a Python value while reading it for the core's encoder
/// (the DroneCAN rules' own refusals are the core's [`ErrorKind`]s). The core's walk adds the
/// field's path; [`codec`] words it.
pub(crate) enum ValueError<'py> {
    /// `value` is not of the kind the field takes.
    WrongType {
        expected: Expected,
        value: Bound<'py, PyAny>,
    },
    /// Text given for a float that names no number (as read: trimmed, lower case).
    NotANumber { text: String },
    /// An integer beyond 64 bits, outside the field's `min..=max` (the core's
    /// `ScalarError::OutOfRange` for the numbers a [`Scalar`] holds).
    OutOfRange {
        value: Bound<'py, PyAny>,
        min: Scalar,
        max: Scalar,
    },
    /// An integer given for a float that no float64 holds (beyond ±1.8e308).
    BeyondFloat64 { value: Bound<'py, PyAny> },
    /// An integer other than 0 and 1 for a boolean.
    NotABoolean { value: Bound<'py, PyAny> },
    /// A struct's key that names none of its fields (`fields`, padding left out).
    UnknownField {
        key: Bound<'py, PyAny>,
        fields: Vec<String>,
    },
    /// A union given as something other than a dict.
    NotAUnion {
        value: Bound<'py, PyAny>,
        variants: Vec<String>,
    },
    /// A union's dict of `keys` keys: it takes exactly one.
    UnionKeys { keys: usize, variants: Vec<String> },
    /// A union's key that names none of its variants.
    UnknownVariant {
        key: Bound<'py, PyAny>,
        variants: Vec<String>,
    },
    /// A str for an array of bytes that has lone surrogates (no UTF-8 encoding).
    NotUtf8,
    /// Python raised while the value was read: propagated as it is.
    Py(PyErr),
}

impl From<PyErr> for ValueError<'_> {
    fn from(e: PyErr) -> Self {
        Self::Py(e)
    }
}

/// The names of `fields` (padding, unnamed, left out), as a value error lists them.
pub(crate) fn names_of(layout: &Layout<'_>, fields: &[Field]) -> Vec<String> {
    let names = fields.iter().map(|f| layout.name(f));
    names.filter(|n| !n.is_empty()).map(str::to_owned).collect()
}

/// Which exception a codec error raises.
#[derive(Clone, Copy)]
pub(crate) enum Class {
    Encode,
    Shape,
    Decode,
    Leaf,
}

impl Class {
    fn new_err(self, message: String) -> PyErr {
        match self {
            Class::Encode => EncodeError::new_err(message),
            Class::Shape => ValueShapeError::new_err(message),
            Class::Decode => DecodeError::new_err(message),
            Class::Leaf => LeafError::new_err(message),
        }
    }
}

/// A value source's or sink's own error: its class and words, or the exception Python code
/// raised (propagated unchanged). (`Display`, the same words, is what the core's errors need
/// to show themselves.)
pub(crate) trait SourceError: fmt::Display {
    fn described(self) -> Result<(Class, String), PyErr>;
}

impl SourceError for std::convert::Infallible {
    fn described(self) -> Result<(Class, String), PyErr> {
        match self {}
    }
}

/// The name of `value`'s type, as messages say `got int`.
fn type_name(value: &Bound<'_, PyAny>) -> String {
    let name = value.get_type().name();
    name.map_or_else(|_| "?".into(), |n| n.to_string())
}

fn scalar_text(value: Scalar) -> String {
    match value {
        Scalar::Uint(v) => v.to_string(),
        Scalar::Int(v) => v.to_string(),
        Scalar::Float(v) => v.to_string(),
        Scalar::Bool(v) => v.to_string(),
    }
}

impl ValueError<'_> {
    fn class(&self) -> Class {
        match self {
            Self::OutOfRange { .. } | Self::BeyondFloat64 { .. } | Self::NotABoolean { .. } => {
                Class::Encode
            }
            _ => Class::Shape,
        }
    }

    /// The words (the raised exception's own for [`ValueError::Py`]); `Err` when showing the
    /// value raised.
    fn words(&self) -> PyResult<String> {
        let expected = |e: &Expected| match e {
            Expected::Integer => "an integer",
            Expected::Number => "a number",
            Expected::Boolean => "a boolean",
            Expected::Struct => "a dict (struct)",
            Expected::Array => "a list (array)",
        };
        Ok(match self {
            Self::WrongType { expected: e, value } => {
                format!("expected {}, got {}", expected(e), type_name(value))
            }
            Self::NotANumber { text } => {
                format!("expected a number (or \"nan\", \"inf\", \"-inf\"), got '{text}'")
            }
            Self::OutOfRange { value, min, max } => format!(
                "value {} is out of range (expected {} to {})",
                value.str()?,
                scalar_text(*min),
                scalar_text(*max)
            ),
            Self::BeyondFloat64 { value } => format!(
                "value {} is out of range of a float64 (at most ±1.8e308)",
                value.str()?
            ),
            Self::NotABoolean { value } => format!(
                "value {} is out of range (expected a boolean: true, false, 0 or 1)",
                value.str()?
            ),
            Self::UnknownField { key, fields } => format!(
                "unknown field {} (expected: {})",
                key.repr()?,
                fields.join(", ")
            ),
            Self::NotAUnion { value, variants } => format!(
                "expected a dict with one key, the union variant ({}), got {}",
                variants.join(", "),
                type_name(value)
            ),
            Self::UnionKeys { keys, variants } => format!(
                "a union takes exactly one variant ({}), got {keys} keys",
                variants.join(", ")
            ),
            Self::UnknownVariant { key, variants } => format!(
                "unknown union variant {} (expected one of: {})",
                key.repr()?,
                variants.join(", ")
            ),
            Self::NotUtf8 => "expected a str encodable as UTF-8 (it has lone surrogates)".into(),
            Self::Py(e) => e.to_string(),
        })
    }
}

impl fmt::Display for ValueError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.words() {
            Ok(text) => f.write_str(&text),
            Err(raised) => write!(f, "{raised}"),
        }
    }
}

impl SourceError for ValueError<'_> {
    fn described(self) -> Result<(Class, String), PyErr> {
        match self {
            Self::Py(e) => Err(e),
            error => Ok((error.class(), error.words()?)),
        }
    }
}

/// A codec error of a value of type `type_name` (or of an instance so named): one line
/// `TYPE: PATH: what (at bit N)`, with `path` and `bit_offset` attributes.
pub(crate) fn codec<E: SourceError>(
    py: Python<'_>,
    type_name: &str,
    layout: &Layout<'_>,
    err: Error<E>,
    op: Op,
) -> PyErr {
    let path = err.path.display(layout).to_string();
    let (class, text) = match err.kind {
        ErrorKind::Value(e) => match e.described() {
            Ok(described) => described,
            Err(raised) => return raised,
        },
        kind => {
            let data_fault = matches!(
                kind,
                ErrorKind::Truncated { .. }
                    | ErrorKind::TrailingBytes { .. }
                    | ErrorKind::BadUnionTag { .. }
                    | ErrorKind::TooDeep
            ) || (op == Op::Decode
                && matches!(kind, ErrorKind::ArrayTooLong { .. }));
            let class = match kind {
                _ if data_fault => Class::Decode,
                ErrorKind::MissingField | ErrorKind::WrongArrayLength { .. } => Class::Shape,
                ErrorKind::NoSuchLeaf { .. }
                | ErrorKind::NoSuchPath
                | ErrorKind::NotALeaf
                | ErrorKind::VariantNotSelected => Class::Leaf,
                _ => Class::Encode,
            };
            let text = match data_fault {
                true => format!("{kind} (at bit {})", err.bit_offset),
                false => kind.to_string(),
            };
            (class, text)
        }
    };
    let bit_offset = (op != Op::Encode).then_some(err.bit_offset);
    raise(py, class, type_name, path, text, bit_offset)
}

/// `TYPE: PATH: text` (no `PATH: ` for the value itself) as `class`, with its position.
fn raise(
    py: Python<'_>,
    class: Class,
    type_name: &str,
    path: String,
    text: String,
    bit_offset: Option<usize>,
) -> PyErr {
    let message = match path.is_empty() {
        true => format!("{type_name}: {text}"),
        false => format!("{type_name}: {path}: {text}"),
    };
    let exc = class.new_err(message);
    let value = exc.value(py);
    let _ = value.setattr("path", path);
    let _ = value.setattr("bit_offset", bit_offset);
    exc
}

/// A value problem outside a codec walk (a leaf value given to `set_leaf`, at `path`), classed
/// and worded as [`codec`] does.
pub(crate) fn value(py: Python<'_>, type_name: &str, path: String, error: ValueError) -> PyErr {
    match error.described() {
        Ok((class, text)) => raise(py, class, type_name, path, text, None),
        Err(raised) => raised,
    }
}

/// A store error of instance `name` (`INA238#2`) of parameter `param_name` (`INA238`), in the
/// core's words.
pub(crate) fn store<E: SourceError>(
    py: Python<'_>,
    name: &str,
    param_name: &str,
    layout: &Layout<'_>,
    err: CoreStoreError<E>,
    op: Op,
) -> PyErr {
    let words = |err: &CoreStoreError<E>| err.display(layout).to_string();
    match err {
        CoreStoreError::Codec(e) => codec(py, name, layout, e, op),
        CoreStoreError::Full { .. } => {
            InstanceError::new_err(format!("{param_name}: {}", words(&err)))
        }
        CoreStoreError::VersionLeaf { .. }
        | CoreStoreError::Memory { .. }
        | CoreStoreError::Unsupported { .. }
        | CoreStoreError::PagesFull { .. }
        | CoreStoreError::UnequalPages => StoreError::new_err(format!("{name}: {}", words(&err))),
        _ => InstanceError::new_err(format!("{name}: {}", words(&err))),
    }
}

/// A store error while the store is planned, its parameter named by `names` (the user knows
/// it by its name): the core words it with the names given as data.
pub(crate) fn store_plan(layout: &Layout<'_>, err: CoreStoreError, names: &[String]) -> PyErr {
    StoreError::new_err(err.display_named(layout, names).to_string())
}

/// A stored value that does not translate to another version of its type.
pub(crate) fn translate(layout: &Layout<'_>, err: Error<TranslateError>) -> PyErr {
    StoreError::new_err(err.display(layout).to_string())
}

/// A store file that does not check, found at `where` (the caller's path, passed through as
/// it is: a file name that is not UTF-8 holds surrogate escapes, which a Rust `str` refuses):
/// `StoreFileError(message, where, offset)`.
pub(crate) fn store_file(err: FileError<'_>, r#where: &Bound<'_, PyString>) -> PyErr {
    StoreFileError::new_err((err.to_string(), r#where.clone().unbind(), err.offset))
}

/// A store whose file cannot be written.
pub(crate) fn save(err: SaveError) -> PyErr {
    PyValueError::new_err(err.to_string())
}

/// CAN frames that do not make a transfer.
pub(crate) fn transfer(err: CoreTransferError) -> PyErr {
    TransferError::new_err(err.to_string())
}

/// A schema model (the dicts of `px4params.dsdl.loader`) the binding cannot compile.
pub(crate) enum ModelError<'a> {
    /// `what` (a type, or a field `TYPE.FIELD`) has no entry `key`.
    NoEntry { what: &'a str, key: String },
    /// A type that contains itself.
    Recursive { key: &'a str },
    /// A type the model does not define.
    UnknownType { key: &'a str },
    /// A field type of an unknown kind.
    UnknownKind { what: &'a str, kind: String },
    /// The core refused the type (a bit length out of range, a union of one variant, ...).
    Layout { what: &'a str, err: BuildError },
}

impl From<ModelError<'_>> for PyErr {
    fn from(err: ModelError<'_>) -> PyErr {
        PyValueError::new_err(match err {
            ModelError::NoEntry { what, key } => format!("schema model: {what} has no '{key}'"),
            ModelError::Recursive { key } => format!("schema model: type {key} contains itself"),
            ModelError::UnknownType { key } => format!("schema model: unknown type {key}"),
            ModelError::UnknownKind { what, kind } => {
                format!("schema model: {what}: unknown type kind '{kind}'")
            }
            ModelError::Layout { what, err } => format!("schema model: {what}: {err}"),
        })
    }
}

/// The binding's refusals of a call (its arguments, not a value's contents).
pub(crate) enum Refusal<'a, 'py> {
    /// A leaf named by an int below 0 or beyond any value's leaves.
    NoLeaf { index: &'a Bound<'py, PyAny> },
    /// A leaf named by neither an int nor a str.
    LeafTarget { target: &'a Bound<'py, PyAny> },
    /// No type of this key in the schema.
    NoType { key: &'a str },
    /// `decode_struct` of a union type.
    UnionStruct { key: &'a str },
    /// Data of a type nested deeper than the codec walks (which has no program).
    TooDeep { key: &'a str },
    /// A store parameter of a type the schema does not have.
    ParamType { name: &'a str, key: &'a str },
    /// A store parameter of `max_instances` 0.
    NoInstances { name: &'a str },
    /// `Store.restore` given a store that is not a copy of this one.
    NotACopy,
    /// A struct value's attribute that is none of its fields.
    NoField {
        key: &'a str,
        name: &'a Bound<'py, pyo3::types::PyString>,
        fields: Vec<String>,
    },
}

impl From<Refusal<'_, '_>> for PyErr {
    fn from(refusal: Refusal<'_, '_>) -> PyErr {
        match refusal {
            Refusal::NoLeaf { index } => {
                let text = index.str().map(|t| t.to_string()).unwrap_or_default();
                let shown = match text.len() {
                    1..=32 => text,
                    _ => "a number of more than 32 digits".into(),
                };
                LeafError::new_err(format!("no leaf [{shown}] (leaf indices are 0 and up)"))
            }
            Refusal::LeafTarget { target } => PyTypeError::new_err(format!(
                "a leaf is named by its index [k] (int >= 0) or a path (str), got {}",
                type_name(target)
            )),
            Refusal::NoType { key } => PyKeyError::new_err(key.to_owned()),
            Refusal::UnionStruct { key } => PyTypeError::new_err(format!(
                "{key}: a union has no struct value; decode() gives its one-key dict"
            )),
            Refusal::TooDeep { key } => DecodeError::new_err(format!(
                "{key}: the type nests deeper than {MAX_DEPTH} levels"
            )),
            Refusal::ParamType { name, key } => {
                PyValueError::new_err(format!("parameter {name}: unknown type {key}"))
            }
            Refusal::NoInstances { name } => PyValueError::new_err(format!(
                "parameter {name}: max_instances must be at least 1"
            )),
            Refusal::NotACopy => PyValueError::new_err(
                "restore takes a copy of this store (same schema and parameters)",
            ),
            Refusal::NoField { key, name, fields } => PyAttributeError::new_err(format!(
                "{key} has no field '{name}' (its fields: {})",
                fields.join(", ")
            )),
        }
    }
}

/// `err`, told that it comes from item `index` of a batch: `item N:` before the message and
/// an `index` attribute on px4params' own codec errors, a note on anything else.
pub(crate) fn at_item(py: Python<'_>, err: PyErr, index: usize) -> PyErr {
    let value = err.value(py);
    // Failing to reword the error (no memory) leaves it as it was: still the right error.
    if value.is_instance_of::<CodecError>() {
        let message = format!("item {index}: {value}");
        let _ = value.setattr("args", (message,));
        let _ = value.setattr("index", index);
    } else {
        let _ = value.call_method1("add_note", (format!("(item {index} of the batch)"),));
    }
    err
}

/// A Rust panic, as pyo3 raises one: `PanicException` with the panic's message.
pub(crate) fn panic(payload: Box<dyn Any + Send>) -> PyErr {
    let text = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned());
    PanicException::new_err(text.unwrap_or_else(|| "panic from Rust code".into()))
}

/// A fast-call method called before the module installed it.
pub(crate) fn not_installed() -> PyErr {
    PanicException::new_err("px4params: DataType methods not installed")
}
