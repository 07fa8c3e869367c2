//! A transfer's frames checked ([`transfer::receive`]) and decoded where they lie, against the
//! walk (`NoPlans`, what firmware runs) over the payload's flat bytes.
//!
//! On hosts, `receive` keeps a short multi-frame payload gathered into one run (as it gathers
//! it for the CRC) and a single frame's payload is one run as it lies, so that the
//! straight-line plan decodes from the frames as from flat bytes
//! ([`px4params_core::scatter::Pieces::contiguous`]); longer payloads stay in pieces for the
//! general decoder. Over random types, payloads of random lengths (a value encoded whole,
//! cut short, with bytes after it, random bytes), classic CAN and CAN FD: the dispatcher
//! over the received pieces gives what the walk gives over the flat bytes, bits, leaves and
//! errors alike.

mod common;

use common::{any_type, same_error, same_leaves, Ty};
use proptest::prelude::*;
use px4params_core::bits::BitRead;
use px4params_core::codec::{self, decode_leaves_with, encode_leaves_with};
use px4params_core::codec::{DecodeOptions, EncodeOptions};
use px4params_core::compile::OwnedLayout;
use px4params_core::error::Error;
use px4params_core::layout::{Layout, NodeId};
use px4params_core::plan::{Active, NoPlans, Plans};
use px4params_core::scatter::{Pieces, Scattered};
use px4params_core::transfer::{frames, receive, Received};
use px4params_core::value::{LeafError, LeafSink};
use px4params_core::Scalar;

type Decoded = Result<(usize, Vec<Scalar>), Error<LeafError>>;

const SEED: u16 = 0xBEEF;

/// The frames of `payload`'s transfer (its CRC first where there are several).
fn split(payload: &[u8], canfd: bool) -> Vec<Vec<u8>> {
    frames(payload, SEED, 7, canfd)
        .map(|f| f.as_bytes().to_vec())
        .collect()
}

fn walk_decoded(layout: &Layout<'_>, root: NodeId, data: &[u8], o: DecodeOptions) -> Decoded {
    let mut leaves = vec![Scalar::Uint(0); 600];
    let d = decode_leaves_with::<NoPlans, _>(layout, root, data, &mut leaves, o)?;
    Ok((d.bits, leaves[..d.leaves].to_vec()))
}

fn received_decoded(
    layout: &Layout<'_>,
    root: NodeId,
    received: &Received<'_, '_>,
    o: DecodeOptions,
) -> Decoded {
    let mut leaves = vec![Scalar::Uint(0); 600];
    let mut sink = LeafSink::new(&mut leaves);
    let data = Scattered::new(&received.payload);
    let bits = codec::decode(layout, root, &data, &mut sink, o)?;
    Ok((bits, sink.leaves().to_vec()))
}

/// A payload of `root`: a value the walk decodes from `seed` bytes and encodes again (else
/// the bytes themselves), then cut to `cut` bytes when given, or lengthened by `extra`.
fn payload_of(
    layout: &Layout<'_>,
    root: NodeId,
    seed: &[u8],
    tao: bool,
    cut: Option<prop::sample::Index>,
    extra: &[u8],
) -> Vec<u8> {
    let options = DecodeOptions {
        tao,
        allow_trailing: true,
    };
    let mut bytes = match walk_decoded(layout, root, seed, options) {
        Ok((_, leaves)) => {
            let mut out = vec![0u8; layout.max_bytes(root) + 8];
            let o = EncodeOptions {
                tao,
                ..EncodeOptions::default()
            };
            match encode_leaves_with::<NoPlans>(layout, root, &leaves, &mut out, o) {
                Ok(n) => out[..n].to_vec(),
                Err(_) => seed.to_vec(),
            }
        }
        Err(_) => seed.to_vec(),
    };
    match cut {
        Some(at) if !bytes.is_empty() => bytes.truncate(at.index(bytes.len())),
        _ => bytes.extend_from_slice(extra),
    }
    bytes
}

fn check(
    layout: &Layout<'_>,
    root: NodeId,
    payload: &[u8],
    canfd: bool,
    o: DecodeOptions,
) -> Result<(), TestCaseError> {
    let sent = split(payload, canfd);
    let refs: Vec<&[u8]> = sent.iter().map(Vec::as_slice).collect();
    let received = receive(&refs, SEED).unwrap();
    // CAN FD pads the last frame to a length it can have: the padding is payload.
    let pieces = &received.payload;
    let payload: Vec<u8> = (0..pieces.count())
        .flat_map(|i| pieces.piece(i).to_vec())
        .collect();
    let payload = &payload[..];
    let stream = Scattered::new(&received.payload);
    prop_assert_eq!(stream.len(), payload.len());
    // Where the plan is on, a short payload is one run: the one the frames carry.
    let short = refs.len() == 1 || payload.len() <= 64;
    if Active::GATHERED_CRC && short && !payload.is_empty() {
        prop_assert_eq!(stream.contiguous(), Some(payload));
        prop_assert_eq!(received.payload.contiguous(), Some(payload));
    }
    let walk = walk_decoded(layout, root, payload, o);
    let ours = received_decoded(layout, root, &received, o);
    match (&ours, &walk) {
        (Ok((a, x)), Ok((b, y))) => {
            prop_assert!(a == b && same_leaves(x, y), "{:?} / {:?}", ours, walk)
        }
        (Err(a), Err(b)) => prop_assert!(same_error(a, b), "{a:?} / {b:?}"),
        _ => prop_assert!(false, "received {ours:?}, walk {walk:?}"),
    }
    Ok(())
}

/// Types of the straight-line plan's shape (fixed fields, perhaps a last dynamic array of
/// primitives) more often than any type would give them.
fn a_type() -> impl Strategy<Value = Ty> {
    let fixed = prop_oneof![
        4 => (common::primitive(), any::<bool>()),
        1 => (1u32..=9).prop_map(|b| (Ty::Void(b), false)),
    ];
    prop_oneof![
        2 => any_type(),
        3 => (
            proptest::collection::vec(fixed, 0..12),
            proptest::option::of((common::primitive(), 1u32..90)),
        )
            .prop_map(|(mut fields, tail)| {
                if let Some((elem, max)) = tail {
                    fields.push((Ty::Dyn(Box::new(elem), max), false));
                }
                Ty::Struct(fields)
            }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn received_frames_decode_as_the_flat_payload(
        ty in a_type(),
        seed in proptest::collection::vec(any::<u8>(), 0..120),
        cut in proptest::option::of(any::<prop::sample::Index>()),
        extra in proptest::collection::vec(any::<u8>(), 0..3),
        tao in any::<bool>(),
        allow_trailing in any::<bool>(),
        canfd in any::<bool>(),
    ) {
        let mut owned = OwnedLayout::default();
        let root = ty.build(&mut owned);
        let layout = owned.as_layout();
        let payload = payload_of(&layout, root, &seed, tao, cut, &extra);
        let o = DecodeOptions { tao, allow_trailing };
        check(&layout, root, &payload, canfd, o)?;
        // The random bytes themselves too: mostly not a value.
        check(&layout, root, &seed, canfd, o)?;
    }
}

/// BatteryInfo, as `benches/instructions.rs` receives it: a multi-frame transfer whose
/// payload is gathered, decoded whole and cut short by a frame.
#[test]
fn battery_info_received_decodes_as_flat_bytes() {
    let mut owned = OwnedLayout::default();
    let root = common::battery_info(&mut owned);
    let layout = owned.as_layout();
    let mut leaves: Vec<Scalar> = [300.5, 16.8, -12.25, 201.0, 55.5, 99.0, 0.0]
        .into_iter()
        .map(Scalar::Float)
        .collect();
    leaves.extend([3, 97, 80, 2, 1, 123_456].map(Scalar::Uint));
    let name = b"PX4 smart battery 6S";
    leaves.push(Scalar::Uint(name.len() as u64));
    leaves.extend(name.iter().map(|&b| Scalar::Uint(b.into())));
    let mut out = [0u8; 64];
    let n =
        codec::encode_leaves(&layout, root, &leaves, &mut out, EncodeOptions::default()).unwrap();
    for len in [n, n - 7, n - 20, 3] {
        let payload = &out[..len];
        check(&layout, root, payload, false, DecodeOptions::default()).unwrap();
    }
    let sent = split(&out[..n], false);
    let refs: Vec<&[u8]> = sent.iter().map(Vec::as_slice).collect();
    assert!(refs.len() > 1);
    let received = receive(&refs, SEED).unwrap();
    let decoded = received_decoded(&layout, root, &received, DecodeOptions::default());
    let (_, got) = decoded.unwrap();
    let (_, flat) = walk_decoded(&layout, root, &out[..n], DecodeOptions::default()).unwrap();
    assert!(same_leaves(&got, &flat) && got.len() == leaves.len());
    assert_eq!(
        got[got.len() - name.len()..],
        leaves[leaves.len() - name.len()..]
    );
}
