//! The one interpreter of the DroneCAN rules (`interp.rs`), held to the rules where its
//! mutation run (issue 40, mutinterp) found the suite blind: each test's bytes are worked by
//! hand from the serialization rules (docs: ../shared/SPEC.md, "DroneCAN serialization: the
//! facts"), not taken from what the code computes.
//!
//! Bits fill each byte most significant bit first; a dynamic array `T[<=X]` has a prefix of
//! `ceil(log2(X+1))` bits, except the last array of the top-level value whose elements are a
//! byte or more (tail array optimization, TAO): no prefix, the remaining whole bytes. TAO
//! passes down to the last field of a struct, the selected variant of a union and the last
//! element of an array, never into the elements of a tail array (whose count is what is left).

use px4params_core::codec::{decode_leaves_with, decode_with, encode_leaves_with, encode_with};
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{Field, Layout, Role};
use px4params_core::plan::{HostPlans, NoPlans};
use px4params_core::rules::{ArrayLen, At, LeafKind, Sink, Source, MAX_DEPTH};
use px4params_core::value::{LeafError, LeafSource};
use px4params_core::{walk, Cast, DecodeOptions, EncodeOptions, ErrorKind, Kind, NodeId, Scalar};

/// A refusal of call `n` is the error where it was made: its kind, the path and bit offset
/// `at` names, and no call after it.
fn assert_refused_at<E: PartialEq + core::fmt::Debug, V: core::fmt::Debug>(
    layout: &Layout<'_>,
    e: &px4params_core::error::Error<E>,
    at: (&str, usize, ErrorKind<E>),
    events: &[V],
    n: usize,
) {
    let (path, bit_offset, kind) = at;
    assert_eq!(e.kind, kind, "call {n}");
    let got = (e.path.display(layout).to_string(), e.bit_offset);
    assert_eq!(
        got,
        (path.to_string(), bit_offset),
        "call {n}: {:?}",
        events.last()
    );
    assert_eq!(events.len(), n, "nothing after the refusal");
}

fn uint(l: &mut OwnedLayout, bits: u32) -> NodeId {
    l.uint(bits, Cast::Saturated).unwrap()
}

/// `struct { uint8 n; E[<=3] items }` with `E = struct { uint8 a; uint8[<=2] b }`: `items` is
/// the value's tail array (E is 10 bits or more), and each E's `b` keeps its 2-bit prefix.
fn tail_of_variable_elements(l: &mut OwnedLayout) -> NodeId {
    let byte = uint(l, 8);
    let b = l.dyn_array(byte, 2).unwrap();
    let e = l
        .structure(&[("a", byte, Role::Data), ("b", b, Role::Data)])
        .unwrap();
    let items = l.dyn_array(e, 3).unwrap();
    l.structure(&[("n", byte, Role::Data), ("items", items, Role::Data)])
        .unwrap()
}

/// n = 5, items = [{a = 0x11, b = [0x22]}]: 0x05, 0x11, then b's prefix `01` and 0x22
/// `0010_0010` from bit 16 (`0100_1000 10..`), zero-padded: 26 bits in 4 bytes. The 6 bits
/// left after the one element are less than a byte: the tail array has one element.
const TAIL_VALUE: [u8; 4] = [0x05, 0x11, 0x48, 0x80];

/// Leaves in order: [0] n, [1] the tail array's length, [2] a, [3] b's length, [4] b[0].
#[test]
fn a_leaf_inside_a_tail_array_of_variable_elements_is_found_by_its_number() {
    let mut l = OwnedLayout::default();
    let root = tail_of_variable_elements(&mut l);
    let layout = l.as_layout();
    let expected = [
        (Scalar::Uint(5), 0),
        (Scalar::Uint(1), 8),
        (Scalar::Uint(0x11), 8),
        (Scalar::Uint(1), 16),
        (Scalar::Uint(0x22), 18),
    ];
    for (k, &(value, bit_offset)) in expected.iter().enumerate() {
        let (leaf, got) = walk::locate(&layout, root, &TAIL_VALUE[..], k, true)
            .unwrap_or_else(|e| panic!("leaf [{k}]: {}", e.display(&layout)));
        assert_eq!((got, leaf.bit_offset), (value, bit_offset), "leaf [{k}]");
    }
    // The lengths: the tail array's has no bits, b's its 2-bit prefix.
    let (leaf, _) = walk::locate(&layout, root, &TAIL_VALUE[..], 1, true).unwrap();
    assert!(
        matches!(leaf.kind, LeafKind::Len { bits: 0, .. }),
        "{:?}",
        leaf.kind
    );
    let (leaf, _) = walk::locate(&layout, root, &TAIL_VALUE[..], 3, true).unwrap();
    assert!(
        matches!(leaf.kind, LeafKind::Len { bits: 2, .. }),
        "{:?}",
        leaf.kind
    );
    let (leaf, _) = walk::locate(&layout, root, &TAIL_VALUE[..], 4, true).unwrap();
    assert!(
        matches!(leaf.kind, LeafKind::Scalar(Kind::Uint { bits: 8, .. })),
        "{:?}",
        leaf.kind
    );
}

/// A rewrite writes the elements of a tail array without TAO of their own: b keeps its prefix.
#[test]
fn a_rewrite_keeps_the_prefixes_inside_a_tail_arrays_elements() {
    let mut l = OwnedLayout::default();
    let root = tail_of_variable_elements(&mut l);
    let layout = l.as_layout();
    let options = EncodeOptions {
        tao: true,
        ..EncodeOptions::default()
    };
    let mut out = [0u8; 16];
    let n = walk::transcode(
        &layout,
        root,
        &TAIL_VALUE[..],
        0,
        Scalar::Uint(6),
        &mut out,
        options,
    )
    .unwrap_or_else(|e| panic!("{}", e.display(&layout)));
    assert_eq!(&out[..n], &[0x06, 0x11, 0x48, 0x80]);
    // And with a second element appended (the tail array's length, leaf [1], set to 2): its
    // default, a = 0 and b empty (prefix 00), 10 bits from bit 26: 0x48 0x80 becomes
    // 0100_1000 1000_0000 0000_0000 (26 + 10 = 36 bits, 5 bytes).
    let n = walk::transcode(
        &layout,
        root,
        &TAIL_VALUE[..],
        1,
        Scalar::Uint(2),
        &mut out,
        options,
    )
    .unwrap_or_else(|e| panic!("{}", e.display(&layout)));
    assert_eq!(&out[..n], &[0x05, 0x11, 0x48, 0x80, 0x00]);
}

/// `struct { uint8 a; S s; U u; uint2[2] f; uint8[<=3] t }`, `S = struct { bool b; int3 c }`,
/// `U = union { uint8 x; uint4 y }` (a 1-bit tag): every kind of node, `t` the tail array.
fn every_kind(l: &mut OwnedLayout) -> NodeId {
    let byte = uint(l, 8);
    let b = l.boolean();
    let c = l.int(3, Cast::Saturated).unwrap();
    let s = l
        .structure(&[("b", b, Role::Data), ("c", c, Role::Data)])
        .unwrap();
    let nibble = uint(l, 4);
    let u = l.union(&[("x", byte), ("y", nibble)]).unwrap();
    let two = uint(l, 2);
    let f = l.array(two, 2).unwrap();
    let t = l.dyn_array(byte, 3).unwrap();
    l.structure(&[
        ("a", byte, Role::Data),
        ("s", s, Role::Data),
        ("u", u, Role::Data),
        ("f", f, Role::Data),
        ("t", t, Role::Data),
    ])
    .unwrap()
}

/// a = 0xA5; s = {b = true, c = -2 (`110`)}; u = y (tag `1`) = 9 (`1001`); f = [1, 2] (`01`,
/// `10`); t = [0x41, 0x42] from bit 21, no prefix. By byte: `1010_0101`, `1 110 1 100`,
/// `1 01 10 010`, `00001 010`, `00010 000` (37 bits, 3 of padding): 11 bits are left after
/// t[0] (a second element), 3 after t[1].
const EVERY_KIND: [u8; 5] = [0xA5, 0xEC, 0xB2, 0x0A, 0x10];

/// A sink that writes down what the decoder tells it, and refuses its `refuse`-th call.
struct Record<'l> {
    layout: &'l Layout<'l>,
    events: Vec<String>,
    refuse: usize,
}

impl Record<'_> {
    fn note(&mut self, event: String) -> Result<(), &'static str> {
        self.events.push(event);
        match self.events.len() == self.refuse {
            true => Err("refused"),
            false => Ok(()),
        }
    }
    fn at(&self, at: &At<'_>) -> String {
        format!("{} @{}", at.path.display(self.layout), at.bit_offset)
    }
}

impl Sink for Record<'_> {
    type Error = &'static str;
    fn scalar(&mut self, value: Scalar, at: At<'_>) -> Result<(), Self::Error> {
        let e = format!("{value:?} {}", self.at(&at));
        self.note(e)
    }
    fn begin_struct(&mut self, fields: usize) -> Result<(), Self::Error> {
        self.note(format!("struct {fields}"))
    }
    fn field(&mut self, _index: u32, name: &str) -> Result<(), Self::Error> {
        self.note(format!("field {name}"))
    }
    fn end_struct(&mut self) -> Result<(), Self::Error> {
        self.note("end struct".into())
    }
    fn begin_union(&mut self, tag: u32, _: u32, name: &str, at: At<'_>) -> Result<(), Self::Error> {
        let e = format!("union {tag} {name} {}", self.at(&at));
        self.note(e)
    }
    fn end_union(&mut self) -> Result<(), Self::Error> {
        self.note("end union".into())
    }
    fn begin_array(&mut self, len: ArrayLen, at: At<'_>) -> Result<(), Self::Error> {
        let e = format!("array {len:?} {}", self.at(&at));
        self.note(e)
    }
    fn end_array(&mut self, len: usize) -> Result<(), Self::Error> {
        self.note(format!("end array {len}"))
    }
}

/// What a sink is told, in order: the Sink contract (a struct announces its field count and
/// each field before its value; a union its tag and variant where the union starts; an array
/// its length, or that it is a tail array, where it starts), with the bits worked above.
const EVERY_KIND_EVENTS: [&str; 23] = [
    "struct 5",
    "field a",
    "Uint(165) a @0",
    "field s",
    "struct 2",
    "field b",
    "Bool(true) s.b @8",
    "field c",
    "Int(-2) s.c @9",
    "end struct",
    "field u",
    "union 1 y u @12",
    "Uint(9) u.y @13",
    "end union",
    "field f",
    "array Fixed(2) f @17",
    "Uint(1) f[0] @17",
    "Uint(2) f[1] @19",
    "end array 2",
    "field t",
    "array Tail t @21",
    "Uint(65) t[0] @21",
    "Uint(66) t[1] @29",
];

#[test]
fn a_sink_is_told_the_value_in_serialization_order() {
    let mut l = OwnedLayout::default();
    let root = every_kind(&mut l);
    let layout = l.as_layout();
    for plans in ["host", "firmware"] {
        let mut sink = Record {
            layout: &layout,
            events: Vec::new(),
            refuse: 0,
        };
        let options = DecodeOptions::default();
        let bits = match plans {
            "host" => {
                decode_with::<HostPlans, _, _>(&layout, root, &EVERY_KIND[..], &mut sink, options)
            }
            _ => decode_with::<NoPlans, _, _>(&layout, root, &EVERY_KIND[..], &mut sink, options),
        };
        assert_eq!(bits, Ok(37), "{plans}");
        let mut expected: Vec<String> = EVERY_KIND_EVENTS.iter().map(|e| e.to_string()).collect();
        expected.extend(["end array 2".into(), "end struct".into()]);
        assert_eq!(sink.events, expected, "{plans}");
    }
}

/// A sink's refusal stops the decoder there, named by the field path and the bit offset where
/// the refused call was made.
#[test]
fn a_sinks_refusal_is_the_error_where_it_was_refused() {
    let mut l = OwnedLayout::default();
    let root = every_kind(&mut l);
    let layout = l.as_layout();
    // Call n (1-based) refused: the error's path and bit offset.
    let cases = [
        (1, "", 0),    // struct 5
        (5, "s", 8),   // struct 2, s's begin
        (10, "s", 12), // s's end
        (12, "u", 13), // the union, its tag read
        (14, "u", 17), // its end
        (16, "f", 17), // the static array
        (19, "f", 21), // its end
        (21, "t", 21), // the tail array
        (24, "t", 37), // its end
        (25, "", 37),  // the root's end
    ];
    for (n, path, bit_offset) in cases {
        let mut sink = Record {
            layout: &layout,
            events: Vec::new(),
            refuse: n,
        };
        let e = decode_with::<NoPlans, _, _>(
            &layout,
            root,
            &EVERY_KIND[..],
            &mut sink,
            DecodeOptions::default(),
        )
        .unwrap_err();
        let at = (path, bit_offset, ErrorKind::Value("refused"));
        assert_refused_at(&layout, &e, at, &sink.events, n);
    }
}

/// A tail array read while editing (the walk) counts its elements ahead: more whole bytes than
/// its maximum is an array too long, one element past the maximum, as the decoder says.
#[test]
fn a_tail_array_read_with_more_bytes_than_its_maximum_is_too_long_by_one() {
    let mut l = OwnedLayout::default();
    let byte = uint(&mut l, 8);
    let t = l.dyn_array(byte, 2).unwrap();
    let root = l.structure(&[("t", t, Role::Data)]).unwrap();
    let layout = l.as_layout();
    let too_long = ErrorKind::ArrayTooLong { len: 3, max: 2 };
    let mut leaves = [Scalar::Uint(0); 8];
    let options = DecodeOptions::default();
    let e = walk::decode(&layout, root, &[1u8, 2, 3][..], &mut leaves, options).unwrap_err();
    assert_eq!(e.kind, too_long);
    let e = walk::locate(&layout, root, &[1u8, 2, 3][..], 1, true).unwrap_err();
    assert_eq!(e.kind.map_value(|_| ErrorKind::TooDeep), too_long);
    let e =
        decode_leaves_with::<HostPlans, _>(&layout, root, &[1u8, 2, 3][..], &mut leaves, options)
            .unwrap_err();
    assert_eq!(e.kind, too_long);
}

/// A source that gives a flat leaf list's leaves through the structured calls (not as a flat
/// list), writes down each call the encoder makes, and refuses its `refuse`-th call.
struct Script<'l> {
    leaves: LeafSource<'l>,
    events: Vec<String>,
    refuse: usize,
    /// Fields the source lacks (by name): a `p_version` is then the type's, another missing.
    absent: &'l [&'l str],
}

impl Script<'_> {
    fn note(&mut self, event: String) -> Result<(), LeafError> {
        self.events.push(event);
        match self.events.len() == self.refuse {
            true => Err(LeafError::Full),
            false => Ok(()),
        }
    }
}

impl Source for Script<'_> {
    type Error = LeafError;
    fn scalar(&mut self, kind: Kind) -> Result<Scalar, LeafError> {
        let v = self.leaves.scalar(kind)?;
        self.note(format!("{v:?}"))?;
        Ok(v)
    }
    fn begin_struct(&mut self) -> Result<(), LeafError> {
        self.note("struct".into())
    }
    fn field(&mut self, _index: u32, name: &str) -> Result<bool, LeafError> {
        self.note(format!("field {name}"))?;
        Ok(!self.absent.contains(&name))
    }
    fn end_field(&mut self) {
        self.events.push("end field".into());
    }
    fn end_struct(
        &mut self,
        _: &Layout<'_>,
        fields: &[Field],
        used: usize,
    ) -> Result<(), LeafError> {
        self.note(format!("end struct {used} of {}", fields.len()))
    }
    fn begin_union(&mut self, layout: &Layout<'_>, variants: &[Field]) -> Result<u32, LeafError> {
        let tag = self.leaves.begin_union(layout, variants)?;
        self.note(format!("union {tag} of {}", variants.len()))?;
        Ok(tag)
    }
    fn end_union(&mut self) {
        self.events.push("end union".into());
    }
    fn begin_array(&mut self, fixed: Option<u32>) -> Result<usize, LeafError> {
        let n = self.leaves.begin_array(fixed)?;
        self.note(format!("array {fixed:?} {n}"))?;
        Ok(n)
    }
    fn element(&mut self, index: usize) -> Result<(), LeafError> {
        self.note(format!("element {index}"))
    }
    fn end_element(&mut self) {
        self.events.push("end element".into());
    }
    fn end_array(&mut self) {
        self.events.push("end array".into());
    }
}

/// EVERY_KIND's leaves, in order: a, s.b, s.c, u's tag, u.y, f[0], f[1], t's length, t[0], t[1].
const EVERY_KIND_LEAVES: [Scalar; 10] = [
    Scalar::Uint(0xA5),
    Scalar::Bool(true),
    Scalar::Int(-2),
    Scalar::Uint(1),
    Scalar::Uint(9),
    Scalar::Uint(1),
    Scalar::Uint(2),
    Scalar::Uint(2),
    Scalar::Uint(0x41),
    Scalar::Uint(0x42),
];

/// What the encoder asks a source, in order (the Source contract: a struct, each field, its
/// value, the field left, the struct ended with the number of fields it had; a union's variant
/// where it starts; an array's length, each element entered and left).
const EVERY_KIND_ASKED: [&str; 40] = [
    "struct",
    "field a",
    "Uint(165)",
    "end field",
    "field s",
    "struct",
    "field b",
    "Bool(true)",
    "end field",
    "field c",
    "Int(-2)",
    "end field",
    "end struct 2 of 2",
    "end field",
    "field u",
    "union 1 of 2",
    "Uint(9)",
    "end union",
    "end field",
    "field f",
    "array Some(2) 2",
    "element 0",
    "Uint(1)",
    "end element",
    "element 1",
    "Uint(2)",
    "end element",
    "end array",
    "end field",
    "field t",
    "array None 2",
    "element 0",
    "Uint(65)",
    "end element",
    "element 1",
    "Uint(66)",
    "end element",
    "end array",
    "end field",
    "end struct 5 of 5",
];

#[test]
fn a_source_is_asked_for_the_value_in_serialization_order() {
    let mut l = OwnedLayout::default();
    let root = every_kind(&mut l);
    let layout = l.as_layout();
    for plans in ["host", "firmware"] {
        let mut source = Script {
            leaves: LeafSource::new(&EVERY_KIND_LEAVES),
            events: Vec::new(),
            refuse: 0,
            absent: &[],
        };
        let mut out = [0u8; 8];
        let options = EncodeOptions::default();
        let n = match plans {
            "host" => encode_with::<HostPlans, _>(&layout, root, &mut source, &mut out, options),
            _ => encode_with::<NoPlans, _>(&layout, root, &mut source, &mut out, options),
        };
        assert_eq!(n, Ok(5), "{plans}");
        assert_eq!(out[..5], EVERY_KIND, "{plans}");
        assert_eq!(source.events, EVERY_KIND_ASKED, "{plans}");
    }
}

/// A source's refusal stops the encoder there, named by the path of the field it was asked
/// about (the step taken before the source is asked) and the bits written so far.
#[test]
fn a_sources_refusal_is_the_error_where_it_was_refused() {
    let mut l = OwnedLayout::default();
    let root = every_kind(&mut l);
    let layout = l.as_layout();
    // Call n (1-based, of those that may refuse) refused: the error's path and bit offset.
    let cases = [
        (1, "", 0),       // struct
        (2, "a", 0),      // field a
        (3, "a", 0),      // its value
        (6, "s", 8),      // s's struct
        (13, "s", 12),    // s's end
        (16, "u", 12),    // the union's variant
        (21, "f", 17),    // the static array
        (22, "f[0]", 17), // its element 0
        (25, "f[1]", 19), // element 1
        (31, "t", 21),    // the dynamic array's length
        (40, "", 37),     // the root's end
    ];
    for (n, path, bit_offset) in cases {
        let mut source = Script {
            leaves: LeafSource::new(&EVERY_KIND_LEAVES),
            events: Vec::new(),
            refuse: n,
            absent: &[],
        };
        let mut out = [0u8; 8];
        let e = encode_with::<NoPlans, _>(
            &layout,
            root,
            &mut source,
            &mut out,
            EncodeOptions::default(),
        )
        .unwrap_err();
        let at = (path, bit_offset, ErrorKind::Value(LeafError::Full));
        assert_refused_at(&layout, &e, at, &source.events, n);
    }
}

/// A field the source lacks: a `p_version` is written as the type's version (and not counted
/// as one the source had), any other is missing, named by its path.
#[test]
fn a_field_the_source_lacks_is_the_types_version_or_missing() {
    let mut l = OwnedLayout::default();
    let byte = uint(&mut l, 8);
    let version = uint(&mut l, 4);
    let root = l
        .structure(&[
            ("p_version", version, Role::Version(3)),
            ("x", byte, Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    let mut source = Script {
        leaves: LeafSource::new(&[Scalar::Uint(0x81)]),
        events: Vec::new(),
        refuse: 0,
        absent: &["p_version"],
    };
    let mut out = [0u8; 4];
    let n = encode_with::<NoPlans, _>(
        &layout,
        root,
        &mut source,
        &mut out,
        EncodeOptions::default(),
    );
    // 3 as uint4 (`0011`), then 0x81 (`1000_0001`), then 4 zero bits: 0011_1000 0001_0000.
    assert_eq!(n, Ok(2));
    assert_eq!(out[..2], [0x38, 0x10]);
    let asked = [
        "struct",
        "field p_version",
        "field x",
        "Uint(129)",
        "end field",
        "end struct 1 of 2",
    ];
    assert_eq!(source.events, asked);
    let mut source = Script {
        leaves: LeafSource::new(&[Scalar::Uint(3)]),
        events: Vec::new(),
        refuse: 0,
        absent: &["x"],
    };
    let e = encode_with::<NoPlans, _>(
        &layout,
        root,
        &mut source,
        &mut out,
        EncodeOptions::default(),
    )
    .unwrap_err();
    assert_eq!(e.kind, ErrorKind::MissingField);
    assert_eq!(
        (e.path.display(&layout).to_string(), e.bit_offset),
        ("x".to_string(), 4)
    );
}

/// `struct { E[<=2] arr }`, `E = struct { bool f; uint8[<=2] g }`: E is 3 bits at least, so
/// `arr` keeps its 2-bit prefix though it ends the value; TAO passes to its last element, whose
/// `g` ends the value and takes the remaining bytes; the other elements' `g` keep theirs.
fn prefixed_array_at_the_end(l: &mut OwnedLayout) -> NodeId {
    let byte = uint(l, 8);
    let flag = l.boolean();
    let g = l.dyn_array(byte, 2).unwrap();
    let e = l
        .structure(&[("f", flag, Role::Data), ("g", g, Role::Data)])
        .unwrap();
    let arr = l.dyn_array(e, 2).unwrap();
    l.structure(&[("arr", arr, Role::Data)]).unwrap()
}

/// arr = [{f = 1, g = [0x33]}, {f = 0, g = [0x44, 0x55]}]: `10`, `1`, `01`, `0011_0011`, then
/// the last element: `0`, `0100_0100`, `0101_0101` (no prefix), 2 bits of padding:
/// 1010_1001 1001_1001 0001_0001 0101_0100.
const PREFIXED_AT_THE_END: [u8; 4] = [0xA9, 0x99, 0x11, 0x54];

/// A rewrite gives TAO to the last element written of an array that ends the value, and to no
/// other (leaves: [0] arr's length, [1] arr[0].f, [2] arr[0].g's length, [3] arr[0].g[0],
/// [4] arr[1].f, [5] arr[1].g's length, [6] and [7] its bytes).
#[test]
fn a_rewrite_gives_tao_to_the_last_element_of_an_array_ending_the_value() {
    let mut l = OwnedLayout::default();
    let root = prefixed_array_at_the_end(&mut l);
    let layout = l.as_layout();
    let mut leaves = [Scalar::Uint(0); 8];
    let read = walk::decode(
        &layout,
        root,
        &PREFIXED_AT_THE_END[..],
        &mut leaves,
        DecodeOptions::default(),
    );
    assert_eq!(read.map(|d| (d.bits, d.leaves)), Ok((30, 8)));
    let (u, b) = (Scalar::Uint, Scalar::Bool);
    let expected = [
        u(2),
        b(true),
        u(1),
        u(0x33),
        b(false),
        u(2),
        u(0x44),
        u(0x55),
    ];
    assert_eq!(leaves, expected);
    let options = EncodeOptions {
        tao: true,
        ..EncodeOptions::default()
    };
    let mut out = [0u8; 16];
    let rewrite = |k: usize, value: Scalar, out: &mut [u8]| {
        walk::transcode(
            &layout,
            root,
            &PREFIXED_AT_THE_END[..],
            k,
            value,
            out,
            options,
        )
        .unwrap_or_else(|e| panic!("{}", e.display(&layout)))
    };
    // arr[0].f cleared: bit 2.
    let n = rewrite(1, Scalar::Bool(false), &mut out);
    assert_eq!(&out[..n], &[0x89, 0x99, 0x11, 0x54]);
    // arr cut to its first element, now the last: its g without prefix, `01` + `0011_0011`
    // becomes `0011_0011`: `01`, `1`, `0011_0011`, padding: 0110_0110 0110_0000.
    let n = rewrite(0, Scalar::Uint(1), &mut out);
    assert_eq!(&out[..n], &[0x66, 0x60]);
}

/// A uint8[<=3] inside `depth - 1` one-field structs (the array `depth - 1` levels below the
/// root, its elements one more): followed while the elements are within MAX_DEPTH, else
/// refused, with the plans as without them.
#[test]
fn primitive_elements_one_past_the_bound_are_refused_with_plans_as_without() {
    fn run<P: px4params_core::plan::Plans>(
        depth: usize,
        tao: bool,
    ) -> Result<(Vec<u8>, Vec<Scalar>), ErrorKind<LeafError>> {
        let mut l = OwnedLayout::default();
        let byte = uint(&mut l, 8);
        let mut node = l.dyn_array(byte, 3).unwrap();
        for _ in 1..depth {
            node = l.structure(&[("x", node, Role::Data)]).unwrap();
        }
        let layout = l.as_layout();
        let leaves = [Scalar::Uint(2), Scalar::Uint(7), Scalar::Uint(9)];
        let mut out = [0u8; 8];
        let options = EncodeOptions {
            tao,
            ..EncodeOptions::default()
        };
        let n = encode_leaves_with::<P>(&layout, node, &leaves, &mut out, options)
            .map_err(|e| e.kind)?;
        let mut back = [Scalar::Uint(0); 4];
        let options = DecodeOptions {
            tao,
            ..DecodeOptions::default()
        };
        let d = decode_leaves_with::<P, _>(&layout, node, &out[..n], &mut back, options)
            .map_err(|e| e.kind)?;
        Ok((out[..n].to_vec(), back[..d.leaves].to_vec()))
    }
    let leaves = vec![Scalar::Uint(2), Scalar::Uint(7), Scalar::Uint(9)];
    for tao in [true, false] {
        // With TAO the array ends the value: no prefix. Without: `10`, then 7 and 9.
        let bytes = match tao {
            true => vec![0x07, 0x09],
            false => vec![0x81, 0xC2, 0x40],
        };
        // The array at depth `depth` (the root is 1), its elements at `depth + 1`.
        for depth in MAX_DEPTH - 2..=MAX_DEPTH + 1 {
            let (host, firmware) = (run::<HostPlans>(depth, tao), run::<NoPlans>(depth, tao));
            assert_eq!(host, firmware, "depth {depth}, tao {tao}");
            match depth < MAX_DEPTH {
                true => assert_eq!(host, Ok((bytes.clone(), leaves.clone())), "depth {depth}"),
                false => assert_eq!(host, Err(ErrorKind::TooDeep), "depth {depth}"),
            }
        }
    }
}

/// A value is zero-padded to a byte boundary at its end, whatever the output held before: the
/// walk's writes (a rewrite, a default, leaves) into a buffer full of ones.
#[test]
fn the_last_bytes_unused_bits_are_zero_whatever_the_output_held() {
    let mut l = OwnedLayout::default();
    let root = every_kind(&mut l);
    let layout = l.as_layout();
    let options = EncodeOptions::default();
    let mut out = [0xFFu8; 8];
    let n = walk::encode(&layout, root, &EVERY_KIND_LEAVES, &mut out, options).unwrap();
    assert_eq!(out[..n], EVERY_KIND);
    let mut out = [0xFFu8; 8];
    // t[1] = 0x43: its last 5 bits `00011` then 3 of padding.
    let n = walk::transcode(
        &layout,
        root,
        &EVERY_KIND[..],
        9,
        Scalar::Uint(0x43),
        &mut out,
        options,
    )
    .unwrap();
    assert_eq!(out[..n], [0xA5, 0xEC, 0xB2, 0x0A, 0x18]);
    // The default: every field zero, variant x (tag 0, 8 bits), t empty: 8 + 4 + 1 + 8 + 4
    // = 25 bits, 4 bytes of zeros.
    let mut out = [0xFFu8; 8];
    let n = walk::encode_default(&layout, root, &mut out, true).unwrap();
    assert_eq!(out[..n], [0, 0, 0, 0]);
}

/// An output too small: the value is walked to its end, and the error says how many bytes it
/// needs, as the encoder does.
#[test]
fn an_output_too_small_says_how_many_bytes_the_value_needs() {
    let mut l = OwnedLayout::default();
    let root = every_kind(&mut l);
    let layout = l.as_layout();
    let options = EncodeOptions::default();
    for size in 0..5 {
        let mut out = vec![0u8; size];
        let e = walk::encode(&layout, root, &EVERY_KIND_LEAVES, &mut out, options).unwrap_err();
        assert_eq!(
            e.kind,
            ErrorKind::BufferTooSmall { needed: 5 },
            "{size} bytes"
        );
        assert_eq!(e.bit_offset, 37, "{size} bytes");
        let e = encode_leaves_with::<NoPlans>(&layout, root, &EVERY_KIND_LEAVES, &mut out, options)
            .unwrap_err();
        assert_eq!(
            e.kind,
            ErrorKind::BufferTooSmall { needed: 5 },
            "{size} bytes"
        );
        let e = walk::transcode(
            &layout,
            root,
            &EVERY_KIND[..],
            0,
            Scalar::Uint(1),
            &mut out,
            options,
        )
        .unwrap_err();
        assert_eq!(
            e.kind,
            ErrorKind::BufferTooSmall { needed: 5 },
            "{size} bytes"
        );
    }
}

/// Data that ends inside a leaf: truncated, with the bits the leaf needs and those there are,
/// named by the leaf's path and where it starts; the walk as the decoder.
#[test]
fn data_ending_inside_a_leaf_is_truncated_at_that_leaf() {
    let mut l = OwnedLayout::default();
    let root = every_kind(&mut l);
    let layout = l.as_layout();
    // Two bytes: a, s, the tag (bits 0-13), then u.y needs bits 13-17.
    let data = &EVERY_KIND[..2];
    let truncated = ErrorKind::Truncated {
        needed_bits: 17,
        available_bits: 16,
    };
    let mut leaves = [Scalar::Uint(0); 16];
    let options = DecodeOptions::default();
    let e = walk::decode(&layout, root, data, &mut leaves, options).unwrap_err();
    assert_eq!(e.kind, truncated);
    assert_eq!(
        (e.path.display(&layout).to_string(), e.bit_offset),
        ("u.y".into(), 13)
    );
    let e =
        decode_leaves_with::<NoPlans, _>(&layout, root, data, &mut leaves, options).unwrap_err();
    assert_eq!(e.kind, truncated);
    assert_eq!(
        (e.path.display(&layout).to_string(), e.bit_offset),
        ("u.y".into(), 13)
    );
}

/// Decoding reads a `p_version` field as any other primitive: its bits, its value, its place.
#[test]
fn a_p_version_field_is_decoded_as_the_primitive_it_is() {
    let mut l = OwnedLayout::default();
    let byte = uint(&mut l, 8);
    let version = uint(&mut l, 4);
    let root = l
        .structure(&[
            ("p_version", version, Role::Version(3)),
            ("x", byte, Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    // 2 as uint4 (`0010`, not the type's 3: decoding does not check it), 0x81, padding.
    let data = [0x28u8, 0x10];
    for plans in ["host", "firmware"] {
        let mut sink = Record {
            layout: &layout,
            events: Vec::new(),
            refuse: 0,
        };
        let options = DecodeOptions::default();
        let bits = match plans {
            "host" => decode_with::<HostPlans, _, _>(&layout, root, &data[..], &mut sink, options),
            _ => decode_with::<NoPlans, _, _>(&layout, root, &data[..], &mut sink, options),
        };
        assert_eq!(bits, Ok(12), "{plans}");
        let told = [
            "struct 2",
            "field p_version",
            "Uint(2) p_version @0",
            "field x",
            "Uint(129) x @4",
            "end struct",
        ];
        assert_eq!(sink.events, told, "{plans}");
    }
}

/// A leaf refused inside a fixed-shape run (encoded in one piece with the plans) is named by
/// its own path: element and field, as the walk names it.
#[test]
fn a_leaf_refused_inside_a_run_of_structs_is_named_by_its_own_path() {
    let mut l = OwnedLayout::default();
    let byte = uint(&mut l, 8);
    let p = l
        .structure(&[("a", byte, Role::Data), ("b", byte, Role::Data)])
        .unwrap();
    let arr = l.array(p, 2).unwrap();
    let root = l.structure(&[("arr", arr, Role::Data)]).unwrap();
    let layout = l.as_layout();
    let options = EncodeOptions {
        saturate: false,
        ..EncodeOptions::default()
    };
    // Leaves arr[0].a, arr[0].b, arr[1].a, arr[1].b: each in turn 300, past uint8's 255.
    for (k, path) in ["arr[0].a", "arr[0].b", "arr[1].a", "arr[1].b"]
        .iter()
        .enumerate()
    {
        let mut leaves = [Scalar::Uint(1); 4];
        leaves[k] = Scalar::Uint(300);
        let mut out = [0u8; 8];
        for plans in ["host", "firmware"] {
            let e = match plans {
                "host" => {
                    encode_leaves_with::<HostPlans>(&layout, root, &leaves, &mut out, options)
                }
                _ => encode_leaves_with::<NoPlans>(&layout, root, &leaves, &mut out, options),
            }
            .unwrap_err();
            assert!(
                matches!(e.kind, ErrorKind::Scalar(_)),
                "{plans}: {:?}",
                e.kind
            );
            assert_eq!(
                e.path.display(&layout).to_string(),
                *path,
                "{plans}, leaf [{k}]"
            );
        }
    }
}
