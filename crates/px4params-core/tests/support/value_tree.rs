//! Values as trees for the tests of value programs (`px4params_core::program`): a program
//! reads them through [`Read`] and builds them through [`Build`]. Arrays of primitives
//! (`List`, read and built whole: `begin_array`, `list`) and of composites or arrays (`Items`,
//! item by item: `begin_items`, `push`) are told apart as the program's traits tell them apart, so a
//! program that takes the wrong road declines.
#![allow(dead_code)]

use core::marker::PhantomData;

use px4params_core::layout::{Kind, Layout, NodeId};
use px4params_core::program::{ValueSink, ValueSource};
use px4params_core::Scalar;

/// A value: primitives, structs as (field index, value) in any order, unions as (variant
/// index among the union's, value), arrays of primitives and of composites.
#[derive(Clone, Debug, PartialEq)]
pub enum Tree {
    Leaf(Scalar),
    Struct(Vec<(u32, Tree)>),
    Union(u32, Box<Tree>),
    List(Vec<Tree>),
    Items(Vec<Tree>),
}

impl Tree {
    /// An array of `elem` in a layout: `List` of primitives, `Items` of anything else.
    pub fn array(layout: &Layout<'_>, elem: NodeId, items: Vec<Tree>) -> Tree {
        match layout.node(elem).kind {
            Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool => {
                Tree::List(items)
            }
            _ => Tree::Items(items),
        }
    }

    /// The elements of an array of either kind.
    pub fn elements(&self) -> Option<&[Tree]> {
        match self {
            Tree::List(items) | Tree::Items(items) => Some(items),
            _ => None,
        }
    }
}

/// Reads trees for a program.
pub struct Read<'a>(PhantomData<&'a Tree>);

impl Read<'_> {
    pub fn new() -> Self {
        Read(PhantomData)
    }
}

impl<'a> ValueSource for Read<'a> {
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
    fn union(&mut self, item: &'a Tree, _first: u32, _count: u32) -> Option<(u32, &'a Tree)> {
        match item {
            Tree::Union(variant, value) => Some((*variant, value)),
            _ => None,
        }
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
    fn begin_items(&mut self, item: &'a Tree) -> Option<(Self::Array, usize)> {
        match item {
            Tree::Items(items) => Some((items, items.len())),
            _ => None,
        }
    }
    fn item(&mut self, array: &Self::Array, index: usize) -> Option<&'a Tree> {
        array.get(index)
    }
}

/// Builds trees for a program of a type in the layout it holds.
pub struct Build<'l, 'a>(pub &'l Layout<'a>);

impl ValueSink for Build<'_, '_> {
    type Value = Tree;
    type Struct = Vec<(u32, Tree)>;
    type Items = Vec<Tree>;
    type Error = core::convert::Infallible;

    fn begin_struct(&mut self, _node: NodeId) -> Result<Self::Struct, Self::Error> {
        Ok(Vec::new())
    }
    fn put(&mut self, fields: &mut Self::Struct, field: u32, v: Tree) -> Result<(), Self::Error> {
        fields.push((field, v));
        Ok(())
    }
    fn end_struct(&mut self, fields: Self::Struct, _node: NodeId) -> Result<Tree, Self::Error> {
        Ok(Tree::Struct(fields))
    }
    fn union(&mut self, node: NodeId, field: u32, value: Tree) -> Result<Tree, Self::Error> {
        let Kind::Union { first, count, .. } = self.0.node(node).kind else {
            panic!("a union's node");
        };
        assert!((first..first + count).contains(&field));
        Ok(Tree::Union(field - first, Box::new(value)))
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
    fn begin_items(&mut self, _len: usize) -> Result<Vec<Tree>, Self::Error> {
        Ok(Vec::new())
    }
    fn push(&mut self, items: &mut Vec<Tree>, value: Tree) -> Result<(), Self::Error> {
        items.push(value);
        Ok(())
    }
    fn end_items(&mut self, items: Vec<Tree>) -> Result<Tree, Self::Error> {
        Ok(Tree::Items(items))
    }
}
