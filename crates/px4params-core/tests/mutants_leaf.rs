//! Leaf access by path (`get_leaf` with `Target::Path`) against DroneCAN's tail array
//! optimization as pydronecan applies it (issue 40): the last element of a length-prefixed
//! dynamic array inherits the optimization, so the byte array that ends that element takes
//! the remaining bytes without a length; the elements before it keep their lengths.
//!
//! The type (`mutcore.Inner`: `uint4 x`, `uint8[<=5] data`; `mutcore.Outer`: `uint8 a`,
//! `mutcore.Inner[<=3] items`): an Inner is at least 7 bits long, under the 8 bits the
//! optimization needs, so `items` keeps its 2-bit length even as the last field; the last
//! Inner's `data` (uint8 elements) is optimized.

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::Role;
use px4params_core::leaf::{get_leaf, Target};
use px4params_core::{Cast, NodeId, Scalar};

/// a = 0x11, items = [{x: 1, data: [0xA1]}, {x: 2, data: [0xB1, 0xB2, 0xB3]}], encoded by
/// pydronecan 1.0.27 from the DSDL above: `transport.bytes_from_bits(value._pack(tao))`.
const WITH_TAO: [u8; 7] = [0x11, 0x84, 0xD0, 0x95, 0x8D, 0x95, 0x98];
/// The same value with `_pack(False)`: the last Inner's data keeps its 3-bit length.
const WITHOUT_TAO: [u8; 7] = [0x11, 0x84, 0xD0, 0x93, 0xB1, 0xB2, 0xB3];

fn outer(l: &mut OwnedLayout) -> NodeId {
    let u4 = l.uint(4, Cast::Saturated).unwrap();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let data = l.dyn_array(u8_, 5).unwrap();
    let inner = l
        .structure(&[("x", u4, Role::Data), ("data", data, Role::Data)])
        .unwrap();
    let items = l.dyn_array(inner, 3).unwrap();
    l.structure(&[("a", u8_, Role::Data), ("items", items, Role::Data)])
        .unwrap()
}

fn leaf_at(bytes: &[u8], path: &str, tao: bool) -> Option<Scalar> {
    let mut l = OwnedLayout::default();
    let root = outer(&mut l);
    get_leaf(&l.as_layout(), root, bytes, Target::Path(path), tao)
        .ok()
        .map(|(_, v)| v)
}

#[test]
fn the_last_element_of_a_prefixed_array_ends_in_a_tail_array_under_tao() {
    for (path, want) in [
        ("a", 0x11),
        ("items[0].x", 1),
        ("items[0].data[0]", 0xA1),
        ("items[1].x", 2),
        ("items[1].data[0]", 0xB1),
        ("items[1].data[1]", 0xB2),
        ("items[1].data[2]", 0xB3),
    ] {
        assert_eq!(
            leaf_at(&WITH_TAO, path, true),
            Some(Scalar::Uint(want)),
            "{path}"
        );
    }
    // The tail array holds three bytes: there is no fourth.
    assert_eq!(leaf_at(&WITH_TAO, "items[1].data[3]", true), None);
}

#[test]
fn without_tao_the_last_element_keeps_its_length() {
    for (path, want) in [
        ("items[0].data[0]", 0xA1),
        ("items[1].x", 2),
        ("items[1].data[2]", 0xB3),
    ] {
        assert_eq!(
            leaf_at(&WITHOUT_TAO, path, false),
            Some(Scalar::Uint(want)),
            "{path}"
        );
    }
    assert_eq!(leaf_at(&WITHOUT_TAO, "items[1].data[3]", false), None);
}

/// `leaf::set_leaf_at`, the build's own plans (tests/leaf_set.rs calls each plan set by
/// name): leaf [k] written, the new encoding's length returned. `{a: uint8, void4, b:
/// uint4}`: 11 F2 with b = 9 is 11 F9 (b is the low nibble of byte 1; the padding stays).
/// `{a: uint8, s: uint8[<=3]}` without tail array optimization (s's length has 2 bits): a =
/// 1, s = [0x41] is 00000001 01 01000001, 01 50 40; its length set to 2 appends a zero
/// element: 00000001 10 01000001 00000000, 01 90 40 00, four bytes.
#[test]
fn set_leaf_at_writes_the_leaf_and_returns_the_new_length() {
    use px4params_core::leaf::set_leaf_at;
    use px4params_core::EncodeOptions;
    let mut l = OwnedLayout::default();
    let u4 = l.uint(4, Cast::Saturated).unwrap();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let pad = l.void(4).unwrap();
    let padded = l
        .structure(&[
            ("a", u8_, Role::Data),
            ("", pad, Role::Padding),
            ("b", u4, Role::Data),
        ])
        .unwrap();
    let s = l.dyn_array(u8_, 3).unwrap();
    let listed = l
        .structure(&[("a", u8_, Role::Data), ("s", s, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let options = EncodeOptions {
        tao: false,
        ..EncodeOptions::default()
    };
    for (root, data, k, value, expected) in [
        (padded, &[0x11, 0xF2][..], 1, 9, &[0x11, 0xF9][..]),
        (listed, &[0x01, 0x50, 0x40], 1, 2, &[0x01, 0x90, 0x40, 0x00]),
    ] {
        let mut out = [0xEE; 8];
        let n = set_leaf_at(
            &layout,
            root,
            data,
            k,
            Scalar::Uint(value),
            &mut out,
            options,
        );
        assert_eq!(n, Ok(expected.len()), "{data:x?}");
        assert_eq!(&out[..expected.len()], expected, "{data:x?}");
    }
}

/// The seek follows a value as deep as the walk does (issue 40): `rules::MAX_DEPTH` (64)
/// nodes from the root to the leaf, the root at depth 1. `s: uint8[<=1]` inside `depth - 2`
/// one-field structs, its element `depth` nodes deep; s = [0xA5] is its 1-bit length 1 then
/// 0xA5, 1 10100101 (D2 80): the element is leaf [1], bit 1, a uint8. The seek (the host's
/// `leaf::seek`) finds it where the walk does, up to the bound; one deeper both give up.
#[test]
fn the_seek_finds_a_leaf_exactly_max_depth_deep_as_the_walk_does() {
    use px4params_core::layout::Kind;
    use px4params_core::leaf::{seek, seek_with, Position};
    use px4params_core::plan::NoPlans;
    use px4params_core::rules::LeafKind;
    use px4params_core::rules::MAX_DEPTH;
    for depth in [MAX_DEPTH - 1, MAX_DEPTH, MAX_DEPTH + 1] {
        let mut l = OwnedLayout::default();
        let u8_ = l.uint(8, Cast::Saturated).unwrap();
        let mut root = l.dyn_array(u8_, 1).unwrap();
        for _ in 2..depth {
            root = l.structure(&[("x", root, Role::Data)]).unwrap();
        }
        let layout = l.as_layout();
        let data = [0xD2u8, 0x80];
        let expected = (depth <= MAX_DEPTH).then_some(Position {
            bit_offset: 1,
            kind: LeafKind::Scalar(Kind::Uint {
                bits: 8,
                cast: Cast::Saturated,
            }),
            version: false,
        });
        assert_eq!(seek(&layout, root, &data[..], 1), expected, "depth {depth}");
        assert_eq!(
            seek_with::<NoPlans, _>(&layout, root, &data[..], 1),
            expected,
            "depth {depth}, the walk"
        );
    }
}

/// Depth is nesting, not the number of parts passed: the seek finds leaf [70] after 69
/// elements of its own depth as the walk does. `{items: {s: uint8[<=1]}[<=100]}` holding 70
/// items with empty s: items' 7-bit length 70 (1000110), then one 0 bit per s (8C, then
/// nine 00); leaf [0] is items' length, leaf [k] the k-th s's length, at bit 7 + k - 1.
#[test]
fn the_seek_finds_the_seventieth_of_seventy_elements_as_the_walk_does() {
    use px4params_core::leaf::{seek, seek_with, Position};
    use px4params_core::plan::NoPlans;
    use px4params_core::rules::LeafKind;
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let s = l.dyn_array(u8_, 1).unwrap();
    let item = l.structure(&[("s", s, Role::Data)]).unwrap();
    let items = l.dyn_array(item, 100).unwrap();
    let root = l.structure(&[("items", items, Role::Data)]).unwrap();
    let layout = l.as_layout();
    let mut data = [0u8; 10];
    data[0] = 0x8C;
    for k in [1, 35, 70] {
        let expected = Some(Position {
            bit_offset: 7 + k - 1,
            kind: LeafKind::Len { bits: 1, array: s },
            version: false,
        });
        assert_eq!(seek(&layout, root, &data[..], k), expected, "leaf [{k}]");
        assert_eq!(
            seek_with::<NoPlans, _>(&layout, root, &data[..], k),
            expected,
            "leaf [{k}], the walk"
        );
    }
}

/// Leaves by number (`Target::Index`: the host seeks first, the walk answers what the seek
/// declines) in the value above, with and without tail array optimization: a, items' length,
/// items[0].x, its data's length and element, items[1].x, its data's length and elements.
/// Under the optimization the last Inner's data has no length on the wire (its three bytes
/// take the rest), and its length leaf is still its number of elements, 3. The same for
/// a = 0x11, items = [{x: 1, data: [0xA1, 0xA2]}], whose one Inner is the last (pydronecan
/// 1.0.27: 11 46 86 88 with the optimization, 11 45 50 D1 00 without).
#[test]
fn leaves_by_number_follow_the_tail_array_of_the_last_element() {
    let mut l = OwnedLayout::default();
    let root = outer(&mut l);
    let layout = l.as_layout();
    let two = [0x11, 2, 1, 1, 0xA1, 2, 3, 0xB1, 0xB2, 0xB3];
    let one = [0x11, 1, 1, 2, 0xA1, 0xA2];
    for (bytes, tao, values) in [
        (&WITH_TAO[..], true, &two[..]),
        (&WITHOUT_TAO, false, &two),
        (&[0x11, 0x46, 0x86, 0x88], true, &one),
        (&[0x11, 0x45, 0x50, 0xD1, 0x00], false, &one),
    ] {
        for (k, &want) in values.iter().enumerate() {
            let got = get_leaf(&layout, root, bytes, Target::Index(k), tao).map(|(_, v)| v);
            assert_eq!(
                got,
                Ok(Scalar::Uint(want)),
                "{bytes:x?} leaf [{k}], tao {tao}"
            );
        }
        let past = get_leaf(&layout, root, bytes, Target::Index(values.len()), tao);
        assert!(past.is_err(), "{bytes:x?} past the last leaf: {past:?}");
    }
}

/// A fixed run as deep as the walk follows (issue 40): a uint8 inside `depth - 1` one-field
/// structs is one flat run of the root, its leaf `depth` nodes from the root; 0xA5 is leaf
/// [0] at bit 0 up to `rules::MAX_DEPTH` (64), and one deeper the seek gives up as the walk
/// does.
#[test]
fn the_seek_finds_a_fixed_run_s_leaf_exactly_max_depth_deep_as_the_walk_does() {
    use px4params_core::layout::Kind;
    use px4params_core::leaf::{seek, seek_with, Position};
    use px4params_core::plan::NoPlans;
    use px4params_core::rules::{LeafKind, MAX_DEPTH};
    for depth in [MAX_DEPTH - 1, MAX_DEPTH, MAX_DEPTH + 1] {
        let mut l = OwnedLayout::default();
        let mut root = l.uint(8, Cast::Saturated).unwrap();
        for _ in 1..depth {
            root = l.structure(&[("x", root, Role::Data)]).unwrap();
        }
        let layout = l.as_layout();
        let expected = (depth <= MAX_DEPTH).then_some(Position {
            bit_offset: 0,
            kind: LeafKind::Scalar(Kind::Uint {
                bits: 8,
                cast: Cast::Saturated,
            }),
            version: false,
        });
        assert_eq!(
            seek(&layout, root, &[0xA5u8][..], 0),
            expected,
            "depth {depth}"
        );
        assert_eq!(
            seek_with::<NoPlans, _>(&layout, root, &[0xA5u8][..], 0),
            expected,
            "depth {depth}, the walk"
        );
    }
}

/// A padding field names no leaf, even where the layout keeps a name for it (`{a: uint8,
/// pad: void4, b: uint4}`, 11 F2): `pad` is no such field, said where the struct that has
/// no such field starts (bit 0, the root), as tests/leaf_path.rs's `u.d` is; `b` is the low
/// nibble of byte 1.
#[test]
fn a_path_to_a_padding_field_names_no_leaf() {
    use px4params_core::ErrorKind;
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let pad = l.void(4).unwrap();
    let u4 = l.uint(4, Cast::Saturated).unwrap();
    let root = l
        .structure(&[
            ("a", u8_, Role::Data),
            ("pad", pad, Role::Padding),
            ("b", u4, Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    let data = [0x11u8, 0xF2];
    for tao in [false, true] {
        let b = get_leaf(&layout, root, &data[..], Target::Path("b"), tao).map(|(_, v)| v);
        assert_eq!(b, Ok(Scalar::Uint(2)));
        let pad = get_leaf(&layout, root, &data[..], Target::Path("pad"), tao);
        let pad = pad.map_err(|e| (e.kind, e.bit_offset, e.path.display(&layout).to_string()));
        assert_eq!(
            pad,
            Err((ErrorKind::NoSuchPath, 0, String::new())),
            "tao {tao}"
        );
    }
}
