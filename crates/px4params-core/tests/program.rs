//! Value programs (`px4params_core::program`) against the codec's general encoder and decoder,
//! over random struct and union types (primitives, padding, versions, nested structs, unions,
//! fixed and dynamic arrays of primitives and of composites, tail arrays of both), random
//! values (decoded from random bytes, then changed at random) and buffers too small, exact and
//! roomy, data complete and cut short: a program answers with the codec's bytes or value, or
//! declines; it declines exactly where the codec fails on a value it was given unchanged.
//!
//! Values are trees (`Tree`, tests/support/value_tree.rs): the program reads and builds them
//! through its traits, the codec through its `Source`, and its leaf lists are compared with a
//! tree's leaves in `[k]` order.

mod common;
#[path = "support/value_tree.rs"]
mod value_tree;

use common::{any_type, ina238, kitchen_sink, primitive, same_leaves, Ty};
use proptest::prelude::*;
use px4params_core::codec::{decode_leaves, encode, DecodeOptions, EncodeOptions, Source};
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{Field, Kind, Layout, NodeId, Role};
use px4params_core::program::Program;
use px4params_core::Scalar;
use value_tree::{Build, Read, Tree};

/// A tree read by the codec's general encoder.
struct General<'a> {
    stack: Vec<&'a Tree>,
}

/// Why the general encoder's source refuses a tree.
#[derive(Debug, PartialEq)]
enum Refused {
    Shape,
    Unknown,
}

impl General<'_> {
    fn top(&self) -> &Tree {
        self.stack.last().expect("a value")
    }
}

impl<'a> Source for General<'a> {
    type Error = Refused;

    fn scalar(&mut self, _kind: Kind) -> Result<Scalar, Refused> {
        match self.top() {
            Tree::Leaf(s) => Ok(*s),
            _ => Err(Refused::Shape),
        }
    }
    fn begin_struct(&mut self) -> Result<(), Refused> {
        match self.top() {
            Tree::Struct(_) => Ok(()),
            _ => Err(Refused::Shape),
        }
    }
    fn field(&mut self, index: u32, _name: &str) -> Result<bool, Refused> {
        let Tree::Struct(fields) = *self.stack.last().unwrap() else {
            return Err(Refused::Shape);
        };
        let found = fields.iter().find(|(i, _)| *i == index).map(|(_, t)| t);
        if let Some(t) = found {
            self.stack.push(t);
        }
        Ok(found.is_some())
    }
    fn end_field(&mut self) {
        self.stack.pop();
    }
    fn end_struct(&mut self, _: &Layout<'_>, _: &[Field], used: usize) -> Result<(), Refused> {
        match self.top() {
            Tree::Struct(fields) if fields.len() == used => Ok(()),
            _ => Err(Refused::Unknown),
        }
    }
    fn begin_union(&mut self, _: &Layout<'_>, _: &[Field]) -> Result<u32, Refused> {
        let Tree::Union(variant, value) = *self.stack.last().unwrap() else {
            return Err(Refused::Shape);
        };
        self.stack.push(value);
        Ok(*variant)
    }
    fn end_union(&mut self) {
        self.stack.pop();
    }
    fn begin_array(&mut self, _fixed: Option<u32>) -> Result<usize, Refused> {
        self.top()
            .elements()
            .map(<[Tree]>::len)
            .ok_or(Refused::Shape)
    }
    fn element(&mut self, index: usize) -> Result<(), Refused> {
        let Some(items) = self.stack.last().unwrap().elements() else {
            return Err(Refused::Shape);
        };
        self.stack.push(&items[index]);
        Ok(())
    }
    fn end_element(&mut self) {
        self.stack.pop();
    }
    fn end_array(&mut self) {}
}

/// The leaves of a tree of node `id` in `[k]` order (dynamic arrays' lengths first), as the
/// codec's leaf lists hold them.
fn leaves_of(layout: &Layout<'_>, id: NodeId, tree: &Tree, out: &mut Vec<Scalar>) {
    match (layout.node(id).kind, tree) {
        (Kind::Struct { first, count }, Tree::Struct(fields)) => {
            let named: Vec<u32> = (first..first + count)
                .filter(|&i| layout.fields[i as usize].role != Role::Padding)
                .collect();
            let order: Vec<u32> = fields.iter().map(|(i, _)| *i).collect();
            assert_eq!(order, named, "a decoded struct's fields, in order");
            for (i, t) in fields {
                leaves_of(layout, layout.fields[*i as usize].node, t, out);
            }
        }
        (Kind::Union { first, .. }, Tree::Union(variant, t)) => {
            out.push(Scalar::Uint((*variant).into()));
            leaves_of(
                layout,
                layout.fields[(first + variant) as usize].node,
                t,
                out,
            );
        }
        (
            Kind::Array { elem, .. } | Kind::DynArray { elem, .. },
            Tree::List(items) | Tree::Items(items),
        ) => {
            if matches!(layout.node(id).kind, Kind::DynArray { .. }) {
                out.push(Scalar::Uint(items.len() as u64));
            }
            for t in items {
                leaves_of(layout, elem, t, out);
            }
        }
        (_, Tree::Leaf(s)) => out.push(*s),
        (kind, tree) => panic!("{kind:?} decoded as {tree:?}"),
    }
}

/// The codec's leaves of `data`, and the bits read.
fn general_decode(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
    options: DecodeOptions,
) -> Option<(usize, Vec<Scalar>)> {
    let mut leaves = vec![Scalar::Uint(0); 2000];
    let d = decode_leaves(layout, root, data, &mut leaves, options).ok()?;
    Some((d.bits, leaves[..d.leaves].to_vec()))
}

/// Struct and union types: structs of primitives, padding, versions and arrays of primitives
/// (the common shapes), holding structs, unions and arrays of composites (static, dynamic, in
/// tail position too: the last field of a struct that ends the value).
fn program_type() -> impl Strategy<Value = Ty> {
    let field = prop_oneof![
        6 => (primitive(), any::<bool>()),
        1 => (1u32..=9).prop_map(|b| (Ty::Void(b), false)),
        1 => (primitive(), 1u32..5).prop_map(|(t, n)| (Ty::Array(Box::new(t), n), false)),
        2 => (primitive(), 1u32..40).prop_map(|(t, n)| (Ty::Dyn(Box::new(t), n), false)),
        1 => (1u32..40).prop_map(|n| (Ty::Dyn(Box::new(Ty::Uint(8)), n), false)),
    ];
    let nested_field = field.clone();
    let flat = proptest::collection::vec(field.clone(), 0..6).prop_map(Ty::Struct);
    let small = flat.prop_recursive(3, 32, 6, move |inner| {
        let variant = prop_oneof![2 => inner.clone(), 1 => primitive()];
        let union = proptest::collection::vec(variant, 2..5).prop_map(Ty::Union);
        let composite = prop_oneof![2 => inner.clone(), 1 => union.clone()];
        let member = prop_oneof![
            6 => field.clone(),
            2 => inner.clone().prop_map(|t| (t, false)),
            2 => union.clone().prop_map(|t| (t, false)),
            1 => (composite.clone(), 1u32..4).prop_map(|(t, n)| (Ty::Array(Box::new(t), n), false)),
            2 => (composite, 1u32..6).prop_map(|(t, n)| (Ty::Dyn(Box::new(t), n), false)),
        ];
        prop_oneof![
            4 => proptest::collection::vec(member, 0..6).prop_map(Ty::Struct),
            1 => union,
        ]
    });
    // Arrays of composites ending the value, whose items end in a dynamic array (under tail
    // array optimization, only the last item's drops its prefix, and only when the outer
    // array keeps its own), the items perhaps unions.
    let nested = (
        proptest::collection::vec(nested_field.clone(), 0..3),
        proptest::collection::vec(nested_field, 0..3),
        primitive(),
        1u32..6,
        1u32..5,
        0u8..4,
    )
        .prop_map(|(mut outer, mut inner, elem, max_in, len_out, shape)| {
            inner.push((Ty::Dyn(Box::new(elem), max_in), false));
            let mut item = Ty::Struct(inner);
            if shape & 2 != 0 {
                item = Ty::Union(vec![Ty::Bool, item]);
            }
            let array = match shape & 1 {
                0 => Ty::Array(Box::new(item), len_out),
                _ => Ty::Dyn(Box::new(item), len_out),
            };
            outer.push((array, false));
            Ty::Struct(outer)
        });
    // Any type of the codec's tests too (arrays of arrays, unions at the root), as a struct's
    // field when it is not a struct or union itself.
    let any = any_type().prop_map(|ty| match ty {
        Ty::Struct(_) | Ty::Union(_) => ty,
        other => Ty::Struct(vec![(other, false)]),
    });
    prop_oneof![3 => small, 1 => nested, 1 => any]
}

/// The nodes of a tree in pre-order, counted.
fn size(tree: &Tree) -> usize {
    1 + match tree {
        Tree::Leaf(_) => 0,
        Tree::Struct(fields) => fields.iter().map(|(_, t)| size(t)).sum(),
        Tree::Union(_, t) => size(t),
        Tree::List(items) | Tree::Items(items) => items.iter().map(size).sum(),
    }
}

/// `tree` with node `at` (pre-order) changed by `how`: a leaf of another kind or value, a
/// field dropped or an unknown one added, an element added or dropped, a struct made a leaf.
fn change(tree: &mut Tree, at: &mut usize, how: u8, raw: u64) -> bool {
    if *at == 0 {
        match (tree, how % 4) {
            (Tree::Leaf(s), _) => {
                *s = match raw % 4 {
                    0 => Scalar::Uint(raw >> 2),
                    1 => Scalar::Int(raw as i64 >> 2),
                    2 => Scalar::Float(f64::from_bits(raw)),
                    _ => Scalar::Bool(raw & 4 != 0),
                }
            }
            (Tree::Struct(fields), 0) if !fields.is_empty() => {
                fields.remove(raw as usize % fields.len());
            }
            (Tree::Struct(fields), 1) => fields.push((u32::MAX, Tree::Leaf(Scalar::Uint(0)))),
            (t @ Tree::Struct(_), _) => *t = Tree::Leaf(Scalar::Uint(raw % 2)),
            (Tree::Union(variant, _), 0) => *variant = (raw % 5) as u32,
            (t @ Tree::Union(..), _) => *t = Tree::Leaf(Scalar::Uint(raw % 2)),
            (Tree::List(items) | Tree::Items(items), 0) => {
                let copy = match items.first() {
                    Some(first) if raw % 2 == 0 => first.clone(),
                    _ => Tree::Leaf(Scalar::Uint(raw % 256)),
                };
                items.push(copy);
            }
            (Tree::List(items) | Tree::Items(items), _) => {
                items.pop();
            }
        }
        return true;
    }
    *at -= 1;
    match tree {
        Tree::Leaf(_) => false,
        Tree::Struct(fields) => fields.iter_mut().any(|(_, t)| change(t, at, how, raw)),
        Tree::Union(_, t) => change(t, at, how, raw),
        Tree::List(items) | Tree::Items(items) => items.iter_mut().any(|t| change(t, at, how, raw)),
    }
}

type Encoded = Option<Vec<u8>>;

fn by_program(program: &Program, tree: &Tree, size: usize, options: EncodeOptions) -> Encoded {
    let mut out = vec![0xA5u8; size];
    let n = program.encode(&mut Read::new(), tree, &mut out, options)?;
    out.truncate(n);
    Some(out)
}

fn by_codec(
    layout: &Layout<'_>,
    root: NodeId,
    tree: &Tree,
    size: usize,
    options: EncodeOptions,
) -> Encoded {
    let mut out = vec![0x5Au8; size];
    let n = encode(
        layout,
        root,
        &mut General { stack: vec![tree] },
        &mut out,
        options,
    )
    .ok()?;
    out.truncate(n);
    Some(out)
}

fn leaf(v: u64) -> Tree {
    Tree::Leaf(Scalar::Uint(v))
}

/// Values of types with a union (INA238's bus) and a tail array of structs (the kitchen sink)
/// are answered, with the codec's bytes, with and without tail array optimization, and read
/// back as given; cut short by a byte, they are declined, as the codec refuses them.
#[test]
fn unions_and_arrays_of_structs_are_answered() {
    let mut l = OwnedLayout::default();
    let ina = ina238(&mut l);
    let sink = kitchen_sink(&mut l);
    // A tail array of structs ending in a dynamic array: the items keep their arrays' prefixes
    // (only the last field of the top-level value drops it).
    let nest_ty = Ty::Struct(vec![(
        Ty::Dyn(
            Box::new(Ty::Struct(vec![
                (Ty::Uint(8), false),
                (Ty::Dyn(Box::new(Ty::Uint(8)), 3), false),
            ])),
            3,
        ),
        false,
    )]);
    let nest = nest_ty.build(&mut l);
    let layout = l.as_layout();
    // Fields are numbered across the layout: the INA238's come after its bus structs'.
    let field = |node: NodeId, name: &str| layout.member_index(node, name).unwrap();
    let node_of = |node: NodeId, name: &str| layout.fields[field(node, name) as usize].node;
    let spi_node = node_of(node_of(ina, "bus"), "spi");
    let spi = Tree::Struct(vec![
        (field(spi_node, "p_version"), leaf(0)),
        (field(spi_node, "bus_id"), leaf(3)),
        (field(spi_node, "device"), leaf(7)),
    ]);
    let ina_value = Tree::Struct(vec![
        (field(ina, "p_version"), leaf(0)),
        (field(ina, "bus"), Tree::Union(1, Box::new(spi))),
        (field(ina, "current"), leaf(1000)),
        (field(ina, "shunt"), Tree::Leaf(Scalar::Float(0.5))),
    ]);
    let choice = node_of(sink, "choice");
    let pair = node_of(choice, "pair");
    let tail = node_of(sink, "tail");
    let Kind::DynArray { elem, .. } = layout.node(tail).kind else {
        unreachable!()
    };
    let item = |a: u64, b: f64| {
        Tree::Struct(vec![
            (field(elem, "a"), leaf(a)),
            (field(elem, "b"), Tree::Leaf(Scalar::Float(b))),
        ])
    };
    let sink_value = Tree::Struct(vec![
        (field(sink, "flag"), Tree::Leaf(Scalar::Bool(true))),
        (
            field(sink, "choice"),
            Tree::Union(
                0,
                Box::new(Tree::Struct(vec![
                    (field(pair, "x"), Tree::Leaf(Scalar::Int(-3))),
                    (field(pair, "flag"), Tree::Leaf(Scalar::Bool(false))),
                ])),
            ),
        ),
        (
            field(sink, "fixed"),
            Tree::List(vec![Tree::Leaf(Scalar::Float(1.5)); 3]),
        ),
        (field(sink, "big"), Tree::Leaf(Scalar::Int(-5))),
        (
            field(sink, "tail"),
            Tree::Items(vec![item(1, 0.5), item(2, -2.0)]),
        ),
    ]);
    let outer = layout.member_index(nest, "f0").unwrap();
    let Kind::DynArray {
        elem: nest_item, ..
    } = layout.node(layout.fields[outer as usize].node).kind
    else {
        unreachable!()
    };
    let nest_elem = |a: u64, d: &[u64]| {
        Tree::Struct(vec![
            (layout.member_index(nest_item, "f0").unwrap(), leaf(a)),
            (
                layout.member_index(nest_item, "f1").unwrap(),
                Tree::List(d.iter().map(|&v| leaf(v)).collect()),
            ),
        ])
    };
    let nest_value = Tree::Struct(vec![(
        outer,
        Tree::Items(vec![nest_elem(1, &[1, 2]), nest_elem(2, &[3])]),
    )]);
    for (root, value) in [(ina, &ina_value), (sink, &sink_value), (nest, &nest_value)] {
        let program = Program::compile(&layout, root).expect("a program");
        let mut encodings = vec![];
        for tao in [true, false] {
            let options = EncodeOptions {
                tao,
                ..EncodeOptions::default()
            };
            let room = layout.max_bytes(root);
            let ours = by_program(&program, value, room, options).expect("answered");
            assert_eq!(
                Some(&ours),
                by_codec(&layout, root, value, room, options).as_ref()
            );
            let read = DecodeOptions {
                tao,
                allow_trailing: false,
            };
            let back = program.decode(&mut Build(&layout), &ours, read).unwrap();
            assert_eq!(back.as_ref(), Some(value));
            let short = &ours[..ours.len() - 1];
            assert_eq!(
                program.decode(&mut Build(&layout), short, read).unwrap(),
                None
            );
            assert!(general_decode(&layout, root, short, read).is_none());
            encodings.push(ours);
        }
        // The kitchen sink's tail array drops its 3-bit prefix (its items then start 3 bits
        // earlier); the INA238 has no dynamic array.
        assert_eq!(encodings[0] != encodings[1], root != ina);
    }
}

/// A random value of node `id` in range of every field (versions the type's own), drawn from
/// `seed`: what the encoder always takes.
fn random_tree(layout: &Layout<'_>, id: NodeId, seed: &mut u64) -> Tree {
    let mut draw = || {
        // xorshift64*
        *seed ^= *seed >> 12;
        *seed ^= *seed << 25;
        *seed ^= *seed >> 27;
        seed.wrapping_mul(0x2545_F491_4F6C_DD1D)
    };
    let mask = |bits: u8| u64::MAX >> (64 - u32::from(bits));
    match layout.node(id).kind {
        Kind::Uint { bits, .. } => leaf(draw() & mask(bits)),
        Kind::Int { bits, .. } => {
            let raw = draw() & mask(bits);
            let shift = 64 - u32::from(bits);
            Tree::Leaf(Scalar::Int(((raw << shift) as i64) >> shift))
        }
        Kind::Float { .. } => Tree::Leaf(Scalar::Float((draw() % 2000) as f64 / 8.0 - 100.0)),
        Kind::Bool => Tree::Leaf(Scalar::Bool(draw() & 1 == 1)),
        Kind::Void { .. } => unreachable!("padding is no value"),
        Kind::Struct { first, count } => Tree::Struct(
            (first..first + count)
                .filter_map(|i| {
                    let field = layout.fields[i as usize];
                    match field.role {
                        Role::Padding => None,
                        Role::Version(v) => Some((i, leaf(v.into()))),
                        Role::Data => Some((i, random_tree(layout, field.node, seed))),
                    }
                })
                .collect(),
        ),
        Kind::Union { first, count, .. } => {
            let variant = (draw() % u64::from(count)) as u32;
            let node = layout.fields[(first + variant) as usize].node;
            Tree::Union(variant, Box::new(random_tree(layout, node, seed)))
        }
        Kind::Array { elem, len } => {
            let items = (0..len).map(|_| random_tree(layout, elem, seed)).collect();
            Tree::array(layout, elem, items)
        }
        Kind::DynArray { elem, max, .. } => {
            let n = draw() % (u64::from(max) + 1);
            let items = (0..n).map(|_| random_tree(layout, elem, seed)).collect();
            Tree::array(layout, elem, items)
        }
    }
}

fn seed_of(data: &[u8]) -> u64 {
    data.iter().fold(0x9E37_79B9_7F4A_7C15u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01B3)
    }) | 1
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Every struct and union type has a program; other nodes have none.
    #[test]
    fn every_type_has_a_program(ty in any_type()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let composite = matches!(ty, Ty::Struct(_) | Ty::Union(_));
        prop_assert_eq!(Program::compile(&l.as_layout(), root).is_some(), composite, "{:?}", ty);
    }

    /// Decoding random bytes, and a value complete and cut short at every byte: the codec's
    /// leaves, or a decline exactly where the codec fails.
    #[test]
    fn decode_as_the_codec(ty in program_type(), data in proptest::collection::vec(any::<u8>(), 0..80), tao in any::<bool>(), allow_trailing in any::<bool>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let program = Program::compile(&layout, root).expect("a program");
        let stored = general_decode(&layout, root, &data, DecodeOptions { tao: false, allow_trailing: true })
            .map(|(bits, _)| data[..bits.div_ceil(8)].to_vec())
            .unwrap_or_default();
        // A random value in range, encoded by the codec.
        let value = random_tree(&layout, root, &mut seed_of(&data));
        let encode_options = EncodeOptions { tao, ..EncodeOptions::default() };
        let encoded = by_codec(&layout, root, &value, layout.max_bytes(root), encode_options)
            .expect("a value in range");
        let mut cases = vec![(&data[..], tao)];
        cases.extend((0..=stored.len()).rev().map(|n| (&stored[..n], false)));
        cases.extend((0..=encoded.len()).rev().map(|n| (&encoded[..n], tao)));
        for (bytes, tao) in cases {
            let options = DecodeOptions { tao, allow_trailing };
            let general = general_decode(&layout, root, bytes, options);
            let ours = program.decode(&mut Build(&layout), bytes, options).unwrap();
            match (&ours, &general) {
                (Some(tree), Some((_, leaves))) => {
                    let mut flat = Vec::new();
                    leaves_of(&layout, root, tree, &mut flat);
                    prop_assert!(same_leaves(&flat, leaves), "{:?} / {:?}", flat, leaves);
                }
                (None, None) => {}
                _ => prop_assert!(false, "{:02x?} tao {}: {:?} / {:?}", bytes, tao, ours, general),
            }
        }
    }

    /// Encoding values (decoded ones, changed at random) into buffers roomy, exact, too small
    /// by one and of a random size: the codec's bytes, or a decline; an unchanged value into
    /// room is never declined.
    #[test]
    fn encode_as_the_codec(
        ty in program_type(),
        data in proptest::collection::vec(any::<u8>(), 0..80),
        changes in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>(), any::<u64>()), 0..3),
        cap in any::<prop::sample::Index>(),
        tao in any::<bool>(),
        saturate in any::<bool>(),
        keep_versions in any::<bool>(),
    ) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let program = Program::compile(&layout, root).expect("a program");
        let room = layout.max_bytes(root);
        let decoded = program.decode(&mut Build(&layout), &data, DecodeOptions { tao, allow_trailing: true }).unwrap();
        let options = EncodeOptions { tao, saturate, keep_versions };
        // A random value in range is never declined.
        let random = random_tree(&layout, root, &mut seed_of(&data));
        let answered = by_program(&program, &random, room, options);
        prop_assert!(answered.is_some(), "{:?}", random);
        prop_assert_eq!(&answered, &by_codec(&layout, root, &random, room, options), "{:?}", random);
        // Values decoded from the bytes when they are one, else the random value.
        let mut tree = match decoded {
            Some(tree) if data.first().is_some_and(|b| b % 2 == 0) => tree,
            _ => random,
        };
        if !keep_versions {
            // A value decoded from random bytes may hold another version than the type's,
            // which the codec refuses.
            let roomy = by_program(&program, &tree, room, options);
            prop_assert_eq!(&roomy, &by_codec(&layout, root, &tree, room, options), "{:?}", tree);
        }
        for (at, how, raw) in changes {
            let mut at = at.index(size(&tree));
            change(&mut tree, &mut at, how, raw);
        }
        let roomy = by_codec(&layout, root, &tree, room, options);
        let exact = roomy.as_ref().map_or(0, Vec::len);
        for size in [room, exact, exact.saturating_sub(1), cap.index(room + 2)] {
            let ours = by_program(&program, &tree, size, options);
            if ours.is_some() {
                prop_assert_eq!(&ours, &by_codec(&layout, root, &tree, size, options), "{:?}", tree);
            }
        }
    }
}
