//! Value programs (`px4params_core::program`) against the codec's general encoder and decoder,
//! over random struct types of the shapes programs cover (primitives, padding, versions,
//! nested structs, fixed and dynamic arrays of primitives, tail arrays), random values (decoded
//! from random bytes, then changed at random) and buffers too small, exact and roomy, data
//! complete and cut short: a program answers with the codec's bytes or value, or declines;
//! it declines exactly where the codec fails on a value it was given unchanged.
//!
//! Values are trees (`Tree`): the program reads and builds them through its traits, the codec
//! through its `Source`, and its leaf lists are compared with a tree's leaves in `[k]` order.

mod common;

use common::{any_type, primitive, same_leaves, Ty};
use proptest::prelude::*;
use px4params_core::codec::{decode_leaves, encode, DecodeOptions, EncodeOptions, Source};
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::{Field, Kind, Layout, NodeId, Role};
use px4params_core::leaf::encode_default;
use px4params_core::program::{Program, ValueSink, ValueSource};
use px4params_core::Scalar;

/// A value: primitives, structs as (field index, value) in any order, arrays of primitives.
#[derive(Clone, Debug, PartialEq)]
enum Tree {
    Leaf(Scalar),
    Struct(Vec<(u32, Tree)>),
    List(Vec<Tree>),
}

/// Reads trees for programs.
struct Trees;

impl<'a> ValueSource for &'a Trees {
    type Item = &'a Tree;
    type Struct = &'a [(u32, Tree)];
    type Array = &'a [Tree];

    fn begin_struct(&mut self, item: &'a Tree) -> Option<Self::Struct> {
        match item {
            Tree::Struct(fields) => Some(fields),
            _ => None,
        }
    }
    fn field(&mut self, fields: &mut Self::Struct, field: u32) -> Option<Option<&'a Tree>> {
        Some(fields.iter().find(|(i, _)| *i == field).map(|(_, t)| t))
    }
    fn end_struct(&mut self, fields: Self::Struct, used: usize) -> Option<()> {
        (fields.len() == used).then_some(())
    }
    fn scalar(&mut self, item: &'a Tree, _kind: Kind) -> Option<Scalar> {
        match item {
            Tree::Leaf(s) => Some(*s),
            _ => None,
        }
    }
    fn begin_array(&mut self, item: &'a Tree, _elem: Kind) -> Option<(Self::Array, usize)> {
        match item {
            Tree::List(items) => Some((items, items.len())),
            _ => None,
        }
    }
    fn element(&mut self, array: &Self::Array, index: usize, kind: Kind) -> Option<Scalar> {
        self.scalar(&array[index], kind)
    }
}

/// Builds trees for programs.
struct Build;

impl ValueSink for Build {
    type Value = Tree;
    type Struct = Vec<(u32, Tree)>;
    type Error = core::convert::Infallible;

    fn begin_struct(&mut self, _node: NodeId) -> Result<Self::Struct, Self::Error> {
        Ok(Vec::new())
    }
    fn put(
        &mut self,
        fields: &mut Self::Struct,
        field: u32,
        value: Tree,
    ) -> Result<(), Self::Error> {
        fields.push((field, value));
        Ok(())
    }
    fn end_struct(&mut self, fields: Self::Struct, _node: NodeId) -> Result<Tree, Self::Error> {
        Ok(Tree::Struct(fields))
    }
    fn scalar(&mut self, value: Scalar) -> Result<Tree, Self::Error> {
        Ok(Tree::Leaf(value))
    }
    fn list(
        &mut self,
        len: usize,
        items: impl Iterator<Item = Scalar>,
    ) -> Result<Tree, Self::Error> {
        let items: Vec<Tree> = items.map(Tree::Leaf).collect();
        assert_eq!(items.len(), len);
        Ok(Tree::List(items))
    }
}

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
        Err(Refused::Shape)
    }
    fn end_union(&mut self) {}
    fn begin_array(&mut self, _fixed: Option<u32>) -> Result<usize, Refused> {
        match self.top() {
            Tree::List(items) => Ok(items.len()),
            _ => Err(Refused::Shape),
        }
    }
    fn element(&mut self, index: usize) -> Result<(), Refused> {
        let Tree::List(items) = *self.stack.last().unwrap() else {
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
        (Kind::Array { .. }, Tree::List(items)) | (Kind::DynArray { .. }, Tree::List(items)) => {
            if matches!(layout.node(id).kind, Kind::DynArray { .. }) {
                out.push(Scalar::Uint(items.len() as u64));
            }
            for t in items {
                let Tree::Leaf(s) = t else {
                    panic!("arrays of primitives")
                };
                out.push(*s);
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

/// Struct types of the shapes programs cover.
fn program_type() -> impl Strategy<Value = Ty> {
    let field = prop_oneof![
        6 => (primitive(), any::<bool>()),
        1 => (1u32..=9).prop_map(|b| (Ty::Void(b), false)),
        1 => (primitive(), 1u32..5).prop_map(|(t, n)| (Ty::Array(Box::new(t), n), false)),
        2 => (primitive(), 1u32..40).prop_map(|(t, n)| (Ty::Dyn(Box::new(t), n), false)),
        1 => (1u32..40).prop_map(|n| (Ty::Dyn(Box::new(Ty::Uint(8)), n), false)),
    ];
    let flat = proptest::collection::vec(field.clone(), 0..6).prop_map(Ty::Struct);
    flat.prop_recursive(3, 32, 6, move |inner| {
        let member = prop_oneof![3 => field.clone(), 1 => inner.prop_map(|t| (t, false))];
        proptest::collection::vec(member, 0..6).prop_map(Ty::Struct)
    })
}

/// Whether programs cover type `ty` (a struct field of it, at any depth).
fn covered(ty: &Ty) -> bool {
    match ty {
        Ty::Union(_) => false,
        Ty::Struct(fields) => fields.iter().all(|(t, _)| covered(t)),
        Ty::Array(t, _) | Ty::Dyn(t, _) => !matches!(
            **t,
            Ty::Struct(_) | Ty::Union(_) | Ty::Array(..) | Ty::Dyn(..)
        ),
        _ => true,
    }
}

/// The nodes of a tree in pre-order, counted.
fn size(tree: &Tree) -> usize {
    1 + match tree {
        Tree::Leaf(_) => 0,
        Tree::Struct(fields) => fields.iter().map(|(_, t)| size(t)).sum(),
        Tree::List(items) => items.iter().map(size).sum(),
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
            (Tree::List(items), 0) => items.push(Tree::Leaf(Scalar::Uint(raw % 256))),
            (Tree::List(items), _) => {
                items.pop();
            }
        }
        return true;
    }
    *at -= 1;
    match tree {
        Tree::Leaf(_) => false,
        Tree::Struct(fields) => fields.iter_mut().any(|(_, t)| change(t, at, how, raw)),
        Tree::List(items) => items.iter_mut().any(|t| change(t, at, how, raw)),
    }
}

type Encoded = Option<Vec<u8>>;

fn by_program(program: &Program, tree: &Tree, size: usize, options: EncodeOptions) -> Encoded {
    let mut out = vec![0xA5u8; size];
    let n = program.encode(&mut &Trees, tree, &mut out, options)?;
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

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// A program is compiled for exactly the struct types of the shapes it covers.
    #[test]
    fn programs_cover_their_shapes(ty in any_type()) {
        let root_ty = match ty {
            Ty::Struct(_) => ty,
            other => Ty::Struct(vec![(other, false)]),
        };
        let mut l = OwnedLayout::default();
        let root = root_ty.build(&mut l);
        prop_assert_eq!(Program::compile(&l.as_layout(), root).is_some(), covered(&root_ty), "{:?}", root_ty);
    }

    /// Decoding random bytes, and a value complete and cut short at every byte: the codec's
    /// leaves, or a decline exactly where the codec fails.
    #[test]
    fn decode_as_the_codec(ty in program_type(), data in proptest::collection::vec(any::<u8>(), 0..80), tao in any::<bool>(), allow_trailing in any::<bool>()) {
        let mut l = OwnedLayout::default();
        let root = ty.build(&mut l);
        let layout = l.as_layout();
        let program = Program::compile(&layout, root).expect("a covered shape");
        let stored = general_decode(&layout, root, &data, DecodeOptions { tao: false, allow_trailing: true })
            .map(|(bits, _)| data[..bits.div_ceil(8)].to_vec())
            .unwrap_or_default();
        let mut cases = vec![(&data[..], tao)];
        cases.extend((0..=stored.len()).rev().map(|n| (&stored[..n], false)));
        for (bytes, tao) in cases {
            let options = DecodeOptions { tao, allow_trailing };
            let general = general_decode(&layout, root, bytes, options);
            let ours = program.decode(&mut Build, bytes, options).unwrap();
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
        let program = Program::compile(&layout, root).expect("a covered shape");
        let room = layout.max_bytes(root);
        let decoded = program.decode(&mut Build, &data, DecodeOptions { tao, allow_trailing: true }).unwrap();
        let mut tree = decoded.unwrap_or_else(|| {
            let mut out = vec![0u8; room];
            let n = encode_default(&layout, root, &mut out, false).unwrap();
            let options = DecodeOptions { tao: false, allow_trailing: false };
            program.decode(&mut Build, &out[..n], options).unwrap().expect("the default value")
        });
        let options = EncodeOptions { tao, saturate, keep_versions };
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
