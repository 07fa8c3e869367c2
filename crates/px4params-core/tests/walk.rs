//! The small walk (`px4params_core::walk`, what firmware builds run) gives what the host's
//! walks give: the codec's encoder and decoder over flat leaf lists, the leaf walk, seeks and
//! translation, on random types with random bytes, random leaves and random buffer sizes;
//! the same bytes, values, leaves and errors.
//!
//! Where the two report one fault differently, the test says so and compares what both must
//! agree on.

mod common;

use common::{any_type, same_error, same_leaves, same_scalar};
use proptest::prelude::*;
use px4params_core::codec::{decode, encode, DecodeOptions, EncodeOptions};
use px4params_core::compile::OwnedLayout;
use px4params_core::error::Error;
use px4params_core::layout::{Layout, NodeId, Role};
use px4params_core::leaf::{get_leaf, seek, Target};
use px4params_core::scatter::Scattered;
use px4params_core::value::{LeafError, LeafSink, LeafSource};
use px4params_core::{walk, Cast, ErrorKind, Scalar};

fn host_decode(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
    options: DecodeOptions,
) -> Result<(usize, Vec<Scalar>), Error<LeafError>> {
    let mut leaves = vec![Scalar::Uint(0); 600];
    let mut sink = LeafSink::new(&mut leaves);
    let bits = decode(layout, root, data, &mut sink, options)?;
    Ok((bits, sink.leaves().to_vec()))
}

fn walk_decode(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
    options: DecodeOptions,
) -> Result<(usize, Vec<Scalar>), Error<LeafError>> {
    let mut leaves = vec![Scalar::Uint(0); 600];
    let decoded = walk::decode(layout, root, data, &mut leaves, options)?;
    Ok((decoded.bits, leaves[..decoded.leaves].to_vec()))
}

fn host_encode(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    options: EncodeOptions,
) -> Result<Vec<u8>, Error<LeafError>> {
    let mut out = vec![0xA5u8; size];
    let n = encode(
        layout,
        root,
        &mut LeafSource::new(leaves),
        &mut out,
        options,
    )?;
    out.truncate(n);
    Ok(out)
}

fn walk_encode(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    size: usize,
    options: EncodeOptions,
) -> Result<Vec<u8>, Error<LeafError>> {
    let mut out = vec![0xA5u8; size];
    let n = walk::encode(layout, root, leaves, &mut out, options)?;
    out.truncate(n);
    Ok(out)
}

fn same_encoding(
    ours: &Result<Vec<u8>, Error<LeafError>>,
    theirs: &Result<Vec<u8>, Error<LeafError>>,
) -> Result<(), TestCaseError> {
    match (ours, theirs) {
        (Ok(x), Ok(y)) => prop_assert_eq!(x, y),
        (Err(x), Err(y)) => prop_assert!(same_error(x, y), "{:?} / {:?}", x, y),
        _ => prop_assert!(false, "{:?} / {:?}", ours, theirs),
    }
    Ok(())
}

/// A value of `root`: the longest prefix of `data` that decodes, re-encoded as stored (no
/// tail array optimization); `None` if none does.
fn value_from(layout: &Layout<'_>, root: NodeId, data: &[u8]) -> Option<Vec<u8>> {
    let options = DecodeOptions {
        tao: false,
        allow_trailing: true,
    };
    let (bits, _) = host_decode(layout, root, data, options).ok()?;
    Some(data[..bits.div_ceil(8)].to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    /// Decoding random bytes: the same leaves and bits, or the same error.
    #[test]
    fn decode_as_the_codec(ty in any_type(), data in proptest::collection::vec(any::<u8>(), 0..64), tao in any::<bool>(), allow_trailing in any::<bool>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let options = DecodeOptions { tao, allow_trailing };
        let theirs = host_decode(&layout, root, &data, options);
        let ours = walk_decode(&layout, root, &data, options);
        match (&ours, &theirs) {
            (Ok((a, x)), Ok((b, y))) => prop_assert!(a == b && same_leaves(x, y), "{:?} / {:?}", ours, theirs),
            (Err(a), Err(b)) => prop_assert!(same_error(a, b), "{:?} / {:?}", a, b),
            _ => prop_assert!(false, "{:?} / {:?}", ours, theirs),
        }
    }

    /// Encoding leaf lists (decoded ones, changed at random, cut or lengthened) into buffers
    /// of any size: the same bytes, or the same error.
    #[test]
    fn encode_as_the_codec(
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
        let decoded = host_decode(&layout, root, &data, DecodeOptions { tao, allow_trailing: true });
        let mut leaves = decoded.map(|(_, leaves)| leaves).unwrap_or_default();
        common::tweak_leaves(&mut leaves, &tweaks, cut);
        let size = cap.index(layout.max_bytes(root) + 2);
        let options = EncodeOptions { tao, saturate, keep_versions };
        let ours = walk_encode(&layout, root, &leaves, size, options);
        let theirs = host_encode(&layout, root, &leaves, size, options);
        let too_small = |r: &Result<Vec<u8>, Error<LeafError>>| matches!(r, Err(e) if matches!(e.kind, ErrorKind::BufferTooSmall { .. }));
        if too_small(&ours) || too_small(&theirs) {
            // Which fault is found first, a short buffer or a bad leaf, is the walks' own
            // order: both fail, and with room they agree. The walk tells the room needed.
            prop_assert!(ours.is_err() && theirs.is_err(), "{:?} / {:?}", ours, theirs);
            let room = layout.max_bytes(root);
            let ours_roomy = walk_encode(&layout, root, &leaves, room, options);
            let theirs_roomy = host_encode(&layout, root, &leaves, room, options);
            same_encoding(&ours_roomy, &theirs_roomy)?;
            if let Err(Error { kind: ErrorKind::BufferTooSmall { needed }, .. }) = ours {
                prop_assert_eq!(ours_roomy.map(|v| v.len()), Ok(needed));
            }
        } else {
            same_encoding(&ours, &theirs)?;
        }
    }

    /// Finding leaf `[k]` in random bytes and in valid values: the same leaf, path and value,
    /// or the same error; `seek` the same position.
    #[test]
    fn locate_as_the_leaf_walk(ty in any_type(), data in proptest::collection::vec(any::<u8>(), 0..64), tao in any::<bool>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let value = value_from(&layout, root, &data).unwrap_or_default();
        // Data that does not decode with tail array optimization: where a tail array is too
        // long or an element of it broken, the host's leaf walk counts the elements its own
        // way; the walk finds what decoding finds.
        let malformed = tao && host_decode(&layout, root, &data, DecodeOptions { tao, allow_trailing: true }).is_err();
        for (bytes, tao) in [(&data, tao), (&value, false)] {
            for k in 0..40 {
                let theirs = get_leaf(&layout, root, &bytes[..], Target::Index(k), tao);
                let ours = walk::locate(&layout, root, &bytes[..], k, tao);
                match (&ours, &theirs) {
                    (Err(_), _) | (_, Err(_)) if malformed && tao => {}
                    (Ok((a, x)), Ok((b, y))) => prop_assert!(a == b && same_scalar(*x, *y), "[{}] {:?} / {:?}", k, ours, theirs),
                    (Err(a), Err(b)) => prop_assert!(same_error(a, b), "[{}] {:?} / {:?}", k, a, b),
                    _ => prop_assert!(false, "[{}] {:?} / {:?}", k, ours, theirs),
                }
                if !tao {
                    prop_assert_eq!(walk::seek(&layout, root, &bytes[..], k), seek(&layout, root, &bytes[..], k), "[{}]", k);
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// A payload in pieces (CAN frames, pool blocks) reads as it does whole: decoding and
    /// every leaf, results and errors alike.
    #[test]
    fn pieces_read_as_whole(ty in any_type(), data in proptest::collection::vec(any::<u8>(), 0..64), cuts in proptest::collection::vec(0usize..64, 0..12), tao in any::<bool>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let mut cuts: Vec<usize> = cuts.iter().map(|c| c % (data.len() + 1)).collect();
        cuts.sort_unstable();
        let mut pieces: Vec<&[u8]> = Vec::new();
        let mut at = 0;
        for c in cuts.iter().chain([&data.len()]) {
            pieces.push(&data[at..*c]);
            at = *c;
        }
        let scattered = Scattered::new(&pieces[..]);
        let options = DecodeOptions { tao, allow_trailing: false };
        let (mut a, mut b) = (vec![Scalar::Uint(0); 600], vec![Scalar::Uint(0); 600]);
        let whole = walk::decode(&layout, root, &data[..], &mut a, options);
        let parts = walk::decode(&layout, root, &scattered, &mut b, options);
        prop_assert_eq!(format!("{whole:?}"), format!("{parts:?}"));
        if let Ok(decoded) = whole {
            prop_assert!(same_leaves(&a[..decoded.leaves], &b[..decoded.leaves]));
        }
        // Leaves from last to first: reads jump backwards through the pieces too.
        for k in (0..40).rev() {
            let whole = walk::locate(&layout, root, &data[..], k, tao);
            let parts = walk::locate(&layout, root, &scattered, k, tao);
            prop_assert_eq!(format!("{whole:?}"), format!("{parts:?}"), "[{}]", k);
        }
    }
}

/// A random type with named fields, and the next version of it.
#[derive(Clone, Debug)]
enum Named {
    Prim(common::Ty),
    Struct(Vec<(String, Named)>),
    Union(Vec<(String, Named)>),
    Array(Box<Named>, u32),
    Dyn(Box<Named>, u32),
}

impl Named {
    fn build(&self, l: &mut OwnedLayout) -> NodeId {
        match self {
            Named::Prim(t) => t.build(l),
            Named::Struct(fields) => {
                let v = l.uint(4, Cast::Saturated).unwrap();
                let mut built: Vec<(String, NodeId, Role)> =
                    vec![("p_version".into(), v, Role::Version(1))];
                for (name, t) in fields {
                    built.push((name.clone(), t.build(l), Role::Data));
                }
                let refs: Vec<(&str, NodeId, Role)> = built
                    .iter()
                    .map(|(n, id, r)| (n.as_str(), *id, *r))
                    .collect();
                l.structure(&refs).unwrap()
            }
            Named::Union(variants) => {
                let built: Vec<(String, NodeId)> = variants
                    .iter()
                    .map(|(n, t)| (n.clone(), t.build(l)))
                    .collect();
                let refs: Vec<(&str, NodeId)> =
                    built.iter().map(|(n, id)| (n.as_str(), *id)).collect();
                l.union(&refs).unwrap()
            }
            Named::Array(t, n) => {
                let e = t.build(l);
                l.array(e, *n).unwrap()
            }
            Named::Dyn(t, n) => {
                let e = t.build(l);
                l.dyn_array(e, *n).unwrap()
            }
        }
    }
}

fn name() -> impl Strategy<Value = String> {
    prop_oneof![Just("a"), Just("b"), Just("c"), Just("d")].prop_map(String::from)
}

/// Members with distinct names.
fn members(
    inner: impl Strategy<Value = Named> + Clone,
    min: usize,
) -> impl Strategy<Value = Vec<(String, Named)>> {
    proptest::collection::vec((name(), inner), min..5).prop_map(|mut v| {
        let mut seen = std::collections::HashSet::new();
        v.retain(|(n, _)| seen.insert(n.clone()));
        v
    })
}

fn named() -> impl Strategy<Value = Named> {
    common::primitive().prop_map(Named::Prim).prop_recursive(3, 24, 4, |inner| {
        prop_oneof![
            3 => members(inner.clone(), 0).prop_map(Named::Struct),
            2 => members(inner.clone(), 2).prop_filter("a union has two variants", |v| v.len() >= 2).prop_map(Named::Union),
            1 => (inner.clone(), 1u32..4).prop_map(|(t, n)| Named::Array(Box::new(t), n)),
            1 => (inner, 1u32..4).prop_map(|(t, n)| Named::Dyn(Box::new(t), n)),
        ]
    })
}

/// Two versions of a type: the second keeps, drops, adds and changes members of the first
/// (by name), as minor versions of a parameter type do.
fn versions() -> impl Strategy<Value = (Named, Named)> {
    named().prop_flat_map(|old| {
        let new = evolve(old.clone());
        (Just(old), new)
    })
}

fn evolve(t: Named) -> BoxedStrategy<Named> {
    match t {
        Named::Struct(fields) => evolve_members(fields, 0).prop_map(Named::Struct).boxed(),
        Named::Union(variants) => evolve_members(variants, 2).prop_map(Named::Union).boxed(),
        Named::Array(t, n) => (evolve(*t), 0u32..2)
            .prop_map(move |(t, more)| Named::Array(Box::new(t), n + more))
            .boxed(),
        Named::Dyn(t, n) => evolve(*t)
            .prop_map(move |t| Named::Dyn(Box::new(t), n))
            .boxed(),
        other => prop_oneof![4 => Just(other), 1 => named()].boxed(),
    }
}

/// Members kept (each evolved) or dropped, and new ones added; at least `min` of them.
fn evolve_members(
    members: Vec<(String, Named)>,
    min: usize,
) -> BoxedStrategy<Vec<(String, Named)>> {
    let kept: Vec<BoxedStrategy<Option<(String, Named)>>> = members
        .into_iter()
        .map(|(n, f)| {
            prop_oneof![
                4 => evolve(f).prop_map(move |f| Some((n.clone(), f))),
                1 => Just(None),
            ]
            .boxed()
        })
        .collect();
    (kept, proptest::collection::vec((name(), named()), 0..2))
        .prop_map(move |(kept, added)| {
            let mut all: Vec<(String, Named)> = kept.into_iter().flatten().collect();
            for (n, f) in added {
                if all.iter().all(|(m, _)| *m != n) {
                    all.push((n, f));
                }
            }
            for spare in ["y", "z"] {
                if all.len() < min {
                    all.push((spare.into(), Named::Prim(common::Ty::Bool)));
                }
            }
            all
        })
        .boxed()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    /// Translating a value to the next version of its type: the same bytes, or the same
    /// error, as the host's translation (which also reports each field's fate).
    #[test]
    fn translate_as_the_host((old, new) in versions(), a in proptest::collection::vec(any::<u8>(), 0..40), b in proptest::collection::vec(any::<u8>(), 0..40), garbage in any::<bool>()) {
        let mut l = OwnedLayout::default();
        let old_root = old.build(&mut l);
        let new_root = new.build(&mut l);
        let layout = l.as_layout();
        // A stored value of the old version, or (to reach the unreadable paths) any bytes.
        let old_data = if garbage { a.clone() } else { value_from(&layout, old_root, &a).unwrap_or_default() };
        let base = match value_from(&layout, new_root, &b) {
            Some(v) => v,
            None => {
                let mut out = vec![0u8; layout.max_bytes(new_root)];
                let n = walk::encode_default(&layout, new_root, &mut out, false).unwrap();
                out.truncate(n);
                out
            }
        };
        let size = layout.max_bytes(new_root) + 1;
        let (mut x, mut y) = (vec![0xA5u8; size], vec![0xA5u8; size]);
        let theirs = px4params_core::translate::translate(&layout, old_root, &old_data[..], new_root, &base[..], &mut y, &mut |_| {});
        let ours = walk::translate(&layout, old_root, &old_data[..], new_root, &base[..], &mut x);
        match (&ours, &theirs) {
            (Ok(p), Ok(q)) => prop_assert!(p == q && x[..*p] == y[..*q], "{:02x?} / {:02x?}", &x[..*p], &y[..*q]),
            (Err(p), Err(q)) => prop_assert!(same_error(p, q), "{:?} / {:?}", p, q),
            _ => prop_assert!(false, "{:?} / {:?}", ours, theirs),
        }
    }
}
