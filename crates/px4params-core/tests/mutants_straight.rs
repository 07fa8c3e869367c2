//! The straight-line plan (`px4params_core::straight`) where its fast paths meet the DroneCAN
//! rules (issue 40): a byte string copied after the fixed run, a `p_version` given another
//! version, a float16 out of range. The codec (which tries the plan first) must answer as the
//! walk (`px4params_core::walk`, no plans) does, with the bytes worked out by hand.

use px4params_core::codec::encode_leaves;
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{Layout, NodeId, Role};
use px4params_core::rules::EncodeOptions;
use px4params_core::{walk, Cast, ErrorKind, Scalar};

/// The codec's bytes and the walk's for `leaves`, each into a buffer filled with 0xEE first
/// (so that a byte the encoder leaves unwritten shows), or the error's kind.
fn both(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    options: EncodeOptions,
) -> [Result<Vec<u8>, String>; 2] {
    let mut by_codec = [0xEEu8; 32];
    let mut by_walk = [0xEEu8; 32];
    let codec = encode_leaves(layout, root, leaves, &mut by_codec, options);
    let walked = walk::encode(layout, root, leaves, &mut by_walk, options);
    [
        codec
            .map(|n| by_codec[..n].to_vec())
            .map_err(|e| format!("{:?}", e.kind)),
        walked
            .map(|n| by_walk[..n].to_vec())
            .map_err(|e| format!("{:?}", e.kind)),
    ]
}

/// `{a: uint8, s: uint8[<=8]}` with tail array optimization: s ends the value and its
/// elements have 8 bits, so its length is left out, and its bytes follow a's on a byte
/// boundary: a = 1, s = "ABC" is 01 41 42 43.
#[test]
fn a_byte_string_after_the_fixed_run_is_written_byte_for_byte() {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let s = l.dyn_array(u8_, 8).unwrap();
    let root = l
        .structure(&[("a", u8_, Role::Data), ("s", s, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let leaves = [1u64, 3, 0x41, 0x42, 0x43].map(Scalar::Uint);
    let expected: Result<Vec<u8>, String> = Ok(vec![0x01, 0x41, 0x42, 0x43]);
    assert_eq!(
        both(&layout, root, &leaves, EncodeOptions::default()),
        [expected.clone(), expected]
    );
}

/// A `p_version` field given a version other than the type's is refused (unless versions are
/// kept as given), as the walk refuses it; kept, it is written as given: `{p_version: uint8
/// (version 3), a: uint8}` with p_version 5 and a = 9 is 05 09.
#[test]
fn a_p_version_given_another_version_is_refused_unless_versions_are_kept() {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let root = l
        .structure(&[("p_version", u8_, Role::Version(3)), ("a", u8_, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let leaves = [Scalar::Uint(5), Scalar::Uint(9)];
    let [codec, walked] = both(&layout, root, &leaves, EncodeOptions::default());
    assert_eq!(codec, walked);
    let mismatch = format!(
        "{:?}",
        ErrorKind::<()>::VersionMismatch {
            given: Scalar::Uint(5),
            expected: 3
        }
    );
    assert_eq!(codec, Err(mismatch));
    let kept = EncodeOptions {
        keep_versions: true,
        ..EncodeOptions::default()
    };
    let written: Result<Vec<u8>, String> = Ok(vec![0x05, 0x09]);
    assert_eq!(
        both(&layout, root, &leaves, kept),
        [written.clone(), written]
    );
}

/// A float out of its type's range in a type too long for the plan's one-word path (a
/// uint64 next to it): refused, or with saturation clamped to the type's largest value, never
/// written as infinity, as the walk does: float16's 65504 is 0x7BFF (little-endian FF 7B),
/// float32's 3.4028235e38 is 0x7F7FFFFF (FF FF 7F 7F), negative with the sign bit. The same
/// for a float `p_version` written as given (versions kept).
#[test]
fn a_float_out_of_range_is_refused_or_clamped_as_the_walk_does() {
    let mut l = OwnedLayout::default();
    let u64_ = l.uint(64, Cast::Saturated).unwrap();
    let f16 = l.float(16, Cast::Saturated).unwrap();
    let f32_ = l.float(32, Cast::Saturated).unwrap();
    let mut roots = Vec::new();
    for (float, big, max, min) in [
        (f16, 1e6, &[0xFF, 0x7B][..], &[0xFF, 0xFB][..]),
        (
            f32_,
            1e39,
            &[0xFF, 0xFF, 0x7F, 0x7F][..],
            &[0xFF, 0xFF, 0x7F, 0xFF][..],
        ),
    ] {
        let leaf = l
            .structure(&[("a", u64_, Role::Data), ("h", float, Role::Data)])
            .unwrap();
        let version = l
            .structure(&[
                ("p_version", float, Role::Version(1)),
                ("a", u64_, Role::Data),
            ])
            .unwrap();
        roots.push((leaf, 1, big, max, min));
        roots.push((version, 0, big, max, min));
    }
    let layout = l.as_layout();
    for (root, k, big, max, min) in roots {
        // The float's bytes: after the uint64, or first.
        let at = if k == 1 { 8 } else { 0 };
        for (v, clamped) in [(big, max), (-big, min)] {
            let mut leaves = [Scalar::Uint(0), Scalar::Uint(0)];
            leaves[k] = Scalar::Float(v);
            for saturate in [false, true] {
                let options = EncodeOptions {
                    saturate,
                    keep_versions: true,
                    ..EncodeOptions::default()
                };
                let [codec, walked] = both(&layout, root, &leaves, options);
                assert_eq!(codec, walked, "{v}, saturate {saturate}, root {root}");
                if saturate {
                    let bytes = walked.expect("clamped");
                    assert_eq!(&bytes[at..at + clamped.len()], clamped, "{v}, root {root}");
                } else {
                    assert!(walked.is_err(), "{v} written unsaturated, root {root}");
                }
            }
        }
    }
}
