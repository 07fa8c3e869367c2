//! A malformed layout (a corrupt firmware table: a struct whose fields, a union whose
//! variants or a value whose node the tables lack) is refused by the small walk as a layout
//! that nests too deeply is, with an error rather than a panic, encoding and decoding alike.

use px4params_core::codec::{decode_leaves_with, encode_leaves_with};
use px4params_core::error::Step;
use px4params_core::layout::{Field, Kind, Layout, Node, NodeId, Role, Span, VARIABLE};
use px4params_core::plan::NoPlans;
use px4params_core::{DecodeOptions, EncodeOptions, ErrorKind, Scalar};

const fn node(kind: Kind, bits: u64) -> Node {
    Node {
        kind,
        min_bits: bits,
        max_bits: bits,
        leaves: VARIABLE,
        segments: Span { first: 0, count: 0 },
    }
}

const FIELD: Field = Field {
    name_start: 0,
    name_len: 1,
    node: 0,
    role: Role::Data,
};

static NODES: [Node; 4] = [
    // 0: a byte.
    node(
        Kind::Uint {
            bits: 8,
            cast: px4params_core::Cast::Saturated,
        },
        8,
    ),
    // 1: a struct of a field beyond the fields table.
    node(Kind::Struct { first: 1, count: 1 }, 8),
    // 2: a union of two variants, the second beyond the fields table.
    node(
        Kind::Union {
            first: 0,
            count: 2,
            tag_bits: 1,
        },
        9,
    ),
    // 3: a dynamic array of a node beyond the nodes table.
    node(
        Kind::DynArray {
            elem: 9,
            max: 2,
            len_bits: 2,
        },
        2,
    ),
];

fn layout() -> Layout<'static> {
    Layout {
        nodes: &NODES,
        fields: &[FIELD],
        names: "x",
        segments: &[],
        flat: &[],
        straight: &[],
    }
}

fn refused(root: NodeId, leaves: &[Scalar], data: &[u8]) {
    let layout = layout();
    let mut out = [0u8; 8];
    let encoded =
        encode_leaves_with::<NoPlans>(&layout, root, leaves, &mut out, EncodeOptions::default());
    assert_eq!(
        encoded.map_err(|e| e.kind),
        Err(ErrorKind::TooDeep),
        "encode {root}"
    );
    let mut slots = [Scalar::Uint(0); 4];
    let options = DecodeOptions {
        tao: false,
        allow_trailing: true,
    };
    let decoded = decode_leaves_with::<NoPlans, _>(&layout, root, data, &mut slots, options);
    assert_eq!(
        decoded.map_err(|e| e.kind),
        Err(ErrorKind::TooDeep),
        "decode {root}"
    );
}

#[test]
fn a_field_the_tables_lack_is_refused() {
    refused(1, &[Scalar::Uint(5)], &[5]);
    // At the struct's start, named by the struct's path (here the root's, empty): the missing
    // field's own step would cost firmware 32 bytes for a table no generator writes.
    let mut out = [0u8; 8];
    let layout = layout();
    let leaves = [Scalar::Uint(5)];
    let encoded =
        encode_leaves_with::<NoPlans>(&layout, 1, &leaves, &mut out, EncodeOptions::default());
    let error = encoded.unwrap_err();
    assert_eq!(error.path.steps().collect::<Vec<Step>>(), []);
    assert_eq!(error.bit_offset, 0);
}

#[test]
fn a_variant_the_tables_lack_is_refused() {
    // Tag 1: the second variant.
    refused(2, &[Scalar::Uint(1), Scalar::Uint(5)], &[0x80, 0x00]);
}

#[test]
fn an_element_or_a_root_the_tables_lack_is_refused() {
    // One element: its node is not there.
    refused(3, &[Scalar::Uint(1), Scalar::Uint(5)], &[0x40, 0x00]);
    refused(7, &[Scalar::Uint(5)], &[5]);
}
