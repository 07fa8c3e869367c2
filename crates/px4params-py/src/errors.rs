//! The one boundary where the core's errors (and a Python value's conversion errors) become
//! the exception classes of `px4params.errors`, which Python owns. Every message is one line
//! and names the type, instance or file, the path and what was expected.

use px4params_core::error::{Error, ErrorKind};
use px4params_core::layout::Layout;
use px4params_core::store::StoreError as CoreStoreError;
use pyo3::prelude::*;

use crate::values::ValueError;

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

/// Which exception a value problem raises.
pub(crate) enum Class {
    /// Wrong shape or kind: `ValueShapeError`.
    Shape,
    /// A number outside its field: `EncodeError`.
    Range,
}

/// How a value source's or sink's own error becomes an exception.
pub(crate) trait ValueErrorClass: std::fmt::Display {
    /// The class, or the exception Python code raised (propagated unchanged).
    fn class(self) -> Result<Class, PyErr>;
}

impl ValueErrorClass for ValueError {
    fn class(self) -> Result<Class, PyErr> {
        match self {
            ValueError::Shape(_) => Ok(Class::Shape),
            ValueError::Range(_) => Ok(Class::Range),
            ValueError::Py(e) => Err(e),
        }
    }
}

impl ValueErrorClass for std::convert::Infallible {
    fn class(self) -> Result<Class, PyErr> {
        match self {}
    }
}

/// A codec error of a value of type `type_name` (or of an instance so named): one line
/// `TYPE: PATH: what (at bit N)`, with `path` and `bit_offset` attributes.
pub(crate) fn codec<E: ValueErrorClass>(
    py: Python<'_>,
    type_name: &str,
    layout: &Layout<'_>,
    err: Error<E>,
    op: Op,
) -> PyErr {
    let path = err.path.display(layout).to_string();
    let kind = err.kind;
    let mut text = match &kind {
        ErrorKind::Value(e) => e.to_string(),
        k => k.to_string(),
    };
    if !path.is_empty() {
        text = format!("{path}: {text}");
    }
    let data_fault = matches!(
        kind,
        ErrorKind::Truncated { .. }
            | ErrorKind::TrailingBytes { .. }
            | ErrorKind::BadUnionTag { .. }
            | ErrorKind::TooDeep
    ) || (op == Op::Decode && matches!(kind, ErrorKind::ArrayTooLong { .. }));
    if data_fault {
        text = format!("{text} (at bit {})", err.bit_offset);
    }
    let message = format!("{type_name}: {text}");
    let exc = match kind {
        ErrorKind::Value(e) => match e.class() {
            Ok(class) => of_class(class, message),
            Err(raised) => return raised,
        },
        _ if data_fault => DecodeError::new_err(message),
        ErrorKind::MissingField | ErrorKind::WrongArrayLength { .. } => {
            ValueShapeError::new_err(message)
        }
        ErrorKind::NoSuchLeaf { .. }
        | ErrorKind::NoSuchPath
        | ErrorKind::NotALeaf
        | ErrorKind::VariantNotSelected => LeafError::new_err(message),
        _ => EncodeError::new_err(message),
    };
    set_position(py, &exc, path, (op != Op::Encode).then_some(err.bit_offset));
    exc
}

fn of_class(class: Class, message: String) -> PyErr {
    match class {
        Class::Shape => ValueShapeError::new_err(message),
        Class::Range => EncodeError::new_err(message),
    }
}

fn set_position(py: Python<'_>, exc: &PyErr, path: String, bit_offset: Option<usize>) {
    let value = exc.value(py);
    let _ = value.setattr("path", path);
    let _ = value.setattr("bit_offset", bit_offset);
}

/// A value problem outside a codec walk (a leaf value given to `set_leaf`), classed as
/// [`codec`] classes it.
pub(crate) fn value(py: Python<'_>, type_name: &str, path: &str, error: ValueError) -> PyErr {
    let message = format!("{type_name}: {path}: {error}");
    match error.class() {
        Ok(class) => {
            let exc = of_class(class, message);
            set_position(py, &exc, path.to_owned(), None);
            exc
        }
        Err(raised) => raised,
    }
}

/// Data of a type nested deeper than the codec walks, which has no program, decoded anyway.
pub(crate) fn too_deep(type_name: &str) -> PyErr {
    DecodeError::new_err(format!(
        "{type_name}: the type nests deeper than {} levels",
        px4params_core::codec::MAX_DEPTH
    ))
}

/// A leaf named by an index that no value has (negative, or beyond any count).
pub(crate) fn no_leaf(shown: &str) -> PyErr {
    LeafError::new_err(format!("no leaf [{shown}] (leaf indices are 0 and up)"))
}

/// A store error of instance `name` (`INA238#2`) of parameter `param_name` (`INA238`).
pub(crate) fn store<E: ValueErrorClass>(
    py: Python<'_>,
    name: &str,
    param_name: &str,
    layout: &Layout<'_>,
    err: CoreStoreError<E>,
    op: Op,
) -> PyErr {
    match err {
        CoreStoreError::Codec(e) => codec(py, name, layout, e, op),
        CoreStoreError::VersionLeaf { path } => {
            let error: CoreStoreError = CoreStoreError::VersionLeaf { path };
            StoreError::new_err(format!("{name}: {}", error.display(layout)))
        }
        CoreStoreError::Full { .. } => {
            InstanceError::new_err(format!("{param_name}: {}", err.display(layout)))
        }
        CoreStoreError::Memory { .. }
        | CoreStoreError::Unsupported { .. }
        | CoreStoreError::PagesFull { .. }
        | CoreStoreError::UnequalPages => {
            StoreError::new_err(format!("{name}: {}", err.display(layout)))
        }
        _ => InstanceError::new_err(format!("{name}: {}", err.display(layout))),
    }
}

/// A store error while the store is planned, the parameter numbered `param` in the core's
/// message named `name` (the user knows it by its name).
pub(crate) fn store_plan(layout: &Layout<'_>, err: CoreStoreError, names: &[String]) -> PyErr {
    let text = err.display(layout).to_string();
    match err {
        CoreStoreError::NoSuchParam { param }
        | CoreStoreError::NotPlanned { param }
        | CoreStoreError::Unsupported { param } => {
            let name = names.get(param as usize).map_or("?", String::as_str);
            StoreError::new_err(
                text.replace(&format!("parameter #{param}"), &format!("parameter {name}")),
            )
        }
        _ => StoreError::new_err(text),
    }
}

/// A stored value that does not translate to another version of its type.
pub(crate) fn translate(message: String) -> PyErr {
    StoreError::new_err(message)
}

/// A store file that does not check, found at `where`, its fault at byte `offset`.
pub(crate) fn store_file(message: String, r#where: &str, offset: usize) -> PyErr {
    StoreFileError::new_err((message, r#where.to_owned(), offset))
}

/// CAN frames that do not make a transfer.
pub(crate) fn transfer(message: String) -> PyErr {
    TransferError::new_err(message)
}
