//! Compiled schemas: a flat table of nodes with their bit lengths precomputed.
//!
//! A layout is plain data borrowed as slices, so firmware can keep one in `static` tables and
//! a host can build one at run time (feature `alloc`, [`crate::build`]). Nodes refer to each
//! other by index; a nested type used in many places is one shared node.

use crate::bits::Order;
use crate::scalar::Cast;

/// Index of a node in [`Layout::nodes`].
pub type NodeId = u32;

/// What a node is.
// `repr(C, u8)` here and on the other table types: firmware keeps layouts in `const` C tables
// (`px4params metadata --firmware`), so their memory layout is C's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, u8)]
pub enum Kind {
    /// `uintN`, `1 <= N <= 64`.
    Uint {
        /// Bit length.
        bits: u8,
        /// Cast mode.
        cast: Cast,
    },
    /// `intN`, `2 <= N <= 64`.
    Int {
        /// Bit length.
        bits: u8,
        /// Cast mode.
        cast: Cast,
    },
    /// `float16`, `float32` or `float64`.
    Float {
        /// Bit length.
        bits: u8,
        /// Cast mode.
        cast: Cast,
    },
    /// `bool`: one bit.
    Bool,
    /// `voidN`: N zero bits, no value.
    Void {
        /// Bit length.
        bits: u8,
    },
    /// A structure: `count` fields starting at `first` in [`Layout::fields`].
    Struct {
        /// First field.
        first: u32,
        /// Number of fields.
        count: u32,
    },
    /// A union: a tag of `tag_bits` bits, then the selected one of `count` variants.
    Union {
        /// First variant in [`Layout::fields`].
        first: u32,
        /// Number of variants.
        count: u32,
        /// Width of the tag: `ceil(log2(count))`.
        tag_bits: u8,
    },
    /// `T[N]`.
    Array {
        /// Element node.
        elem: NodeId,
        /// Number of elements.
        len: u32,
    },
    /// `T[<=N]`: a length prefix of `len_bits` bits (unless tail-array optimized), then elements.
    DynArray {
        /// Element node.
        elem: NodeId,
        /// Maximum number of elements.
        max: u32,
        /// Width of the length prefix: `ceil(log2(max + 1))`.
        len_bits: u8,
    },
}

/// A range of entries in one of the layout's tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[repr(C)]
pub struct Span {
    /// First entry.
    pub first: u32,
    /// Number of entries.
    pub count: u32,
}

impl Span {
    /// The entries of `table` in this span (empty when out of bounds).
    #[inline]
    pub fn of<T>(self, table: &[T]) -> &[T] {
        table
            .get(self.first as usize..(self.first + self.count) as usize)
            .unwrap_or(&[])
    }
}

/// One primitive position of a flattened fixed-shape value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, u8)]
pub enum FlatItem {
    /// A primitive leaf (one of the scalar kinds).
    Leaf(Kind),
    /// A `p_version` leaf and the type's version.
    Version(Kind, u32),
    /// Padding bits.
    Pad(u8),
}

/// A piece of a struct, for walking flat leaf lists quickly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, u8)]
pub enum Segment {
    /// Consecutive fixed-shape fields, flattened to primitive items.
    Flat {
        /// The fields, in [`Layout::fields`].
        fields: Span,
        /// Their items, in [`Layout::flat`].
        items: Span,
        /// Number of leaves (items that are not padding).
        leaves: u32,
        /// Total bit length.
        bits: u32,
        /// The nesting the run covers: the most nodes from one of its fields down to a
        /// primitive (1 for a primitive field). A plan that steps over the run declines where
        /// the struct's depth plus this passes [`crate::rules::MAX_DEPTH`], as the walk
        /// refuses such a type.
        height: u32,
    },
    /// A field containing a union or a dynamic array: its index in [`Layout::fields`].
    Field(u32),
}

/// A node with its precomputed sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct Node {
    /// What the node is.
    pub kind: Kind,
    /// Smallest encoded length in bits (without tail array optimization).
    pub min_bits: u64,
    /// Largest encoded length in bits (without tail array optimization).
    pub max_bits: u64,
    /// For nodes without unions or dynamic arrays inside: the number of leaves; [`VARIABLE`]
    /// for the others (see [`Node::fixed_leaves`]).
    pub leaves: u32,
    /// For structs: the struct split into [`Segment`]s (in [`Layout::segments`]).
    pub segments: Span,
}

/// [`Node::leaves`] of a node whose shape varies (it has a union or a dynamic array inside).
pub const VARIABLE: u32 = u32::MAX;

impl Node {
    /// For nodes without unions or dynamic arrays inside: the number of leaves. Such a node
    /// always encodes to exactly `min_bits` bits, so it can be skipped without reading it.
    #[inline]
    pub fn fixed_leaves(&self) -> Option<u32> {
        (self.leaves != VARIABLE).then_some(self.leaves)
    }
}

/// What a field of a struct (or a union variant) is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, u8)]
pub enum Role {
    /// An ordinary field.
    Data,
    /// A `voidN` field: padding, no value.
    Padding,
    /// The `p_version` field: written with this value when the input leaves it out.
    Version(u32),
}

/// A named member of a struct or union.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct Field {
    /// Start of the name in [`Layout::names`].
    pub name_start: u32,
    /// Length of the name in bytes.
    pub name_len: u32,
    /// The field's type.
    pub node: NodeId,
    /// What the field is for.
    pub role: Role,
}

/// A compiled schema, borrowed.
#[derive(Clone, Copy, Debug)]
pub struct Layout<'a> {
    /// All nodes.
    pub nodes: &'a [Node],
    /// All struct fields and union variants, each struct's or union's contiguous.
    pub fields: &'a [Field],
    /// All field names, concatenated.
    pub names: &'a str,
    /// Struct segments, each struct's contiguous.
    pub segments: &'a [Segment],
    /// Flattened items of fixed-shape runs.
    pub flat: &'a [FlatItem],
    /// The straight-line plan of each node that has one, by [`NodeId`]
    /// ([`crate::straight`]; compiled by [`crate::compile`], empty in firmware's tables).
    pub straight: &'a [Option<Straight>],
}

impl<'a> Layout<'a> {
    /// The node with this index.
    #[inline]
    pub fn node(&self, id: NodeId) -> &'a Node {
        &self.nodes[id as usize]
    }

    /// A field's name.
    #[inline]
    pub fn name(&self, field: &Field) -> &'a str {
        let start = field.name_start as usize;
        self.names
            .get(start..start + field.name_len as usize)
            .unwrap_or("?")
    }

    /// The fields of a struct or the variants of a union (empty for other nodes).
    #[inline]
    pub fn members(&self, id: NodeId) -> &'a [Field] {
        match self.node(id).kind {
            Kind::Struct { first, count } | Kind::Union { first, count, .. } => {
                &self.fields[first as usize..(first + count) as usize]
            }
            _ => &[],
        }
    }

    /// The position in [`Layout::fields`] of a member of `id` found by name.
    pub fn member_index(&self, id: NodeId, name: &str) -> Option<u32> {
        let first = match self.node(id).kind {
            Kind::Struct { first, .. } | Kind::Union { first, .. } => first,
            _ => return None,
        };
        self.members(id)
            .iter()
            .position(|f| self.name(f) == name)
            .map(|i| first + i as u32)
    }

    /// Largest encoded length of `id` in bytes.
    pub fn max_bytes(&self, id: NodeId) -> usize {
        self.node(id).max_bits.div_ceil(8) as usize
    }
}

/// Width of a union tag for `count` variants: `ceil(log2(count))`.
pub const fn union_tag_bits(count: u32) -> u8 {
    if count <= 1 {
        0
    } else {
        (32 - (count - 1).leading_zeros()) as u8
    }
}

/// Width of a dynamic array's length prefix: `ceil(log2(max + 1))`.
pub const fn array_len_bits(max: u32) -> u8 {
    (32 - max.leading_zeros()) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefix_widths_follow_the_spec() {
        assert_eq!(union_tag_bits(2), 1);
        assert_eq!(union_tag_bits(3), 2);
        assert_eq!(union_tag_bits(6), 3);
        assert_eq!(union_tag_bits(8), 3);
        assert_eq!(union_tag_bits(9), 4);
        assert_eq!(array_len_bits(1), 1);
        assert_eq!(array_len_bits(7), 3);
        assert_eq!(array_len_bits(8), 4);
        assert_eq!(array_len_bits(31), 5);
        assert_eq!(array_len_bits(255), 8);
    }
}

/// The dynamic array of primitives that may end a straight-line type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Tail {
    /// The element's kind (a primitive).
    pub(crate) elem: Kind,
    /// Its width in bits.
    pub(crate) elem_bits: u32,
    /// Largest length.
    pub(crate) max: u32,
    /// Bits of the length prefix as encoded without and with tail array optimization (which
    /// drops it for elements of 8 bits or more: the array then takes the remaining whole
    /// bytes).
    pub(crate) prefixes: [u8; 2],
    /// Whether the elements are bytes (`uint8`).
    pub(crate) bytes: bool,
}

impl Tail {
    /// Bits of the length prefix as encoded with or without tail array optimization.
    #[inline(always)]
    pub(crate) fn prefix(&self, tao: bool) -> u32 {
        self.prefixes[usize::from(tao)].into()
    }
}

/// The straight-line plan of a type, compiled once ([`crate::straight::compile`], by
/// [`crate::compile::OwnedLayout`] for each struct) and kept in [`Layout::straight`] at the
/// type's node, so that choosing it is one load: a struct whose fields are its fixed run
/// (the layout's one flat segment of it), then perhaps one dynamic array of primitives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Straight {
    /// The fixed run's items in [`Layout::flat`], in stream order (none when the struct is
    /// the array alone).
    pub(crate) items: Span,
    /// Leaves of the fixed run.
    pub(crate) leaves: u32,
    /// Bits of the fixed run.
    pub(crate) bits: u32,
    pub(crate) tail: Option<Tail>,
    /// The fixed run as steps, where it fits one 64-bit register and [`SMALL_STEPS`] steps.
    pub(crate) small: Option<Small>,
}

/// Most items of a fixed run that a [`Small`] plan holds.
pub(crate) const SMALL_STEPS: usize = 8;

/// A fixed run of at most 64 bits as steps held in the plan itself: what a small value
/// costs is the steps, without a look into [`Layout::flat`] or a match on [`Kind`] per item.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Small {
    /// The steps, then steps of 0 bits.
    pub(crate) steps: [Step; SMALL_STEPS],
    /// The type's version, for its [`Op::Version`] step (at most one).
    pub(crate) version: u32,
}

/// One item of a [`Small`] plan: what it is, its width in bits (`1..=64`; 0 ends the
/// steps) and how its bytes are ordered in the stream.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Step {
    pub(crate) op: Op,
    pub(crate) bits: u8,
    pub(crate) order: Order,
}

/// What a [`Step`] is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(u8)]
pub(crate) enum Op {
    /// Padding: zeros, no leaf.
    #[default]
    Pad,
    Uint,
    Int,
    Float16,
    Float32,
    Float64,
    Bool,
    /// A `p_version` field (an unsigned integer): the type's version unless versions are kept
    /// as given.
    Version,
}
