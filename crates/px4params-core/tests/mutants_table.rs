//! The leaf table's nesting bound (issue 40): the table covers a leaf no deeper than the walk
//! follows (`rules::MAX_DEPTH`, the root at depth 1, each field or element one deeper) and
//! leaves a deeper one to the walk, which refuses it; so the table answers as the walk does on
//! both sides of the bound, for elements of fixed arrays as for fields of structs.

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::Role;
use px4params_core::leaf::{get_leaf, Target};
use px4params_core::rules::MAX_DEPTH;
use px4params_core::table::{LeafSlot, LeafTable};
use px4params_core::{Cast, ErrorKind, NodeId, Scalar};

/// A uint8 at the bottom of `depth - 1` levels: fixed arrays of one element, or one-field
/// structs.
fn nested(l: &mut OwnedLayout, depth: usize, arrays: bool) -> NodeId {
    let mut node = l.uint(8, Cast::Saturated).unwrap();
    for _ in 1..depth {
        node = if arrays {
            l.array(node, 1).unwrap()
        } else {
            l.structure(&[("x", node, Role::Data)]).unwrap()
        };
    }
    node
}

/// Leaf [0] of the one-byte value 0x5A read through the table and by the walk.
fn both(depth: usize, arrays: bool) -> (Option<Scalar>, Option<Scalar>, Vec<ErrorKind<()>>) {
    let mut l = OwnedLayout::default();
    let root = nested(&mut l, depth, arrays);
    let layout = l.as_layout();
    let mut slots = vec![LeafSlot::default(); LeafTable::slots_needed(&layout, root).max(64)];
    let table = LeafTable::build(&layout, root, &mut slots).unwrap();
    let data = [0x5Au8];
    let tabled = table.get_leaf(&layout, &data[..], Target::Index(0), false);
    let walked = get_leaf(&layout, root, &data[..], Target::Index(0), false);
    let errors = [&tabled, &walked]
        .iter()
        .filter_map(|r| r.as_ref().err())
        .map(|e| e.kind.map_value(|never| match never {}))
        .collect();
    (
        tabled.ok().map(|(_, v)| v),
        walked.ok().map(|(_, v)| v),
        errors,
    )
}

#[test]
fn the_table_reads_a_leaf_exactly_max_depth_deep() {
    for arrays in [true, false] {
        let (tabled, walked, errors) = both(MAX_DEPTH, arrays);
        assert_eq!(walked, Some(Scalar::Uint(0x5A)), "arrays: {arrays}");
        assert_eq!(tabled, walked, "arrays: {arrays}");
        assert!(errors.is_empty());
    }
}

#[test]
fn the_table_leaves_a_deeper_leaf_to_the_walk_which_refuses_it() {
    for arrays in [true, false] {
        let (tabled, walked, errors) = both(MAX_DEPTH + 1, arrays);
        assert_eq!((tabled, walked), (None, None), "arrays: {arrays}");
        assert_eq!(errors, [ErrorKind::TooDeep, ErrorKind::TooDeep]);
    }
}

/// `LeafTable::read`, leaf by leaf, against the bytes worked by hand and the walk's
/// `leaf::seek`: each leaf's value, and whether it is the `p_version` field. The type is
/// `{p_version: uint8 (version 3), a: int16, u: {x: uint8 | y: bool}, b: uint8}`; the value
/// `{p_version: 3, a: -2, u: {y: true}, b: 0x5A}` is 03, FE FF (little-endian), then the bits
/// 1 (the tag: y), 1 (y), 0101 1010 (b) and zeros: D6 80. A built table is not empty.
#[test]
fn the_table_reads_each_leaf_and_tells_the_version_field() {
    use px4params_core::leaf::seek;
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let i16_ = l.int(16, Cast::Saturated).unwrap();
    let bool_ = l.boolean();
    let u = l.union(&[("x", u8_), ("y", bool_)]).unwrap();
    let root = l
        .structure(&[
            ("p_version", u8_, Role::Version(3)),
            ("a", i16_, Role::Data),
            ("u", u, Role::Data),
            ("b", u8_, Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    let mut slots = vec![LeafSlot::default(); LeafTable::slots_needed(&layout, root)];
    let table = LeafTable::build(&layout, root, &mut slots).unwrap();
    assert!(!table.is_empty());
    let data = [0x03u8, 0xFE, 0xFF, 0xD6, 0x80];
    let expected = [
        Some((Scalar::Uint(3), true)),
        Some((Scalar::Int(-2), false)),
        Some((Scalar::Uint(1), false)),
        Some((Scalar::Bool(true), false)),
        Some((Scalar::Uint(0x5A), false)),
        None,
    ];
    for (k, want) in expected.into_iter().enumerate() {
        let walked = seek(&layout, root, &data[..], k).map(|p| (p.read(&data[..]), p.version));
        assert_eq!(walked, want, "[{k}] by the walk");
        assert_eq!(
            table.read(&layout, &data[..], k),
            want,
            "[{k}] by the table"
        );
    }
}
