//! Building a [`Layout`] at run time (feature `alloc`).

use alloc::string::String;
use alloc::vec::Vec;

use crate::layout::{
    array_len_bits, union_tag_bits, Field, FlatItem, Kind, Layout, Node, NodeId, Role, Segment,
    Span, VARIABLE,
};
use crate::scalar::Cast;

/// [`Node::leaves`] from a count that is `None` for a node whose shape varies.
fn leaves_or_variable(leaves: Option<u32>) -> u32 {
    leaves.filter(|&n| n != VARIABLE).unwrap_or(VARIABLE)
}

/// Why a type could not be compiled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildError {
    /// An integer or void bit length outside its allowed range.
    BadBitLength {
        /// The length given.
        bits: u32,
    },
    /// A float that is not 16, 32 or 64 bits wide.
    BadFloatLength {
        /// The length given.
        bits: u32,
    },
    /// A union needs at least two variants.
    UnionTooSmall,
    /// A dynamic array needs a maximum of at least one element.
    EmptyArray,
    /// A node index that does not exist (yet).
    UnknownNode(NodeId),
    /// A union variant that is padding.
    VoidVariant,
}

/// An owned, compiled schema; [`OwnedLayout::as_layout`] borrows it for the codec.
#[derive(Clone, Debug, Default)]
pub struct OwnedLayout {
    nodes: Vec<Node>,
    fields: Vec<Field>,
    names: String,
    segments: Vec<Segment>,
    flat: Vec<FlatItem>,
    /// By node: the straight-line plan compiled for it ([`crate::straight::compile`]).
    straight: Vec<Option<crate::straight::Straight>>,
    /// By node: the most nodes from it down to a primitive (1 for a primitive), for the
    /// height of flat segments.
    heights: Vec<u32>,
}

impl OwnedLayout {
    /// The layout, borrowed.
    pub fn as_layout(&self) -> Layout<'_> {
        Layout {
            nodes: &self.nodes,
            fields: &self.fields,
            names: &self.names,
            segments: &self.segments,
            flat: &self.flat,
            straight: &self.straight,
        }
    }

    /// Adds a node for `uintN`.
    pub fn uint(&mut self, bits: u32, cast: Cast) -> Result<NodeId, BuildError> {
        check_bits(bits, 1, 64)?;
        Ok(self.scalar(
            Kind::Uint {
                bits: bits as u8,
                cast,
            },
            bits,
        ))
    }

    /// Adds a node for `intN`.
    pub fn int(&mut self, bits: u32, cast: Cast) -> Result<NodeId, BuildError> {
        check_bits(bits, 2, 64)?;
        Ok(self.scalar(
            Kind::Int {
                bits: bits as u8,
                cast,
            },
            bits,
        ))
    }

    /// Adds a node for `float16`, `float32` or `float64`.
    pub fn float(&mut self, bits: u32, cast: Cast) -> Result<NodeId, BuildError> {
        if !matches!(bits, 16 | 32 | 64) {
            return Err(BuildError::BadFloatLength { bits });
        }
        Ok(self.scalar(
            Kind::Float {
                bits: bits as u8,
                cast,
            },
            bits,
        ))
    }

    /// Adds a node for `bool`.
    pub fn boolean(&mut self) -> NodeId {
        self.scalar(Kind::Bool, 1)
    }

    /// Adds a node for `voidN`.
    pub fn void(&mut self, bits: u32) -> Result<NodeId, BuildError> {
        check_bits(bits, 1, 64)?;
        Ok(self.push(Node {
            kind: Kind::Void { bits: bits as u8 },
            min_bits: u64::from(bits),
            max_bits: u64::from(bits),
            leaves: 0,
            segments: Span::default(),
        }))
    }

    /// Adds a node for `T[len]`.
    pub fn array(&mut self, elem: NodeId, len: u32) -> Result<NodeId, BuildError> {
        let e = *self.get(elem)?;
        Ok(self.push(Node {
            kind: Kind::Array { elem, len },
            min_bits: e.min_bits.saturating_mul(u64::from(len)),
            max_bits: e.max_bits.saturating_mul(u64::from(len)),
            leaves: leaves_or_variable(e.fixed_leaves().and_then(|l| l.checked_mul(len))),
            segments: Span::default(),
        }))
    }

    /// Adds a node for `T[<=max]`.
    pub fn dyn_array(&mut self, elem: NodeId, max: u32) -> Result<NodeId, BuildError> {
        if max == 0 {
            return Err(BuildError::EmptyArray);
        }
        let e = *self.get(elem)?;
        let len_bits = array_len_bits(max);
        Ok(self.push(Node {
            kind: Kind::DynArray {
                elem,
                max,
                len_bits,
            },
            min_bits: u64::from(len_bits),
            max_bits: e
                .max_bits
                .saturating_mul(u64::from(max))
                .saturating_add(u64::from(len_bits)),
            leaves: VARIABLE,
            segments: Span::default(),
        }))
    }

    /// Adds a structure with these `(name, node, role)` fields, in order.
    pub fn structure(&mut self, fields: &[(&str, NodeId, Role)]) -> Result<NodeId, BuildError> {
        let first = self.fields.len() as u32;
        let (mut min_bits, mut max_bits, mut leaves) = (0u64, 0u64, Some(0u32));
        for &(name, node, role) in fields {
            let n = *self.get(node)?;
            // Saturating: a size beyond u64 reads as u64::MAX instead of wrapping.
            min_bits = min_bits.saturating_add(n.min_bits);
            max_bits = max_bits.saturating_add(n.max_bits);
            leaves = match (leaves, n.fixed_leaves()) {
                (Some(a), Some(b)) => a.checked_add(b),
                _ => None,
            };
            self.add_field(name, node, role);
        }
        let segments = self.segment(first, fields.len() as u32);
        let id = self.push(Node {
            kind: Kind::Struct {
                first,
                count: fields.len() as u32,
            },
            min_bits,
            max_bits,
            leaves: leaves_or_variable(leaves),
            segments,
        });
        self.straight[id as usize] = crate::straight::compile(&self.as_layout(), id);
        Ok(id)
    }

    /// Adds a union with these `(name, node)` variants, in tag order.
    pub fn union(&mut self, variants: &[(&str, NodeId)]) -> Result<NodeId, BuildError> {
        if variants.len() < 2 {
            return Err(BuildError::UnionTooSmall);
        }
        let first = self.fields.len() as u32;
        let tag_bits = union_tag_bits(variants.len() as u32);
        let (mut min_bits, mut max_bits) = (u64::MAX, 0u64);
        for &(name, node) in variants {
            let n = *self.get(node)?;
            if matches!(n.kind, Kind::Void { .. }) {
                return Err(BuildError::VoidVariant);
            }
            min_bits = min_bits.min(n.min_bits);
            max_bits = max_bits.max(n.max_bits);
            self.add_field(name, node, Role::Data);
        }
        Ok(self.push(Node {
            kind: Kind::Union {
                first,
                count: variants.len() as u32,
                tag_bits,
            },
            min_bits: min_bits.saturating_add(u64::from(tag_bits)),
            max_bits: max_bits.saturating_add(u64::from(tag_bits)),
            leaves: VARIABLE,
            segments: Span::default(),
        }))
    }

    fn scalar(&mut self, kind: Kind, bits: u32) -> NodeId {
        // Scalars are interned: a schema of hundreds of types has a handful of distinct ones.
        if let Some(i) = self.nodes.iter().position(|n| n.kind == kind) {
            return i as NodeId;
        }
        self.push(Node {
            kind,
            min_bits: u64::from(bits),
            max_bits: u64::from(bits),
            leaves: 1,
            segments: Span::default(),
        })
    }

    /// Splits the struct's fields `first..first + count` into runs of fixed-shape fields
    /// (flattened) and single fields holding unions or dynamic arrays.
    fn segment(&mut self, first: u32, count: u32) -> Span {
        let start = self.segments.len() as u32;
        let mut i = first;
        while i < first + count {
            let field = self.fields[i as usize];
            if self.nodes[field.node as usize].fixed_leaves().is_none() {
                self.segments.push(Segment::Field(i));
                i += 1;
                continue;
            }
            let run_first = i;
            let items_first = self.flat.len() as u32;
            let (mut leaves, mut bits, mut height) = (0u32, 0u64, 0u32);
            while i < first + count {
                let f = self.fields[i as usize];
                let node = self.nodes[f.node as usize];
                let Some(n) = node.fixed_leaves() else { break };
                leaves += n;
                bits += node.min_bits;
                height = height.max(self.heights[f.node as usize]);
                match f.role {
                    Role::Version(v) => self.flat.push(FlatItem::Version(node.kind, v)),
                    _ => self.flatten(f.node),
                }
                i += 1;
            }
            self.segments.push(Segment::Flat {
                fields: Span {
                    first: run_first,
                    count: i - run_first,
                },
                items: Span {
                    first: items_first,
                    count: self.flat.len() as u32 - items_first,
                },
                leaves,
                bits: u32::try_from(bits).unwrap_or(u32::MAX),
                height,
            });
        }
        Span {
            first: start,
            count: self.segments.len() as u32 - start,
        }
    }

    /// Appends the flat items of a fixed-shape node.
    fn flatten(&mut self, id: NodeId) {
        let node = self.nodes[id as usize];
        match node.kind {
            Kind::Void { bits } => self.flat.push(FlatItem::Pad(bits)),
            Kind::Struct { first, count } => {
                for i in first..first + count {
                    let f = self.fields[i as usize];
                    match f.role {
                        Role::Version(v) => {
                            let kind = self.nodes[f.node as usize].kind;
                            self.flat.push(FlatItem::Version(kind, v));
                        }
                        _ => self.flatten(f.node),
                    }
                }
            }
            Kind::Array { elem, len } => {
                for _ in 0..len {
                    self.flatten(elem);
                }
            }
            // Unions and dynamic arrays are never fixed-shape.
            Kind::Union { .. } | Kind::DynArray { .. } => {}
            kind => self.flat.push(FlatItem::Leaf(kind)),
        }
    }

    fn get(&self, id: NodeId) -> Result<&Node, BuildError> {
        self.nodes
            .get(id as usize)
            .ok_or(BuildError::UnknownNode(id))
    }

    fn push(&mut self, node: Node) -> NodeId {
        // Below the node: its members' or elements' heights (those nodes exist already).
        let below = match node.kind {
            Kind::Struct { first, count } | Kind::Union { first, count, .. } => self.fields
                [first as usize..(first + count) as usize]
                .iter()
                .map(|f| self.heights[f.node as usize])
                .max()
                .unwrap_or(0),
            Kind::Array { elem, .. } | Kind::DynArray { elem, .. } => self.heights[elem as usize],
            _ => 0,
        };
        self.heights.push(below.saturating_add(1));
        self.nodes.push(node);
        self.straight.push(None);
        (self.nodes.len() - 1) as NodeId
    }

    fn add_field(&mut self, name: &str, node: NodeId, role: Role) {
        let name_start = self.names.len() as u32;
        self.names.push_str(name);
        self.fields.push(Field {
            name_start,
            name_len: name.len() as u32,
            node,
            role,
        });
    }
}

fn check_bits(bits: u32, min: u32, max: u32) -> Result<(), BuildError> {
    if (min..=max).contains(&bits) {
        Ok(())
    } else {
        Err(BuildError::BadBitLength { bits })
    }
}

impl core::fmt::Display for BuildError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadBitLength { bits } => write!(f, "bit length {bits} is out of range"),
            Self::BadFloatLength { bits } => {
                write!(
                    f,
                    "float{bits} does not exist (expected float16, float32 or float64)"
                )
            }
            Self::UnionTooSmall => f.write_str("a union needs at least two variants"),
            Self::EmptyArray => f.write_str("a dynamic array needs a maximum of at least 1"),
            Self::UnknownNode(id) => write!(f, "node {id} does not exist"),
            Self::VoidVariant => f.write_str("a union variant cannot be padding"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_saturate_instead_of_wrapping() {
        let mut layout = OwnedLayout::default();
        let mut node = layout.uint(8, Cast::Saturated).unwrap();
        for _ in 0..4 {
            node = layout.array(node, u32::MAX).unwrap();
        }
        let dynamic = layout.dyn_array(node, u32::MAX).unwrap();
        let layout = layout.as_layout();
        assert_eq!(layout.node(node).max_bits, u64::MAX);
        assert_eq!(layout.node(dynamic).max_bits, u64::MAX);
    }
}
