//! The layout compiler's refusals and its nesting heights (issue 40: survivors of the run over
//! compile.rs). The bit-length ranges are DSDL's (the DroneCAN specification, "Primitive data
//! types": `uintN` for N in 1..=64, `intN` in 2..=64, `floatN` for N in 16, 32, 64, `voidN` in
//! 1..=64); each refusal is one line a person reads, checked word for word.

use px4params_core::codec::{decode_leaves_with, encode_leaves_with};
use px4params_core::compile::{BuildError, OwnedLayout};
use px4params_core::layout::Role;
use px4params_core::plan::{Active, NoPlans, Plans};
use px4params_core::rules::MAX_DEPTH;
use px4params_core::value::LeafError;
use px4params_core::{Cast, DecodeOptions, EncodeOptions, ErrorKind, NodeId, Scalar};

const SAT: Cast = Cast::Saturated;

#[test]
fn bit_lengths_are_taken_exactly_within_dsdl_s_ranges() {
    let mut l = OwnedLayout::default();
    for bits in [1, 2, 7, 8, 33, 63, 64] {
        assert!(l.uint(bits, SAT).is_ok(), "uint{bits}");
        assert!(l.void(bits).is_ok(), "void{bits}");
    }
    for bits in [2, 3, 64] {
        assert!(l.int(bits, SAT).is_ok(), "int{bits}");
    }
    for bits in [16, 32, 64] {
        assert!(l.float(bits, SAT).is_ok(), "float{bits}");
    }
    let refused = |r: Result<NodeId, BuildError>| r.unwrap_err().to_string();
    for bits in [0, 65, 128] {
        let said = format!("bit length {bits} is out of range");
        assert_eq!(refused(l.uint(bits, SAT)), said);
        assert_eq!(refused(l.void(bits)), said);
        assert_eq!(refused(l.int(bits, SAT)), said);
    }
    // int1 would hold only a sign
    assert_eq!(refused(l.int(1, SAT)), "bit length 1 is out of range");
    for bits in [0, 8, 24, 128] {
        assert_eq!(
            refused(l.float(bits, SAT)),
            format!("float{bits} does not exist (expected float16, float32 or float64)")
        );
    }
}

#[test]
fn each_malformed_type_is_refused_in_words() {
    let mut l = OwnedLayout::default();
    let byte = l.uint(8, SAT).unwrap();
    let pad = l.void(3).unwrap();
    let cases: [(Result<NodeId, BuildError>, &str); 5] = [
        (
            l.union(&[("only", byte)]),
            "a union needs at least two variants",
        ),
        (
            l.dyn_array(byte, 0),
            "a dynamic array needs a maximum of at least 1",
        ),
        (l.array(99, 2), "node 99 does not exist"),
        (
            l.structure(&[("a", byte, Role::Data), ("b", 1234, Role::Data)]),
            "node 1234 does not exist",
        ),
        (
            l.union(&[("a", byte), ("gap", pad)]),
            "a union variant cannot be padding",
        ),
    ];
    for (result, said) in cases {
        assert_eq!(result.unwrap_err().to_string(), said);
    }
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

/// A struct whose one field is a uint8 inside fixed arrays of one element, nested so that
/// the leaf is `depth` nodes from the root (the struct, `depth - 2` arrays, the uint8): a
/// fixed-shape field, which the plans step over in one flat run.
fn nested_arrays(l: &mut OwnedLayout, depth: usize) -> NodeId {
    let mut node = l.uint(8, SAT).unwrap();
    for _ in 2..depth {
        node = l.array(node, 1).unwrap();
    }
    l.structure(&[("x", node, Role::Data)]).unwrap()
}

fn round_trip<P: Plans>(depth: usize) -> Result<Scalar, (ErrorKind<LeafError>, String)> {
    let mut l = OwnedLayout::default();
    let root = nested_arrays(&mut l, depth);
    let layout = l.as_layout();
    let said = |e: px4params_core::Error<_>| (e.kind, e.display(&layout).to_string());
    let mut out = [0u8; 4];
    let n = encode_leaves_with::<P>(&layout, root, &[Scalar::Uint(0x5A)], &mut out, ENCODE)
        .map_err(said)?;
    assert_eq!(
        &out[..n],
        &[0x5A],
        "one byte however deep (arrays of one add no bits)"
    );
    let mut leaves = [Scalar::Uint(0); 1];
    decode_leaves_with::<P, _>(&layout, root, &[0x5Au8][..], &mut leaves, DECODE).map_err(said)?;
    Ok(leaves[0])
}

/// Each array element is one level deeper, as each struct field is: a flat run's height
/// counts the arrays inside it, so the plans decline a run nested past the bound and the walk
/// refuses it in its own words (a height that forgot the arrays would let a plan answer).
#[test]
fn nested_arrays_count_toward_the_depth_bound_in_every_plan() {
    assert_eq!(round_trip::<NoPlans>(MAX_DEPTH), Ok(Scalar::Uint(0x5A)));
    assert_eq!(round_trip::<Active>(MAX_DEPTH), Ok(Scalar::Uint(0x5A)));
    for depth in [MAX_DEPTH + 1, MAX_DEPTH + 2] {
        let walk = round_trip::<NoPlans>(depth).unwrap_err();
        assert_eq!(walk.0, ErrorKind::TooDeep, "depth {depth}");
        assert!(walk.1.starts_with("x[0][0]"), "{}", walk.1);
        assert!(walk.1.ends_with("...: type nests too deeply"), "{}", walk.1);
        assert_eq!(round_trip::<Active>(depth), Err(walk), "depth {depth}");
    }
}
