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

/// A union's tag entry keeps the union's node number in bits 12..31 of its description, so
/// unions numbered from 2^19 on are left out of tables (the walk reads their leaves). Three
/// unions numbered 2^19 - 1, 2^19 and 2^19 + 1, each `{x: uint8 | y: uint8}`, in a struct: the
/// table reads every leaf as the walk does, each tag's kind naming its own union. The value
/// {x: 0x11}, {y: 0x22}, {x: 0x33} is the bits 0 00010001 1 00100010 0 00110011 and zeros.
#[test]
fn unions_numbered_around_the_tables_limit_are_read_as_the_walk_reads_them() {
    use px4params_core::rules::LeafKind;
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    // Nodes 1 to 2^19 - 2 (arrays: scalars are interned): the next is number 2^19 - 1.
    for _ in 1..(1u32 << 19) - 1 {
        l.array(u8_, 1).unwrap();
    }
    let unions: Vec<NodeId> = (0..3)
        .map(|_| l.union(&[("x", u8_), ("y", u8_)]).unwrap())
        .collect();
    assert_eq!(unions, [(1 << 19) - 1, 1 << 19, (1 << 19) + 1]);
    let root = l
        .structure(&[
            ("a", unions[0], Role::Data),
            ("b", unions[1], Role::Data),
            ("c", unions[2], Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    let mut slots = vec![LeafSlot::default(); LeafTable::slots_needed(&layout, root)];
    let table = LeafTable::build(&layout, root, &mut slots).unwrap();
    // 0 00010001 1 0010001|0 0 0011001|1 0000000
    let data = [0b0000_1000, 0b1100_1000, 0b1000_0110, 0b0110_0000];
    for k in 0..6 {
        let tabled = table.get_leaf(&layout, &data[..], Target::Index(k), false);
        let walked = get_leaf(&layout, root, &data[..], Target::Index(k), false);
        assert_eq!(tabled, walked, "[{k}]");
        let (leaf, value) = walked.unwrap();
        if k % 2 == 0 {
            assert_eq!(value, Scalar::Uint([0, 1, 0][k / 2]), "[{k}]");
            let union = unions[k / 2];
            assert_eq!(leaf.kind, LeafKind::Tag { bits: 1, union }, "[{k}]");
        } else {
            assert_eq!(value, Scalar::Uint([0x11, 0x22, 0x33][k / 2]), "[{k}]");
        }
    }
}

/// Unions in unions (`Uk = {a: Uk-1 | b: uint8}`, U0 = uint8), from `MAX_DEPTH - 2` to
/// `MAX_DEPTH + 1` levels, each variant a level deeper as the walk counts: every leaf (the
/// tags, 0 each, then the uint8 0x5A) read through the table as the walk reads it, the
/// deepest refused by both where it passes the bound.
#[test]
fn the_table_follows_union_variants_exactly_as_deep_as_the_walk() {
    use px4params_core::bits::write_bits;
    let mut refused = 0;
    for levels in MAX_DEPTH - 2..=MAX_DEPTH + 1 {
        let mut l = OwnedLayout::default();
        let u8_ = l.uint(8, Cast::Saturated).unwrap();
        let mut root = u8_;
        for _ in 0..levels {
            root = l.union(&[("a", root), ("b", u8_)]).unwrap();
        }
        let layout = l.as_layout();
        let mut slots = vec![LeafSlot::default(); LeafTable::slots_needed(&layout, root)];
        let table = LeafTable::build(&layout, root, &mut slots).unwrap();
        // `levels` zero bits (the tags), then 0x5A.
        let mut data = vec![0u8; levels / 8 + 2];
        write_bits(&mut data, levels, 0x5A, 8);
        for k in 0..=levels {
            let tabled = table.get_leaf(&layout, &data[..], Target::Index(k), false);
            let walked = get_leaf(&layout, root, &data[..], Target::Index(k), false);
            assert_eq!(tabled, walked, "{levels} levels, [{k}]");
            refused += usize::from(walked.is_err());
        }
        let deepest = get_leaf(&layout, root, &data[..], Target::Index(levels), false);
        if levels < MAX_DEPTH {
            assert_eq!(
                deepest.map(|(_, v)| v),
                Ok(Scalar::Uint(0x5A)),
                "{levels} levels"
            );
        }
    }
    assert!(refused > 0);
}
