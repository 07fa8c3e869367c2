//! The codec against the DroneCAN rules: golden vector, the talk's INA238, leaf access,
//! and properties over random data.

mod common;

use proptest::prelude::*;
use px4params_core::codec::{decode, encode, DecodeOptions, EncodeOptions};
use px4params_core::compile::OwnedLayout;
use px4params_core::leaf::{encode_default, get_leaf, set_leaf, Target};
use px4params_core::value::{LeafSink, LeafSource};
use px4params_core::{ErrorKind, NodeId, Scalar};

fn enc(l: &OwnedLayout, root: NodeId, leaves: &[Scalar], tao: bool) -> Vec<u8> {
    let mut out = vec![0u8; l.as_layout().max_bytes(root) + 1];
    let n = encode(
        &l.as_layout(),
        root,
        &mut LeafSource::new(leaves),
        &mut out,
        EncodeOptions {
            tao,
            saturate: false,
            keep_versions: true,
        },
    )
    .unwrap_or_else(|e| panic!("{}", e.display(&l.as_layout())));
    out.truncate(n);
    out
}

fn dec(l: &OwnedLayout, root: NodeId, data: &[u8], tao: bool) -> Result<Vec<Scalar>, String> {
    let mut storage = [Scalar::Uint(0); 256];
    let mut sink = LeafSink::new(&mut storage);
    let layout = l.as_layout();
    decode(
        &layout,
        root,
        data,
        &mut sink,
        DecodeOptions {
            tao,
            allow_trailing: false,
        },
    )
    .map_err(|e| e.display(&layout).to_string())?;
    Ok(sink.leaves().to_vec())
}

/// Decodes the value at the start of `data` (random data is mostly longer than a value).
fn dec_prefix(l: &OwnedLayout, root: NodeId, data: &[u8], tao: bool) -> Option<Vec<u8>> {
    let mut storage = [Scalar::Uint(0); 256];
    let mut sink = LeafSink::new(&mut storage);
    let opts = DecodeOptions {
        tao,
        allow_trailing: true,
    };
    let bits = decode(&l.as_layout(), root, data, &mut sink, opts).ok()?;
    Some(data[..bits.div_ceil(8)].to_vec())
}

/// Leaves compared with NaN equal to NaN.
fn same(a: &[Scalar], b: &[Scalar]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| match (x, y) {
            (Scalar::Float(x), Scalar::Float(y)) => x == y || (x.is_nan() && y.is_nan()),
            _ => x == y,
        })
}

#[test]
fn golden_vector_is_da_ef_7c_00() {
    let mut l = OwnedLayout::default();
    let root = common::golden(&mut l);
    let leaves = [
        Scalar::Uint(0xBEDA),
        Scalar::Int(-1),
        Scalar::Int(-5),
        Scalar::Int(-1),
        Scalar::Uint(0x88),
    ];
    assert_eq!(enc(&l, root, &leaves, true), [0xDA, 0xEF, 0x7C, 0x00]);
    // Decoding gives the truncated values back.
    let back = dec(&l, root, &[0xDA, 0xEF, 0x7C, 0x00], true).unwrap();
    assert_eq!(
        back,
        [
            Scalar::Uint(0xEDA),
            Scalar::Int(-1),
            Scalar::Int(-5),
            Scalar::Int(-1),
            Scalar::Uint(0x8)
        ]
    );
}

fn talk_ina238() -> [Scalar; 7] {
    [
        Scalar::Uint(0),
        Scalar::Uint(0),
        Scalar::Uint(0),
        Scalar::Uint(1),
        Scalar::Uint(0x45),
        Scalar::Uint(200),
        Scalar::Float(0.0003),
    ]
}

#[test]
fn talk_ina238_example_bytes_and_leaves() {
    let mut l = OwnedLayout::default();
    let root = common::ina238(&mut l);
    let bytes = enc(&l, root, &talk_ina238(), true);
    // 0000 000 0000 0001 1000101 | 200 as uint10 (C8, then 00) | float16 0x0CEA (EA, then 0C)
    assert_eq!(bytes, [0x00, 0x03, 0x17, 0x20, 0xEA, 0x0C]);
    let layout = l.as_layout();
    let (leaf, v) = get_leaf(&layout, root, &bytes[..], Target::Index(4), true).unwrap();
    assert_eq!(v, Scalar::Uint(69));
    assert_eq!(leaf.path.display(&layout).to_string(), "bus.i2c.address");
    let (leaf, v) = get_leaf(
        &layout,
        root,
        &bytes[..],
        Target::Path("bus.i2c.address"),
        true,
    )
    .unwrap();
    assert_eq!((leaf.index, v), (4, Scalar::Uint(69)));
    let (_, shunt) = get_leaf(&layout, root, &bytes[..], Target::Index(6), true).unwrap();
    assert_eq!(
        shunt,
        Scalar::Float(f64::from(px4params_core::scalar::f32_from_f16(0x0CEA)))
    );
    let (leaf, tag) = get_leaf(&layout, root, &bytes[..], Target::Path("bus._tag"), true).unwrap();
    assert_eq!((leaf.index, tag), (1, Scalar::Uint(0)));
}

#[test]
fn set_leaf_in_place_and_structural() {
    let mut l = OwnedLayout::default();
    let root = common::ina238(&mut l);
    let layout = l.as_layout();
    let bytes = enc(&l, root, &talk_ina238(), true);
    let mut out = [0u8; 16];
    let opts = EncodeOptions::default();
    let n = set_leaf(
        &layout,
        root,
        &bytes[..],
        Target::Index(4),
        Scalar::Uint(0x46),
        &mut out,
        opts,
    )
    .unwrap();
    let leaves = dec(&l, root, &out[..n], true).unwrap();
    assert_eq!(leaves[4], Scalar::Uint(0x46));
    assert_eq!(leaves[5], Scalar::Uint(200));
    // Out of range for uint7.
    let err = set_leaf(
        &layout,
        root,
        &bytes[..],
        Target::Index(4),
        Scalar::Uint(200),
        &mut out,
        opts,
    )
    .unwrap_err();
    assert_eq!(
        err.display(&layout).to_string(),
        "bus.i2c.address: value 200 is out of range (expected 0 to 127)"
    );
    // Select the spi variant: its default value appears and the fields after the union survive.
    let n = set_leaf(
        &layout,
        root,
        &bytes[..],
        Target::Path("bus._tag"),
        Scalar::Uint(1),
        &mut out,
        opts,
    )
    .unwrap();
    let leaves = dec(&l, root, &out[..n], true).unwrap();
    assert_eq!(
        leaves[1..5],
        [
            Scalar::Uint(1),
            Scalar::Uint(0),
            Scalar::Uint(0),
            Scalar::Uint(0)
        ]
    );
    assert_eq!(leaves[5], Scalar::Uint(200));
    let err = get_leaf(
        &layout,
        root,
        &out[..n],
        Target::Path("bus.i2c.address"),
        true,
    )
    .unwrap_err();
    assert_eq!(
        err.display(&layout).to_string(),
        "bus.i2c: this union variant is not the selected one"
    );
    let err = set_leaf(
        &layout,
        root,
        &bytes[..],
        Target::Index(1),
        Scalar::Uint(5),
        &mut out,
        opts,
    )
    .unwrap_err();
    assert!(matches!(err.kind, ErrorKind::Scalar(_)), "{err:?}");
}

#[test]
fn leaf_errors_name_the_problem() {
    let mut l = OwnedLayout::default();
    let root = common::ina238(&mut l);
    let layout = l.as_layout();
    let bytes = enc(&l, root, &talk_ina238(), true);
    let msg = |t| {
        get_leaf(&layout, root, &bytes[..], t, true)
            .unwrap_err()
            .display(&layout)
            .to_string()
    };
    assert_eq!(
        msg(Target::Index(7)),
        "no leaf [7] (the value has 7 leaves: [0]..[6])"
    );
    assert_eq!(msg(Target::Path("bus.i2c.nope")), "bus.i2c: no such field");
    assert_eq!(
        msg(Target::Path("bus")),
        "bus: not a leaf (a struct, union or array)"
    );
    assert_eq!(msg(Target::Path("current.x")), "current: no such field");
    assert_eq!(msg(Target::Path("bus..")), "bus: no such field");
    let short = get_leaf(&layout, root, &bytes[..3], Target::Index(6), true).unwrap_err();
    assert_eq!(
        short.display(&layout).to_string(),
        "shunt: data is truncated: needs at least 48 bits, has 24"
    );
}

#[test]
fn decode_errors_carry_offset_and_path() {
    let mut l = OwnedLayout::default();
    let root = common::ina238(&mut l);
    // Tag 7 does not exist (5 variants).
    let err = dec(&l, root, &[0x0E, 0, 0, 0, 0, 0], true).unwrap_err();
    assert_eq!(
        err,
        "union tag 7 selects no variant (expected 0..4)".replace("union", "bus: union")
    );
    assert_eq!(
        dec(&l, root, &[0; 5], true).unwrap_err(),
        "shunt: data is truncated: needs at least 48 bits, has 40"
    );
    assert_eq!(
        dec(&l, root, &[0; 7], true).unwrap_err(),
        "data is too long: the value ends after 6 bytes, the data has 7"
    );
}

#[test]
fn missing_and_version_fields() {
    let mut l = OwnedLayout::default();
    let root = common::ina238(&mut l);
    let layout = l.as_layout();
    let mut out = [0u8; 16];
    // A wrong p_version is refused.
    let mut leaves = talk_ina238();
    leaves[0] = Scalar::Uint(3);
    let err = encode(
        &layout,
        root,
        &mut LeafSource::new(&leaves),
        &mut out,
        EncodeOptions::default(),
    )
    .unwrap_err();
    assert_eq!(
        err.display(&layout).to_string(),
        "p_version: p_version is set automatically; got 3, the type's version is 0"
    );
    // The default value: zeros, first variant.
    let n = encode_default(&layout, root, &mut out, true).unwrap();
    assert_eq!(&out[..n], &[0u8; 6]);
    // Too few leaves.
    let err = encode(
        &layout,
        root,
        &mut LeafSource::new(&talk_ina238()[..3]),
        &mut out,
        EncodeOptions::default(),
    )
    .unwrap_err();
    assert_eq!(
        err.display(&layout).to_string(),
        "bus.i2c.bus_id: the leaf list ends before the value"
    );
    // Buffer too small.
    let err = encode(
        &layout,
        root,
        &mut LeafSource::new(&talk_ina238()),
        &mut out[..2],
        EncodeOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(err.kind, ErrorKind::BufferTooSmall { .. }));
}

#[test]
fn battery_info_tail_array() {
    let mut l = OwnedLayout::default();
    let root = common::battery_info(&mut l);
    let mut leaves: Vec<Scalar> = (0..7).map(|i| Scalar::Float(f64::from(i) * 1.5)).collect();
    leaves.extend([
        Scalar::Uint(3),
        Scalar::Uint(90),
        Scalar::Uint(80),
        Scalar::Uint(2),
        Scalar::Uint(1),
        Scalar::Uint(77),
    ]);
    leaves.push(Scalar::Uint(3));
    leaves.extend(b"abc".iter().map(|&b| Scalar::Uint(b.into())));
    let with_tao = enc(&l, root, &leaves, true);
    let without = enc(&l, root, &leaves, false);
    // 7*16 + 11 + 3*7 + 8 + 32 = 184 bits = 23 bytes, then the name: 3 bytes, or 5 bits + 24.
    assert_eq!(with_tao.len(), 26);
    assert_eq!(without.len(), 27);
    assert_eq!(&with_tao[23..], b"abc");
    assert!(same(&dec(&l, root, &with_tao, true).unwrap(), &leaves));
    assert!(same(&dec(&l, root, &without, false).unwrap(), &leaves));
}

/// TAO applies to the last field only: a dynamic byte array before it keeps its length prefix.
/// Bytes written down by hand from the DroneCAN rules: `uint8[<=3] a = [1, 2]`, `uint8[<=3] b
/// = [3]` is `10` (a's length, 2 bits) `00000001 00000010`, then b: with TAO `00000011`, else
/// `01 00000011`.
#[test]
fn tao_only_for_the_last_field() {
    use px4params_core::layout::Role;
    use px4params_core::Cast;

    let mut l = OwnedLayout::default();
    let byte = l.uint(8, Cast::Saturated).unwrap();
    let a = l.dyn_array(byte, 3).unwrap();
    let b = l.dyn_array(byte, 3).unwrap();
    let root = l
        .structure(&[("a", a, Role::Data), ("b", b, Role::Data)])
        .unwrap();
    let leaves = [2u64, 1, 2, 1, 3].map(Scalar::Uint);
    assert_eq!(enc(&l, root, &leaves, true), [0x80, 0x40, 0x80, 0xC0]);
    assert_eq!(enc(&l, root, &leaves, false), [0x80, 0x40, 0x90, 0x30]);
    assert!(same(
        &dec(&l, root, &[0x80, 0x40, 0x80, 0xC0], true).unwrap(),
        &leaves
    ));
    assert!(same(
        &dec(&l, root, &[0x80, 0x40, 0x90, 0x30], false).unwrap(),
        &leaves
    ));
}

fn layouts() -> Vec<(OwnedLayout, NodeId)> {
    let builders: [fn(&mut OwnedLayout) -> NodeId; 4] = [
        common::ina238,
        common::battery_info,
        common::golden,
        common::kitchen_sink,
    ];
    builders
        .iter()
        .map(|b| {
            let mut l = OwnedLayout::default();
            let r = b(&mut l);
            (l, r)
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Random bytes never panic; whatever decodes re-encodes to a canonical fixpoint.
    #[test]
    fn random_bytes_decode_or_fail_cleanly(data in proptest::collection::vec(any::<u8>(), 0..64), tao in any::<bool>()) {
        for (l, root) in layouts() {
            let layout = l.as_layout();
            let prefix = dec_prefix(&l, root, &data, tao).unwrap_or_default();
            if let Ok(leaves) = dec(&l, root, &prefix, tao) {
                let canonical = enc(&l, root, &leaves, tao);
                let again = dec(&l, root, &canonical, tao).unwrap();
                prop_assert!(same(&leaves, &again));
                prop_assert_eq!(enc(&l, root, &again, tao), canonical.clone());
                // Every leaf reads the same through leaf access.
                for (k, v) in leaves.iter().enumerate() {
                    let (leaf, got) = get_leaf(&layout, root, &canonical[..], Target::Index(k), tao).unwrap();
                    prop_assert_eq!(leaf.index, k);
                    prop_assert!(same(&[got], &[*v]), "leaf {} {:?} != {:?}", k, got, v);
                    let path = leaf.path.display(&layout).to_string();
                    if !path.is_empty() && !matches!(leaf.kind, px4params_core::codec::LeafKind::Len { .. } | px4params_core::codec::LeafKind::Tag { .. }) {
                        let (by_path, _) = get_leaf(&layout, root, &canonical[..], Target::Path(&path), tao).unwrap();
                        prop_assert_eq!(by_path.index, k, "path {}", path);
                    }
                }
            }
            // Leaf access on arbitrary data fails cleanly too.
            for k in 0..12 {
                let _ = get_leaf(&layout, root, &data[..], Target::Index(k), tao);
                let mut out = vec![0u8; layout.max_bytes(root) + 8];
                let _ = set_leaf(&layout, root, &data[..], Target::Index(k), Scalar::Uint(1), &mut out, EncodeOptions { tao, saturate: true, keep_versions: true });
            }
        }
    }

    /// Setting leaf k changes exactly that leaf (scalars) or re-shapes after it (tags, lengths).
    #[test]
    fn set_leaf_changes_only_what_it_should(data in proptest::collection::vec(any::<u8>(), 0..64), k in 0usize..40, new in 0u64..4, tao in any::<bool>()) {
        for (l, root) in layouts() {
            let layout = l.as_layout();
            let prefix = dec_prefix(&l, root, &data, tao).unwrap_or_default();
            let Ok(leaves) = dec(&l, root, &prefix, tao) else { continue };
            if k >= leaves.len() { continue; }
            let canonical = enc(&l, root, &leaves, tao);
            let mut out = vec![0u8; layout.max_bytes(root) + 8];
            let value = match leaves[k] { Scalar::Float(_) => Scalar::Float(new as f64), Scalar::Bool(_) => Scalar::Bool(new % 2 == 1), Scalar::Int(_) => Scalar::Int(new as i64 - 1), Scalar::Uint(_) => Scalar::Uint(new) };
            match set_leaf(&layout, root, &canonical[..], Target::Index(k), value, &mut out, EncodeOptions { tao, saturate: false, keep_versions: true }) {
                Ok(n) => {
                    let after = dec(&l, root, &out[..n], tao).unwrap();
                    prop_assert!(same(&after[..k], &leaves[..k]));
                    prop_assert!(same(&after[k..=k], &[value]));
                }
                Err(e) => prop_assert!(matches!(e.kind, ErrorKind::Scalar(_)), "{:?}", e),
            }
        }
    }
}

/// The leaf source without its flat fast path: every field goes through the generic walk.
struct Walked<'a>(LeafSource<'a>);

impl px4params_core::codec::Source for Walked<'_> {
    type Error = px4params_core::value::LeafError;
    fn scalar(&mut self, kind: px4params_core::Kind) -> Result<Scalar, Self::Error> {
        self.0.scalar(kind)
    }
    fn begin_struct(&mut self) -> Result<(), Self::Error> {
        self.0.begin_struct()
    }
    fn field(&mut self, index: u32, name: &str) -> Result<bool, Self::Error> {
        self.0.field(index, name)
    }
    fn end_field(&mut self) {
        self.0.end_field()
    }
    fn end_struct(
        &mut self,
        layout: &px4params_core::Layout<'_>,
        fields: &[px4params_core::layout::Field],
        used: usize,
    ) -> Result<(), Self::Error> {
        self.0.end_struct(layout, fields, used)
    }
    fn begin_union(
        &mut self,
        layout: &px4params_core::Layout<'_>,
        variants: &[px4params_core::layout::Field],
    ) -> Result<u32, Self::Error> {
        self.0.begin_union(layout, variants)
    }
    fn end_union(&mut self) {
        self.0.end_union()
    }
    fn begin_array(&mut self, fixed: Option<u32>) -> Result<usize, Self::Error> {
        self.0.begin_array(fixed)
    }
    fn element(&mut self, index: usize) -> Result<(), Self::Error> {
        self.0.element(index)
    }
    fn end_element(&mut self) {
        self.0.end_element()
    }
    fn end_array(&mut self) {
        self.0.end_array()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// The flat fast paths (fixed-shape runs, primitive arrays, byte strings) give exactly the
    /// bytes and errors of the field-by-field walk.
    #[test]
    fn flat_paths_match_the_walk(data in proptest::collection::vec(any::<u8>(), 0..64), tao in any::<bool>(), tweak in 0usize..40, big in any::<u64>()) {
        for (l, root) in layouts() {
            let layout = l.as_layout();
            let prefix = dec_prefix(&l, root, &data, tao).unwrap_or_default();
            let Ok(mut leaves) = dec(&l, root, &prefix, tao) else { continue };
            // Sometimes put an out-of-range value somewhere, to compare the errors too.
            if tweak < leaves.len() && big % 3 == 0 {
                leaves[tweak] = Scalar::Uint(big);
            }
            let opts = EncodeOptions { tao, saturate: false, keep_versions: true };
            let mut flat = vec![0u8; layout.max_bytes(root) + 1];
            let mut walked = vec![0u8; layout.max_bytes(root) + 1];
            let a = encode(&layout, root, &mut LeafSource::new(&leaves), &mut flat, opts);
            let b = encode(&layout, root, &mut Walked(LeafSource::new(&leaves)), &mut walked, opts);
            match (a, b) {
                (Ok(n), Ok(m)) => prop_assert_eq!(&flat[..n], &walked[..m]),
                (Err(x), Err(y)) => prop_assert_eq!(x.kind, y.kind),
                (x, y) => prop_assert!(false, "flat {:?} vs walked {:?}", x, y),
            }
        }
    }
}

/// Decoding `scattered` gives what decoding `flat` (the same bytes, joined) gives: the same
/// result, error or leaves; and every leaf read in place (last to first, so that the reads
/// jump backwards too) has the same offset and value.
fn decodes_like_flat<P: px4params_core::scatter::Pieces + ?Sized>(
    layout: &px4params_core::layout::Layout<'_>,
    root: NodeId,
    flat: &[u8],
    scattered: &px4params_core::scatter::Scattered<'_, P>,
    opts: DecodeOptions,
) -> Result<(), TestCaseError> {
    let mut a = [Scalar::Uint(0); 256];
    let mut b = [Scalar::Uint(0); 256];
    let mut flat_sink = LeafSink::new(&mut a);
    let mut scat_sink = LeafSink::new(&mut b);
    let from_flat = decode(layout, root, flat, &mut flat_sink, opts);
    let from_pieces = decode(layout, root, scattered, &mut scat_sink, opts);
    match (from_flat, from_pieces) {
        (Ok(x), Ok(y)) => {
            prop_assert_eq!(x, y);
            prop_assert!(same(flat_sink.leaves(), scat_sink.leaves()));
            for k in (0..flat_sink.leaves().len()).rev() {
                let f = get_leaf(layout, root, flat, Target::Index(k), opts.tao).unwrap();
                let s = get_leaf(layout, root, scattered, Target::Index(k), opts.tao).unwrap();
                prop_assert_eq!(f.0.bit_offset, s.0.bit_offset);
                prop_assert!(same(&[f.1], &[s.1]));
            }
        }
        (Err(x), Err(y)) => prop_assert_eq!(x, y),
        (x, y) => prop_assert!(false, "flat {:?} vs pieces {:?}", x, y),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Decoding and leaf access from a payload in random pieces equal the flat results.
    #[test]
    fn scattered_equals_flat(data in proptest::collection::vec(any::<u8>(), 0..64), cuts in proptest::collection::vec(0usize..64, 0..12), tao in any::<bool>()) {
        use px4params_core::scatter::Scattered;
        for (l, root) in layouts() {
            let layout = l.as_layout();
            let prefix = dec_prefix(&l, root, &data, tao).unwrap_or(data.clone());
            let mut cuts: Vec<usize> = cuts.iter().map(|c| c % (prefix.len() + 1)).collect();
            cuts.sort_unstable();
            let mut pieces: Vec<&[u8]> = Vec::new();
            let mut at = 0;
            for c in cuts.iter().chain([&prefix.len()]) {
                pieces.push(&prefix[at..*c]);
                at = *c;
            }
            let scattered = Scattered::new(&pieces[..]);
            let opts = DecodeOptions { tao, allow_trailing: false };
            decodes_like_flat(&layout, root, &prefix, &scattered, opts)?;
        }
    }
}

/// One step of a reader: `n` bits, or `n` whole bytes where the reader stands on a byte
/// boundary, or a read at any offset from the stream itself in between.
#[derive(Clone, Debug)]
enum Step {
    Bits(u32),
    Bytes(usize),
    At(usize, u32),
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        (1u32..=64).prop_map(Step::Bits),
        (0usize..20).prop_map(Step::Bytes),
        (0usize..1024, 1u32..=64).prop_map(|(at, n)| Step::At(at, n)),
    ]
}

/// A reader's start: often 0 or a byte boundary, where byte strings are read.
fn start() -> impl Strategy<Value = usize> {
    prop_oneof![Just(0usize), (0usize..80).prop_map(|b| b * 8), 0usize..640]
}

fn cut<'d>(data: &'d [u8], cuts: &[usize]) -> Vec<&'d [u8]> {
    let mut cuts: Vec<usize> = cuts.iter().map(|c| c % (data.len() + 1)).collect();
    cuts.sort_unstable();
    let mut pieces = Vec::new();
    let mut at = 0;
    for c in cuts.iter().chain([&data.len()]) {
        pieces.push(&data[at..*c]);
        at = *c;
    }
    pieces
}

/// Runs `steps` on a reader over `pieces` and on one over `flat` (the pieces joined): the same
/// bits, bytes and positions, from any start and after reads at other offsets.
fn readers_agree<P: px4params_core::scatter::Pieces + ?Sized>(
    pieces: &P,
    flat: &[u8],
    start: usize,
    steps: &[Step],
) -> Result<(), TestCaseError> {
    use px4params_core::bits::{BitRead, BitReader};
    use px4params_core::scatter::Scattered;
    let scattered = Scattered::new(pieces);
    prop_assert_eq!(scattered.len(), flat.len());
    let bits = flat.len() * 8;
    let start = start % (bits + 1);
    let mut slice = flat.reader(start);
    let mut scat = scattered.reader(start);
    for step in steps {
        match *step {
            Step::Bits(n) if slice.position() + n as usize <= bits => {
                prop_assert_eq!(scat.read(n), slice.read(n));
            }
            Step::Bytes(n) if slice.position() % 8 == 0 && slice.position() + 8 * n <= bits => {
                let (mut a, mut b) = (vec![0u8; n], vec![0xEEu8; n]);
                slice.read_bytes(&mut a);
                scat.read_bytes(&mut b);
                prop_assert_eq!(a, b);
            }
            Step::At(at, n) if bits >= n as usize => {
                let at = at % (bits - n as usize + 1);
                prop_assert_eq!(scattered.read_bits(at, n), flat.read_bits(at, n));
                // A new reader starts from where the stream's window is now.
                scat = scattered.reader(slice.position());
            }
            _ => {}
        }
        prop_assert_eq!(scat.position(), slice.position());
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    /// Readers over slices cut anywhere (empty pieces included) read like the joined bytes.
    #[test]
    fn scattered_reader_equals_slice_reader(
        data in proptest::collection::vec(any::<u8>(), 0..80),
        cuts in proptest::collection::vec(0usize..80, 0..16),
        start in start(),
        steps in proptest::collection::vec(step(), 0..40),
    ) {
        let pieces = cut(&data, &cuts);
        readers_agree(&pieces[..], &data, start, &steps)?;
    }

    /// So do readers over any list of CAN frames (classic, FD, malformed short ones), whose
    /// word-at-a-time paths must agree with their payload pieces.
    #[test]
    fn frame_payload_readers_equal_slice_reader(
        frames in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..20), 0..8),
        start in start(),
        steps in proptest::collection::vec(step(), 0..40),
    ) {
        use px4params_core::scatter::{FramePayloads, Pieces};
        let refs: Vec<&[u8]> = frames.iter().map(Vec::as_slice).collect();
        let payloads = FramePayloads::new(&refs);
        let flat: Vec<u8> = (0..payloads.count()).flat_map(|i| payloads.piece(i).to_vec()).collect();
        readers_agree(&payloads, &flat, start, &steps)?;
    }

    /// And readers over a value stored across fixed-size pages.
    #[test]
    fn paged_value_readers_equal_slice_reader(
        memory in proptest::collection::vec(any::<u8>(), 1..120),
        page in 1usize..24,
        from in 0usize..120,
        len in 0usize..120,
        start in start(),
        steps in proptest::collection::vec(step(), 0..40),
    ) {
        use px4params_core::pages::PagedValue;
        let from = from % memory.len();
        let len = len % (memory.len() - from + 1);
        let pages: Vec<&[u8]> = memory.chunks(page).collect();
        let value = PagedValue { param: 0, instance: 0, start: from as u32, len: len as u32 };
        let pieces = value.pieces(&pages);
        readers_agree(&pieces, &memory[from..from + len], start, &steps)?;
    }

    /// Values decoded straight from the payloads of their CAN frames (classic and FD) equal
    /// values decoded from the joined payload; so do errors and leaves.
    #[test]
    fn frame_payloads_decode_like_flat(
        data in proptest::collection::vec(any::<u8>(), 0..120),
        canfd in any::<bool>(),
        tao in any::<bool>(),
    ) {
        use px4params_core::scatter::Scattered;
        use px4params_core::transfer::{frames, receive};
        for (l, root) in layouts() {
            let layout = l.as_layout();
            let payload = dec_prefix(&l, root, &data, tao).unwrap_or(data.clone());
            let sent: Vec<Vec<u8>> =
                frames(&payload, 0xBEEF, 7, canfd).map(|f| f.as_bytes().to_vec()).collect();
            let refs: Vec<&[u8]> = sent.iter().map(Vec::as_slice).collect();
            let received = receive(&refs, 0xBEEF).unwrap();
            let scattered = Scattered::new(&received.payload);
            // CAN FD pads the last frame to its length code: those zeros count as trailing.
            let opts = DecodeOptions { tao, allow_trailing: canfd };
            let mut padded = payload.clone();
            padded.resize(scattered.len(), 0);
            decodes_like_flat(&layout, root, &padded, &scattered, opts)?;
        }
    }
}

/// The loop words each DroneCAN rule's fault, the same under both plan sets (the straight
/// plan and the flat runs only answer or decline): a union tag that selects no variant, a
/// given length over the maximum, and a tail array that counts more elements than it may
/// hold; each at the bit where the tag, the prefix or the element starts.
#[test]
fn the_loop_words_each_rule() {
    use px4params_core::codec::{decode_with, encode_with};
    use px4params_core::layout::Role;
    use px4params_core::plan::{HostPlans, NoPlans, Plans};
    use px4params_core::scalar::Cast;

    let mut l = OwnedLayout::default();
    let u8n = l.uint(8, Cast::Saturated).unwrap();
    let u16n = l.uint(16, Cast::Saturated).unwrap();
    let choice = l.union(&[("a", u8n), ("b", u16n)]).unwrap();
    let bytes = l.dyn_array(u8n, 3).unwrap();
    let root = l
        .structure(&[("u", choice, Role::Data), ("s", bytes, Role::Data)])
        .unwrap();
    let layout = l.as_layout();

    fn encoded<P: Plans>(
        layout: &px4params_core::Layout<'_>,
        root: NodeId,
        leaves: &[Scalar],
        tao: bool,
    ) -> (String, usize) {
        let mut out = [0u8; 16];
        let options = EncodeOptions {
            tao,
            ..EncodeOptions::default()
        };
        let e = encode_with::<P, _>(
            layout,
            root,
            &mut LeafSource::new(leaves),
            &mut out,
            options,
        )
        .unwrap_err();
        let text = e.display(layout).to_string();
        (text, e.bit_offset)
    }
    fn decoded<P: Plans>(
        layout: &px4params_core::Layout<'_>,
        root: NodeId,
        data: &[u8],
    ) -> (String, usize) {
        let mut storage = [Scalar::Uint(0); 16];
        let mut sink = LeafSink::new(&mut storage);
        let e = decode_with::<P, _, _>(layout, root, data, &mut sink, DecodeOptions::default())
            .unwrap_err();
        let text = e.display(layout).to_string();
        (text, e.bit_offset)
    }

    for tao in [false, true] {
        // Tag 2 of a union of two variants (its 1-bit tag is the value's first bit).
        let bad_tag = [2, 7, 0].map(Scalar::Uint);
        let want = (
            "u: union tag 2 selects no variant (expected 0..1)".to_string(),
            0,
        );
        assert_eq!(encoded::<HostPlans>(&layout, root, &bad_tag, tao), want);
        assert_eq!(encoded::<NoPlans>(&layout, root, &bad_tag, tao), want);
        // Four elements for an array of at most three: refused where its prefix (or, tail
        // optimized, its first element) would start, after the 1-bit tag and 8-bit variant.
        let long = [0, 7, 4, 1, 2, 3, 4].map(Scalar::Uint);
        let want = ("s: array has 4 elements, at most 3 allowed".to_string(), 9);
        assert_eq!(encoded::<HostPlans>(&layout, root, &long, tao), want);
        assert_eq!(encoded::<NoPlans>(&layout, root, &long, tao), want);
    }
    // Tail optimized, the array takes the whole bytes after bit 9: 39 bits hold four, one
    // more than it may have; the fourth is refused where it starts (bit 9 + 3 * 8).
    let data = [0x03, 0x80, 0x81, 0x01, 0x82, 0x00];
    let want = ("s: array has 4 elements, at most 3 allowed".to_string(), 33);
    assert_eq!(decoded::<HostPlans>(&layout, root, &data), want);
    assert_eq!(decoded::<NoPlans>(&layout, root, &data), want);
}

/// A new array length rewrites the value (store encoding, no tail array optimization): the
/// first elements kept, appended ones zero, dropped ones gone, and the field after the array
/// kept. Bytes worked out by hand from the DroneCAN rules: `uint8[<=3] a` has a 2-bit length
/// prefix, then its elements; `uint8 b` follows; the last byte is padded with zeros.
#[test]
fn set_leaf_length_appends_zeros_and_keeps_what_follows() {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, px4params_core::Cast::Saturated).unwrap();
    let a = l.dyn_array(u8_, 3).unwrap();
    let root = l
        .structure(&[
            ("a", a, px4params_core::layout::Role::Data),
            ("b", u8_, px4params_core::layout::Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    // a = [7], b = 9: 01 00000111 00001001
    let bytes = [0x41, 0xC2, 0x40];
    assert_eq!(
        enc(&l, root, &[1, 7, 9].map(Scalar::Uint), false),
        bytes,
        "the value set out from"
    );
    let opts = EncodeOptions::default();
    let cases: [(u64, &[u8]); 4] = [
        // a = [7, 0, 0]: 11 00000111 00000000 00000000 00001001
        (3, &[0xC1, 0xC0, 0x00, 0x02, 0x40]),
        // a = [7, 0]: 10 00000111 00000000 00001001
        (2, &[0x81, 0xC0, 0x02, 0x40]),
        // a = []: 00 00001001
        (0, &[0x02, 0x40]),
        // unchanged
        (1, &bytes),
    ];
    for (len, expected) in cases {
        let mut out = [0xA5u8; 8];
        let n = set_leaf(
            &layout,
            root,
            &bytes[..],
            Target::Index(0),
            Scalar::Uint(len),
            &mut out,
            opts,
        )
        .unwrap();
        assert_eq!(&out[..n], expected, "a._len = {len}");
    }
    // And from the longest value down: the elements dropped are read past, b kept.
    let long = [0xC1, 0xC0, 0x00, 0x02, 0x40];
    let mut out = [0xA5u8; 8];
    let n = set_leaf(
        &layout,
        root,
        &long[..],
        Target::Index(0),
        Scalar::Uint(1),
        &mut out,
        opts,
    )
    .unwrap();
    assert_eq!(&out[..n], bytes);
    // One past the maximum: refused, worded at the length.
    let err = set_leaf(
        &layout,
        root,
        &bytes[..],
        Target::Index(0),
        Scalar::Uint(4),
        &mut out,
        opts,
    )
    .unwrap_err();
    assert_eq!(
        err.display(&layout).to_string(),
        "a: value 4 is out of range (expected 0 to 3)"
    );
}

/// A type's default (what a new instance starts from) holds the type's version in
/// `p_version`, the first union variant and empty arrays; the stored-version check accepts it
/// and refuses another version. Bytes by hand: `p_version` (uint4) = 3 is 0011, the 1-bit tag
/// 0, variant `a` (uint8) zero, the 2-bit length of `uint8[<=3]` zero: 15 bits, one pad bit.
#[test]
fn a_default_holds_the_types_version_and_the_check_refuses_another() {
    use px4params_core::codec::check_stored;
    use px4params_core::layout::Role;
    let mut l = OwnedLayout::default();
    let u4 = l.uint(4, px4params_core::Cast::Saturated).unwrap();
    let u8_ = l.uint(8, px4params_core::Cast::Saturated).unwrap();
    let choice = l.union(&[("a", u8_), ("b", u4)]).unwrap();
    let list = l.dyn_array(u8_, 3).unwrap();
    let root = l
        .structure(&[
            ("p_version", u4, Role::Version(3)),
            ("choice", choice, Role::Data),
            ("list", list, Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    let mut out = [0xA5u8; 8];
    let n = encode_default(&layout, root, &mut out, false).unwrap();
    assert_eq!(&out[..n], [0x30, 0x00]);
    check_stored(&layout, root, &out[..n]).unwrap();
    let err = check_stored(&layout, root, &[0x20, 0x00]).unwrap_err();
    assert_eq!(
        (err.bit_offset, err.path.steps().count()),
        (4, 1),
        "{err:?}"
    );
    assert_eq!(
        err.display(&layout).to_string(),
        "p_version: p_version is set automatically; got 2, the type's version is 3"
    );
    assert!(
        matches!(
            err.kind,
            ErrorKind::VersionMismatch {
                given: Scalar::Uint(2),
                expected: 3
            }
        ),
        "{err:?}"
    );
}

#[test]
fn a_signed_version_field_holds_the_types_version_too() {
    // int4 p_version of version 3: 0011 then uint4 9 = 0x39; a default written so is checked
    // as stored, and -3 (1101) is refused as another version.
    use px4params_core::codec::check_stored;
    use px4params_core::layout::Role;
    let mut l = OwnedLayout::default();
    let i4 = l.int(4, px4params_core::Cast::Saturated).unwrap();
    let u4 = l.uint(4, px4params_core::Cast::Saturated).unwrap();
    let root = l
        .structure(&[("p_version", i4, Role::Version(3)), ("x", u4, Role::Data)])
        .unwrap();
    let layout = l.as_layout();
    let mut out = [0u8; 2];
    let n = encode_default(&layout, root, &mut out, false).unwrap();
    assert_eq!(&out[..n], [0x30]);
    check_stored(&layout, root, &[0x39]).unwrap();
    let err = check_stored(&layout, root, &[0xD9]).unwrap_err();
    assert_eq!(
        err.display(&layout).to_string(),
        "p_version: p_version is set automatically; got -3, the type's version is 3"
    );
}
