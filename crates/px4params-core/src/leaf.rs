//! Leaf access directly in encoded data: find leaf `[k]` or a leaf by path, read it, write it,
//! without decoding the rest of the value.
//!
//! Leaves are numbered in serialization order over the value as it is (following the selected
//! union variant): every primitive field (`p_version` included), every union tag, and every
//! dynamic array's length. Padding and static array lengths are not leaves.

use core::convert::Infallible;

use crate::bits::BitRead;
use crate::error::{Error, ErrorKind, Path, Step};
use crate::layout::{FlatItem, Kind, Layout, NodeId, Role, Segment, Span};
use crate::plan::{Active, Plans};
pub(crate) use crate::rules::read_uint;
use crate::rules::{
    read_scalar, scalar_bits, scalar_raw, tail_optimized, EncodeOptions, LeafKind, MAX_DEPTH,
};
pub use crate::rules::{Leaf, LeafAccessError, Position, Target};
use crate::scalar::Scalar;
use crate::walk;

/// Finds a leaf in `data`, a value of type `root`.
pub fn locate<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    target: Target<'_>,
    tao: bool,
) -> Result<Leaf, LeafAccessError> {
    let path = match target {
        Target::Index(k) => return locate_at(layout, root, data, k, tao),
        Target::Path(path) => path,
    };
    let mut walk = Walk::new(layout, data);
    let leaf = walk.by_path(root, tao, &mut Tokens { rest: path })?;
    within(data, leaf)
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

/// [`locate_at`] with the plans `P`: the leaf walk that steps over fixed-shape parts
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
        if let Some(leaf) = locate_plan(layout, root, data, k, tao) {
            return Ok(leaf);
        }
    }
    walk::locate(layout, root, data, k, tao).map(|(leaf, _)| leaf)
}

/// The plan of [`locate_at`]: the leaf walk that steps over fixed-shape parts. It answers or
/// declines (`None`: no such leaf, or malformed data, which [`crate::walk`] words).
fn locate_plan<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Option<Leaf> {
    let mut walk = Walk::new(layout, data);
    let mut left = k;
    let leaf = walk.by_index(root, tao, &mut left).ok()??;
    within(data, leaf).ok()
}

/// `leaf`, checked to lie within `data` (the walks pass over fixed-shape parts unread).
fn within<R: BitRead + ?Sized>(data: &R, leaf: Leaf) -> Result<Leaf, LeafAccessError> {
    let end = leaf.bit_offset + leaf_bits(&leaf) as usize;
    if end > data.bit_len() {
        return Err(Error {
            kind: ErrorKind::Truncated {
                needed_bits: end,
                available_bits: data.bit_len(),
            },
            bit_offset: leaf.bit_offset,
            path: leaf.path,
        });
    }
    Ok(leaf)
}

/// Reads a located leaf's value. A tag or length reads as [`Scalar::Uint`].
pub fn read_leaf<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    data: &R,
    leaf: &Leaf,
    tao: bool,
) -> Result<Scalar, LeafAccessError> {
    Ok(match leaf.kind {
        LeafKind::Scalar(kind) => read_scalar(data, leaf.bit_offset, kind),
        LeafKind::Tag { bits, .. } => Scalar::Uint(read_uint(data, leaf.bit_offset, bits.into())),
        LeafKind::Len { bits: 0, array } => {
            // Tail-optimized: count the elements up to the end of the data.
            let mut walk = Walk::new(layout, data);
            (walk.pos, walk.path) = (leaf.bit_offset, leaf.path);
            let Kind::DynArray { elem, .. } = layout.node(array).kind else {
                return Ok(Scalar::Uint(0));
            };
            Scalar::Uint(walk.tail_count(elem, tao)? as u64)
        }
        LeafKind::Len { bits, .. } => Scalar::Uint(read_uint(data, leaf.bit_offset, bits.into())),
    })
}

/// Reads leaf `target` of `data`.
pub fn get_leaf<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    target: Target<'_>,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    if let Target::Index(k) = target {
        return get_leaf_at(layout, root, data, k, tao);
    }
    let leaf = locate(layout, root, data, target, tao)?;
    let value = read_leaf(layout, data, &leaf, tao)?;
    Ok((leaf, value))
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

/// [`get_leaf_at`] with the plans `P`: located by the leaf walk and read ([`Plans::SEEK`]),
/// which answers or declines; else (and for what it declines) found and read in one
/// [`crate::walk`], which words every error.
pub fn get_leaf_at_with<P: Plans, R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    if P::SEEK {
        if let Some(leaf) = locate_plan(layout, root, data, k, tao) {
            if let Ok(value) = read_leaf(layout, data, &leaf, tao) {
                return Ok((leaf, value));
            }
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

/// [`set_leaf_at`] with the plans `P`: the leaf located as [`locate_at_with`] finds it, then
/// written ([`set_located`]).
pub fn set_leaf_at_with<P: Plans, R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    value: Scalar,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, LeafAccessError> {
    let leaf = locate_at_with::<P, R>(layout, root, data, k, options.tao)?;
    set_located(layout, root, data, &leaf, value, out, options)
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
    let raw = scalar_raw(kind, value, options.saturate).map_err(|e| Error {
        kind: ErrorKind::Scalar(e),
        bit_offset: leaf.bit_offset,
        path: leaf.path,
    })?;
    let len = data.bit_len() / 8;
    if out.len() < len {
        return Err(Error {
            kind: ErrorKind::BufferTooSmall { needed: len },
            bit_offset: 0,
            path: Path::default(),
        });
    }
    for (i, byte) in out[..len].iter_mut().enumerate() {
        *byte = data.byte(i);
    }
    walk::put(out, leaf.bit_offset, raw, scalar_bits(kind));
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
    let mut seek = Seek {
        layout,
        data,
        pos: 0,
        k,
        depth: 0,
    };
    let found = seek.node(root, None).ok()??;
    let bits = match found.kind {
        LeafKind::Scalar(kind) => scalar_bits(kind),
        LeafKind::Tag { bits, .. } | LeafKind::Len { bits, .. } => bits.into(),
    };
    (found.bit_offset + bits as usize <= data.bit_len()).then_some(found)
}

struct Seek<'l, 'a, 'd, R: ?Sized> {
    layout: &'l Layout<'a>,
    data: &'d R,
    pos: usize,
    k: usize,
    depth: usize,
}

impl<R: BitRead + ?Sized> Seek<'_, '_, '_, R> {
    /// `Err` gives up (malformed data), `Ok(None)` means not inside this node.
    fn node(&mut self, id: NodeId, field: Option<u32>) -> Result<Option<Position>, ()> {
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
            Kind::Struct { .. } => self.segments(node.segments)?,
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
                    self.node(layout.fields[variant as usize].node, Some(variant))?
                }
            }
            Kind::Array { elem, len } => self.elements(elem, len, field)?,
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => {
                if self.k == 0 {
                    Some(here(LeafKind::Len {
                        bits: len_bits,
                        array: id,
                    }))
                } else {
                    self.k -= 1;
                    let n = self.count(len_bits, max)?;
                    self.elements(elem, n, field)?
                }
            }
        };
        self.depth -= 1;
        Ok(found)
    }

    /// Looks through a struct's segments, skipping whole fixed-shape runs by their counts.
    fn segments(&mut self, segments: Span) -> Result<Option<Position>, ()> {
        let layout = self.layout;
        for segment in segments.of(layout.segments) {
            match *segment {
                Segment::Flat {
                    items,
                    leaves,
                    bits,
                    ..
                } => {
                    if self.k >= leaves as usize {
                        self.k -= leaves as usize;
                        self.pos += bits as usize;
                        continue;
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
                    let found = self.node(layout.fields[f as usize].node, Some(f))?;
                    if found.is_some() {
                        return Ok(found);
                    }
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
    ) -> Result<Option<Position>, ()> {
        for _ in 0..n {
            if let Some(found) = self.node(elem, field)? {
                return Ok(Some(found));
            }
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

fn leaf_bits(leaf: &Leaf) -> u32 {
    match leaf.kind {
        LeafKind::Scalar(kind) => scalar_bits(kind),
        LeafKind::Tag { bits, .. } | LeafKind::Len { bits, .. } => bits.into(),
    }
}

/// One step of a textual path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Token<'p> {
    Name(&'p str),
    Index(u32),
}

struct Tokens<'p> {
    rest: &'p str,
}

impl<'p> Tokens<'p> {
    /// The next step; `Err` when the path does not parse.
    fn next(&mut self) -> Result<Option<Token<'p>>, ()> {
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
}

/// Walks encoded data without producing values, counting leaves.
struct Walk<'l, 'd, R: BitRead + ?Sized> {
    layout: &'l Layout<'l>,
    data: &'d R,
    pos: usize,
    path: Path,
    leaves: usize,
    depth: usize,
}

impl<'l, 'd, R: BitRead + ?Sized> Walk<'l, 'd, R> {
    fn new(layout: &'l Layout<'l>, data: &'d R) -> Self {
        Self {
            layout,
            data,
            pos: 0,
            path: Path::default(),
            leaves: 0,
            depth: 0,
        }
    }

    #[cold]
    #[inline(never)]
    fn fail(&self, kind: ErrorKind<Infallible>) -> LeafAccessError {
        Error {
            kind,
            bit_offset: self.pos,
            path: self.path,
        }
    }

    fn read(&mut self, bits: u32) -> Result<u64, LeafAccessError> {
        if bits == 0 {
            return Ok(0);
        }
        let available = self.data.bit_len();
        if self.pos + bits as usize > available {
            return Err(self.fail(ErrorKind::Truncated {
                needed_bits: self.pos + bits as usize,
                available_bits: available,
            }));
        }
        let v = read_uint(self.data, self.pos, bits);
        self.pos += bits as usize;
        Ok(v)
    }

    fn enter(&mut self) -> Result<(), LeafAccessError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.fail(ErrorKind::TooDeep));
        }
        Ok(())
    }

    fn tag(&mut self, count: u32, tag_bits: u8) -> Result<u32, LeafAccessError> {
        let at = self.pos;
        let tag = self.read(tag_bits.into())?;
        if tag >= u64::from(count) {
            self.pos = at;
            return Err(self.fail(ErrorKind::BadUnionTag {
                tag,
                variants: count,
            }));
        }
        Ok(tag as u32)
    }

    fn prefixed_len(&mut self, max: u32, len_bits: u8) -> Result<u32, LeafAccessError> {
        let at = self.pos;
        let n = self.read(len_bits.into())?;
        if n > u64::from(max) {
            self.pos = at;
            return Err(self.fail(ErrorKind::ArrayTooLong { len: n, max }));
        }
        Ok(n as u32)
    }

    /// Number of elements of a tail-optimized array starting here (position restored).
    fn tail_count(&mut self, elem: NodeId, _tao: bool) -> Result<usize, LeafAccessError> {
        let (start, leaves) = (self.pos, self.leaves);
        let mut n = 0;
        while self.data.bit_len().saturating_sub(self.pos) >= 8 {
            self.skip(elem, false)?;
            n += 1;
        }
        (self.pos, self.leaves) = (start, leaves);
        Ok(n)
    }

    /// Skips a value, counting its leaves.
    fn skip(&mut self, id: NodeId, tao: bool) -> Result<(), LeafAccessError> {
        let layout = self.layout;
        let node = layout.node(id);
        if let Some(n) = node.fixed_leaves() {
            self.pos += node.min_bits as usize;
            self.leaves += n as usize;
            return Ok(());
        }
        self.enter()?;
        match node.kind {
            Kind::Struct { count, .. } => {
                for (i, f) in layout.members(id).iter().enumerate() {
                    self.skip(f.node, tao && i + 1 == count as usize)?;
                }
            }
            Kind::Union {
                first,
                count,
                tag_bits,
            } => {
                let tag = self.tag(count, tag_bits)?;
                self.leaves += 1;
                self.skip(layout.fields[(first + tag) as usize].node, tao)?;
            }
            Kind::Array { elem, len } => {
                for i in 0..len {
                    self.skip(elem, tao && i + 1 == len)?;
                }
            }
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => {
                self.leaves += 1;
                if tail_optimized(layout, elem, tao) {
                    let mut n = 0;
                    while self.data.bit_len().saturating_sub(self.pos) >= 8 {
                        if n == max {
                            return Err(self.fail(ErrorKind::ArrayTooLong {
                                len: u64::from(n) + 1,
                                max,
                            }));
                        }
                        self.skip(elem, false)?;
                        n += 1;
                    }
                } else {
                    let n = self.prefixed_len(max, len_bits)?;
                    for i in 0..n {
                        self.skip(elem, tao && i + 1 == n)?;
                    }
                }
            }
            // Scalars and padding have fixed leaves and were handled above.
            _ => {}
        }
        self.depth -= 1;
        Ok(())
    }

    fn found(&self, kind: LeafKind) -> Leaf {
        Leaf {
            index: self.leaves,
            bit_offset: self.pos,
            kind,
            path: self.path,
        }
    }

    /// Looks for leaf `*k` (counted from here) inside node `id`.
    fn by_index(
        &mut self,
        id: NodeId,
        tao: bool,
        k: &mut usize,
    ) -> Result<Option<Leaf>, LeafAccessError> {
        let layout = self.layout;
        let node = layout.node(id);
        if let Some(n) = node.fixed_leaves() {
            if *k >= n as usize {
                *k -= n as usize;
                self.pos += node.min_bits as usize;
                self.leaves += n as usize;
                return Ok(None);
            }
        }
        self.enter()?;
        let found = match node.kind {
            kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool) => {
                // fixed_leaves is 1 and *k < 1.
                Some(self.found(LeafKind::Scalar(kind)))
            }
            Kind::Void { .. } => None,
            Kind::Struct { first, count } => {
                let mut found = None;
                for i in 0..count {
                    let field = layout.fields[(first + i) as usize];
                    self.path.push(Step::Field(first + i));
                    found = self.by_index(field.node, tao && i + 1 == count, k)?;
                    if found.is_some() {
                        break;
                    }
                    self.path.pop();
                }
                found
            }
            Kind::Union {
                first,
                count,
                tag_bits,
            } => {
                if *k == 0 {
                    Some(self.found(LeafKind::Tag {
                        bits: tag_bits,
                        union: id,
                    }))
                } else {
                    *k -= 1;
                    self.leaves += 1;
                    let tag = self.tag(count, tag_bits)?;
                    self.path.push(Step::Field(first + tag));
                    let found =
                        self.by_index(layout.fields[(first + tag) as usize].node, tao, k)?;
                    if found.is_none() {
                        self.path.pop();
                    }
                    found
                }
            }
            Kind::Array { elem, len } => {
                let mut found = None;
                for i in 0..len {
                    self.path.push(Step::Index(i));
                    found = self.by_index(elem, tao && i + 1 == len, k)?;
                    if found.is_some() {
                        break;
                    }
                    self.path.pop();
                }
                found
            }
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => {
                let tail = tail_optimized(layout, elem, tao);
                if *k == 0 {
                    let bits = if tail { 0 } else { len_bits };
                    Some(self.found(LeafKind::Len { bits, array: id }))
                } else {
                    *k -= 1;
                    self.leaves += 1;
                    let n = if tail {
                        self.tail_count(elem, tao)? as u32
                    } else {
                        self.prefixed_len(max, len_bits)?
                    };
                    if n > max {
                        return Err(self.fail(ErrorKind::ArrayTooLong { len: n.into(), max }));
                    }
                    let mut found = None;
                    for i in 0..n {
                        self.path.push(Step::Index(i));
                        found = self.by_index(elem, !tail && tao && i + 1 == n, k)?;
                        if found.is_some() {
                            break;
                        }
                        self.path.pop();
                    }
                    found
                }
            }
        };
        self.depth -= 1;
        Ok(found)
    }

    fn next_token<'p>(
        &self,
        tokens: &mut Tokens<'p>,
    ) -> Result<Option<Token<'p>>, LeafAccessError> {
        tokens.next().map_err(|()| self.fail(ErrorKind::NoSuchPath))
    }

    /// Follows a textual path inside node `id`.
    fn by_path(
        &mut self,
        id: NodeId,
        tao: bool,
        tokens: &mut Tokens<'_>,
    ) -> Result<Leaf, LeafAccessError> {
        self.enter()?;
        let layout = self.layout;
        let token = self.next_token(tokens)?;
        let leaf = match (layout.node(id).kind, token) {
            (
                kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool),
                None,
            ) => self.found(LeafKind::Scalar(kind)),
            (
                Kind::Struct { .. }
                | Kind::Union { .. }
                | Kind::Array { .. }
                | Kind::DynArray { .. },
                None,
            ) => return Err(self.fail(ErrorKind::NotALeaf)),
            (Kind::Struct { first, count }, Some(Token::Name(name))) => {
                let Some(index) = layout.member_index(id, name) else {
                    return Err(self.fail(ErrorKind::NoSuchPath));
                };
                if layout.fields[index as usize].role == Role::Padding {
                    return Err(self.fail(ErrorKind::NoSuchPath));
                }
                for i in first..index {
                    self.skip(layout.fields[i as usize].node, false)?;
                }
                self.path.push(Step::Field(index));
                let last = tao && index + 1 == first + count;
                self.by_path(layout.fields[index as usize].node, last, tokens)?
            }
            (
                Kind::Union {
                    first,
                    count,
                    tag_bits,
                },
                Some(Token::Name(name)),
            ) => {
                if name == "_tag" {
                    if self.next_token(tokens)?.is_some() {
                        return Err(self.fail(ErrorKind::NoSuchPath));
                    }
                    self.found(LeafKind::Tag {
                        bits: tag_bits,
                        union: id,
                    })
                } else {
                    let Some(index) = layout.member_index(id, name) else {
                        return Err(self.fail(ErrorKind::NoSuchPath));
                    };
                    self.leaves += 1;
                    let tag = self.tag(count, tag_bits)?;
                    self.path.push(Step::Field(index));
                    if index != first + tag {
                        return Err(self.fail(ErrorKind::VariantNotSelected));
                    }
                    self.by_path(layout.fields[index as usize].node, tao, tokens)?
                }
            }
            (Kind::Array { elem, len }, Some(Token::Index(i))) => {
                if i >= len {
                    return Err(self.fail(ErrorKind::NoSuchPath));
                }
                for _ in 0..i {
                    self.skip(elem, false)?;
                }
                self.path.push(Step::Index(i));
                self.by_path(elem, tao && i + 1 == len, tokens)?
            }
            (
                Kind::DynArray {
                    elem,
                    max,
                    len_bits,
                },
                Some(token),
            ) => {
                let tail = tail_optimized(layout, elem, tao);
                if token == Token::Name("_len") {
                    if self.next_token(tokens)?.is_some() {
                        return Err(self.fail(ErrorKind::NoSuchPath));
                    }
                    let bits = if tail { 0 } else { len_bits };
                    return Ok(self.found(LeafKind::Len { bits, array: id }));
                }
                let Token::Index(i) = token else {
                    return Err(self.fail(ErrorKind::NoSuchPath));
                };
                self.leaves += 1;
                let n = if tail {
                    self.tail_count(elem, tao)? as u32
                } else {
                    self.prefixed_len(max, len_bits)?
                };
                if i >= n {
                    return Err(self.fail(ErrorKind::NoSuchPath));
                }
                for _ in 0..i {
                    self.skip(elem, false)?;
                }
                self.path.push(Step::Index(i));
                self.by_path(elem, !tail && tao && i + 1 == n, tokens)?
            }
            _ => return Err(self.fail(ErrorKind::NoSuchPath)),
        };
        self.depth -= 1;
        Ok(leaf)
    }
}
