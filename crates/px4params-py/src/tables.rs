//! A store's layout and plan as plain tuples, for `px4params metadata --firmware` to write as
//! `const` C tables (the core's `repr(C)` table types, declared in the C ABI's header).

use px4params_core::layout::{FlatItem, Kind, Role, Segment};
use px4params_core::Cast;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::store::Store;

fn cast(c: Cast) -> &'static str {
    match c {
        Cast::Saturated => "Saturated",
        Cast::Truncated => "Truncated",
    }
}

/// `(variant, members...)` of a node kind, members as the C union's body names them.
fn kind<'py>(py: Python<'py>, k: Kind) -> PyResult<Bound<'py, PyTuple>> {
    let t = match k {
        Kind::Uint { bits, cast: c } => ("Uint", bits, cast(c)).into_pyobject(py)?,
        Kind::Int { bits, cast: c } => ("Int", bits, cast(c)).into_pyobject(py)?,
        Kind::Float { bits, cast: c } => ("Float", bits, cast(c)).into_pyobject(py)?,
        Kind::Bool => ("Bool",).into_pyobject(py)?,
        Kind::Void { bits } => ("Void", bits).into_pyobject(py)?,
        Kind::Struct { first, count } => ("Struct", first, count).into_pyobject(py)?,
        Kind::Union {
            first,
            count,
            tag_bits,
        } => ("Union", first, count, tag_bits).into_pyobject(py)?,
        Kind::Array { elem, len } => ("Array", elem, len).into_pyobject(py)?,
        Kind::DynArray {
            elem,
            max,
            len_bits,
        } => ("DynArray", elem, max, len_bits).into_pyobject(py)?,
    };
    Ok(t)
}

/// The store's tables: a dict of `nodes`, `fields`, `names`, `segments`, `flat`, `defs` and
/// `capacity`, and `roots` (key: root node).
pub(crate) fn tables<'py>(
    py: Python<'py>,
    store: &Store,
    roots: &[String],
) -> PyResult<Bound<'py, PyDict>> {
    let layout = store.layout();
    let out = PyDict::new(py);
    let mut nodes = Vec::new();
    for n in layout.nodes {
        let segments = (n.segments.first, n.segments.count);
        nodes.push((
            kind(py, n.kind)?,
            n.min_bits,
            n.max_bits,
            n.leaves,
            segments,
        ));
    }
    out.set_item("nodes", nodes)?;
    let mut fields = Vec::new();
    for f in layout.fields {
        let role = match f.role {
            Role::Data => ("Data", 0u32),
            Role::Padding => ("Padding", 0),
            Role::Version(v) => ("Version", v),
        };
        fields.push((f.name_start, f.name_len, f.node, role));
    }
    out.set_item("fields", fields)?;
    out.set_item("names", layout.names)?;
    let mut segments = Vec::new();
    for s in layout.segments {
        segments.push(match *s {
            Segment::Flat {
                fields,
                items,
                leaves,
                bits,
                height,
            } => (
                "Flat",
                (fields.first, fields.count),
                (items.first, items.count),
                leaves,
                bits,
                height,
            )
                .into_pyobject(py)?,
            Segment::Field(index) => ("Field", index).into_pyobject(py)?,
        });
    }
    out.set_item("segments", segments)?;
    let mut flat = Vec::new();
    for item in layout.flat {
        flat.push(match *item {
            FlatItem::Leaf(k) => ("Leaf", kind(py, k)?).into_pyobject(py)?,
            FlatItem::Version(k, v) => ("Version", kind(py, k)?, v).into_pyobject(py)?,
            FlatItem::Pad(bits) => ("Pad", bits).into_pyobject(py)?,
        });
    }
    out.set_item("flat", flat)?;
    let defs: Vec<_> = store
        .core()
        .defs()
        .iter()
        .map(|d| {
            (
                d.root,
                d.instances,
                d.shared,
                d.first_slot,
                d.first_byte,
                d.slot_bytes,
            )
        })
        .collect();
    out.set_item("defs", defs)?;
    out.set_item(
        "capacity",
        (store.capacity_of().slots, store.capacity_of().bytes),
    )?;
    let found = PyDict::new(py);
    for key in roots {
        let root = store.root_of(key)?;
        found.set_item(key, root)?;
    }
    out.set_item("roots", found)?;
    Ok(out)
}
