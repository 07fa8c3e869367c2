//! Leaves looked up by path (`get_leaf` with `Target::Path`, a visit that follows the path
//! through the one loop) in values encoded by hand from DroneCAN's rules: where the leaf is,
//! and where and why a path names nothing in the value.

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{Layout, Role};
use px4params_core::leaf::{get_leaf, Target};
use px4params_core::{Cast, ErrorKind, NodeId, Scalar};

/// `(index, bit offset, value)` of a leaf found, or `(error, bit offset, its path)`.
type Looked = Result<(usize, usize, Scalar), (ErrorKind<()>, usize, String)>;

/// The leaf at `path` of `data`.
fn look(layout: &Layout<'_>, root: NodeId, data: &[u8], path: &str) -> Looked {
    match get_leaf(layout, root, data, Target::Path(path), false) {
        Ok((leaf, value)) => Ok((leaf.index, leaf.bit_offset, value)),
        Err(e) => Err((
            e.kind.map_value(|never| match never {}),
            e.bit_offset,
            e.path.display(layout).to_string(),
        )),
    }
}

/// `uint4[<=3][2]` holding `[[1, 2], [3]]`, without tail array optimization: each inner
/// array a 2-bit length and its elements, `10 0001 0010 | 01 0011` = `0x84 0x93`. Leaves:
/// `[0]` the first length, `[1]` 1, `[2]` 2, `[3]` the second length, `[4]` 3.
#[test]
fn elements_of_nested_arrays_are_told_apart_by_depth() {
    let mut l = OwnedLayout::default();
    let u4 = l.uint(4, Cast::Saturated).unwrap();
    let inner = l.dyn_array(u4, 3).unwrap();
    let root = l.array(inner, 2).unwrap();
    let layout = l.as_layout();
    let data = [0x84, 0x93];
    // `[1][0]`: the walk passes the first inner array's `[1]` on its way (a step of the same
    // index, one part deeper).
    assert_eq!(
        look(&layout, root, &data, "[1][0]"),
        Ok((4, 12, Scalar::Uint(3)))
    );
    assert_eq!(
        look(&layout, root, &data, "[0][1]"),
        Ok((2, 6, Scalar::Uint(2)))
    );
    assert_eq!(
        look(&layout, root, &data, "[0]._len"),
        Ok((0, 0, Scalar::Uint(2)))
    );
    assert_eq!(
        look(&layout, root, &data, "[1]._len"),
        Ok((3, 10, Scalar::Uint(1)))
    );
    // The second inner array holds one element: there is no `[1][1]`, said after its length.
    let none = |at, path: &str| Err((ErrorKind::NoSuchPath, at, path.to_string()));
    assert_eq!(look(&layout, root, &data, "[1][1]"), none(12, "[1]"));
    // A static array has two elements whatever the data: said where it starts.
    assert_eq!(look(&layout, root, &data, "[2]"), none(0, ""));
    let not_a_leaf = Err((ErrorKind::NotALeaf, 10, "[1]".to_string()));
    assert_eq!(look(&layout, root, &data, "[1]"), not_a_leaf);
}

/// `{u: union {a: uint3, b: uint5, c: uint2}, z: uint8}` with `u = b(5)`, `z = 0xAA`: a
/// 2-bit tag 01, `00101`, `10101010` = `0x4B 0x54` (15 bits). Leaves: `[0]` the tag, `[1]`
/// b, `[2]` z.
#[test]
fn a_union_on_the_way_is_read_and_checked_before_its_variant_is_named() {
    let mut l = OwnedLayout::default();
    let (u3, u5, u2) = (
        l.uint(3, Cast::Saturated).unwrap(),
        l.uint(5, Cast::Saturated).unwrap(),
        l.uint(2, Cast::Saturated).unwrap(),
    );
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let u = l.union(&[("a", u3), ("b", u5), ("c", u2)]).unwrap();
    let root = l
        .structure(&[("u", u, Role::Data), ("z", u8_, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let data = [0x4B, 0x54];
    assert_eq!(
        look(&layout, root, &data, "u.b"),
        Ok((1, 2, Scalar::Uint(5)))
    );
    assert_eq!(
        look(&layout, root, &data, "z"),
        Ok((2, 7, Scalar::Uint(0xAA)))
    );
    assert_eq!(
        look(&layout, root, &data, "u._tag"),
        Ok((0, 0, Scalar::Uint(1)))
    );
    // Another variant: said after the tag, at that variant's path.
    let not_selected = Err((ErrorKind::VariantNotSelected, 2, "u.a".to_string()));
    assert_eq!(look(&layout, root, &data, "u.a"), not_selected);
    let none = Err((ErrorKind::NoSuchPath, 0, "u".to_string()));
    assert_eq!(look(&layout, root, &data, "u.d"), none);
    // Tag 3 selects no variant: the data's fault comes before the path's.
    let bad = [0xCB, 0x54];
    let tag = Err((
        ErrorKind::BadUnionTag {
            tag: 3,
            variants: 3,
        },
        0,
        "u".to_string(),
    ));
    assert_eq!(look(&layout, root, &bad, "u.a"), tag);
    // No data: the tag on the way is not there.
    let truncated = ErrorKind::Truncated {
        needed_bits: 2,
        available_bits: 0,
    };
    let short = Err((truncated, 0, "u".to_string()));
    assert_eq!(look(&layout, root, &[], "u.b"), short);
    // Cut inside the leaf: its bits are not all there.
    let truncated = ErrorKind::Truncated {
        needed_bits: 15,
        available_bits: 8,
    };
    assert_eq!(
        look(&layout, root, &data[..1], "z"),
        Err((truncated, 7, "z".to_string()))
    );
}
