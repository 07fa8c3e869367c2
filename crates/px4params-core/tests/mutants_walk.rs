//! The walk's nesting bound (issue 40): `rules::MAX_DEPTH` (64) nodes deep is followed, one
//! more is refused with `TooDeep` ("type nests too deeply"). DSDL cannot express recursion, so
//! only a malformed layout nests so deep; the bound counts the root as depth 1 and each field
//! or element one deeper. The walk answers whatever the plans decline: `NoPlans` (firmware's
//! build) reaches it directly; the build's own plans must give the same answers, up to the
//! bound and beyond it.

use px4params_core::codec::{decode_leaves_with, encode_leaves_with};
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::Role;
use px4params_core::plan::{Active, NoPlans, Plans};
use px4params_core::rules::MAX_DEPTH;
use px4params_core::{Cast, DecodeOptions, EncodeOptions, ErrorKind, NodeId, Scalar};

/// A uint8 inside `depth - 1` one-field structs: `depth` nodes from the root to the leaf.
fn nested_structs(l: &mut OwnedLayout, depth: usize) -> NodeId {
    let mut node = l.uint(8, Cast::Saturated).unwrap();
    for _ in 1..depth {
        node = l.structure(&[("x", node, Role::Data)]).unwrap();
    }
    node
}

const ENCODE: EncodeOptions = EncodeOptions {
    tao: true,
    saturate: false,
    keep_versions: false,
};
const DECODE: DecodeOptions = DecodeOptions {
    tao: true,
    allow_trailing: false,
};

fn round_trip<P: Plans>(depth: usize) -> Result<Scalar, String> {
    let mut l = OwnedLayout::default();
    let root = nested_structs(&mut l, depth);
    let layout = l.as_layout();
    let mut out = [0u8; 4];
    let n = encode_leaves_with::<P>(&layout, root, &[Scalar::Uint(0xA5)], &mut out, ENCODE)
        .map_err(|e| {
            assert_eq!(e.kind, ErrorKind::TooDeep, "encode at depth {depth}");
            e.display(&layout).to_string()
        })?;
    // One byte: the uint8, whatever the nesting (structs add no bits).
    assert_eq!(&out[..n], &[0xA5], "encoded at depth {depth}");
    let mut leaves = [Scalar::Uint(0); 1];
    decode_leaves_with::<P, _>(&layout, root, &[0xA5u8][..], &mut leaves, DECODE).map_err(|e| {
        assert_eq!(e.kind, ErrorKind::TooDeep, "decode at depth {depth}");
        e.display(&layout).to_string()
    })?;
    Ok(leaves[0])
}

#[test]
fn the_walk_follows_a_type_exactly_max_depth_deep() {
    assert_eq!(MAX_DEPTH, 64);
    assert_eq!(round_trip::<NoPlans>(MAX_DEPTH), Ok(Scalar::Uint(0xA5)));
    assert_eq!(round_trip::<Active>(MAX_DEPTH), Ok(Scalar::Uint(0xA5)));
}

#[test]
fn the_walk_refuses_one_level_deeper_with_a_worded_error() {
    for depth in [MAX_DEPTH + 1, MAX_DEPTH + 2] {
        // Named by the path down to where it gave up (cut short with "..."), then the reason.
        let message = round_trip::<NoPlans>(depth).unwrap_err();
        assert!(message.starts_with("x.x.x."), "{message}");
        assert!(message.ends_with("...: type nests too deeply"), "{message}");
    }
}

/// codec.rs promises the plans "answer or decline" and the walk words every error: the same
/// answers with and without plans. A flat run steps over nesting levels without counting
/// them, so each run knows the height it covers and the plans (the straight-line plan, the
/// flat encoder and decoder) decline a type deeper than the walk follows (issue 40, mutrust;
/// issue 39, tiny): 65 to 67 deep is refused with the walk's own words.
#[test]
fn the_plans_refuse_one_level_deeper_as_the_walk_does() {
    for depth in [MAX_DEPTH + 1, MAX_DEPTH + 2, MAX_DEPTH + 3] {
        let message = round_trip::<Active>(depth).unwrap_err();
        assert_eq!(message, round_trip::<NoPlans>(depth).unwrap_err());
        assert!(message.ends_with("...: type nests too deeply"), "{message}");
    }
}

/// The same where the straight-line plan declines (a union follows the deep run): the flat
/// encoder and decoder step over the run only where the walk would follow it, so that both
/// builds give the same bytes, leaves and errors at the bound and past it.
#[test]
fn the_flat_codec_refuses_a_deep_run_as_the_walk_does() {
    type Outcome = (Result<Vec<u8>, String>, Result<Vec<Scalar>, String>);
    // 0xA5, then tag 1 (one bit) and 7 (eight bits), padded: 1000_0011 1000_0000.
    const BYTES: [u8; 3] = [0xA5, 0x83, 0x80];
    const LEAVES: [Scalar; 3] = [Scalar::Uint(0xA5), Scalar::Uint(1), Scalar::Uint(7)];
    fn run<P: Plans>(depth: usize) -> Outcome {
        let mut l = OwnedLayout::default();
        // The run's leaf is `depth` nodes from the root: the root, then `depth - 1` below.
        let deep = nested_structs(&mut l, depth - 1);
        let byte = l.uint(8, Cast::Saturated).unwrap();
        let union = l.union(&[("a", byte), ("b", byte)]).unwrap();
        let root = l
            .structure(&[("deep", deep, Role::Data), ("u", union, Role::Data)])
            .unwrap();
        let layout = l.as_layout();
        let mut out = [0u8; 8];
        let encoded = encode_leaves_with::<P>(&layout, root, &LEAVES, &mut out, ENCODE)
            .map(|n| out[..n].to_vec())
            .map_err(|e| e.display(&layout).to_string());
        let mut back = [Scalar::Uint(0); 3];
        let decoded = decode_leaves_with::<P, _>(&layout, root, &BYTES[..], &mut back, DECODE)
            .map(|d| back[..d.leaves].to_vec())
            .map_err(|e| e.display(&layout).to_string());
        (encoded, decoded)
    }
    for depth in MAX_DEPTH - 1..=MAX_DEPTH + 2 {
        let (plans, walk) = (run::<Active>(depth), run::<NoPlans>(depth));
        assert_eq!(plans, walk, "depth {depth}");
        let (encoded, decoded) = plans;
        if depth <= MAX_DEPTH {
            assert_eq!(encoded.unwrap(), BYTES, "depth {depth}");
            assert_eq!(decoded.unwrap(), LEAVES, "depth {depth}");
        } else {
            assert!(encoded.unwrap_err().ends_with("...: type nests too deeply"));
            assert!(decoded.unwrap_err().ends_with("...: type nests too deeply"));
        }
    }
}

/// A union tag or array length written as a signed integer (`Scalar::Int`, as a host may
/// give it): within range it is that number, as a `Scalar::Uint` would be; a negative one,
/// or one past the last variant or the array's maximum, is refused as out of range 0 to
/// that bound, the value as given. Bytes by hand, without tail array optimization:
/// `{a: uint8, s: uint8[<=3]}` (a 2-bit length) with a = 1, s = [0x41] is 00000001 01
/// 01000001 (01 50 40); length 0 leaves 00000001 00 (01 00), 2 appends a zero element
/// (01 90 40 00), 3 two (00000001 11 01000001 0x00 0x00: 01 D0 40 00 00).
/// `{u: union {a: uint8, b: uint4}, z: uint8}` (a 1-bit tag) with u = a(0x41), z = 0x99 is
/// 0 01000001 10011001 (20 CC 80); tag 1 selects b, zero: 1 0000 10011001 (84 C8).
#[test]
fn a_tag_or_length_given_as_a_signed_integer_is_that_number_or_refused() {
    use px4params_core::leaf::set_leaf_at;
    use px4params_core::scalar::ScalarError;
    let mut l = OwnedLayout::default();
    let u4 = l.uint(4, Cast::Saturated).unwrap();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let s = l.dyn_array(u8_, 3).unwrap();
    let listed = l
        .structure(&[("a", u8_, Role::Data), ("s", s, Role::Data)])
        .unwrap();
    let u = l.union(&[("a", u8_), ("b", u4)]).unwrap();
    let tagged = l
        .structure(&[("u", u, Role::Data), ("z", u8_, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let options = EncodeOptions {
        tao: false,
        ..EncodeOptions::default()
    };
    let out_of_range = |value, max| {
        Err(ErrorKind::Scalar(ScalarError::OutOfRange {
            value: Scalar::Int(value),
            min: Scalar::Uint(0),
            max: Scalar::Uint(max),
        }))
    };
    let listed_data = [0x01, 0x50, 0x40];
    let tagged_data = [0x20, 0xCC, 0x80];
    /// The value's type, its bytes, the leaf, the number written, and the bytes or error.
    type Case<'d> = (
        NodeId,
        &'d [u8],
        usize,
        i64,
        Result<&'d [u8], ErrorKind<core::convert::Infallible>>,
    );
    let cases: [Case<'_>; 10] = [
        (listed, &listed_data, 1, 0, Ok(&[0x01, 0x00])),
        (listed, &listed_data, 1, 1, Ok(&listed_data)),
        (listed, &listed_data, 1, 2, Ok(&[0x01, 0x90, 0x40, 0x00])),
        (
            listed,
            &listed_data,
            1,
            3,
            Ok(&[0x01, 0xD0, 0x40, 0x00, 0x00]),
        ),
        (listed, &listed_data, 1, 4, out_of_range(4, 3)),
        (listed, &listed_data, 1, -1, out_of_range(-1, 3)),
        (tagged, &tagged_data, 0, 0, Ok(&tagged_data)),
        (tagged, &tagged_data, 0, 1, Ok(&[0x84, 0xC8])),
        (tagged, &tagged_data, 0, 2, out_of_range(2, 1)),
        (tagged, &tagged_data, 0, -1, out_of_range(-1, 1)),
    ];
    for (root, data, k, value, expected) in cases {
        let mut out = [0xEE; 16];
        let written = set_leaf_at(
            &layout,
            root,
            data,
            k,
            Scalar::Int(value),
            &mut out,
            options,
        )
        .map(|n| &out[..n])
        .map_err(|e| e.kind);
        assert_eq!(
            written, expected,
            "leaf [{k}] of {data:x?} set to Int({value})"
        );
    }
}

/// A stored value is exactly one value (issue 40): `{p_version: uint8 (version 3), a: uint8}`
/// stored as 03 09 passes the check; with a byte after it, 03 09 00, it is refused as
/// trailing bytes (2 used of 3) where the value ends, bit 16, by the build's plans and by the
/// walk alone (firmware's), which answers whatever the plans decline.
#[test]
fn a_stored_value_with_a_byte_after_it_is_refused() {
    use px4params_core::codec::{check_stored, check_stored_with};
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let root = l
        .structure(&[("p_version", u8_, Role::Version(3)), ("a", u8_, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let trailing = Err((ErrorKind::TrailingBytes { used: 2, len: 3 }, 16));
    for check in [check_stored, check_stored_with::<NoPlans>] {
        let checked = |data: &[u8]| check(&layout, root, data).map_err(|e| (e.kind, e.bit_offset));
        assert_eq!(checked(&[0x03, 0x09]), Ok(()));
        assert_eq!(checked(&[0x03, 0x09, 0x00]), trailing);
    }
}
