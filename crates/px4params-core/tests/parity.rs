//! Every plan against the walk: each operation's dispatcher run with the host's plans
//! (`HostPlans`) and with none (`NoPlans`, the walk alone, what firmware runs), in one build,
//! over random types, random values (decoded from random bytes, then changed at random),
//! buffers too small, exact and roomy, and data complete and cut short: the same bytes,
//! leaves, positions and errors.
//!
//! The one loop of the codec ([`codec::encode_with`], [`codec::decode_with`] over a leaf list,
//! under either set: with the flat runs of `HostPlans` inside it and without) is also held to
//! the general walk ([`walk::encode`], [`walk::decode`], what firmware runs for leaf lists):
//! the same bytes, leaves and errors.
//!
//! Where the two report one fault differently, the test says so and compares what both must
//! agree on (as `tests/walk.rs` does for the walk against the host's own walks). The store's
//! leaf tables and in-place writes follow the build's plans: `cargo test --features
//! alloc,compact` runs the store's tests over the walk.

mod common;

use common::{any_type, same_error, same_leaves, same_scalar};
use proptest::prelude::*;
use px4params_core::codec::{
    self, check_stored_with, decode_leaves_with, encode_leaves_with, DecodeOptions, EncodeOptions,
};
use px4params_core::compile::OwnedLayout;
use px4params_core::error::Error;
use px4params_core::layout::{Layout, NodeId};
use px4params_core::leaf::{
    encode_default, get_leaf_at_with, locate_at_with, seek_with, set_leaf_at_with,
};
use px4params_core::plan::{HostPlans, NoPlans, Plans};
use px4params_core::translate::translate_value_with;
use px4params_core::value::{LeafError, LeafSink, LeafSource};
use px4params_core::walk;
use px4params_core::{ErrorKind, Scalar};

type Decoded = Result<(usize, Vec<Scalar>), Error<LeafError>>;
type Encoded = Result<Vec<u8>, Error<LeafError>>;

fn decoded<P: Plans>(layout: &Layout<'_>, root: NodeId, data: &[u8], o: DecodeOptions) -> Decoded {
    let mut leaves = vec![Scalar::Uint(0); 600];
    let d = decode_leaves_with::<P, _>(layout, root, data, &mut leaves, o)?;
    Ok((d.bits, leaves[..d.leaves].to_vec()))
}

fn encoded<P: Plans>(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    options: EncodeOptions,
) -> Encoded {
    let mut out = vec![0xA5u8; size];
    let n = encode_leaves_with::<P>(layout, root, leaves, &mut out, options)?;
    out.truncate(n);
    Ok(out)
}

/// What the codec's loop decodes into a leaf list with the plans `P`, as [`decoded`] gives it.
fn loop_decoded<P: Plans>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
    o: DecodeOptions,
) -> Decoded {
    let mut leaves = vec![Scalar::Uint(0); 600];
    let mut sink = LeafSink::new(&mut leaves);
    let bits = codec::decode_with::<P, _, _>(layout, root, data, &mut sink, o)?;
    let n = sink.leaves().len();
    Ok((bits, leaves[..n].to_vec()))
}

/// What the codec's loop encodes from a leaf list with the plans `P`, as [`encoded`] gives it.
fn loop_encoded<P: Plans>(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    options: EncodeOptions,
) -> Encoded {
    let mut out = vec![0xA5u8; size];
    let mut source = LeafSource::new(leaves);
    let n = codec::encode_with::<P, _>(layout, root, &mut source, &mut out, options)?;
    out.truncate(n);
    Ok(out)
}

/// What the general walk decodes, as [`decoded`] gives it.
fn walk_decoded(layout: &Layout<'_>, root: NodeId, data: &[u8], o: DecodeOptions) -> Decoded {
    let mut leaves = vec![Scalar::Uint(0); 600];
    let d = walk::decode(layout, root, data, &mut leaves, o)?;
    Ok((d.bits, leaves[..d.leaves].to_vec()))
}

/// What the general walk encodes, as [`encoded`] gives it.
fn walk_encoded(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    options: EncodeOptions,
) -> Encoded {
    let mut out = vec![0xA5u8; size];
    let n = walk::encode(layout, root, leaves, &mut out, options)?;
    out.truncate(n);
    Ok(out)
}

fn same_decoding(plan: &Decoded, walk: &Decoded) -> Result<(), TestCaseError> {
    match (plan, walk) {
        (Ok((a, x)), Ok((b, y))) => {
            prop_assert!(a == b && same_leaves(x, y), "{:?} / {:?}", plan, walk)
        }
        (Err(a), Err(b)) => prop_assert!(same_error(a, b), "{:?} / {:?}", a, b),
        _ => prop_assert!(false, "{:?} / {:?}", plan, walk),
    }
    Ok(())
}

fn same_encoding(plan: &Encoded, walk: &Encoded) -> Result<(), TestCaseError> {
    match (plan, walk) {
        (Ok(x), Ok(y)) => prop_assert_eq!(x, y),
        (Err(x), Err(y)) => prop_assert!(same_error(x, y), "{:?} / {:?}", x, y),
        _ => prop_assert!(false, "{:?} / {:?}", plan, walk),
    }
    Ok(())
}

/// A stored value of `root` (no tail array optimization): the longest prefix of `data` that
/// decodes; `None` if none does.
fn value_from(layout: &Layout<'_>, root: NodeId, data: &[u8]) -> Option<Vec<u8>> {
    let options = DecodeOptions {
        tao: false,
        allow_trailing: true,
    };
    let (bits, _) = decoded::<NoPlans>(layout, root, data, options).ok()?;
    Some(data[..bits.div_ceil(8)].to_vec())
}

/// `data`, and every prefix of it: the value complete and cut short.
fn cut_short(data: &[u8]) -> impl Iterator<Item = &[u8]> {
    (0..=data.len()).rev().map(move |n| &data[..n])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Decoding random bytes, and a value complete and cut short at every byte: the same
    /// leaves and bits, or the same error.
    #[test]
    fn decode_plan_as_the_walk(ty in any_type(), data in proptest::collection::vec(any::<u8>(), 0..64), tao in any::<bool>(), allow_trailing in any::<bool>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let options = DecodeOptions { tao, allow_trailing };
        let walked = walk_decoded(&layout, root, &data, options);
        same_decoding(&decoded::<HostPlans>(&layout, root, &data, options), &walked)?;
        same_decoding(&decoded::<NoPlans>(&layout, root, &data, options), &walked)?;
        same_decoding(&loop_decoded::<HostPlans>(&layout, root, &data, options), &walked)?;
        same_decoding(&loop_decoded::<NoPlans>(&layout, root, &data, options), &walked)?;
        let value = value_from(&layout, root, &data).unwrap_or_default();
        for bytes in cut_short(&value) {
            let options = DecodeOptions { tao: false, allow_trailing };
            let walked = walk_decoded(&layout, root, bytes, options);
            same_decoding(&decoded::<HostPlans>(&layout, root, bytes, options), &walked)?;
            same_decoding(&decoded::<NoPlans>(&layout, root, bytes, options), &walked)?;
            same_decoding(&loop_decoded::<HostPlans>(&layout, root, bytes, options), &walked)?;
            same_decoding(&loop_decoded::<NoPlans>(&layout, root, bytes, options), &walked)?;
        }
    }

    /// Encoding leaf lists (decoded ones, changed at random, cut or lengthened) into buffers
    /// too small by one, exact, roomy and of a random size: the same bytes, or the same error.
    #[test]
    fn encode_plan_as_the_walk(
        ty in any_type(),
        data in proptest::collection::vec(any::<u8>(), 0..64),
        tweaks in proptest::collection::vec((any::<prop::sample::Index>(), any::<u64>(), 0u8..4), 0..3),
        cut in 0usize..3,
        cap in any::<prop::sample::Index>(),
        tao in any::<bool>(),
        saturate in any::<bool>(),
        keep_versions in any::<bool>(),
    ) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let decoded = decoded::<NoPlans>(&layout, root, &data, DecodeOptions { tao, allow_trailing: true });
        let mut leaves = decoded.map(|(_, leaves)| leaves).unwrap_or_default();
        common::tweak_leaves(&mut leaves, &tweaks, cut);
        let options = EncodeOptions { tao, saturate, keep_versions };
        let room = layout.max_bytes(root);
        let roomy = walk_encoded(&layout, root, &leaves, room, options);
        same_encoding(&encoded::<HostPlans>(&layout, root, &leaves, room, options), &roomy)?;
        same_encoding(&encoded::<NoPlans>(&layout, root, &leaves, room, options), &roomy)?;
        same_encoding(&loop_encoded::<HostPlans>(&layout, root, &leaves, room, options), &roomy)?;
        same_encoding(&loop_encoded::<NoPlans>(&layout, root, &leaves, room, options), &roomy)?;
        let exact = roomy.as_ref().map_or(0, Vec::len);
        for size in [exact, exact.saturating_sub(1), cap.index(room + 2)] {
            let walk = walk_encoded(&layout, root, &leaves, size, options);
            let plans = [
                encoded::<HostPlans>(&layout, root, &leaves, size, options),
                encoded::<NoPlans>(&layout, root, &leaves, size, options),
                loop_encoded::<HostPlans>(&layout, root, &leaves, size, options),
                loop_encoded::<NoPlans>(&layout, root, &leaves, size, options),
            ];
            for plan in plans {
                let too_small = |r: &Encoded| matches!(r, Err(e) if matches!(e.kind, ErrorKind::BufferTooSmall { .. }));
                if too_small(&plan) || too_small(&walk) {
                    // Which fault is found first, a short buffer or a bad leaf, is each one's
                    // own order (the loop stops at the first byte that finds no room, the
                    // walk tells how many bytes the value needs): both fail, and with room
                    // (above) they agree.
                    prop_assert!(plan.is_err() && walk.is_err(), "{:?} / {:?}", plan, walk);
                } else {
                    same_encoding(&plan, &walk)?;
                }
            }
        }
    }

    /// Leaf `[k]` of random bytes and of a value complete and cut short: located, read and
    /// sought alike, or the same error.
    #[test]
    fn leaf_plans_as_the_walk(ty in any_type(), data in proptest::collection::vec(any::<u8>(), 0..64), tao in any::<bool>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let value = value_from(&layout, root, &data).unwrap_or_default();
        // Where a tail array is too long or an element of it broken, the leaf walk counts the
        // elements its own way; the walk finds what decoding finds.
        let malformed = tao && decoded::<NoPlans>(&layout, root, &data, DecodeOptions { tao, allow_trailing: true }).is_err();
        let mut cases = vec![(&data[..], tao)];
        cases.extend(cut_short(&value).map(|bytes| (bytes, false)));
        for (bytes, tao) in cases {
            for k in 0..24 {
                let plan = get_leaf_at_with::<HostPlans, _>(&layout, root, bytes, k, tao);
                let walk = get_leaf_at_with::<NoPlans, _>(&layout, root, bytes, k, tao);
                let located = (locate_at_with::<HostPlans, _>(&layout, root, bytes, k, tao), locate_at_with::<NoPlans, _>(&layout, root, bytes, k, tao));
                match (&plan, &walk) {
                    (Err(_), _) | (_, Err(_)) if malformed && tao => {}
                    (Ok((a, x)), Ok((b, y))) => {
                        prop_assert!(a == b && same_scalar(*x, *y), "[{}] {:?} / {:?}", k, plan, walk);
                        prop_assert_eq!(located.0, Ok(*a), "[{}]", k);
                        prop_assert_eq!(located.1, Ok(*b), "[{}]", k);
                    }
                    (Err(a), Err(b)) => prop_assert!(same_error(a, b), "[{}] {:?} / {:?}", k, a, b),
                    _ => prop_assert!(false, "[{}] {:?} / {:?}", k, plan, walk),
                }
                if !tao {
                    prop_assert_eq!(seek_with::<HostPlans, _>(&layout, root, bytes, k), seek_with::<NoPlans, _>(&layout, root, bytes, k), "[{}]", k);
                }
            }
        }
    }

    /// Translating a stored value of one random type (complete, cut short, or random bytes)
    /// onto a value of another, whose fields meet by name: the same bytes, or the same error.
    #[test]
    fn translate_plan_as_the_walk(old in any_type(), new in any_type(), a in proptest::collection::vec(any::<u8>(), 0..40), b in proptest::collection::vec(any::<u8>(), 0..40)) {
        let mut l = OwnedLayout::default();
        let old_root = old.build(&mut l);
        let new_root = new.build(&mut l);
        let layout = l.as_layout();
        let base = match value_from(&layout, new_root, &b) {
            Some(v) => v,
            None => {
                let mut out = vec![0u8; layout.max_bytes(new_root)];
                let n = encode_default(&layout, new_root, &mut out, false).unwrap();
                out.truncate(n);
                out
            }
        };
        let value = value_from(&layout, old_root, &a).unwrap_or_default();
        let size = layout.max_bytes(new_root) + 1;
        for old_data in cut_short(&value).chain([&a[..]]) {
            let (mut x, mut y) = (vec![0xA5u8; size], vec![0xA5u8; size]);
            let plan = translate_value_with::<HostPlans, _, _>(&layout, old_root, old_data, new_root, &base[..], &mut x);
            let walk = translate_value_with::<NoPlans, _, _>(&layout, old_root, old_data, new_root, &base[..], &mut y);
            match (&plan, &walk) {
                (Ok(p), Ok(q)) => prop_assert!(p == q && x[..*p] == y[..*q], "{:02x?} / {:02x?}", &x[..*p], &y[..*q]),
                (Err(p), Err(q)) => prop_assert!(same_error(p, q), "{:?} / {:?}", p, q),
                _ => prop_assert!(false, "{:?} / {:?}", plan, walk),
            }
        }
    }

    /// Writing leaf `[k]` of a stored value (complete, cut short, or random bytes) with a
    /// random value of each kind, into buffers roomy and too small: the same bytes, or the
    /// same error.
    #[test]
    fn set_leaf_plan_as_the_walk(
        ty in any_type(),
        data in proptest::collection::vec(any::<u8>(), 0..64),
        raw in any::<u64>(),
        kind in 0u8..4,
        saturate in any::<bool>(),
        short in 0usize..3,
    ) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let value = value_from(&layout, root, &data).unwrap_or_default();
        let v = match kind {
            0 => Scalar::Uint(raw % 8),
            1 => Scalar::Int(raw as i64),
            2 => Scalar::Float(f64::from_bits(raw)),
            _ => Scalar::Bool(raw % 2 == 1),
        };
        let options = EncodeOptions { tao: false, saturate, keep_versions: false };
        let size = (layout.max_bytes(root).max(data.len()) + 1).saturating_sub(short * 2);
        for bytes in cut_short(&value).chain([&data[..]]) {
            for k in 0..24 {
                let (mut x, mut y) = (vec![0xA5u8; size], vec![0xA5u8; size]);
                let plan = set_leaf_at_with::<HostPlans, _>(&layout, root, bytes, k, v, &mut x, options);
                let walk = set_leaf_at_with::<NoPlans, _>(&layout, root, bytes, k, v, &mut y, options);
                match (&plan, &walk) {
                    (Ok(p), Ok(q)) => prop_assert!(p == q && x[..*p] == y[..*q], "[{}] {:02x?} / {:02x?}", k, &x[..*p], &y[..*q]),
                    (Err(p), Err(q)) => prop_assert!(same_error(p, q), "[{}] {:?} / {:?}", k, p, q),
                    _ => prop_assert!(false, "[{}] {:?} / {:?}", k, plan, walk),
                }
            }
        }
    }

    /// Checking a stored value's `p_version` fields (a value complete, cut short, with a
    /// byte too many, or random bytes): the same answer, or the same error.
    #[test]
    fn check_plan_as_the_walk(ty in any_type(), data in proptest::collection::vec(any::<u8>(), 0..64)) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let mut value = value_from(&layout, root, &data).unwrap_or_default();
        let mut longer = value.clone();
        longer.push(0);
        for bytes in cut_short(&value).chain([&longer[..], &data[..]]) {
            let plan = check_stored_with::<HostPlans>(&layout, root, bytes);
            let walk = check_stored_with::<NoPlans>(&layout, root, bytes);
            match (&plan, &walk) {
                (Ok(()), Ok(())) => {}
                (Err(p), Err(q)) => prop_assert!(same_error(p, q), "{:?} / {:?}", p, q),
                _ => prop_assert!(false, "{:?} / {:?}", plan, walk),
            }
        }
        // A stored value with its version spoiled: both refuse it alike.
        if let Some(b) = value.first_mut() {
            *b ^= 0x01;
        }
        let (plan, walk) = (check_stored_with::<HostPlans>(&layout, root, &value), check_stored_with::<NoPlans>(&layout, root, &value));
        prop_assert!(plan.is_ok() == walk.is_ok(), "{:?} / {:?}", plan, walk);
    }
}

/// The lookup by path (a visit that follows a way through the loop) against leaf `[k]` found
/// by the walk.
mod path_lookup {
    use super::*;
    use px4params_core::codec::LeafKind;
    use px4params_core::leaf::{get_leaf, Leaf, Target};

    /// The textual path of a leaf, as a user writes it (`None` past the depth a path keeps).
    fn text(layout: &Layout<'_>, leaf: &Leaf) -> Option<String> {
        let path = leaf.path.display(layout).to_string();
        let own = match leaf.kind {
            LeafKind::Scalar(_) => return (!path.ends_with("...")).then_some(path),
            LeafKind::Tag { .. } => "_tag",
            LeafKind::Len { .. } => "_len",
        };
        let dot = if path.is_empty() { "" } else { "." };
        (!path.ends_with("...")).then(|| format!("{path}{dot}{own}"))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Each leaf of a value (random bytes, or a stored value complete and cut short at
        /// every byte), looked up by the path of the leaf `[k]` it is in the whole value: the
        /// same leaf (number, position, kind, path) and value as the walk finds for `[k]`, or
        /// the same error (the data ending or breaking before it); in the whole value, found.
        #[test]
        fn path_lookup_as_the_walk(ty in any_type(), data in proptest::collection::vec(any::<u8>(), 0..64), tao in any::<bool>()) {
            let mut l = OwnedLayout::default();
            let root = ty.build(&mut l);
            let layout = l.as_layout();
            let value = value_from(&layout, root, &data).unwrap_or_default();
            // The leaves as the codec decodes them (its own code): what leaf `[k]` holds.
            let all = |bytes: &[u8], tao| decoded::<HostPlans>(&layout, root, bytes, DecodeOptions { tao, allow_trailing: true }).map(|(_, leaves)| leaves).ok();
            let mut cases = vec![(&data[..], &data[..], tao)];
            cases.extend(cut_short(&value).map(|bytes| (&value[..], bytes, false)));
            for (whole, bytes, tao) in cases {
                for k in 0..24 {
                    let Ok((leaf, _)) = walk::locate(&layout, root, whole, k, tao) else {
                        continue;
                    };
                    let Some(path) = text(&layout, &leaf) else {
                        continue;
                    };
                    let by_path = get_leaf(&layout, root, bytes, Target::Path(&path), tao);
                    let walked = walk::locate(&layout, root, bytes, k, tao);
                    match (&by_path, &walked) {
                        (Ok((a, x)), Ok((b, y))) => prop_assert!(a == b && same_scalar(*x, *y), "{} [{}] {:?} / {:?}", path, k, by_path, walked),
                        (Err(a), Err(b)) => prop_assert!(same_error(a, b), "{} [{}] {:?} / {:?}", path, k, a, b),
                        _ => prop_assert!(false, "{} [{}] {:?} / {:?}", path, k, by_path, walked),
                    }
                    if bytes.len() == whole.len() {
                        prop_assert!(by_path.is_ok(), "{} [{}] {:?}", path, k, by_path);
                        if let (Some(leaves), Ok((leaf, v))) = (all(bytes, tao), &by_path) {
                            prop_assert!(leaf.index == k && same_scalar(*v, leaves[k]), "{} [{}] {:?} / {:?}", path, k, v, leaves[k]);
                        }
                    }
                }
            }
        }
    }
}

/// Receiving a transfer with the host's plans (full classic frames checked and gathered in
/// one pass) against the general path (`NoPlans`): random payloads sent as classic CAN or CAN
/// FD frames, then spoiled the ways a bus or a sender spoils them (a bit flipped, a frame
/// lost, repeated, swapped, cut or lengthened, the transfer ID changed): the same transfer
/// ID and payload, or the same error; and into a buffer, the same bytes.
mod transfer_plan {
    use super::*;
    use px4params_core::scatter::Pieces;
    use px4params_core::transfer::{frames, receive_into_with, receive_with, TransferError};

    const SEED: u16 = 0x5EED;

    type Got = Result<(u8, Vec<u8>), TransferError>;

    fn received<P: Plans>(frames: &[&[u8]]) -> Got {
        let r = receive_with::<P>(frames, SEED)?;
        let bytes = (0..r.payload.count()).flat_map(|i| r.payload.piece(i).to_vec());
        Ok((r.transfer_id, bytes.collect()))
    }

    /// `receive_into` with the plans `P` into a buffer of `room` bytes (filled with 0xA5):
    /// the transfer ID and the payload, or the error with the buffer as it was left.
    fn received_into<P: Plans>(frames: &[&[u8]], room: usize) -> (Got, Vec<u8>) {
        let mut out = vec![0xA5; room];
        let got = receive_into_with::<P>(frames, SEED, &mut out);
        match got {
            Ok((id, len)) => (Ok((id, out[..len].to_vec())), out[len..].to_vec()),
            Err(e) => (Err(e), out),
        }
    }

    #[derive(Clone, Debug)]
    enum Spoil {
        None,
        Flip {
            frame: prop::sample::Index,
            byte: prop::sample::Index,
            bit: u8,
        },
        Drop(prop::sample::Index),
        Repeat(prop::sample::Index),
        Swap(prop::sample::Index),
        Cut(prop::sample::Index),
        Lengthen(prop::sample::Index, u8),
        TransferId(prop::sample::Index),
    }

    fn spoil() -> impl Strategy<Value = Spoil> {
        use prop::sample::Index;
        prop_oneof![
            3 => Just(Spoil::None),
            2 => (any::<Index>(), any::<Index>(), 0u8..8).prop_map(|(frame, byte, bit)| Spoil::Flip { frame, byte, bit }),
            1 => any::<Index>().prop_map(Spoil::Drop),
            1 => any::<Index>().prop_map(Spoil::Repeat),
            1 => any::<Index>().prop_map(Spoil::Swap),
            1 => any::<Index>().prop_map(Spoil::Cut),
            1 => (any::<Index>(), any::<u8>()).prop_map(|(i, b)| Spoil::Lengthen(i, b)),
            1 => any::<Index>().prop_map(Spoil::TransferId),
        ]
    }

    fn spoiled(mut frames: Vec<Vec<u8>>, how: &Spoil) -> Vec<Vec<u8>> {
        let n = frames.len();
        match how {
            Spoil::None => {}
            Spoil::Flip { frame, byte, bit } => {
                let f = &mut frames[frame.index(n)];
                let at = byte.index(f.len());
                f[at] ^= 1 << bit;
            }
            Spoil::Drop(i) => {
                frames.remove(i.index(n));
            }
            Spoil::Repeat(i) => {
                let i = i.index(n);
                frames.insert(i, frames[i].clone());
            }
            Spoil::Swap(i) => {
                let i = i.index(n);
                frames.swap(i, (i + 1) % n);
            }
            Spoil::Cut(i) => {
                let f = &mut frames[i.index(n)];
                f.remove(0);
            }
            Spoil::Lengthen(i, b) => frames[i.index(n)].insert(0, *b),
            Spoil::TransferId(i) => {
                let f = &mut frames[i.index(n)];
                *f.last_mut().unwrap() ^= 0x01;
            }
        }
        frames
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn receive_plan_as_the_general_path(
            payload in proptest::collection::vec(any::<u8>(), 0..140),
            canfd in any::<bool>(),
            transfer_id in 0u8..32,
            how in spoil(),
            slack in 0usize..3,
        ) {
            let sent: Vec<Vec<u8>> = frames(&payload, SEED, transfer_id, canfd)
                .map(|f| f.as_bytes().to_vec())
                .collect();
            let sent = spoiled(sent, &how);
            let refs: Vec<&[u8]> = sent.iter().map(Vec::as_slice).collect();
            let plan = received::<HostPlans>(&refs);
            let walk = received::<NoPlans>(&refs);
            prop_assert_eq!(&plan, &walk);
            if matches!(how, Spoil::None) {
                let (id, bytes) = plan.clone().unwrap();
                prop_assert_eq!(id, transfer_id);
                // CAN FD pads the last frame to a length it can have: the padding is payload.
                prop_assert_eq!(&bytes[..payload.len()], &payload[..]);
            }
            // Into a buffer one byte short, exact, and roomier.
            let len = plan.as_ref().map_or(payload.len(), |(_, b)| b.len());
            for room in [len.saturating_sub(1), len + slack] {
                let (plan_into, plan_left) = received_into::<HostPlans>(&refs, room);
                let (walk_into, walk_left) = received_into::<NoPlans>(&refs, room);
                prop_assert_eq!(&plan_into, &walk_into);
                match &plan_into {
                    Ok(_) => {
                        prop_assert_eq!(&plan_into, &plan);
                        // Bytes after the payload are left alone.
                        prop_assert!(plan_left.iter().chain(&walk_left).all(|&b| b == 0xA5));
                    }
                    // Frames that do not fit leave the buffer alone.
                    Err(TransferError::TooLong { .. }) => {
                        prop_assert!(plan_left.iter().chain(&walk_left).all(|&b| b == 0xA5));
                    }
                    Err(_) => {}
                }
            }
        }
    }

    /// The plan's own edges, each against the general path: two frames, the most the run
    /// holds (64 bytes) and one more, a last frame of one payload byte, and of none (the tail
    /// byte alone, which the plan leaves to the general path).
    #[test]
    fn the_plans_edges_as_the_general_path() {
        for len in [6, 7, 12, 13, 63, 64, 65, 66] {
            let payload: Vec<u8> = (0..len as u8).map(|b| b.wrapping_mul(29)).collect();
            let sent: Vec<Vec<u8>> = frames(&payload, SEED, 9, false)
                .map(|f| f.as_bytes().to_vec())
                .collect();
            let refs: Vec<&[u8]> = sent.iter().map(Vec::as_slice).collect();
            let plan = received::<HostPlans>(&refs);
            assert_eq!(plan, received::<NoPlans>(&refs), "{len} bytes");
            assert_eq!(plan, Ok((9, payload.clone())), "{len} bytes");
        }
        // A last frame of its tail byte alone: no sender makes one, the rules allow it.
        let payload: Vec<u8> = (0..12).collect();
        let mut sent: Vec<Vec<u8>> = frames(&payload, SEED, 4, false)
            .map(|f| f.as_bytes().to_vec())
            .collect();
        assert_eq!(sent.len(), 2);
        let last = sent[1].clone();
        // The last frame's payload moved into a middle frame of its own, toggle and all.
        let (tail, piece) = last.split_last().unwrap();
        let mut middle = piece.to_vec();
        middle.push(tail & !0x40);
        sent[1] = middle;
        sent.push(vec![(tail & 0x1F) | 0x40]);
        let refs: Vec<&[u8]> = sent.iter().map(Vec::as_slice).collect();
        let plan = received::<HostPlans>(&refs);
        assert_eq!(plan, received::<NoPlans>(&refs));
        assert_eq!(plan, Ok((4, payload)));
    }
}
