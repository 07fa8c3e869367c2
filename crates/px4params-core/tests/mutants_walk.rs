//! The walk's nesting bound (issue 40): `rules::MAX_DEPTH` (64) nodes deep is followed, one
//! more is refused with `TooDeep` ("type nests too deeply"). DSDL cannot express recursion, so
//! only a malformed layout nests so deep; the bound counts the root as depth 1 and each field
//! or element one deeper. The walk answers whatever the plans decline: `NoPlans` (firmware's
//! build) reaches it directly; the build's own plans must give the same answers, and do up to
//! the bound (beyond it they do not yet: the ignored test below).

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
/// answers with and without plans. The host's flat plan encodes and decodes a type 65 to 67
/// deep that the walk (and firmware's build) refuses (issue 40, mutrust; the core's src/ is
/// interp's, reported there).
#[test]
#[ignore = "product bug: the host's plans answer beyond MAX_DEPTH, where the walk refuses"]
fn the_plans_refuse_one_level_deeper_as_the_walk_does() {
    let message = round_trip::<Active>(MAX_DEPTH + 1).unwrap_err();
    assert!(message.ends_with("type nests too deeply"), "{message}");
}
