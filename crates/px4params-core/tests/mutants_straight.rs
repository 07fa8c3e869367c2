//! The straight-line plan (`px4params_core::straight`) where its fast paths meet the DroneCAN
//! rules (issue 40): a byte string copied after the fixed run, a `p_version` given another
//! version, a float16 out of range. The codec (which tries the plan first) must answer as the
//! walk (`px4params_core::walk`, no plans) does, with the bytes worked out by hand.

use px4params_core::codec::{encode, encode_leaves};
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{Layout, NodeId, Role};
use px4params_core::rules::EncodeOptions;
use px4params_core::value::LeafSource;
use px4params_core::{walk, Cast, ErrorKind, Scalar};

/// The codec's bytes and the walk's for `leaves`, each into a buffer filled with 0xEE first
/// (so that a byte the encoder leaves unwritten shows), or the error's kind.
fn both(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    options: EncodeOptions,
) -> [Result<Vec<u8>, String>; 2] {
    let mut by_codec = [0xEEu8; 128];
    let mut by_walk = [0xEEu8; 128];
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
/// boundary: a = 1, s = "ABC" is 01 41 42 43; in `uint8[<=100]`, 70 bytes follow a's the
/// same way.
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
    // 70 bytes 0x00..0x45 in `uint8[<=100]` after a = 1: 01 00 01 .. 45.
    let long = l.dyn_array(u8_, 100).unwrap();
    let root = l
        .structure(&[("a", u8_, Role::Data), ("s", long, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let leaves: Vec<Scalar> = [1, 70].into_iter().chain(0..70).map(Scalar::Uint).collect();
    let expected: Result<Vec<u8>, String> = Ok([1].into_iter().chain(0..70).collect());
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

/// Values the straight plan's fast paths must not take as they are: integers out of their
/// field's range, floats beyond float16's and float32's largest, a byte string holding 300,
/// `p_version` given as another kind of number or in a field too small for the type's
/// version, two `p_version` fields; in small types (the one-word path) and long ones (a
/// uint64 first, the plan's general loop), with and without saturation, tail array
/// optimization and kept versions: the codec answers as the walk does, bytes or error, and
/// takes the value's leaves from a longer list.
#[test]
fn values_out_of_range_are_encoded_or_refused_as_the_walk_does() {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let u64_ = l.uint(64, Cast::Saturated).unwrap();
    let i8_ = l.int(8, Cast::Saturated).unwrap();
    let f16 = l.float(16, Cast::Saturated).unwrap();
    let f32_ = l.float(32, Cast::Saturated).unwrap();
    let bytes = l.dyn_array(u8_, 4).unwrap();
    let (data, version) = (Role::Data, Role::Version(3));
    let mut cases: Vec<(NodeId, Vec<Scalar>)> = Vec::new();
    let mut too_large_at: Vec<NodeId> = Vec::new();
    let (big_f16, big_f32) = (Scalar::Float(1e6), Scalar::Float(1e39));
    let odd = [
        Scalar::Int(300),
        Scalar::Int(-129),
        Scalar::Int(100),
        Scalar::Uint(300),
    ];
    for first in [u8_, u64_] {
        let a = Scalar::Uint(1);
        for (field, values) in [
            (f16, vec![big_f16, Scalar::Float(-1e6), Scalar::Float(1.5)]),
            (
                f32_,
                vec![big_f32, Scalar::Float(-1e39), Scalar::Float(1.5)],
            ),
            (i8_, odd.to_vec()),
            (u8_, odd.to_vec()),
        ] {
            let root = l
                .structure(&[("a", first, data), ("x", field, data)])
                .unwrap();
            cases.extend(values.into_iter().map(|v| (root, vec![a, v])));
        }
        // The byte string alone (after its 3-bit length without tail array optimization),
        // after 8 or 64 bits (the one-word path), or 16 or 72 (a uint8 between: after 72,
        // the general loop's).
        let short = l
            .structure(&[("a", first, data), ("s", bytes, data)])
            .unwrap();
        let long = l
            .structure(&[("a", first, data), ("b", u8_, data), ("s", bytes, data)])
            .unwrap();
        let alone = l.structure(&[("s", bytes, data)]).unwrap();
        for s in [&[0x41, 300, 0x43][..], &[300], &[0x41, 0x42, 0x43], &[]] {
            let n = Scalar::Uint(s.len() as u64);
            let s = s.iter().map(|&b| Scalar::Uint(b));
            cases.push((short, [a, n].into_iter().chain(s.clone()).collect()));
            cases.push((long, [a, a, n].into_iter().chain(s.clone()).collect()));
            cases.push((alone, [n].into_iter().chain(s).collect()));
        }
        for field in [u8_, i8_] {
            let root = l
                .structure(&[("p_version", field, version), ("a", first, data)])
                .unwrap();
            for v in [
                Scalar::Uint(3),
                Scalar::Int(3),
                Scalar::Float(3.0),
                Scalar::Bool(true),
                Scalar::Int(300),
                Scalar::Uint(300),
            ] {
                cases.push((root, vec![v, a]));
            }
        }
        // A type's version too large for its field (300 in a uint8), and two p_version
        // fields of different versions.
        let too_large = l
            .structure(&[("p_version", u8_, Role::Version(300)), ("a", first, data)])
            .unwrap();
        for v in [Scalar::Uint(300), Scalar::Uint(44)] {
            cases.push((too_large, vec![v, a]));
        }
        too_large_at.push(too_large);
        let twice = l
            .structure(&[
                ("p_version", u8_, Role::Version(3)),
                ("again", u8_, Role::Version(5)),
                ("a", first, data),
            ])
            .unwrap();
        for (v, w) in [(3, 5), (5, 5), (3, 3)] {
            cases.push((twice, vec![Scalar::Uint(v), Scalar::Uint(w), a]));
        }
    }
    let layout = l.as_layout();
    let (mut written, mut refused) = (0, 0);
    for (root, leaves) in &cases {
        for (saturate, tao, keep_versions) in (0..8).map(|b| (b & 1 != 0, b & 2 != 0, b & 4 != 0)) {
            let options = EncodeOptions {
                tao,
                saturate,
                keep_versions,
            };
            let [codec, walked] = both(&layout, *root, leaves, options);
            assert_eq!(codec, walked, "{leaves:?}, {options:?}, root {root}");
            if walked.is_err() {
                refused += 1;
                continue;
            }
            written += 1;
            if *root == too_large_at[0] || *root == too_large_at[1] {
                // A version its field cannot hold: the walk writes it cut, the general
                // encoder's value pass refuses it (the DSDL loader refuses such a type).
                continue;
            }
            // From a leaf list that goes on, the value takes its own leaves, no more.
            let mut longer = leaves.clone();
            longer.push(Scalar::Uint(0x99));
            let mut source = LeafSource::new(&longer);
            let mut out = [0u8; 32];
            encode(&layout, *root, &mut source, &mut out, options).unwrap();
            assert_eq!(source.consumed(), leaves.len(), "{leaves:?}, {options:?}");
        }
    }
    assert!(
        written > 0 && refused > 0,
        "{written} written, {refused} refused"
    );
}

/// `{a: uint4, s: uint8[<=8]}` with tail array optimization: s takes every whole byte after
/// a's 4 bits, so 0xA1 0x23 is a = 10 and s = [0x12], a 3 left over (fewer than 8 bits: not
/// an element); the codec (the straight plan first) reads what the walk reads, from 1 to 5
/// bytes, its leaves and where the value ends.
#[test]
fn a_byte_string_after_four_bits_takes_the_whole_bytes_left() {
    let mut l = OwnedLayout::default();
    let u4 = l.uint(4, Cast::Saturated).unwrap();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let s = l.dyn_array(u8_, 8).unwrap();
    let root = l
        .structure(&[("a", u4, Role::Data), ("s", s, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let options = px4params_core::DecodeOptions {
        tao: true,
        allow_trailing: false,
    };
    let data = [0xA1, 0x23, 0x45, 0x67, 0x89];
    for n in 1..=data.len() {
        let mut by_codec = [Scalar::Uint(0xEE); 12];
        let mut by_walk = [Scalar::Uint(0xEE); 12];
        let codec =
            px4params_core::codec::decode_leaves(&layout, root, &data[..n], &mut by_codec, options);
        let walked = walk::decode(&layout, root, &data[..n], &mut by_walk, options);
        let (codec, walked) = (codec.unwrap(), walked.unwrap());
        assert_eq!(
            (codec.leaves, codec.bits),
            (walked.leaves, walked.bits),
            "{n} bytes"
        );
        assert_eq!(by_codec, by_walk, "{n} bytes");
        // a, the length and n - 1 elements: a's 4 bits and the last 4 do not make a byte.
        assert_eq!(codec.leaves, 2 + (n - 1), "{n} bytes");
        assert_eq!(by_codec[0], Scalar::Uint(10));
        assert_eq!(by_codec[1], Scalar::Uint(n as u64 - 1));
        if n == 2 {
            assert_eq!(by_codec[2], Scalar::Uint(0x12));
        }
    }
}

/// A type's version too large for its `p_version` field (300 in a uint8; the DSDL loader
/// refuses such a type, a layout built by hand can hold it) after another field: the plan
/// declines it as the walk's rules decide, and a's byte is a's alone: `{a: uint8, p_version:
/// uint8 (version 300)}` with a = 2 starts 02, whatever becomes of the version's bits.
#[test]
fn a_version_too_large_for_its_field_never_reaches_the_field_before_it() {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let root = l
        .structure(&[
            ("a", u8_, Role::Data),
            ("p_version", u8_, Role::Version(300)),
        ])
        .unwrap();
    let layout = l.as_layout();
    for keep_versions in [false, true] {
        for version in [Scalar::Uint(300), Scalar::Uint(44)] {
            let options = EncodeOptions {
                keep_versions,
                ..EncodeOptions::default()
            };
            let leaves = [Scalar::Uint(2), version];
            let [codec, walked] = both(&layout, root, &leaves, options);
            assert_eq!(codec, walked, "{version:?}, {options:?}");
            if let Ok(bytes) = codec {
                assert_eq!(
                    (bytes.len(), bytes[0]),
                    (2, 0x02),
                    "{version:?}, {options:?}"
                );
            }
        }
    }
}

/// An int64 `p_version` written as given (versions kept) in a type the plan's one-word path
/// does not take (a uint8 before it: 72 bits): -2 is two's complement, FE then seven FF
/// (little-endian), its sign bit set like the others: `{a: uint8, p_version: int64}` with
/// a = 1 is 01 FE FF FF FF FF FF FF FF.
#[test]
fn a_negative_int64_version_kept_as_given_keeps_its_sign_bit() {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let i64_ = l.int(64, Cast::Saturated).unwrap();
    let root = l
        .structure(&[
            ("a", u8_, Role::Data),
            ("p_version", i64_, Role::Version(3)),
        ])
        .unwrap();
    let layout = l.as_layout();
    let kept = EncodeOptions {
        keep_versions: true,
        ..EncodeOptions::default()
    };
    let expected: Result<Vec<u8>, String> =
        Ok(vec![0x01, 0xFE, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF]);
    assert_eq!(
        both(&layout, root, &[Scalar::Uint(1), Scalar::Int(-2)], kept),
        [expected.clone(), expected]
    );
}
