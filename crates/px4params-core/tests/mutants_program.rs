//! Value programs (`px4params_core::program`) where the codec stops following a type (issue
//! 40): a type as deep as the walk follows has a program, which answers with the walk's bytes
//! and reads them back as given; a deeper one, whose values the walk refuses, has none, or a
//! program that declines. The walk (`px4params_core::walk`) is the independent answer, over
//! chains of nested structs, unions, arrays of composites and unions held by structs, each
//! from a few levels short of the limit to a few past it.

#[path = "support/value_tree.rs"]
mod value_tree;

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{Kind, NodeId, Role};
use px4params_core::program::Program;
use px4params_core::rules::{DecodeOptions, EncodeOptions, MAX_DEPTH};
use px4params_core::{walk, Cast, Scalar};
use value_tree::{Build, Read, Tree};

/// A type `levels` containers deep, a value of it and that value's leaves in `[k]` order.
struct Chain {
    layout: OwnedLayout,
    root: NodeId,
    value: Tree,
    leaves: Vec<Scalar>,
}

fn first_field(l: &OwnedLayout, id: NodeId) -> u32 {
    match l.as_layout().node(id).kind {
        Kind::Struct { first, .. } | Kind::Union { first, .. } => first,
        kind => panic!("{kind:?} has no fields"),
    }
}

const LEAF: u64 = 0x5A;

/// Structs in structs: `S1 = {x: uint8}`, `Sk = {x: Sk-1}`.
fn structs(levels: usize) -> Chain {
    let mut l = OwnedLayout::default();
    let mut node = l.uint(8, Cast::Saturated).unwrap();
    let mut value = Tree::Leaf(Scalar::Uint(LEAF));
    for _ in 0..levels {
        node = l.structure(&[("x", node, Role::Data)]).unwrap();
        value = Tree::Struct(vec![(first_field(&l, node), value)]);
    }
    let leaves = vec![Scalar::Uint(LEAF)];
    Chain {
        layout: l,
        root: node,
        value,
        leaves,
    }
}

/// Unions in unions, each holding the next as its first variant: `Uk = {a: Uk-1 | b: uint8}`.
fn unions(levels: usize) -> Chain {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let (mut node, mut value) = (u8_, Tree::Leaf(Scalar::Uint(LEAF)));
    for _ in 0..levels {
        node = l.union(&[("a", node), ("b", u8_)]).unwrap();
        value = Tree::Union(0, Box::new(value));
    }
    let mut leaves = vec![Scalar::Uint(0); levels];
    leaves.push(Scalar::Uint(LEAF));
    Chain {
        layout: l,
        root: node,
        value,
        leaves,
    }
}

/// A struct whose first field is `levels - 1` fixed arrays of one in each other, of `uint8`,
/// and whose last is a `uint8` (so that the arrays do not end the value).
fn arrays(levels: usize) -> Chain {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let (mut node, mut value) = (u8_, Tree::Leaf(Scalar::Uint(LEAF)));
    for level in 1..levels {
        node = l.array(node, 1).unwrap();
        // The innermost array is of primitives, the others of arrays.
        value = match level {
            1 => Tree::List(vec![value]),
            _ => Tree::Items(vec![value]),
        };
    }
    let root = l
        .structure(&[("a", node, Role::Data), ("b", u8_, Role::Data)])
        .unwrap();
    let first = first_field(&l, root);
    let value = Tree::Struct(vec![
        (first, value),
        (first + 1, Tree::Leaf(Scalar::Uint(7))),
    ]);
    let leaves = vec![Scalar::Uint(LEAF), Scalar::Uint(7)];
    Chain {
        layout: l,
        root,
        value,
        leaves,
    }
}

/// Structs and unions in turn, each union a struct's field (and its first variant the next
/// struct): `Sk = {u: Uk-1}`, `Uk = {a: Sk-1 | b: uint8}`, down to a `uint8`.
fn structs_holding_unions(levels: usize) -> Chain {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let (mut node, mut value) = (u8_, Tree::Leaf(Scalar::Uint(LEAF)));
    let mut tags = 0;
    for level in 0..levels {
        if level % 2 == 0 {
            node = l.structure(&[("u", node, Role::Data)]).unwrap();
            value = Tree::Struct(vec![(first_field(&l, node), value)]);
        } else {
            node = l.union(&[("a", node), ("b", u8_)]).unwrap();
            value = Tree::Union(0, Box::new(value));
            tags += 1;
        }
    }
    let mut leaves = vec![Scalar::Uint(0); tags];
    leaves.push(Scalar::Uint(LEAF));
    Chain {
        layout: l,
        root: node,
        value,
        leaves,
    }
}

/// Makes a chain of so many levels.
type Shape = fn(usize) -> Chain;

/// For each chain from `MAX_DEPTH - 3` to `MAX_DEPTH + 3` levels: where the walk encodes the
/// value, the type has a program, which writes the walk's bytes and reads them back as the
/// value; where the walk refuses it (too deep), the type has no program, or one that declines
/// the value and any data. Both sides of the limit are met for every shape.
#[test]
fn a_program_follows_a_type_exactly_as_deep_as_the_walk() {
    let shapes: [(&str, Shape); 4] = [
        ("structs", structs),
        ("unions", unions),
        ("arrays", arrays),
        ("structs holding unions", structs_holding_unions),
    ];
    let encode = EncodeOptions::default();
    let decode = DecodeOptions::default();
    for (shape, chain) in shapes {
        let (mut answered, mut refused) = (0, 0);
        for levels in MAX_DEPTH - 3..=MAX_DEPTH + 3 {
            let Chain {
                layout,
                root,
                value,
                leaves,
            } = chain(levels);
            let layout = layout.as_layout();
            let what = format!("{shape}, {levels} levels");
            let program = Program::compile(&layout, root);
            let mut walked = [0u8; 64];
            match walk::encode(&layout, root, &leaves, &mut walked, encode) {
                Ok(n) => {
                    answered += 1;
                    let program = program.unwrap_or_else(|| panic!("{what}: no program"));
                    assert_eq!(program.root(), root, "{what}");
                    let mut out = [0xA5u8; 64];
                    let written = program.encode(&mut Read::new(), &value, &mut out, encode);
                    assert_eq!(written.map(|m| &out[..m]), Some(&walked[..n]), "{what}");
                    let read = program.decode(&mut Build(&layout), &walked[..n], decode);
                    assert_eq!(read, Ok(Some(value.clone())), "{what}");
                }
                Err(_) => {
                    refused += 1;
                    let Some(program) = program else { continue };
                    let mut out = [0u8; 64];
                    let written = program.encode(&mut Read::new(), &value, &mut out, encode);
                    assert_eq!(written, None, "{what}: encoded by the program");
                    // Data of any length (zero bits: every tag and length 0, every leaf 0).
                    let lenient = DecodeOptions {
                        tao: true,
                        allow_trailing: true,
                    };
                    for len in 0..24 {
                        let data = [0u8; 24];
                        let mut slots = [Scalar::Uint(0); 8];
                        let by_walk =
                            walk::decode(&layout, root, &data[..len], &mut slots, lenient);
                        assert!(by_walk.is_err(), "{what}: the walk decodes {len} bytes");
                        let read = program.decode(&mut Build(&layout), &data[..len], lenient);
                        assert_eq!(read, Ok(None), "{what}: {len} bytes decoded by the program");
                    }
                }
            }
        }
        assert!(
            answered > 0 && refused > 0,
            "{shape}: {answered} answered, {refused} refused"
        );
    }
}

/// The leaves of a decoded tree of structs, unions and primitives in `[k]` order (a union's
/// tag first), as the walk's leaf lists hold them.
fn leaves_of(tree: &Tree, out: &mut Vec<Scalar>) {
    match tree {
        Tree::Leaf(s) => out.push(*s),
        Tree::Struct(fields) => fields.iter().for_each(|(_, t)| leaves_of(t, out)),
        Tree::Union(variant, t) => {
            out.push(Scalar::Uint((*variant).into()));
            leaves_of(t, out);
        }
        Tree::List(items) | Tree::Items(items) => items.iter().for_each(|t| leaves_of(t, out)),
    }
}

/// A `p_version` field is a primitive in DSDL; a layout may still give the role to a struct
/// (the binding names any field `p_version` so): the program reads such a value as the walk
/// does, or declines. The value `{p_version: {a: 0x11}, b: 0x22}` is the bytes 11 22.
#[test]
fn a_p_version_field_that_is_a_struct_is_read_as_the_walk_reads_it() {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let inner = l.structure(&[("a", u8_, Role::Data)]).unwrap();
    let root = l
        .structure(&[
            ("p_version", inner, Role::Version(1)),
            ("b", u8_, Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    let Some(program) = Program::compile(&layout, root) else {
        return;
    };
    for allow_trailing in [false, true] {
        let options = DecodeOptions {
            tao: true,
            allow_trailing,
        };
        for data in [&[0x11u8, 0x22][..], &[0x11], &[0x11, 0x22, 0x33]] {
            let mut slots = [Scalar::Uint(0); 4];
            let by_walk = walk::decode(&layout, root, data, &mut slots, options)
                .map(|d| slots[..d.leaves].to_vec())
                .ok();
            let read = program.decode(&mut Build(&layout), data, options);
            let Ok(Some(tree)) = read else { continue };
            let mut leaves = Vec::new();
            leaves_of(&tree, &mut leaves);
            assert_eq!(
                Some(leaves),
                by_walk,
                "{data:02x?}, trailing {allow_trailing}"
            );
        }
    }
}

/// A field of the structs of the next test.
#[derive(Clone, Copy)]
enum Part {
    /// `uint8`.
    Byte,
    /// `uint8[<=3]`.
    Bytes,
    /// `X[<=3]`, `X = {x: uint8}`.
    Structs,
}

/// Dynamic arrays (`T[<=3]`) given 0 to 5 items, in the middle of a struct and ending it,
/// with and without tail array optimization, of bytes and of structs: the program writes
/// the walk's bytes, and declines where the walk refuses the value (more than 3 items).
#[test]
fn a_dynamic_array_is_written_as_the_walk_writes_it_up_to_its_maximum_and_no_further() {
    use Part::*;
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let x = l.structure(&[("x", u8_, Role::Data)]).unwrap();
    let bytes = l.dyn_array(u8_, 3).unwrap();
    let structs = l.dyn_array(x, 3).unwrap();
    let x_field = first_field(&l, x);
    let types = [
        [Bytes, Structs, Byte],
        [Byte, Structs, Bytes],
        [Byte, Bytes, Structs],
    ];
    let mut roots = Vec::new();
    for parts in types {
        let fields: Vec<(&str, NodeId, Role)> = parts
            .iter()
            .zip(["a", "b", "c"])
            .map(|(part, name)| {
                let node = match part {
                    Byte => u8_,
                    Bytes => bytes,
                    Structs => structs,
                };
                (name, node, Role::Data)
            })
            .collect();
        roots.push((parts, l.structure(&fields).unwrap()));
    }
    let layout = l.as_layout();
    let (mut answered, mut refused) = (0, 0);
    for (parts, root) in roots {
        let program = Program::compile(&layout, root).expect("a program");
        let first = first_field(&l, root);
        for n in 0..=5u64 {
            let (mut fields, mut leaves) = (Vec::new(), Vec::new());
            for (i, part) in parts.iter().enumerate() {
                let items = (1..=n).map(|v| Scalar::Uint(0x10 + v));
                let value = match part {
                    Byte => Tree::Leaf(Scalar::Uint(0x77)),
                    Bytes => Tree::List(items.map(Tree::Leaf).collect()),
                    Structs => Tree::Items(
                        items
                            .map(|s| Tree::Struct(vec![(x_field, Tree::Leaf(s))]))
                            .collect(),
                    ),
                };
                match part {
                    Byte => leaves.push(Scalar::Uint(0x77)),
                    _ => {
                        leaves.push(Scalar::Uint(n));
                        leaves.extend((1..=n).map(|v| Scalar::Uint(0x10 + v)));
                    }
                }
                fields.push((first + i as u32, value));
            }
            let value = Tree::Struct(fields);
            for tao in [false, true] {
                let options = EncodeOptions {
                    tao,
                    ..EncodeOptions::default()
                };
                let mut walked = [0u8; 32];
                let by_walk = walk::encode(&layout, root, &leaves, &mut walked, options)
                    .ok()
                    .map(|m| walked[..m].to_vec());
                let mut out = [0xA5u8; 32];
                let by_program = program
                    .encode(&mut Read::new(), &value, &mut out, options)
                    .map(|m| out[..m].to_vec());
                assert_eq!(by_program, by_walk, "{n} items, tao {tao}");
                match by_walk {
                    Some(_) => answered += 1,
                    None => refused += 1,
                }
            }
        }
    }
    // 0 to 3 items written, 4 and 5 refused.
    assert_eq!((answered, refused), (24, 12));
}
