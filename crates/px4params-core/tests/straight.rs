//! The straight-line plan ([`px4params_core::straight`]) against the walk (`NoPlans`, what
//! firmware runs): over random small fixed-shape types (a run of primitives, padding, nested
//! structs and static arrays, perhaps ended by a dynamic array of primitives), random values
//! (decoded from random bytes, then spoiled at random), buffers too small, exact and roomy,
//! data complete and cut short. Where the plan answers, the walk gives the same bytes, bits
//! and leaves; where the walk fails, the plan declines (it never words an error); and the
//! dispatchers ([`codec::encode`], [`codec::decode`]) give what the walk gives, errors
//! included. Types of other shapes are always declined.

mod common;

use common::{any_type, primitive, same_error, same_leaves, tweak_leaves, Ty};
use proptest::prelude::*;
use px4params_core::codec::{
    self, decode_leaves_with, encode_leaves_with, DecodeOptions, EncodeOptions,
};
use px4params_core::compile::OwnedLayout;
use px4params_core::error::Error;
use px4params_core::layout::{Layout, NodeId};
use px4params_core::plan::{Active, HostPlans, NoPlans, Plans};
use px4params_core::straight;
use px4params_core::value::{LeafError, LeafSink, LeafSource};
use px4params_core::{ErrorKind, Scalar};

type Decoded = Result<(usize, Vec<Scalar>), Error<LeafError>>;
type Encoded = Result<Vec<u8>, Error<LeafError>>;

/// A field of fixed shape: a primitive, padding, a struct of primitives, a static array.
fn fixed_field() -> impl Strategy<Value = (Ty, bool)> {
    prop_oneof![
        6 => (primitive(), any::<bool>()),
        1 => (1u32..=9).prop_map(|b| (Ty::Void(b), false)),
        1 => proptest::collection::vec((primitive(), any::<bool>()), 0..4)
            .prop_map(|fields| (Ty::Struct(fields), false)),
        1 => (primitive(), 1u32..4).prop_map(|(t, n)| (Ty::Array(Box::new(t), n), false)),
    ]
}

/// A type the plan is for: fixed fields, perhaps a last dynamic array of primitives.
fn straight_type() -> impl Strategy<Value = Ty> {
    (
        proptest::collection::vec(fixed_field(), 0..7),
        proptest::option::of((primitive(), 1u32..12)),
    )
        .prop_map(|(mut fields, tail)| {
            if let Some((elem, max)) = tail {
                fields.push((Ty::Dyn(Box::new(elem), max), false));
            }
            Ty::Struct(fields)
        })
}

/// Whether a type has a union anywhere, or a dynamic array that is not the root's last field
/// (or not of primitives): what the plan must decline.
fn other_shape(ty: &Ty) -> bool {
    fn has_union(ty: &Ty) -> bool {
        match ty {
            Ty::Union(_) => true,
            Ty::Struct(fields) => fields.iter().any(|(t, _)| has_union(t)),
            Ty::Array(t, _) | Ty::Dyn(t, _) => has_union(t),
            _ => false,
        }
    }
    match ty {
        Ty::Struct(fields) => {
            let (last, rest) = match fields.split_last() {
                Some(split) => split,
                None => return false,
            };
            let last_ok = match &last.0 {
                Ty::Dyn(elem, _) => {
                    matches!(**elem, Ty::Uint(_) | Ty::Int(_) | Ty::Float(_) | Ty::Bool)
                }
                t => !t.has_dyn(),
            };
            has_union(ty) || !last_ok || rest.iter().any(|(t, _)| t.has_dyn())
        }
        _ => true,
    }
}

fn walk_decoded(layout: &Layout<'_>, root: NodeId, data: &[u8], o: DecodeOptions) -> Decoded {
    let mut leaves = vec![Scalar::Uint(0); 600];
    let d = decode_leaves_with::<NoPlans, _>(layout, root, data, &mut leaves, o)?;
    Ok((d.bits, leaves[..d.leaves].to_vec()))
}

fn dispatched_decoded(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
    room: usize,
    o: DecodeOptions,
) -> Decoded {
    let mut leaves = vec![Scalar::Uint(0); room];
    let mut sink = LeafSink::new(&mut leaves);
    let bits = codec::decode(layout, root, data, &mut sink, o)?;
    Ok((bits, sink.leaves().to_vec()))
}

/// The plan's decoding into `room` leaf slots: `None` where it declines, and then the sink
/// must be untouched.
fn plan_decoded(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
    room: usize,
    o: DecodeOptions,
) -> Option<(usize, Vec<Scalar>)> {
    let mut leaves = vec![Scalar::Uint(0); room];
    let mut sink = LeafSink::new(&mut leaves);
    match straight::decode(layout, root, data, &mut sink, o) {
        Some(bits) => Some((bits, sink.leaves().to_vec())),
        None => {
            assert!(sink.leaves().is_empty(), "a declining plan filled the sink");
            None
        }
    }
}

fn walk_encoded(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    o: EncodeOptions,
) -> Encoded {
    let mut out = vec![0xA5u8; size];
    let n = encode_leaves_with::<NoPlans>(layout, root, leaves, &mut out, o)?;
    out.truncate(n);
    Ok(out)
}

/// The general path's and the dispatcher's encoding, with the leaves each took.
fn dispatched_encoded(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    o: EncodeOptions,
) -> (Encoded, usize) {
    let mut out = vec![0xA5u8; size];
    let mut source = LeafSource::new(leaves);
    let r = codec::encode(layout, root, &mut source, &mut out, o).map(|n| out[..n].to_vec());
    (r, source.consumed())
}

/// The plan's encoding: `None` where it declines, and then the source must be untouched.
fn plan_encoded(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    o: EncodeOptions,
) -> Option<(Vec<u8>, usize)> {
    let mut out = vec![0x5Au8; size];
    let mut source = LeafSource::new(leaves);
    match straight::encode(layout, root, &mut source, &mut out, o) {
        Some(n) => {
            // Only the bytes returned are written.
            assert!(
                out[n..].iter().all(|&b| b == 0x5A),
                "bytes past the value written"
            );
            Some((out[..n].to_vec(), source.consumed()))
        }
        None => {
            assert_eq!(source.consumed(), 0, "a declining plan took leaves");
            None
        }
    }
}

/// A leaf list of `root`: what the walk decodes from `data` (roomy, trailing bytes allowed),
/// else none.
fn leaves_from(layout: &Layout<'_>, root: NodeId, data: &[u8], tao: bool) -> Vec<Scalar> {
    let options = DecodeOptions {
        tao,
        allow_trailing: true,
    };
    walk_decoded(layout, root, data, options)
        .map(|(_, leaves)| leaves)
        .unwrap_or_default()
}

fn check_decoding(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
    room: usize,
    options: DecodeOptions,
) -> Result<(), TestCaseError> {
    let walk = walk_decoded(layout, root, data, options);
    let plan = plan_decoded(layout, root, data, room, options);
    match (&plan, &walk) {
        (Some((a, x)), Ok((b, y))) => {
            prop_assert!(a == b && same_leaves(x, y), "{:?} / {:?}", plan, walk)
        }
        (Some(_), Err(e)) => prop_assert!(false, "the plan answered where the walk says {e:?}"),
        (None, _) => {}
    }
    // The dispatcher: the walk's answer (with room for every leaf), its error word for word.
    let dispatched = dispatched_decoded(layout, root, data, 600, options);
    match (&dispatched, &walk) {
        (Ok((a, x)), Ok((b, y))) => {
            prop_assert!(a == b && same_leaves(x, y), "{:?} / {:?}", dispatched, walk)
        }
        (Err(a), Err(b)) => prop_assert!(same_error(a, b), "{:?} / {:?}", a, b),
        _ => prop_assert!(false, "{:?} / {:?}", dispatched, walk),
    }
    Ok(())
}

fn check_encoding(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    options: EncodeOptions,
) -> Result<(), TestCaseError> {
    let walk = walk_encoded(layout, root, leaves, size, options);
    let plan = plan_encoded(layout, root, leaves, size, options);
    let (dispatched, taken) = dispatched_encoded(layout, root, leaves, size, options);
    match (&plan, &walk) {
        (Some((x, plan_taken)), Ok(y)) => {
            prop_assert_eq!(x, y);
            // The plan takes the leaves the general path takes.
            prop_assert_eq!(*plan_taken, taken);
        }
        (Some(_), Err(e)) => prop_assert!(false, "the plan answered where the walk says {e:?}"),
        (None, _) => {}
    }
    match (&dispatched, &walk) {
        (Ok(x), Ok(y)) => prop_assert_eq!(x, y),
        (Err(a), Err(b)) => {
            let short = |e: &Error<LeafError>| matches!(e.kind, ErrorKind::BufferTooSmall { .. });
            // Which fault is found first, a short buffer or a bad leaf, is each path's own
            // order (as in tests/parity.rs); any other error is the walk's, word for word.
            if !(short(a) || short(b)) {
                prop_assert!(same_error(a, b), "{:?} / {:?}", a, b);
            }
        }
        _ => prop_assert!(false, "{:?} / {:?}", dispatched, walk),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Random bytes, and a value complete and cut short at every byte, into room for every
    /// leaf and for a few too few: the plan answers as the walk or declines.
    #[test]
    fn decoding_answers_as_the_walk_or_declines(
        ty in straight_type(),
        data in proptest::collection::vec(any::<u8>(), 0..48),
        tao in any::<bool>(),
        allow_trailing in any::<bool>(),
        short_by in 0usize..3,
    ) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let options = DecodeOptions { tao, allow_trailing };
        let full = walk_decoded(&layout, root, &data, DecodeOptions { tao, allow_trailing: true });
        let (bits, leaves) = full.clone().unwrap_or((0, Vec::new()));
        let value = &data[..bits.div_ceil(8).min(data.len())];
        for room in [600, leaves.len().saturating_sub(short_by)] {
            check_decoding(&layout, root, &data, room, options)?;
            for n in (0..=value.len()).rev() {
                check_decoding(&layout, root, &value[..n], room, options)?;
            }
        }
        // A whole value with room for it is the plan's to answer.
        if full.is_ok() && !value.is_empty() {
            let exact = DecodeOptions { tao, allow_trailing: true };
            prop_assert!(plan_decoded(&layout, root, &data, 600, exact).is_some(), "declined {:02x?}", data);
        }
    }

    /// Leaf lists (decoded ones, spoiled, cut or lengthened) into buffers too small by one,
    /// exact, roomy and of a random size, with every option: the plan answers as the walk
    /// (taking the leaves the general path takes) or declines.
    #[test]
    fn encoding_answers_as_the_walk_or_declines(
        ty in straight_type(),
        data in proptest::collection::vec(any::<u8>(), 0..48),
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
        let mut leaves = leaves_from(&layout, root, &data, tao);
        let untouched = leaves.clone();
        tweak_leaves(&mut leaves, &tweaks, cut);
        let options = EncodeOptions { tao, saturate, keep_versions };
        let room = layout.max_bytes(root);
        let exact = walk_encoded(&layout, root, &leaves, room, options).map_or(0, |v| v.len());
        for size in [room, exact, exact.saturating_sub(1), cap.index(room + 2)] {
            check_encoding(&layout, root, &leaves, size, options)?;
        }
        // A valid value with room for it is the plan's to answer.
        if !untouched.is_empty() || layout.max_bytes(root) == 0 {
            let plain = EncodeOptions { tao, saturate: false, keep_versions: true };
            if walk_encoded(&layout, root, &untouched, room, plain).is_ok() {
                prop_assert!(plan_encoded(&layout, root, &untouched, room, plain).is_some(), "declined {:?}", untouched);
            }
        }
    }

    /// Types of any other shape (unions, dynamic arrays inside or not last): declined, and
    /// the dispatchers answer as the walk.
    #[test]
    fn other_shapes_are_declined(
        ty in any_type(),
        data in proptest::collection::vec(any::<u8>(), 0..48),
        tao in any::<bool>(),
    ) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let leaves = leaves_from(&layout, root, &data, tao);
        let room = layout.max_bytes(root);
        let encode = EncodeOptions { tao, ..EncodeOptions::default() };
        let decode = DecodeOptions { tao, allow_trailing: true };
        if other_shape(&ty) {
            prop_assert!(plan_encoded(&layout, root, &leaves, room, encode).is_none());
            prop_assert!(plan_decoded(&layout, root, &data, 600, decode).is_none());
        }
        check_encoding(&layout, root, &leaves, room, encode)?;
        check_decoding(&layout, root, &data, 600, decode)?;
    }
}

/// The messages the plan is for, with the benches' values: answered by the plan, bytes as
/// DroneCAN defines them (NodeStatus: uptime little-endian, then health, mode and sub-mode
/// packed into one byte, then the vendor code; an empty read: the error code alone).
#[test]
fn node_status_and_an_empty_read_are_the_plans() {
    let mut l = OwnedLayout::default();
    let node_status = common::node_status(&mut l);
    let read = common::file_read_response(&mut l);
    let layout = l.as_layout();
    let status = [12345, 2, 3, 5, 7].map(Scalar::Uint);
    let (bytes, taken) = plan_encoded(&layout, node_status, &status, 16, EncodeOptions::default())
        .expect("NodeStatus is the plan's");
    // 12345 = 0x3039; health 2 (2 bits), mode 3 (3 bits), sub_mode 5 (3 bits): 10 011 101.
    assert_eq!(bytes, [0x39, 0x30, 0x00, 0x00, 0b1001_1101, 0x07, 0x00]);
    assert_eq!(taken, 5);
    let (bits, leaves) = plan_decoded(&layout, node_status, &bytes, 8, DecodeOptions::default())
        .expect("NodeStatus is the plan's");
    assert_eq!((bits, leaves), (56, status.to_vec()));

    let empty = [Scalar::Int(-2), Scalar::Uint(0)];
    let (bytes, _) = plan_encoded(&layout, read, &empty, 300, EncodeOptions::default())
        .expect("an empty read is the plan's");
    assert_eq!(bytes, (-2i16).to_le_bytes());
    let decoded = plan_decoded(&layout, read, &bytes, 4, DecodeOptions::default());
    assert_eq!(decoded, Some((16, empty.to_vec())));
    // Without tail array optimization the length goes first: 256 fits 9 bits.
    let options = EncodeOptions {
        tao: false,
        ..EncodeOptions::default()
    };
    let with = [
        Scalar::Int(1),
        Scalar::Uint(2),
        Scalar::Uint(0xAB),
        Scalar::Uint(0xCD),
    ];
    let (bytes, _) = plan_encoded(&layout, read, &with, 300, options).unwrap();
    assert_eq!(
        bytes,
        [
            0x01,
            0x00,
            0b0000_0001,
            0b0101_0101,
            0b1110_0110,
            0b1000_0000
        ]
    );
}

/// Where the DroneCAN rules refuse a value the plan declines, and the dispatcher reports the
/// walk's error: a NodeStatus health of 4 in 2 bits, a read of 257 bytes, a buffer too small.
#[test]
fn refused_values_are_declined_and_worded_by_the_walk() {
    let mut l = OwnedLayout::default();
    let node_status = common::node_status(&mut l);
    let read = common::file_read_response(&mut l);
    let layout = l.as_layout();
    let truncated = EncodeOptions::default();
    let bad = [12345, 4, 0, 0, 7].map(Scalar::Uint);
    // Saturated uint2: 4 is out of range unless saturating.
    assert!(plan_encoded(&layout, node_status, &bad, 16, truncated).is_none());
    let (err, _) = dispatched_encoded(&layout, node_status, &bad, 16, truncated);
    let walk = walk_encoded(&layout, node_status, &bad, 16, truncated);
    assert_eq!(err, walk);
    let err = err.unwrap_err();
    // At field `health` (the second), its first bit (after the 32-bit uptime).
    assert!(matches!(err.kind, ErrorKind::Scalar(_)), "{err:?}");
    assert_eq!(err.bit_offset, 32);

    let mut long = vec![Scalar::Int(0), Scalar::Uint(257)];
    long.extend(std::iter::repeat(Scalar::Uint(1)).take(257));
    assert!(plan_encoded(&layout, read, &long, 300, truncated).is_none());
    let (err, _) = dispatched_encoded(&layout, read, &long, 300, truncated);
    assert!(
        matches!(
            err.as_ref().unwrap_err().kind,
            ErrorKind::ArrayTooLong { len: 257, max: 256 }
        ),
        "{err:?}"
    );

    let status = [1, 0, 0, 0, 0].map(Scalar::Uint);
    assert!(plan_encoded(&layout, node_status, &status, 6, truncated).is_none());
    let (err, _) = dispatched_encoded(&layout, node_status, &status, 6, truncated);
    assert!(
        matches!(
            err.as_ref().unwrap_err().kind,
            ErrorKind::BufferTooSmall { .. }
        ),
        "{err:?}"
    );
    // Data cut short: declined, the walk's truncation reported.
    assert!(plan_decoded(&layout, node_status, &[0; 6], 8, DecodeOptions::default()).is_none());
    let cut = dispatched_decoded(&layout, node_status, &[0; 6], 8, DecodeOptions::default());
    assert!(matches!(cut.unwrap_err().kind, ErrorKind::Truncated { .. }));
}

/// Firmware builds (`NoPlans`) do not run the plan; hosts do.
#[test]
fn the_plan_is_the_hosts() {
    const { assert!(!NoPlans::STRAIGHT && HostPlans::STRAIGHT) };
    assert_eq!(Active::STRAIGHT, cfg!(not(feature = "compact")));
}

/// Payloads in pieces (CAN frames) are the general decoder's: the plan declines them, and
/// the dispatcher decodes them as the walk does.
#[test]
fn payloads_in_pieces_are_declined() {
    use px4params_core::scatter::Scattered;
    let mut l = OwnedLayout::default();
    let node_status = common::node_status(&mut l);
    let layout = l.as_layout();
    let bytes = [0x39u8, 0x30, 0, 0, 0b1001_1101, 7, 0];
    let pieces: [&[u8]; 2] = [&bytes[..3], &bytes[3..]];
    let data = Scattered::new(&pieces[..]);
    let mut leaves = [Scalar::Uint(0); 8];
    let mut sink = LeafSink::new(&mut leaves);
    let options = DecodeOptions::default();
    assert_eq!(
        straight::decode(&layout, node_status, &data, &mut sink, options),
        None
    );
    assert_eq!(
        codec::decode(&layout, node_status, &data, &mut sink, options),
        Ok(56)
    );
    assert_eq!(sink.leaves(), [12345, 2, 3, 5, 7].map(Scalar::Uint));
}

/// The plan is the one compiled into the layout at the type's node: a layout without plans
/// (firmware's tables, `straight: &[]`) is declined, and the dispatcher gives the walk's bytes.
#[test]
fn a_layout_without_plans_is_declined() {
    let mut l = OwnedLayout::default();
    let node_status = common::node_status(&mut l);
    let compiled = l.as_layout();
    assert!(compiled.straight[node_status as usize].is_some());
    let bare = Layout {
        straight: &[],
        ..compiled
    };
    let leaves = [12345, 2, 3, 5, 7].map(Scalar::Uint);
    let mut out = [0u8; 8];
    let options = EncodeOptions::default();
    let mut source = LeafSource::new(&leaves);
    assert_eq!(
        straight::encode(&bare, node_status, &mut source, &mut out, options),
        None
    );
    assert_eq!(source.consumed(), 0);
    let n = codec::encode(
        &bare,
        node_status,
        &mut LeafSource::new(&leaves),
        &mut out,
        options,
    );
    assert_eq!(&out[..n.unwrap()], [0x39, 0x30, 0, 0, 0b1001_1101, 7, 0]);
}
