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
