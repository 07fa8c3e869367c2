//! Leaf access directly in encoded data: find leaf `[k]` or a leaf by path, read it, write it,
//! without decoding the rest of the value.
//!
//! Leaves are numbered in serialization order over the value as it is (following the selected
//! union variant): every primitive field (`p_version` included), every union tag, and every
//! dynamic array's length. Padding and static array lengths are not leaves.

use core::convert::Infallible;

use crate::bits::{put_scalar, BitRead, BitReader};
use crate::error::{Error, ErrorKind, Path, Step};
use crate::interp::{is_scalar, push_flat_path};
use crate::layout::{FlatItem, Kind, Layout, NodeId, Role, Segment, Span};
use crate::plan::{Active, Plans};
pub(crate) use crate::rules::read_uint;
use crate::rules::{scalar_bits, scalar_raw, tail_optimized, EncodeOptions, LeafKind, MAX_DEPTH};
pub use crate::rules::{Leaf, LeafAccessError, Position, Target};
use crate::scalar::Scalar;
use crate::walk::{self, LeafClass, Next, Way};

/// Finds a leaf in `data`, a value of type `root`.
pub fn locate<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    target: Target<'_>,
    tao: bool,
) -> Result<Leaf, LeafAccessError> {
    match target {
        Target::Index(k) => locate_at(layout, root, data, k, tao),
        Target::Path(_) => get_leaf(layout, root, data, target, tao).map(|(leaf, _)| leaf),
    }
}

/// Finds leaf `[k]` in `data`, a value of type `root`.
pub fn locate_at<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Result<Leaf, LeafAccessError> {
    locate_at_with::<Active, R>(layout, root, data, k, tao)
}

/// [`locate_at`] with the plans `P`: the seek that steps over fixed-shape parts
/// ([`Plans::SEEK`]) answers or declines; [`crate::walk`] answers the rest and words every
/// error.
#[inline]
pub fn locate_at_with<P: Plans, R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Result<Leaf, LeafAccessError> {
    if P::SEEK {
        if let Some((leaf, _)) = seek_leaf(layout, root, data, k, tao) {
            return Ok(leaf);
        }
    }
    walk::locate(layout, root, data, k, tao).map(|(leaf, _)| leaf)
}

/// The plan of [`locate_at`]: the seek, keeping the leaf's path. It answers or declines
/// (`None`: no such leaf, malformed data, or a tail array on the way, which [`crate::walk`]
/// counts).
fn seek_leaf<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Option<(Leaf, Position)> {
    let mut seek = Seek::<R, true>::new(layout, data, k);
    let found = seek.within(root, tao)?;
    let leaf = Leaf {
        index: k,
        bit_offset: found.bit_offset,
        kind: found.kind,
        path: seek.path,
    };
    Some((leaf, found))
}

/// Reads leaf `target` of `data`.
#[inline]
pub fn get_leaf<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    target: Target<'_>,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    match target {
        Target::Index(k) => get_leaf_at(layout, root, data, k, tao),
        Target::Path(path) => walk::locate_by(layout, root, data, &mut Tokens { rest: path }, tao),
    }
}

/// Reads leaf `[k]` of `data`.
pub fn get_leaf_at<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    get_leaf_at_with::<Active, R>(layout, root, data, k, tao)
}

/// [`get_leaf_at`] with the plans `P`: located by the seek and read ([`Plans::SEEK`]), which
/// answers or declines; else (and for what it declines) found and read in one
/// [`crate::walk`], which words every error.
pub fn get_leaf_at_with<P: Plans, R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    if P::SEEK {
        if let Some((leaf, found)) = seek_leaf(layout, root, data, k, tao) {
            return Ok((leaf, found.read(data)));
        }
    }
    walk::locate(layout, root, data, k, tao)
}

/// Writes `value` to leaf `target`, producing the new encoding in `out`; returns its length.
///
/// A primitive leaf is overwritten in place. Changing a union tag selects that variant with
/// its default value; changing an array length drops elements at the end or appends default
/// ones. `out` must hold the new value ([`Layout::max_bytes`] always suffices).
pub fn set_leaf<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    target: Target<'_>,
    value: Scalar,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, LeafAccessError> {
    let leaf = locate(layout, root, data, target, options.tao)?;
    set_located(layout, root, data, &leaf, value, out, options)
}

/// [`set_leaf`] of leaf `[k]`.
pub fn set_leaf_at<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    value: Scalar,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, LeafAccessError> {
    set_leaf_at_with::<Active, R>(layout, root, data, k, value, out, options)
}

/// [`set_leaf_at`] with the plans `P`: the leaf located as [`get_leaf_at_with`] finds it,
/// then written ([`set_located`]).
pub fn set_leaf_at_with<P: Plans, R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    value: Scalar,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, LeafAccessError> {
    // Found as a read finds it (the walk's own result, not a copy of its leaf), and written
    // from where it lies in the result (a `?` would copy it out).
    match &get_leaf_at_with::<P, R>(layout, root, data, k, options.tao) {
        Ok((leaf, _)) => set_located(layout, root, data, leaf, value, out, options),
        Err(e) => Err(*e),
    }
}

/// [`set_leaf`] of a leaf already located in `data`.
pub(crate) fn set_located<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    leaf: &Leaf,
    value: Scalar,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, LeafAccessError> {
    let LeafKind::Scalar(kind) = leaf.kind else {
        // A new tag or length changes the value's shape: written anew.
        return walk::transcode(layout, root, data, leaf.index, value, out, options);
    };
    // Errors returned where they are made (a `map_err(..)?` builds one and copies it).
    let raw = match scalar_raw(kind, value, options.saturate) {
        Ok(raw) => raw,
        Err(e) => {
            return Err(Error {
                kind: ErrorKind::Scalar(e),
                bit_offset: leaf.bit_offset,
                path: leaf.path,
            })
        }
    };
    let len = data.bit_len() / 8;
    let Some(copy) = out.get_mut(..len) else {
        return Err(Error {
            kind: ErrorKind::BufferTooSmall { needed: len },
            bit_offset: 0,
            path: Path::default(),
        });
    };
    data.reader(0).read_bytes(copy);
    put_scalar(out, leaf.bit_offset, raw, scalar_bits(kind));
    Ok(len)
}

/// Writes the default encoding of `root` into `out`: zeros, `p_version` set to the type's
/// version, the first union variant, empty dynamic arrays. Returns the length in bytes.
pub fn encode_default(
    layout: &Layout<'_>,
    root: NodeId,
    out: &mut [u8],
    tao: bool,
) -> Result<usize, LeafAccessError> {
    walk::encode_default(layout, root, out, tao)
}

/// Finds leaf `[k]` of `data`, a value of type `root` encoded without tail array optimization
/// (as the store keeps values). `None` when there is no such leaf or the data is malformed:
/// [`locate`] then says why.
pub fn seek<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
) -> Option<Position> {
    seek_with::<Active, R>(layout, root, data, k)
}

/// [`seek`] with the plans `P`: the seek that keeps no path ([`Plans::SEEK`]), else
/// [`crate::walk`].
pub fn seek_with<P: Plans, R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
) -> Option<Position> {
    if !P::SEEK {
        return walk::seek(layout, root, data, k);
    }
    Seek::<R, false>::new(layout, data, k).within(root, false)
}

/// The seek: finds leaf `[k]` stepping over fixed-shape parts by their counts, keeping the
/// leaf's path where `PATH` asks for it.
struct Seek<'l, 'a, 'd, R: ?Sized, const PATH: bool> {
    layout: &'l Layout<'a>,
    data: &'d R,
    pos: usize,
    k: usize,
    depth: usize,
    path: Path,
}

impl<'l, 'a, 'd, R: BitRead + ?Sized, const PATH: bool> Seek<'l, 'a, 'd, R, PATH> {
    fn new(layout: &'l Layout<'a>, data: &'d R, k: usize) -> Self {
        Seek {
            layout,
            data,
            pos: 0,
            k,
            depth: 0,
            path: Path::default(),
        }
    }

    /// Leaf `[k]` of a value of `root`, if it lies within the data (`tao`: as encoded with
    /// tail array optimization).
    fn within(&mut self, root: NodeId, tao: bool) -> Option<Position> {
        let found = self.node(root, None, tao).ok()??;
        let bits = match found.kind {
            LeafKind::Scalar(kind) => scalar_bits(kind),
            LeafKind::Tag { bits, .. } | LeafKind::Len { bits, .. } => bits.into(),
        };
        (found.bit_offset + bits as usize <= self.data.bit_len()).then_some(found)
    }

    fn push(&mut self, step: Step) {
        if PATH {
            self.path.push(step);
        }
    }

    fn pop(&mut self) {
        if PATH {
            self.path.pop();
        }
    }

    /// `Err` gives up (malformed data, or a tail array, which it does not count), `Ok(None)`
    /// means not inside this node (`tao`: it ends the value).
    fn node(&mut self, id: NodeId, field: Option<u32>, tao: bool) -> Result<Option<Position>, ()> {
        let layout = self.layout;
        let node = layout.node(id);
        if let Some(n) = node.fixed_leaves() {
            if self.k >= n as usize {
                self.k -= n as usize;
                self.pos += node.min_bits as usize;
                return Ok(None);
            }
        }
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(());
        }
        let version = field
            .and_then(|f| layout.fields.get(f as usize))
            .is_some_and(|f| matches!(f.role, Role::Version(_)));
        let here = |kind| Position {
            bit_offset: self.pos,
            kind,
            version: version && matches!(kind, LeafKind::Scalar(_)),
        };
        let found = match node.kind {
            kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool) => {
                Some(here(LeafKind::Scalar(kind)))
            }
            Kind::Void { .. } => None,
            Kind::Struct { first, count } => self.segments(node.segments, first + count, tao)?,
            Kind::Union {
                first,
                count,
                tag_bits,
            } => {
                if self.k == 0 {
                    Some(here(LeafKind::Tag {
                        bits: tag_bits,
                        union: id,
                    }))
                } else {
                    self.k -= 1;
                    let tag = self.count(tag_bits, count - 1)?;
                    let variant = first + tag;
                    self.push(Step::Field(variant));
                    let found =
                        self.node(layout.fields[variant as usize].node, Some(variant), tao)?;
                    found.or_else(|| {
                        self.pop();
                        None
                    })
                }
            }
            Kind::Array { elem, len } => self.elements(elem, len, field, tao)?,
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => {
                if tail_optimized(layout, elem, tao) {
                    return Err(());
                }
                if self.k == 0 {
                    Some(here(LeafKind::Len {
                        bits: len_bits,
                        array: id,
                    }))
                } else {
                    self.k -= 1;
                    let n = self.count(len_bits, max)?;
                    self.elements(elem, n, field, tao)?
                }
            }
        };
        self.depth -= 1;
        Ok(found)
    }

    /// Looks through a struct's segments (`end`: one past its last field), skipping whole
    /// fixed-shape runs by their counts.
    fn segments(&mut self, segments: Span, end: u32, tao: bool) -> Result<Option<Position>, ()> {
        let layout = self.layout;
        for segment in segments.of(layout.segments) {
            match *segment {
                Segment::Flat {
                    fields,
                    items,
                    leaves,
                    bits,
                    height,
                } => {
                    if self.k >= leaves as usize {
                        self.k -= leaves as usize;
                        self.pos += bits as usize;
                        continue;
                    }
                    if self.depth + height as usize > MAX_DEPTH {
                        return Err(()); // deeper than the walk follows
                    }
                    if PATH {
                        push_flat_path(layout, fields, self.k as u32, &mut self.path);
                    }
                    for item in items.of(layout.flat) {
                        let (kind, version) = match *item {
                            FlatItem::Pad(bits) => {
                                self.pos += usize::from(bits);
                                continue;
                            }
                            FlatItem::Leaf(kind) => (kind, false),
                            FlatItem::Version(kind, _) => (kind, true),
                        };
                        if self.k == 0 {
                            return Ok(Some(Position {
                                bit_offset: self.pos,
                                kind: LeafKind::Scalar(kind),
                                version,
                            }));
                        }
                        self.k -= 1;
                        self.pos += scalar_bits(kind) as usize;
                    }
                    return Err(()); // the counts and the items disagree: a malformed layout
                }
                Segment::Field(f) => {
                    self.push(Step::Field(f));
                    let node = layout.fields[f as usize].node;
                    let found = self.node(node, Some(f), tao && f + 1 == end)?;
                    if found.is_some() {
                        return Ok(found);
                    }
                    self.pop();
                }
            }
        }
        Ok(None)
    }

    fn elements(
        &mut self,
        elem: NodeId,
        n: u32,
        field: Option<u32>,
        tao: bool,
    ) -> Result<Option<Position>, ()> {
        for i in 0..n {
            self.push(Step::Index(i));
            if let Some(found) = self.node(elem, field, tao && i + 1 == n)? {
                return Ok(Some(found));
            }
            self.pop();
        }
        Ok(None)
    }

    /// Reads a union tag or array length of `bits` bits that must not exceed `max`.
    fn count(&mut self, bits: u8, max: u32) -> Result<u32, ()> {
        if self.pos + bits as usize > self.data.bit_len() {
            return Err(());
        }
        let n = read_uint(self.data, self.pos, bits.into());
        if n > u64::from(max) {
            return Err(());
        }
        self.pos += bits as usize;
        Ok(n as u32)
    }
}

/// One step of a textual path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Token<'p> {
    Name(&'p str),
    Index(u32),
}

/// A textual path, such as `bus.i2c.address`, `cells[3]`, `bus._tag` or `cells._len`.
struct Tokens<'p> {
    rest: &'p str,
}

impl<'p> Tokens<'p> {
    /// The next step; `Err` when the path does not parse.
    fn token(&mut self) -> Result<Option<Token<'p>>, ()> {
        let s = self.rest.strip_prefix('.').unwrap_or(self.rest);
        if s.is_empty() {
            return Ok(None);
        }
        if let Some(after) = s.strip_prefix('[') {
            let close = after.find(']').ok_or(())?;
            let index = after[..close].trim().parse::<u32>().map_err(|_| ())?;
            self.rest = &after[close + 1..];
            return Ok(Some(Token::Index(index)));
        }
        let end = s.find(['.', '[']).unwrap_or(s.len());
        if end == 0 {
            return Err(());
        }
        self.rest = &s[end..];
        Ok(Some(Token::Name(&s[..end])))
    }

    /// Leaf `leaf` of the node, where the path ends there.
    fn last(&mut self, leaf: LeafClass) -> Result<Next, ErrorKind<Infallible>> {
        match self.token() {
            Ok(None) => Ok(Next::Leaf(leaf)),
            _ => Err(ErrorKind::NoSuchPath),
        }
    }
}

impl Way for Tokens<'_> {
    /// What the path names from the type alone: a field by name, a static array's element
    /// below its length, a tag or length by `_tag` or `_len`. Whether the value holds a
    /// union variant or a dynamic array's element is for the walk to see.
    fn next(&mut self, layout: &Layout<'_>, id: NodeId) -> Result<Next, ErrorKind<Infallible>> {
        let token = self.token().map_err(|()| ErrorKind::NoSuchPath)?;
        let kind = layout.node(id).kind;
        Ok(match (kind, token) {
            (kind, None) if is_scalar(kind) => Next::Leaf(LeafClass::Scalar),
            (_, None) => return Err(ErrorKind::NotALeaf),
            (Kind::Union { .. }, Some(Token::Name("_tag"))) => return self.last(LeafClass::Tag),
            (Kind::DynArray { .. }, Some(Token::Name("_len"))) => return self.last(LeafClass::Len),
            (Kind::Struct { .. } | Kind::Union { .. }, Some(Token::Name(name))) => {
                match layout.member_index(id, name) {
                    Some(index) if layout.fields[index as usize].role != Role::Padding => {
                        Next::Step(Step::Field(index))
                    }
                    _ => return Err(ErrorKind::NoSuchPath),
                }
            }
            (Kind::Array { len, .. }, Some(Token::Index(i))) if i < len => {
                Next::Step(Step::Index(i))
            }
            (Kind::DynArray { .. }, Some(Token::Index(i))) => Next::Step(Step::Index(i)),
            _ => return Err(ErrorKind::NoSuchPath),
        })
    }
}
