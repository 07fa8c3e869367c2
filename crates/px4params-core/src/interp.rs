//! The one interpreter of the DroneCAN rules for whole values: a single loop over a type's
//! nodes that encodes and decodes as two passes of it.
//!
//! The loop is where the rules live for both directions: a union's tag selects one of its
//! variants (`tag < count`), a dynamic array's length is at most its maximum (`len <= max`)
//! and its prefix is `len_bits` wide, and tail array optimization (the last dynamic array of a
//! value whose elements are at least a byte drops its prefix and takes the remaining whole
//! bytes) applies where the value ends. The loop alone words the errors, with their field
//! path and bit offset. A [`Pass`] only moves bits and values: the encoding one from a
//! [`Source`] into bytes, the decoding one from bits into a [`Sink`]. Both are generic, so
//! that each call site gets a loop compiled for its source or sink (as small and as fast as a
//! dedicated encoder or decoder), and generic over the build's [`Plans`]: with
//! [`Plans::FLAT`], a flat leaf list's fixed-shape runs go through in one piece each (a plan
//! inside the loop that declines to it, field by field, wherever it cannot answer).

use crate::bits::{
    clear_after, from_stream, pair_word, put_scalar, read_scalar, to_stream, BitRead, BitReader,
    BitWriter,
};
use crate::error::{Error, ErrorKind, Path, Step};
use crate::layout::{Field, FlatItem, Kind, Layout, Node, NodeId, Role, Segment, Span};
use crate::plan::Plans;
use crate::rules::{
    scalar_bits, scalar_of, scalar_raw, tail_elements, tail_goes_on, tail_optimized, ArrayLen, At,
    DecodeOptions, EncodeOptions, LeafError, LeafKind, Sink, Source, MAX_DEPTH,
};
use crate::scalar::{self, Scalar, ScalarError};

/// The loop stopped: the pass keeps the fault, [`Run::at`] where it was met, and the path is
/// where the loop stands (results stay register-sized, and no error value is moved on the way:
/// the caller words the error where it returns it).
pub(crate) struct Stop;

/// Whether a part ends the value read and the value written: tail array optimization applies
/// to its last field. The two differ only inside an array whose length an edit changes.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) struct Tao(u8);

impl Tao {
    const NONE: Tao = Tao(0);
    const READ: u8 = 1;
    const WRITE: u8 = 2;

    /// For a whole value: `tao` for reading and writing alike.
    pub(crate) fn both(tao: bool) -> Tao {
        Tao(if tao { Self::READ | Self::WRITE } else { 0 })
    }
    fn read(self) -> bool {
        self.0 & Self::READ != 0
    }
    fn write(self) -> bool {
        self.0 & Self::WRITE != 0
    }
    /// For the elements of an array: kept where the array is not itself tail-optimized
    /// (`read`, `write`).
    fn ends(self, read: bool, write: bool) -> Tao {
        Tao(self.0 & ((u8::from(read) * Self::READ) | (u8::from(write) * Self::WRITE)))
    }
}

/// For a member: `tao` only for the `is_last` one.
#[inline(always)]
fn last(tao: Tao, is_last: bool) -> Tao {
    if is_last {
        tao
    } else {
        Tao::NONE
    }
}

/// Where a part of the value comes from, editing ([`Visiting`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Mode {
    /// Read from the data, visited, and written as the visit says.
    Data,
    /// Read (every bit of it) and passed over: an old union variant or array elements that
    /// are dropped, or the elements of a tail array counted.
    Skip,
    /// Given by the visit.
    Given,
    /// The default: zeros, versions, the first union variant, empty dynamic arrays.
    Default,
}

impl Mode {
    pub(crate) fn reads(self) -> bool {
        matches!(self, Mode::Data | Mode::Skip)
    }

    fn visits(self) -> bool {
        matches!(self, Mode::Data | Mode::Given)
    }
}

/// What a fixed-shape run of leaves came to in one piece ([`Pass::run`]).
pub(crate) enum Ran<E> {
    /// Every leaf of the run went through.
    Done,
    /// Not in one piece: the loop walks the run field by field.
    Declined,
    /// Too few leaves: field by field, which names the first one missing.
    Short,
    /// A fault at leaf `j` of the run (`None`: of the run as a whole).
    Failed(Option<u32>, ErrorKind<E>),
}

/// What primitive elements came to in one piece ([`Pass::elements`]): how many went through
/// (`None`: declined), or the fault (at element `i`, if at one).
pub(crate) type Elements<E> = Result<Option<u64>, (Option<u64>, ErrorKind<E>)>;

/// What encoding and decoding each do at the loop's steps: where bits and values come from
/// and go. Errors are returned as their kind; the loop words them.
pub(crate) trait Pass {
    /// The source's or sink's own error.
    type Error;
    /// Whether fixed-shape runs may go through in one piece ([`Pass::run`]), for a flat leaf
    /// list under plans that allow it; the loop then does not speak of structs.
    const RUNS: bool;
    /// Encoding: a field's path step is taken before the source is asked for the field.
    const ENCODES: bool;
    /// Editing ([`Visiting`]): a value read and written at once, whose new union tags and
    /// array lengths may differ from those read; a tail array's length counted ahead.
    const EDITS: bool = false;

    /// Keeps the loop's own fault (a method that stops keeps its own, so that results stay
    /// register-sized).
    fn set_fault(&mut self, kind: ErrorKind<Self::Error>);
    /// Bits read or written so far.
    fn pos(&self) -> usize;
    /// A primitive value.
    fn scalar(&mut self, kind: Kind, path: &Path) -> Result<(), Stop>;
    /// A `p_version` field the input has (decoding: a primitive like any other).
    fn version(&mut self, kind: Kind, version: u32, path: &Path) -> Result<(), Stop>;
    /// A primitive, a `p_version` field's where `version` is given.
    #[inline(always)]
    fn leaf(&mut self, kind: Kind, version: Option<u32>, path: &Path) -> Result<(), Stop> {
        match version {
            Some(v) => self.version(kind, v, path),
            None => self.scalar(kind, path),
        }
    }
    /// A `p_version` field the input leaves out (encoding only): the type's version.
    fn absent_version(&mut self, kind: Kind, version: u32) -> Result<(), Stop>;
    /// `bits` zero bits.
    fn void(&mut self, bits: u32) -> Result<(), Stop>;
    fn begin_struct(&mut self, count: u32) -> Result<(), Stop>;
    /// Field `index`; whether the input has it.
    fn field(&mut self, index: u32, name: &str) -> Result<bool, Stop>;
    fn end_field(&mut self);
    fn end_struct(&mut self, layout: &Layout<'_>, id: NodeId, used: usize) -> Result<(), Stop>;
    /// A union's tag, read or given (unchecked): the tag read (or given) and the one the
    /// value written selects (the same, except where an edit changes it).
    fn tag(
        &mut self,
        layout: &Layout<'_>,
        id: NodeId,
        bits: u8,
        path: &Path,
    ) -> Result<(u64, u64), Stop>;
    /// The tag, checked, selects variant `index` (`name`): written, or told to the sink.
    fn variant(&mut self, tag: u64, index: u32, name: &str, at: At<'_>) -> Result<(), Stop>;
    fn end_union(&mut self) -> Result<(), Stop>;
    /// A static array of `len` elements begins.
    fn fixed(&mut self, len: u32, at: At<'_>) -> Result<(), Stop>;
    /// A dynamic array's length, read (from a prefix of `bits`) or given; `None` for a tail
    /// array read, whose elements are counted as they come.
    fn length(&mut self, bits: u8, tail: bool) -> Result<Option<u64>, Stop>;
    /// The length of the value written (unchecked): the length read or given, except where
    /// an edit changes it.
    #[inline(always)]
    fn relength(&mut self, n: Option<u64>, _at: At<'_>) -> Result<Option<u64>, Stop> {
        Ok(n)
    }
    /// The length, checked, begins the array: its prefix written (`bits` wide: none for a
    /// tail array), or told to the sink.
    fn prefix(&mut self, n: Option<u64>, bits: u8, at: At<'_>) -> Result<(), Stop>;
    /// Whether element `i` is there: below the length, or for a tail array read, while
    /// whole bytes remain.
    fn more(&self, i: u64, n: Option<u64>) -> bool;
    fn element(&mut self, i: u64) -> Result<(), Stop>;
    fn end_element(&mut self);
    fn end_array(&mut self, n: u64) -> Result<(), Stop>;
    /// Editing ([`Pass::EDITS`]): where the part walked now comes from.
    #[inline(always)]
    fn mode(&self) -> Mode {
        Mode::Data
    }
    #[inline(always)]
    fn set_mode(&mut self, _mode: Mode) {}
    /// Editing: whether the part the loop comes to next may be passed over unread
    /// ([`Pass::pass_over`]).
    #[inline(always)]
    fn steered(&self) -> bool {
        false
    }
    /// Editing: passes over part `at` (of `node`) unread, when nothing is looked for in it.
    #[inline(always)]
    fn pass_over(&mut self, _node: &Node, _at: &PartAt<'_>) -> bool {
        false
    }
    /// Editing: where reading stands, in bits, and how many are left.
    #[inline(always)]
    fn read_pos(&self) -> usize {
        0
    }
    #[inline(always)]
    fn read_left(&self) -> usize {
        0
    }
    /// Editing: reading goes on from bit `pos`.
    #[inline(always)]
    fn seek_read(&mut self, _pos: usize) {}
    /// A plan: a fixed-shape run of `leaves` leaves (`items`, `bits` long) in one piece.
    fn run(&mut self, items: &[FlatItem], leaves: u32, bits: u32) -> Ran<Self::Error>;
    /// A plan: primitive elements of `kind` in one piece (`n`: the length, `None` for a tail
    /// array read, at most `max`); how many went through, or the fault (at element `i`).
    fn elements(&mut self, kind: Kind, n: Option<u64>, max: u32) -> Elements<Self::Error>;
}

/// The loop: a pass walked over a type.
pub(crate) struct Run<'l, P: Pass> {
    layout: &'l Layout<'l>,
    pub(crate) pass: P,
    /// The field path where the loop stands: where it stopped at a fault, the error's.
    pub(crate) path: Path,
    depth: usize,
    /// Where the loop stopped at a fault met where a node starts (a union's tag or an array's
    /// length); `None` for any other: met where the loop stands, which it does not leave once
    /// stopped. (The fault itself is the pass's.)
    pub(crate) at: Option<usize>,
}

impl<'l, P: Pass> Run<'l, P> {
    pub(crate) fn new(layout: &'l Layout<'l>, pass: P) -> Self {
        Run {
            layout,
            pass,
            path: Path::default(),
            depth: 0,
            at: None,
        }
    }

    /// Stops at a fault where the loop stands, here on the path. (Inline, so that the kind is
    /// made where the pass keeps it: no error value is moved.)
    #[inline(always)]
    fn fail(&mut self, kind: ErrorKind<P::Error>) -> Stop {
        self.pass.set_fault(kind);
        Stop
    }

    /// [`ErrorKind::TooDeep`], where the loop stands.
    #[cold]
    #[inline(never)]
    fn too_deep(&mut self) -> Stop {
        self.fail(ErrorKind::TooDeep)
    }

    /// A union's tag `n` that selects none of its `bound` variants (`tag`), or an array
    /// length `n` over its maximum `bound`, at `bit_offset` (`None`: where the loop stands).
    #[cold]
    #[inline(never)]
    fn over(&mut self, bit_offset: Option<usize>, tag: bool, n: u64, bound: u32) -> Stop {
        let kind = match tag {
            true => ErrorKind::BadUnionTag {
                tag: n,
                variants: bound,
            },
            false => ErrorKind::ArrayTooLong { len: n, max: bound },
        };
        self.at = bit_offset;
        self.fail(kind)
    }

    /// A pass's result: where it stopped, the loop stops there (the fault it keeps is met where
    /// the loop stands, [`Run::at`] `None`).
    #[inline(always)]
    fn ok<T>(&mut self, r: Result<T, Stop>) -> Result<T, Stop> {
        r
    }

    /// A primitive (a field, an element or a variant), one past the nesting bound refused.
    #[inline]
    fn scalar(&mut self, kind: Kind) -> Result<(), Stop> {
        if self.depth >= MAX_DEPTH {
            return Err(self.too_deep());
        }
        let r = self.pass.scalar(kind, &self.path);
        self.ok(r)
    }

    /// Walks node `id`; `tao`: it ends the value (tail array optimization applies to it).
    #[inline(always)]
    pub(crate) fn node(&mut self, id: NodeId, tao: Tao) -> Result<(), Stop> {
        self.part(id, tao, None, None)
    }

    /// Walks node `id` (`version`: the type's, where it is a `p_version` field) one `step`
    /// down the path (none for padding, the root, and the encoding and decoding passes, which
    /// take their steps themselves).
    fn part(
        &mut self,
        id: NodeId,
        tao: Tao,
        version: Option<u32>,
        step: Option<Step>,
    ) -> Result<(), Stop> {
        if let Some(step) = step {
            self.path.push(step);
        }
        let layout = self.layout;
        // A node or field the layout lacks (a malformed one, such as a corrupt firmware
        // table) is refused as the layout that nests too deeply is, not a panic: the walk
        // then links none.
        let Some(node) = layout.nodes.get(id as usize) else {
            return Err(self.too_deep());
        };
        if P::EDITS && self.pass.steered() {
            let at = PartAt {
                node: id,
                step,
                depth: self.depth,
                path: &self.path,
            };
            if self.pass.pass_over(node, &at) {
                if step.is_some() {
                    self.path.pop();
                }
                return Ok(());
            }
        }
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.too_deep());
        }
        let at_pos = self.pass.pos();
        // An array's elements: walked after the match, from one place in the code.
        let mut array = None;
        match node.kind {
            kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool) => {
                let r = self.pass.leaf(kind, version, &self.path);
                self.ok(r)?;
            }
            Kind::Void { bits } => {
                let r = self.pass.void(bits.into());
                self.ok(r)?;
            }
            Kind::Struct { first, count } => {
                if P::RUNS {
                    self.runs(id, first + count, tao)?;
                } else {
                    let r = self.pass.begin_struct(count);
                    self.ok(r)?;
                    let mut used = 0;
                    for i in first..first + count {
                        used += self.field(i, last(tao, i + 1 == first + count))?;
                    }
                    let r = self.pass.end_struct(layout, id, used);
                    self.ok(r)?;
                }
            }
            Kind::Union {
                first,
                count,
                tag_bits,
            } => {
                let r = self.pass.tag(layout, id, tag_bits, &self.path);
                let (read, tag) = self.ok(r)?;
                // The rule: the tag selects one of the variants.
                let limit = u64::from(count);
                self.counts(true, Some(read), Some(tag), limit, at_pos)?;
                let index = first + tag as u32;
                let Some(&variant) = layout.fields.get(index as usize) else {
                    return Err(self.too_deep());
                };
                let at = At {
                    path: &self.path,
                    bit_offset: at_pos,
                    kind: LeafKind::Tag {
                        bits: tag_bits,
                        union: id,
                    },
                };
                let r = self.pass.variant(tag, index, layout.name(&variant), at);
                self.ok(r)?;
                if P::EDITS {
                    let mode = self.pass.mode();
                    if read != tag {
                        // A new tag: the old variant is passed over, the new one written with
                        // its default value.
                        let old = first + read as u32;
                        self.pass.set_mode(Mode::Skip);
                        let Some(&Field { node, .. }) = layout.fields.get(old as usize) else {
                            return Err(self.too_deep());
                        };
                        self.part(node, tao, None, Some(Step::Field(old)))?;
                        self.pass.set_mode(Mode::Default);
                    }
                    self.part(variant.node, tao, None, Some(Step::Field(index)))?;
                    self.pass.set_mode(mode);
                } else {
                    self.path.push(Step::Field(index));
                    self.node(variant.node, tao)?;
                    self.path.pop();
                }
                let r = self.pass.end_union();
                self.ok(r)?;
            }
            Kind::Array { elem, len } => {
                let at = At {
                    path: &self.path,
                    bit_offset: at_pos,
                    kind: LeafKind::Len { bits: 0, array: id },
                };
                let r = self.pass.fixed(len, at);
                self.ok(r)?;
                if P::EDITS {
                    for i in 0..len {
                        self.part(elem, last(tao, i + 1 == len), None, Some(Step::Index(i)))?;
                    }
                } else {
                    array = Some((elem, Some(len.into()), len, tao));
                }
            }
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => {
                // The rule: the last array of a value, of elements of a byte or more, has no
                // prefix and takes the remaining whole bytes (in the value read, and in the
                // value written, which differ in their last element when a length changes).
                // (Whether the elements allow it, asked once for both.)
                let tail_elements = tail_optimized(layout, elem, true);
                let rtail = tao.read() && tail_elements;
                let wtail = match P::EDITS {
                    true => tao.write() && tail_elements,
                    false => rtail,
                };
                let r = self.pass.length(len_bits, rtail);
                let mut n = self.ok(r)?;
                if P::EDITS && n.is_none() {
                    // A tail array read where its length is a leaf: its elements counted ahead.
                    n = Some(self.count_tail(elem, max)?);
                }
                let tail = match P::EDITS && !self.pass.mode().reads() {
                    true => wtail,
                    false => rtail,
                };
                let kind = LeafKind::Len {
                    bits: if tail { 0 } else { len_bits },
                    array: id,
                };
                let at = At {
                    path: &self.path,
                    bit_offset: at_pos,
                    kind,
                };
                let r = self.pass.relength(n, at);
                let new = self.ok(r)?;
                // The rule: at most `max` elements.
                let limit = u64::from(max) + 1;
                self.counts(false, n, new, limit, at_pos)?;
                let at = At {
                    path: &self.path,
                    bit_offset: at_pos,
                    kind,
                };
                let r = self.pass.prefix(new, if wtail { 0 } else { len_bits }, at);
                self.ok(r)?;
                if P::EDITS {
                    // Both are checked against the maximum: 32 bits hold them.
                    let (old, new) = (n.unwrap_or(0) as u32, new.unwrap_or(0) as u32);
                    self.resized(elem, old, new, tao.ends(!rtail, !wtail))?;
                } else {
                    array = Some((elem, n, max, if tail { Tao::NONE } else { tao }));
                }
            }
        }
        if let Some((elem, n, max, tao)) = array {
            self.elements(elem, n, max, tao)?;
        }
        self.depth -= 1;
        if step.is_some() {
            self.path.pop();
        }
        Ok(())
    }

    /// The rules on a union's tag (`tag`) and a dynamic array's length: the one read (or
    /// given), where the node starts, and then, editing, the one written, where the loop
    /// stands, are below `limit` (the number of variants, or the maximum length plus one).
    #[inline(always)]
    fn counts(
        &mut self,
        tag: bool,
        read: Option<u64>,
        new: Option<u64>,
        limit: u64,
        at_pos: usize,
    ) -> Result<(), Stop> {
        let bound = if tag { limit } else { limit - 1 } as u32;
        if let Some(n) = read.filter(|&n| n >= limit) {
            return Err(self.over(Some(at_pos), tag, n, bound));
        }
        if let Some(n) = new.filter(|&n| P::EDITS && n >= limit) {
            return Err(self.over(None, tag, n, bound));
        }
        Ok(())
    }

    #[inline(always)]
    /// The elements of an array (`n`: its length, `None` for a tail array read: as many as
    /// whole bytes remain for, at most `max`).
    fn elements(&mut self, elem: NodeId, n: Option<u64>, max: u32, tao: Tao) -> Result<(), Stop> {
        let mut i = 0;
        if !self.pass.more(i, n) {
            // Empty (a common case: an empty read, an unnamed model): nothing to set up.
            let r = self.pass.end_array(i);
            return self.ok(r);
        }
        let kind = self.layout.node(elem).kind;
        let scalar = is_scalar(kind);
        if scalar && self.depth < MAX_DEPTH {
            match self.pass.elements(kind, n, max) {
                Ok(Some(done)) => i = done,
                Ok(None) => {}
                Err((at, fault)) => {
                    if let Some(at) = at {
                        self.path.push(Step::Index(at as u32));
                    }
                    return Err(self.fail(fault));
                }
            }
        }
        while self.pass.more(i, n) {
            // Counted elements stop at the maximum (given lengths are checked already).
            if i == u64::from(max) {
                return Err(self.over(None, false, i + 1, max));
            }
            self.path.push(Step::Index(i as u32));
            let r = self.pass.element(i);
            self.ok(r)?;
            if scalar {
                self.scalar(kind)?;
            } else {
                self.node(elem, last(tao, Some(i + 1) == n))?;
            }
            self.pass.end_element();
            self.path.pop();
            i += 1;
        }
        let r = self.pass.end_array(i);
        self.ok(r)
    }

    /// Field `index` of a struct; 1 when the input had it (0 for padding and filled-in
    /// versions), so that the struct can tell unknown input fields.
    fn field(&mut self, index: u32, tao: Tao) -> Result<usize, Stop> {
        let layout = self.layout;
        let Some(&field) = layout.fields.get(index as usize) else {
            return Err(self.too_deep());
        };
        if P::EDITS {
            // Every field is there: a part like any other, a `p_version` one with its version.
            let version = match field.role {
                Role::Version(v) => Some(v),
                _ => None,
            };
            let step = (field.role != Role::Padding).then_some(Step::Field(index));
            self.part(field.node, tao, version, step)?;
            return Ok(1);
        }
        if field.role == Role::Padding {
            self.node(field.node, tao)?;
            return Ok(0);
        }
        if P::ENCODES {
            self.path.push(Step::Field(index));
        }
        let r = self.pass.field(index, layout.name(&field));
        let present = self.ok(r)?;
        if !P::ENCODES {
            self.path.push(Step::Field(index));
        }
        let kind = layout.node(field.node).kind;
        // Decoding reads a `p_version` as any other primitive.
        let role = if P::ENCODES || P::EDITS {
            field.role
        } else {
            Role::Data
        };
        let used = match (present, role) {
            (true, role) => {
                if !is_scalar(kind) {
                    self.node(field.node, tao)?;
                } else {
                    if self.depth >= MAX_DEPTH {
                        return Err(self.too_deep());
                    }
                    let r = match role {
                        Role::Version(v) => self.pass.version(kind, v, &self.path),
                        _ => self.pass.scalar(kind, &self.path),
                    };
                    self.ok(r)?;
                }
                self.pass.end_field();
                1
            }
            (false, Role::Version(v)) => {
                let r = self.pass.absent_version(kind, v);
                self.ok(r)?;
                0
            }
            (false, _) => return Err(self.fail(ErrorKind::MissingField)),
        };
        self.path.pop();
        Ok(used)
    }

    /// Editing, a dynamic array's elements: the first `new` of those read (`old`) written,
    /// the rest read and passed over, and default ones appended (`tao`: for the elements of
    /// the array, the last one read and the last one written).
    #[inline(always)]
    fn resized(&mut self, elem: NodeId, old: u32, new: u32, tao: Tao) -> Result<(), Stop> {
        let mode = self.pass.mode();
        for i in 0..old.max(new) {
            let part = match mode {
                _ if i >= new => Mode::Skip,
                Mode::Data if i >= old => Mode::Default,
                mode => mode,
            };
            self.pass.set_mode(part);
            let ends = tao.ends(i + 1 == old, i + 1 == new);
            self.part(elem, ends, None, Some(Step::Index(i)))?;
        }
        self.pass.set_mode(mode);
        Ok(())
    }

    /// Editing, the number of elements of a tail-optimized array from here: as many as there
    /// are whole bytes left for. Elements of variable shape are read ahead (every bit, so that
    /// a fault is found where reading them in order finds it), fixed-shape ones counted by
    /// their length; reading then starts again at the first one.
    fn count_tail(&mut self, elem: NodeId, max: u32) -> Result<u64, Stop> {
        let (start, mode) = (self.pass.read_pos(), self.pass.mode());
        let mut n = 0;
        while tail_goes_on(self.pass.read_left()) {
            if n == max {
                return Err(self.over(None, false, u64::from(n) + 1, max));
            }
            // (An element node the layout lacks is refused where it is walked.)
            let fixed = self.layout.nodes.get(elem as usize);
            if let Some(node) = fixed.filter(|node| node.fixed_leaves().is_some()) {
                // Any fault in it is found when it is read.
                self.pass
                    .seek_read(self.pass.read_pos() + node.min_bits as usize);
            } else {
                self.pass.set_mode(Mode::Skip);
                self.part(elem, Tao::NONE, None, Some(Step::Index(n)))?;
                self.pass.set_mode(mode);
            }
            n += 1;
        }
        self.pass.seek_read(start);
        Ok(n.into())
    }

    /// A struct's fields by its segments: fixed-shape runs in one piece where the pass takes
    /// them, other fields one by one (`end`: one past its last field).
    fn runs(&mut self, id: NodeId, end: u32, tao: Tao) -> Result<(), Stop> {
        let layout = self.layout;
        for segment in layout.node(id).segments.of(layout.segments) {
            match *segment {
                Segment::Flat {
                    fields,
                    items,
                    leaves,
                    bits,
                    height,
                } => {
                    // Deeper than the loop follows: field by field, which refuses the type.
                    let ran = if self.depth + height as usize > MAX_DEPTH {
                        Ran::Declined
                    } else {
                        self.pass.run(items.of(layout.flat), leaves, bits)
                    };
                    match ran {
                        Ran::Done => {}
                        Ran::Declined => {
                            for i in fields.first..fields.first + fields.count {
                                self.field(i, last(tao, i + 1 == end))?;
                            }
                        }
                        Ran::Short => return Err(self.missing_leaf(fields, end, tao)),
                        Ran::Failed(leaf, kind) => {
                            if let Some(leaf) = leaf {
                                push_flat_path(layout, fields, leaf, &mut self.path);
                            }
                            return Err(self.fail(kind));
                        }
                    }
                }
                Segment::Field(i) => {
                    self.field(i, last(tao, i + 1 == end))?;
                }
            }
        }
        Ok(())
    }

    /// A run the input has too few leaves for: its fields one by one, to fail at the first
    /// leaf missing.
    #[cold]
    #[inline(never)]
    fn missing_leaf(&mut self, fields: Span, end: u32, tao: Tao) -> Stop {
        for i in fields.first..fields.first + fields.count {
            if let Err(stop) = self.field(i, last(tao, i + 1 == end)) {
                return stop;
            }
        }
        // The leaves were there after all: the input is inconsistent.
        self.fail(ErrorKind::MissingField)
    }
}

/// Extends `path` to leaf `leaf` of a run of fixed-shape `fields`.
pub(crate) fn push_flat_path(layout: &Layout<'_>, fields: Span, leaf: u32, path: &mut Path) {
    let mut j = leaf;
    for index in fields.first..fields.first + fields.count {
        let node = layout.fields[index as usize].node;
        let n = layout.node(node).fixed_leaves().unwrap_or(0);
        if j < n {
            path.push(Step::Field(index));
            push_fixed_path(layout, node, j, path);
            return;
        }
        j -= n;
    }
}

fn push_fixed_path(layout: &Layout<'_>, id: NodeId, leaf: u32, path: &mut Path) {
    match layout.node(id).kind {
        Kind::Struct { first, count } => push_flat_path(layout, Span { first, count }, leaf, path),
        Kind::Array { elem, .. } => {
            let n = layout.node(elem).fixed_leaves().unwrap_or(1).max(1);
            path.push(Step::Index(leaf / n));
            push_fixed_path(layout, elem, leaf % n, path);
        }
        _ => {}
    }
}

#[inline]
pub(crate) fn is_scalar(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool
    )
}

/// Encodes the value of type `root` from `source` into `out` with the plans `P`; returns the
/// length in bytes.
#[inline(never)]
pub(crate) fn encode<P: Plans, S: Source>(
    layout: &Layout<'_>,
    root: NodeId,
    source: &mut S,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<S::Error>> {
    let pass = Encode::<P, S> {
        out: BitWriter::new(out),
        source,
        saturate: options.saturate,
        keep_versions: options.keep_versions,
        fault: None,
        plans: core::marker::PhantomData,
    };
    let mut run = Run::new(layout, pass);
    if run.node(root, Tao::both(options.tao)).is_err() {
        let at = run.at.unwrap_or(run.pass.out.bit_pos());
        return Err(host_error(run.pass.fault.take(), at, run.path));
    }
    let pos = run.pass.out.bit_pos();
    run.pass.out.finish().map_err(|needed| Error {
        kind: ErrorKind::BufferTooSmall { needed },
        bit_offset: pos,
        path: Path::default(),
    })
}

/// Decodes a value of type `root` from `data` into `sink` with the plans `P`; returns the
/// bits used.
#[inline(never)]
pub(crate) fn decode<P: Plans, R: BitRead + ?Sized, K: Sink>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    sink: &mut K,
    options: DecodeOptions,
) -> Result<usize, Error<K::Error>> {
    let pass = Decode::<P, R, K> {
        reader: data.reader(0),
        bit_len: data.bit_len(),
        sink,
        fault: None,
        plans: core::marker::PhantomData,
    };
    let mut run = Run::new(layout, pass);
    if run.node(root, Tao::both(options.tao)).is_err() {
        let at = run.at.unwrap_or(run.pass.reader.position());
        return Err(host_error(run.pass.fault.take(), at, run.path));
    }
    let end = run.pass.reader.position();
    let used = end.div_ceil(8);
    let len = data.bit_len() / 8;
    if !options.allow_trailing && len > used {
        return Err(Error {
            kind: ErrorKind::TrailingBytes { used, len },
            bit_offset: end,
            path: Path::default(),
        });
    }
    Ok(end)
}

/// The error an encoding or decoding loop stopped at: its pass's fault, where the loop met it
/// and its path. (Every stop of these passes is a fault.)
#[cold]
fn host_error<E>(kind: Option<ErrorKind<E>>, bit_offset: usize, path: Path) -> Error<E> {
    Error {
        kind: kind.unwrap_or(ErrorKind::TooDeep),
        bit_offset,
        path,
    }
}

/// The encoding pass: values from a [`Source`], bits into a [`BitWriter`].
struct Encode<'o, P, S: Source> {
    out: BitWriter<'o>,
    source: &'o mut S,
    saturate: bool,
    keep_versions: bool,
    fault: Option<ErrorKind<S::Error>>,
    plans: core::marker::PhantomData<P>,
}

impl<P: Plans, S: Source> Encode<'_, P, S> {
    #[cold]
    #[inline(never)]
    fn refuse(&mut self, kind: ErrorKind<S::Error>) -> Stop {
        self.fault = Some(kind);
        Stop
    }

    // One out-of-line copy in firmware builds: every kind of node writes.
    #[cfg_attr(not(feature = "compact"), inline(always))]
    #[cfg_attr(feature = "compact", inline(never))]
    fn write(&mut self, raw: u64, bits: u32) -> Result<(), Stop> {
        self.out
            .write(to_stream(raw, bits), bits)
            .map_err(|needed| self.refuse(ErrorKind::BufferTooSmall { needed }))
    }

    #[inline(never)]
    fn put(&mut self, kind: Kind, value: Scalar) -> Result<(), Stop> {
        let raw = fast_raw::<P>(kind, value, self.saturate)
            .map_err(|e| self.refuse(ErrorKind::Scalar(e)))?;
        self.write(raw, scalar_bits(kind))
    }
}

impl<P: Plans, S: Source> Pass for Encode<'_, P, S> {
    type Error = S::Error;
    const RUNS: bool = S::FLAT && P::FLAT;
    const ENCODES: bool = true;

    #[inline(always)]
    fn set_fault(&mut self, kind: ErrorKind<S::Error>) {
        self.fault = Some(kind);
    }

    #[inline(always)]
    fn pos(&self) -> usize {
        self.out.bit_pos()
    }
    #[inline]
    fn scalar(&mut self, kind: Kind, _: &Path) -> Result<(), Stop> {
        let v = self
            .source
            .scalar(kind)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))?;
        self.put(kind, v)
    }
    fn version(&mut self, kind: Kind, version: u32, _: &Path) -> Result<(), Stop> {
        let given = self
            .source
            .scalar(kind)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))?;
        if self.keep_versions {
            return self.put(kind, given);
        }
        if !scalar::same_integer(given, version) {
            return Err(self.refuse(ErrorKind::VersionMismatch {
                given,
                expected: version,
            }));
        }
        self.put(kind, Scalar::Uint(version.into()))
    }
    fn absent_version(&mut self, kind: Kind, version: u32) -> Result<(), Stop> {
        self.put(kind, Scalar::Uint(version.into()))
    }
    fn void(&mut self, bits: u32) -> Result<(), Stop> {
        self.write(0, bits)
    }
    fn begin_struct(&mut self, _count: u32) -> Result<(), Stop> {
        self.source
            .begin_struct()
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    #[inline]
    fn field(&mut self, index: u32, name: &str) -> Result<bool, Stop> {
        self.source
            .field(index, name)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    #[inline]
    fn end_field(&mut self) {
        self.source.end_field();
    }
    fn end_struct(&mut self, layout: &Layout<'_>, id: NodeId, used: usize) -> Result<(), Stop> {
        let r = self.source.end_struct(layout, layout.members(id), used);
        r.map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    fn tag(
        &mut self,
        layout: &Layout<'_>,
        id: NodeId,
        _: u8,
        _: &Path,
    ) -> Result<(u64, u64), Stop> {
        let tag = self.source.begin_union(layout, layout.members(id));
        tag.map(|t| (u64::from(t), u64::from(t)))
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    fn variant(&mut self, tag: u64, _index: u32, _name: &str, at: At<'_>) -> Result<(), Stop> {
        match at.kind {
            LeafKind::Tag { bits, .. } => self.write(tag, bits.into()),
            _ => Ok(()),
        }
    }
    fn end_union(&mut self) -> Result<(), Stop> {
        self.source.end_union();
        Ok(())
    }
    fn fixed(&mut self, len: u32, _at: At<'_>) -> Result<(), Stop> {
        let n = self
            .source
            .begin_array(Some(len))
            .map_err(|e| self.refuse(ErrorKind::Value(e)))?;
        if n != len as usize {
            return Err(self.refuse(ErrorKind::WrongArrayLength {
                len: n as u64,
                expected: len,
            }));
        }
        Ok(())
    }
    fn length(&mut self, _bits: u8, _tail: bool) -> Result<Option<u64>, Stop> {
        let n = self
            .source
            .begin_array(None)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))?;
        Ok(Some(n as u64))
    }
    fn prefix(&mut self, n: Option<u64>, bits: u8, _at: At<'_>) -> Result<(), Stop> {
        match n {
            Some(n) if bits > 0 => self.write(n, bits.into()),
            _ => Ok(()),
        }
    }
    #[inline(always)]
    fn more(&self, i: u64, n: Option<u64>) -> bool {
        Some(i) < n
    }
    #[inline]
    fn element(&mut self, i: u64) -> Result<(), Stop> {
        self.source
            .element(i as usize)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    #[inline]
    fn end_element(&mut self) {
        self.source.end_element();
    }
    fn end_array(&mut self, _n: u64) -> Result<(), Stop> {
        self.source.end_array();
        Ok(())
    }
    fn run(&mut self, items: &[FlatItem], leaves: u32, _bits: u32) -> Ran<S::Error> {
        let (saturate, keep) = (self.saturate, self.keep_versions);
        match self.source.leaf_run(leaves as usize) {
            Some(Ok(run)) => match encode_items::<P>(&mut self.out, items, run, saturate, keep) {
                Ok(()) => Ran::Done,
                Err((leaf, fail)) => Ran::Failed(Some(leaf), fail.into_kind()),
            },
            // Not enough leaves (nothing was taken).
            Some(Err(_)) => Ran::Short,
            None => Ran::Declined,
        }
    }
    fn elements(&mut self, kind: Kind, n: Option<u64>, _max: u32) -> Elements<S::Error> {
        if !(S::FLAT && P::FLAT) {
            return Ok(None);
        }
        let n = n.unwrap_or(0);
        let saturate = self.saturate;
        match self.source.leaf_run(n as usize) {
            Some(Ok(run)) => match encode_scalars::<P>(&mut self.out, kind, run, saturate) {
                Ok(()) => Ok(Some(n)),
                Err((i, fail)) => Err((Some(i as u64), fail.into_kind())),
            },
            // Not enough leaves: element by element names the first one missing.
            Some(Err(_)) | None => Ok(None),
        }
    }
}

/// The decoding pass: bits from a reader, values into a [`Sink`].
struct Decode<'d, P, R: BitRead + ?Sized + 'd, K: Sink> {
    /// Where the pass stands: it reads forwards only.
    reader: R::Reader<'d>,
    bit_len: usize,
    sink: &'d mut K,
    fault: Option<ErrorKind<K::Error>>,
    plans: core::marker::PhantomData<P>,
}

impl<'d, P: Plans, R: BitRead + ?Sized + 'd, K: Sink> Decode<'d, P, R, K> {
    #[cold]
    #[inline(never)]
    fn refuse(&mut self, kind: ErrorKind<K::Error>) -> Stop {
        self.fault = Some(kind);
        Stop
    }

    /// Bits left to read.
    #[inline(always)]
    fn remaining(&self) -> usize {
        self.bit_len.saturating_sub(self.reader.position())
    }

    #[inline]
    fn read(&mut self, bits: u32) -> Result<u64, Stop> {
        let needed = self.reader.position() + bits as usize;
        if needed > self.bit_len {
            return Err(self.refuse(ErrorKind::Truncated {
                needed_bits: needed,
                available_bits: self.bit_len,
            }));
        }
        let stream = self.reader.read(bits);
        Ok(from_stream(stream, bits))
    }
}

impl<'d, P: Plans, R: BitRead + ?Sized + 'd, K: Sink> Pass for Decode<'d, P, R, K> {
    type Error = K::Error;
    const RUNS: bool = K::FLAT && P::FLAT;
    const ENCODES: bool = false;

    #[inline(always)]
    fn set_fault(&mut self, kind: ErrorKind<K::Error>) {
        self.fault = Some(kind);
    }

    #[inline(always)]
    fn pos(&self) -> usize {
        self.reader.position()
    }
    #[inline]
    fn scalar(&mut self, kind: Kind, path: &Path) -> Result<(), Stop> {
        let at_pos = self.reader.position();
        let value = scalar_of(kind, self.read(scalar_bits(kind))?);
        let at = At {
            path,
            bit_offset: at_pos,
            kind: LeafKind::Scalar(kind),
        };
        self.sink
            .scalar(value, at)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    fn version(&mut self, kind: Kind, _: u32, path: &Path) -> Result<(), Stop> {
        self.scalar(kind, path)
    }
    fn absent_version(&mut self, _: Kind, _: u32) -> Result<(), Stop> {
        Ok(())
    }
    fn void(&mut self, bits: u32) -> Result<(), Stop> {
        self.read(bits).map(|_| ())
    }
    fn begin_struct(&mut self, count: u32) -> Result<(), Stop> {
        self.sink
            .begin_struct(count as usize)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    #[inline]
    fn field(&mut self, index: u32, name: &str) -> Result<bool, Stop> {
        self.sink
            .field(index, name)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))?;
        Ok(true)
    }
    #[inline]
    fn end_field(&mut self) {}
    fn end_struct(&mut self, _: &Layout<'_>, _: NodeId, _: usize) -> Result<(), Stop> {
        self.sink
            .end_struct()
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    fn tag(&mut self, _: &Layout<'_>, _: NodeId, bits: u8, _: &Path) -> Result<(u64, u64), Stop> {
        self.read(bits.into()).map(|t| (t, t))
    }
    fn variant(&mut self, tag: u64, index: u32, name: &str, at: At<'_>) -> Result<(), Stop> {
        let r = self.sink.begin_union(tag as u32, index, name, at);
        r.map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    fn end_union(&mut self) -> Result<(), Stop> {
        self.sink
            .end_union()
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    fn fixed(&mut self, len: u32, at: At<'_>) -> Result<(), Stop> {
        let r = self.sink.begin_array(ArrayLen::Fixed(len as usize), at);
        r.map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    fn length(&mut self, bits: u8, tail: bool) -> Result<Option<u64>, Stop> {
        if tail {
            return Ok(None);
        }
        self.read(bits.into()).map(Some)
    }
    fn prefix(&mut self, n: Option<u64>, _bits: u8, at: At<'_>) -> Result<(), Stop> {
        let len = match n {
            Some(n) => ArrayLen::Prefixed(n as usize),
            None => ArrayLen::Tail,
        };
        self.sink
            .begin_array(len, at)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    #[inline(always)]
    fn more(&self, i: u64, n: Option<u64>) -> bool {
        match n {
            Some(n) => i < n,
            None => tail_goes_on(self.remaining()),
        }
    }
    #[inline]
    fn element(&mut self, _i: u64) -> Result<(), Stop> {
        Ok(())
    }
    #[inline]
    fn end_element(&mut self) {}
    fn end_array(&mut self, n: u64) -> Result<(), Stop> {
        self.sink
            .end_array(n as usize)
            .map_err(|e| self.refuse(ErrorKind::Value(e)))
    }
    fn run(&mut self, items: &[FlatItem], leaves: u32, bits: u32) -> Ran<K::Error> {
        // Enough data for the whole run means no read inside it can fail; if not, the
        // field-by-field walk finds where exactly it ends.
        if bits as usize > self.remaining() {
            return Ran::Declined;
        }
        match self.sink.leaf_slots(leaves as usize) {
            Some(Ok(slots)) => {
                // A local copy of the reader stays in registers for the run.
                let mut reader = self.reader;
                decode_items(&mut reader, items, slots);
                self.reader = reader;
                Ran::Done
            }
            // No room: field by field, which names the first leaf that finds none.
            Some(Err(_)) | None => Ran::Declined,
        }
    }
    fn elements(&mut self, kind: Kind, n: Option<u64>, max: u32) -> Elements<K::Error> {
        if !(K::FLAT && P::FLAT) {
            return Ok(None);
        }
        let bits = scalar_bits(kind) as usize;
        let n = match n {
            Some(n) => n as usize,
            // A tail array (one whose last element runs past the end is refused below).
            None if tail_goes_on(self.remaining()) => tail_elements(self.remaining(), bits),
            None => return Ok(None),
        };
        if n > max as usize || bits.saturating_mul(n) > self.remaining() {
            return Ok(None);
        }
        let mut reader = self.reader;
        match self.sink.leaf_slots(n) {
            Some(Ok(slots)) => {
                if matches!(kind, Kind::Uint { bits: 8, .. }) && reader.position() % 8 == 0 {
                    // Byte strings on a byte boundary: plain bytes, a chunk at a time.
                    let mut chunk = [0u8; 32];
                    for group in slots.chunks_mut(chunk.len()) {
                        let bytes = &mut chunk[..group.len()];
                        reader.read_bytes(bytes);
                        for (slot, &b) in group.iter_mut().zip(bytes.iter()) {
                            *slot = Scalar::Uint(b.into());
                        }
                    }
                } else {
                    let bits = bits as u32;
                    for slot in slots.iter_mut() {
                        *slot = scalar_of(kind, from_stream(reader.read(bits), bits));
                    }
                }
                self.reader = reader;
                Ok(Some(n as u64))
            }
            // No room: element by element, which names the first one that finds none.
            Some(Err(_)) | None => Ok(None),
        }
    }
}

/// Decodes the flat items of a fixed-shape run into `slots`. The caller has checked that the
/// data holds the whole run.
#[inline]
fn decode_items<B: BitReader>(reader: &mut B, items: &[FlatItem], slots: &mut [Scalar]) {
    let mut slots = slots.iter_mut();
    for item in items {
        match *item {
            FlatItem::Pad(bits) => reader.skip(usize::from(bits)),
            FlatItem::Leaf(kind) | FlatItem::Version(kind, _) => {
                let bits = scalar_bits(kind);
                let raw = if bits == 0 { 0 } else { reader.read(bits) };
                if let Some(slot) = slots.next() {
                    *slot = scalar_of(kind, from_stream(raw, bits));
                }
            }
        }
    }
}

/// Why a flat run could not be encoded, without the source's error type.
#[derive(Clone, Copy)]
enum FlatFail {
    Scalar(scalar::ScalarError),
    Version { given: Scalar, expected: u32 },
    Buffer(usize),
}

impl FlatFail {
    fn into_kind<E>(self) -> ErrorKind<E> {
        match self {
            Self::Scalar(e) => ErrorKind::Scalar(e),
            Self::Version { given, expected } => ErrorKind::VersionMismatch { given, expected },
            Self::Buffer(needed) => ErrorKind::BufferTooSmall { needed },
        }
    }
}

/// Encodes the flat items of a fixed-shape run from its leaves; on failure, the number of the
/// leaf within the run.
#[inline]
fn encode_items<P: Plans>(
    out: &mut BitWriter<'_>,
    items: &[FlatItem],
    run: &[Scalar],
    saturate: bool,
    keep_versions: bool,
) -> Result<(), (u32, FlatFail)> {
    let mut j = 0usize;
    let mut items = items.iter();
    let mut leaves = run.iter().copied();
    let written = out.write_run(items.len(), |_| {
        let Some(&item) = items.next() else {
            return Ok((0, 0));
        };
        let (raw, bits) = match item {
            FlatItem::Pad(bits) => return Ok((0, u32::from(bits))),
            FlatItem::Leaf(kind) => {
                let v = leaves.next().unwrap_or(Scalar::Uint(0));
                (
                    fast_raw::<P>(kind, v, saturate).map_err(FlatFail::Scalar)?,
                    scalar_bits(kind),
                )
            }
            FlatItem::Version(kind, version) => {
                let v = leaves.next().unwrap_or(Scalar::Uint(0));
                let raw = if keep_versions {
                    fast_raw::<P>(kind, v, saturate).map_err(FlatFail::Scalar)?
                } else if scalar::same_integer(v, version) {
                    u64::from(version)
                } else {
                    return Err(FlatFail::Version {
                        given: v,
                        expected: version,
                    });
                };
                (raw, scalar_bits(kind))
            }
        };
        j += 1;
        Ok((to_stream(raw, bits), bits))
    });
    written.map_err(|e| (j as u32, e.unwrap_or_else(FlatFail::Buffer)))
}

/// Encodes an array of primitives from its leaves.
#[inline]
fn encode_scalars<P: Plans>(
    out: &mut BitWriter<'_>,
    kind: Kind,
    run: &[Scalar],
    saturate: bool,
) -> Result<(), (usize, FlatFail)> {
    let bits = scalar_bits(kind);
    if let Kind::Uint { bits: 8, .. } = kind {
        // Byte strings on a byte boundary (e.g. a tail-optimized name) are plain bytes.
        let in_range = run
            .iter()
            .all(|v| matches!(v, Scalar::Uint(b) if *b <= 0xFF));
        if in_range {
            if let Some(bytes) = out.aligned_bytes(run.len()) {
                for (byte, v) in bytes.iter_mut().zip(run) {
                    if let Scalar::Uint(b) = v {
                        *byte = *b as u8;
                    }
                }
                return Ok(());
            }
        }
    }
    let mut at = 0;
    let written = out.write_run(run.len(), |i| {
        at = i;
        let raw = fast_raw::<P>(kind, run[i], saturate).map_err(FlatFail::Scalar)?;
        Ok((to_stream(raw, bits), bits))
    });
    written.map_err(|e| (at, e.unwrap_or_else(FlatFail::Buffer)))
}

/// [`scalar_raw`] with the in-range cases first (where the plans `P` run the flat codec).
#[inline(always)]
pub(crate) fn fast_raw<P: Plans>(
    kind: Kind,
    value: Scalar,
    saturate: bool,
) -> Result<u64, scalar::ScalarError> {
    if !P::FLAT {
        return scalar_raw(kind, value, saturate);
    }
    match (kind, value) {
        (Kind::Uint { bits, .. }, Scalar::Uint(v)) if v <= crate::bits::field_mask(bits.into()) => {
            Ok(v)
        }
        // In range (NaN compares false and takes the general path, as do infinities).
        (Kind::Float { bits: 16, .. }, Scalar::Float(v)) if v.abs() <= scalar::FLOAT16_MAX => {
            Ok(u64::from(scalar::f16_from_f32(v as f32)))
        }
        (Kind::Float { bits: 32, .. }, Scalar::Float(v)) if v.abs() <= f64::from(f32::MAX) => {
            Ok(u64::from((v as f32).to_bits()))
        }
        _ => scalar_raw(kind, value, saturate),
    }
}

/// Bits the visiting pass reads: [`BitRead`] behind a pointer, so that one copy of the loop
/// serves every kind of data.
pub(crate) trait Input {
    /// Total number of bits.
    fn bit_len(&self) -> usize;
    /// Bytes `index` and `index + 1` as [`pair_word`] makes them, 0 for the second one where
    /// it lies beyond the end; the caller checks that the first one does not.
    fn pair(&self, index: usize) -> u16;
}

/// Any [`BitRead`] as an [`Input`] (a pointer to it: the data itself may be unsized).
pub(crate) struct Bits<'d, R: ?Sized>(pub(crate) &'d R);

impl<R: BitRead + ?Sized> Input for Bits<'_, R> {
    fn bit_len(&self) -> usize {
        self.0.bit_len()
    }
    fn pair(&self, index: usize) -> u16 {
        if let Some(bytes) = self.0.contiguous() {
            // Bytes in one run (any but scattered payloads): taken by checked accessors, 0
            // beyond the end, so that reading them links no bounds-check panic.
            let at = |i: usize| bytes.get(i).copied().unwrap_or(0);
            return pair_word([at(index), at(index + 1)]);
        }
        let next = match index + 1 < self.0.bit_len() / 8 {
            true => self.0.byte(index + 1),
            false => 0,
        };
        pair_word([self.0.byte(index), next])
    }
}

/// A leaf as the visiting pass hands it to its [`Visit`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct LeafAt<'w> {
    /// Its number `[k]` in the value read (or, when nothing is read, in the value written).
    pub index: usize,
    /// What it is.
    pub kind: LeafKind,
    /// The type's version, when the leaf is a `p_version` field.
    pub version: Option<u32>,
    /// Where its bits start (in the data read, or when nothing is read, in the output).
    pub bit_offset: usize,
    /// Its field path.
    pub path: &'w Path,
}

/// Why a [`Visit`] stops the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Halt {
    /// What the visit looked for is found: the loop ends without error.
    Found,
    /// The loop fails at the leaf, with the error [`Visit::refusal`] gives.
    Refused,
}

/// What the visiting pass does at each leaf, besides reading and writing it: the operations
/// on values other than whole-value encoding and decoding (finding a leaf, rewriting a value
/// with a new tag or length, a type's default, checking stored versions, translating) are
/// visits, and so are firmware's leaf lists.
pub(crate) trait Visit {
    /// Leaf `at`, whose value read is `old` (`None` when nothing is read there). Returns the
    /// value to write in its place (`None`: the value read, or when nothing is read, the
    /// default: zero, or the type's version for `p_version`).
    fn leaf(&mut self, at: &LeafAt<'_>, old: Option<Scalar>) -> Result<Option<Scalar>, Halt>;

    /// The error of the last [`Halt::Refused`]. The visits' own errors are those of leaf
    /// lists (a translation's is one: a leaf it cannot read).
    ///
    /// Written into `fault`, where the loop keeps it (so that a large one is not moved).
    fn refusal(&self, fault: &mut Option<ErrorKind<LeafError>>) {
        *fault = Some(ErrorKind::TooDeep);
    }

    /// A static array of `len` elements is about to be written at `path` from given values
    /// (its length is not a leaf).
    fn fixed_len(&mut self, _path: &Path, _len: u32) -> Result<(), Halt> {
        Ok(())
    }

    /// A reading walk the visit steers ([`Steer::Visit`]): part `at` begins where `reading`
    /// stands. Returns whether the visit passed it over ([`Reading::pass`]); a visit that is
    /// done passes over every part, and the loop winds down reading nothing more.
    fn part(&mut self, _at: &PartAt<'_>, _reading: &mut Reading<'_>) -> bool {
        false
    }
}

/// Where a reading walk stands, for a visit that steers it ([`Visit::part`]).
pub(crate) struct Reading<'r> {
    /// Bits read.
    pub bits: &'r mut usize,
    /// Leaves counted.
    pub leaves: &'r mut usize,
}

impl Reading<'_> {
    /// Passes over node `id` unread, its leaves counted, if it has a fixed shape.
    pub(crate) fn pass(&mut self, layout: &Layout<'_>, id: NodeId) -> bool {
        let node = layout.node(id);
        match node.fixed_leaves() {
            Some(n) => {
                *self.bits += node.min_bits as usize;
                *self.leaves += n as usize;
                true
            }
            None => false,
        }
    }
}

/// A part of the value about to be walked, as the loop hands it to [`Pass::pass_over`].
pub(crate) struct PartAt<'w> {
    /// Its node.
    pub node: NodeId,
    /// Its step down the path: `None` for the root and padding.
    pub step: Option<Step>,
    /// The parts it lies in (0: the root).
    pub depth: usize,
    /// Its field path.
    pub path: &'w Path,
}

/// The visiting pass: a value read from an [`Input`], written into bytes, or both at once,
/// every leaf handed to a [`Visit`]. Its visit is behind a pointer, so that firmware compiles
/// the loop once for all its operations.
pub(crate) struct Visiting<'w> {
    /// What it is asked to do (the caller's: not copied).
    job: &'w mut Job<'w>,
    rpos: usize,
    wpos: usize,
    leaves: usize,
    mode: Mode,
    visit: &'w mut dyn Visit,
    /// The fault the loop stopped at, as it keeps it until the error is worded where the loop
    /// returns it ([`visit`]): made in place or swapped in, never moved (a move of its size
    /// is a `memcpy` call, which firmware then links).
    fault: Option<ErrorKind<LeafError>>,
    /// The output is too small: the loop goes on without writing, to tell how small.
    overflow: bool,
}

/// What a visiting loop is asked to do.
pub(crate) struct Job<'w> {
    pub input: Option<&'w dyn Input>,
    pub out: &'w mut [u8],
    pub writing: bool,
    /// Reading only: which parts are passed over unread.
    pub steer: Steer,
    pub options: EncodeOptions,
}

/// Which parts a reading walk passes over unread.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Steer {
    /// None: every part is read.
    No,
    /// Fixed-shape parts whose leaves all come before leaf `[k]` (finding it): counted, not
    /// read, without asking the visit.
    Below(usize),
    /// Those the visit passes over ([`Visit::part`]).
    Visit,
}

impl<'w> Job<'w> {
    /// Reads `input` and writes nothing (`steer`: see [`Job::steer`]).
    pub(crate) fn reading(input: &'w dyn Input, tao: bool, steer: Steer) -> Self {
        Job {
            input: Some(input),
            out: &mut [],
            writing: false,
            steer,
            options: EncodeOptions {
                tao,
                ..EncodeOptions::default()
            },
        }
    }
}

/// Where a visiting loop ended.
pub(crate) struct Walked {
    /// Bits read.
    pub read: usize,
    /// Bits written.
    pub written: usize,
    /// Leaves visited (with those passed over unread).
    pub leaves: usize,
}

/// Runs the loop with the visiting pass over `root` (out of line: one copy of the wording of
/// its error, for the operations that hand it on).
#[inline(never)]
pub(crate) fn visit(
    layout: &Layout<'_>,
    root: NodeId,
    job: Job<'_>,
    visit: &mut dyn Visit,
) -> Result<Walked, Error<LeafError>> {
    visit_here(layout, root, job, visit)
}

/// [`visit`] for a caller that returns the error to the firmware: the loop is set up and run
/// out of line, and the error worded here, where it is returned, so that it is never moved on
/// the way (firmware that drops it, or looks at part of it, copies nothing: a move of its
/// size is a `memcpy` call).
#[inline(always)]
pub(crate) fn visit_here(
    layout: &Layout<'_>,
    root: NodeId,
    job: Job<'_>,
    visit: &mut dyn Visit,
) -> Result<Walked, Error<LeafError>> {
    let mut job = job;
    let mut run = visiting(layout, &mut job, visit);
    match run.walk(root) {
        Ok(walked) => Ok(walked),
        Err(Stop) => Err(run.error()),
    }
}

/// The loop with the visiting pass, set up where the caller keeps it.
#[inline(never)]
fn visiting<'l, 'w>(
    layout: &'l Layout<'l>,
    job: &'w mut Job<'w>,
    visit: &'w mut dyn Visit,
) -> Run<'l, Visiting<'w>> {
    let mode = if job.input.is_some() {
        Mode::Data
    } else {
        Mode::Given
    };
    let pass = Visiting {
        job,
        rpos: 0,
        wpos: 0,
        leaves: 0,
        mode,
        visit,
        fault: None,
        overflow: false,
    };
    Run::new(layout, pass)
}

impl Run<'_, Visiting<'_>> {
    /// Walks `root`; where it stopped at a fault, `Err` (the fault kept to be worded).
    #[inline(never)]
    fn walk(&mut self, root: NodeId) -> Result<Walked, Stop> {
        let tao = Tao::both(self.pass.job.options.tao);
        // (A visit that found what it looked for stops the loop without a fault.)
        if self.node(root, tao).is_err() && self.pass.fault.is_some() {
            return Err(Stop);
        }
        let pass = &mut self.pass;
        if pass.overflow {
            let needed = pass.wpos.div_ceil(8);
            pass.fault = Some(ErrorKind::BufferTooSmall { needed });
            // The walk ended: its path is empty again, and it stands at its end.
            self.at = Some(pass.wpos);
            return Err(Stop);
        }
        Ok(Walked {
            read: pass.rpos,
            written: pass.wpos,
            leaves: pass.leaves,
        })
    }

    /// The error the loop stopped at, worded.
    #[inline(always)]
    fn error(&self) -> Error<LeafError> {
        let pass = &self.pass;
        let kind = match &pass.fault {
            Some(kind) => *kind,
            None => ErrorKind::TooDeep,
        };
        Error {
            kind,
            bit_offset: self.at.unwrap_or(pass.pos()),
            path: self.path,
        }
    }
}

/// Runs the loop with the visiting pass to write a whole value into `out` (reading `input`
/// if any); its length in bytes, the last byte's unused bits zero.
pub(crate) fn write_whole(
    layout: &Layout<'_>,
    root: NodeId,
    input: Option<&dyn Input>,
    out: &mut [u8],
    options: EncodeOptions,
    v: &mut dyn Visit,
) -> Result<usize, Error<LeafError>> {
    write_whole_by::<false>(layout, root, input, out, options, v)
}

/// [`write_whole`] with the error worded here ([`visit_here`]).
#[inline(always)]
pub(crate) fn write_whole_here(
    layout: &Layout<'_>,
    root: NodeId,
    input: Option<&dyn Input>,
    out: &mut [u8],
    options: EncodeOptions,
    v: &mut dyn Visit,
) -> Result<usize, Error<LeafError>> {
    write_whole_by::<true>(layout, root, input, out, options, v)
}

#[inline(always)]
fn write_whole_by<const HERE: bool>(
    layout: &Layout<'_>,
    root: NodeId,
    input: Option<&dyn Input>,
    out: &mut [u8],
    options: EncodeOptions,
    v: &mut dyn Visit,
) -> Result<usize, Error<LeafError>> {
    let job = Job {
        input,
        out: &mut *out,
        writing: true,
        steer: Steer::No,
        options,
    };
    let walked = match HERE {
        true => visit_here(layout, root, job, v),
        false => visit(layout, root, job, v),
    };
    let end = walked?.written;
    // The last byte's unused bits (the walk wrote within `out`).
    clear_after(out, end);
    Ok(end.div_ceil(8))
}

impl Visiting<'_> {
    /// (Inline, so that the kind is made where it is kept.)
    #[inline(always)]
    fn refuse(&mut self, kind: ErrorKind<LeafError>) -> Stop {
        self.fault = Some(kind);
        Stop
    }

    #[cold]
    fn halt(&mut self, halt: Halt) -> Stop {
        // Found: no fault, so the loop ends without error.
        if halt == Halt::Refused {
            self.visit.refusal(&mut self.fault);
        }
        Stop
    }

    /// Reads `bits` bits into `raw` where the mode reads (elsewhere `raw` stays: the
    /// default). (The value in place, not in a result: one register-sized result.)
    fn read(&mut self, bits: u32, raw: &mut u64) -> Result<(), Stop> {
        let Some(input) = self.job.input.filter(|_| bits > 0 && self.mode.reads()) else {
            return Ok(());
        };
        let (needed, available) = (self.rpos + bits as usize, input.bit_len());
        if needed > available {
            return Err(self.refuse(ErrorKind::Truncated {
                needed_bits: needed,
                available_bits: available,
            }));
        }
        *raw = read_scalar(move |i| input.pair(i), self.rpos, needed);
        self.rpos = needed;
        Ok(())
    }

    fn write(&mut self, raw: u64, bits: u32) {
        if !self.job.writing || self.mode == Mode::Skip {
            return;
        }
        let end = self.wpos + bits as usize;
        // A value too long for the output is still walked to its end (its faults come
        // first). Positions only grow: once one write is past the end, so are the rest.
        if end > self.job.out.len() * 8 {
            self.overflow = true;
        } else {
            put_scalar(self.job.out, self.wpos, raw, bits);
        }
        self.wpos = end;
    }

    /// A leaf (`kind`; `version`: the type's, for a `p_version` field) at bit `at`, its raw
    /// bits `raw` (read, or where nothing is read, its default), visited where the mode
    /// visits: `raw` becomes the raw bits to write, those of the value the visit gives (or
    /// stays). A union tag or array length is visited before it is checked (a bad one can be
    /// looked at).
    #[inline(never)]
    fn visited(
        &mut self,
        kind: LeafKind,
        version: Option<u32>,
        at: usize,
        raw: &mut u64,
        path: &Path,
    ) -> Result<(), Stop> {
        if !self.mode.visits() {
            return Ok(());
        }
        let old = self.mode.reads().then(|| match kind {
            LeafKind::Scalar(kind) => scalar_of(kind, *raw),
            _ => Scalar::Uint(*raw),
        });
        let at = LeafAt {
            index: self.leaves,
            kind,
            version,
            bit_offset: at,
            path,
        };
        self.leaves += 1;
        let v = match self.visit.leaf(&at, old) {
            Ok(Some(v)) => v,
            Ok(None) => return Ok(()),
            Err(halt) => return Err(self.halt(halt)),
        };
        // (Each fault made where it is kept: see `Visiting::fault`.)
        match (kind, version) {
            (LeafKind::Scalar(_), Some(expected))
                if self.mode == Mode::Given && !self.job.options.keep_versions =>
            {
                if scalar::same_integer(v, expected) {
                    *raw = expected.into();
                    return Ok(());
                }
                let given = Scalar::Uint(0);
                self.fault = Some(ErrorKind::VersionMismatch { given, expected });
                if let Some(ErrorKind::VersionMismatch { given, .. }) = &mut self.fault {
                    *given = v;
                }
                Err(Stop)
            }
            (LeafKind::Scalar(kind), _) => {
                let mut r = scalar_raw(kind, v, self.job.options.saturate);
                match &mut r {
                    Ok(bits) => {
                        *raw = *bits;
                        Ok(())
                    }
                    // Swapped in, not moved (see `Visiting::fault`).
                    Err(e) => {
                        let wrong = ScalarError::WrongKind { expected: "" };
                        self.fault = Some(ErrorKind::Scalar(wrong));
                        if let Some(ErrorKind::Scalar(fault)) = &mut self.fault {
                            core::mem::swap(fault, e);
                        }
                        Err(Stop)
                    }
                }
            }
            // A count.
            _ => match v {
                Scalar::Uint(n) => {
                    *raw = n;
                    Ok(())
                }
                Scalar::Int(n) if n >= 0 => {
                    *raw = n as u64;
                    Ok(())
                }
                _ => Err(self.refuse(ErrorKind::Value(LeafError::NotACount))),
            },
        }
    }

    /// A primitive leaf (`version`: the type's, for a `p_version` field).
    fn primitive(&mut self, kind: Kind, version: Option<u32>, path: &Path) -> Result<(), Stop> {
        let bits = scalar_bits(kind);
        let at = self.pos();
        let mut raw: u64 = version.unwrap_or(0).into();
        self.read(bits, &mut raw)?;
        self.visited(LeafKind::Scalar(kind), version, at, &mut raw, path)?;
        self.write(raw, bits);
        Ok(())
    }
}

impl Pass for Visiting<'_> {
    type Error = LeafError;
    const RUNS: bool = false;
    const ENCODES: bool = false;
    const EDITS: bool = true;

    #[inline(always)]
    fn set_fault(&mut self, kind: ErrorKind<LeafError>) {
        self.fault = Some(kind);
    }
    /// The position errors and leaves are reported at: in the data read, if any.
    fn pos(&self) -> usize {
        if self.job.input.is_some() {
            self.rpos
        } else {
            self.wpos
        }
    }
    fn scalar(&mut self, kind: Kind, path: &Path) -> Result<(), Stop> {
        self.primitive(kind, None, path)
    }
    fn version(&mut self, kind: Kind, version: u32, path: &Path) -> Result<(), Stop> {
        self.primitive(kind, Some(version), path)
    }
    fn leaf(&mut self, kind: Kind, version: Option<u32>, path: &Path) -> Result<(), Stop> {
        self.primitive(kind, version, path)
    }
    fn absent_version(&mut self, _: Kind, _: u32) -> Result<(), Stop> {
        Ok(())
    }
    fn void(&mut self, bits: u32) -> Result<(), Stop> {
        self.read(bits, &mut 0)?;
        self.write(0, bits);
        Ok(())
    }
    fn begin_struct(&mut self, _: u32) -> Result<(), Stop> {
        Ok(())
    }
    fn field(&mut self, _: u32, _: &str) -> Result<bool, Stop> {
        Ok(true)
    }
    fn end_field(&mut self) {}
    fn end_struct(&mut self, _: &Layout<'_>, _: NodeId, _: usize) -> Result<(), Stop> {
        Ok(())
    }
    fn tag(
        &mut self,
        _: &Layout<'_>,
        id: NodeId,
        bits: u8,
        path: &Path,
    ) -> Result<(u64, u64), Stop> {
        let at = self.pos();
        let mut old = 0;
        self.read(bits.into(), &mut old)?;
        let kind = LeafKind::Tag { bits, union: id };
        let mut new = old;
        self.visited(kind, None, at, &mut new, path)?;
        // (A tag read too large for 32 bits is refused as read, before this one is used.)
        let new = new.min(u32::MAX.into());
        // Nothing read: the given tag is checked where the union starts.
        Ok((if self.mode.reads() { old } else { new }, new))
    }
    fn variant(&mut self, tag: u64, _: u32, _: &str, at: At<'_>) -> Result<(), Stop> {
        if let LeafKind::Tag { bits, .. } = at.kind {
            self.write(tag, bits.into());
        }
        Ok(())
    }
    fn end_union(&mut self) -> Result<(), Stop> {
        Ok(())
    }
    fn fixed(&mut self, len: u32, at: At<'_>) -> Result<(), Stop> {
        if self.mode == Mode::Given {
            let r = self.visit.fixed_len(at.path, len);
            r.map_err(|halt| self.halt(halt))?;
        }
        Ok(())
    }
    fn length(&mut self, bits: u8, tail: bool) -> Result<Option<u64>, Stop> {
        match self.mode.reads() && tail {
            // Counted ahead by the loop.
            true => Ok(None),
            false => {
                let mut n = 0;
                self.read(bits.into(), &mut n)?;
                Ok(Some(n))
            }
        }
    }
    fn relength(&mut self, n: Option<u64>, at: At<'_>) -> Result<Option<u64>, Stop> {
        // The loop has counted a tail array read: `n` is always there.
        let mut new = n.unwrap_or(0);
        self.visited(at.kind, None, at.bit_offset, &mut new, at.path)?;
        Ok(Some(new))
    }
    fn prefix(&mut self, n: Option<u64>, bits: u8, _: At<'_>) -> Result<(), Stop> {
        self.write(n.unwrap_or(0), bits.into());
        Ok(())
    }
    fn more(&self, i: u64, n: Option<u64>) -> bool {
        Some(i) < n
    }
    fn element(&mut self, _: u64) -> Result<(), Stop> {
        Ok(())
    }
    fn end_element(&mut self) {}
    fn end_array(&mut self, _: u64) -> Result<(), Stop> {
        Ok(())
    }
    fn mode(&self) -> Mode {
        self.mode
    }
    fn set_mode(&mut self, mode: Mode) {
        self.mode = mode;
    }
    #[inline(always)]
    fn steered(&self) -> bool {
        // (Steered walks only read.)
        self.mode == Mode::Data && !matches!(self.job.steer, Steer::No)
    }
    #[inline(always)]
    fn pass_over(&mut self, node: &Node, at: &PartAt<'_>) -> bool {
        match self.job.steer {
            Steer::Below(k) => match node.fixed_leaves() {
                Some(n) if self.leaves + n as usize <= k => {
                    self.rpos += node.min_bits as usize;
                    self.leaves += n as usize;
                    true
                }
                _ => false,
            },
            _ => {
                let mut reading = Reading {
                    bits: &mut self.rpos,
                    leaves: &mut self.leaves,
                };
                self.visit.part(at, &mut reading)
            }
        }
    }
    fn read_pos(&self) -> usize {
        self.rpos
    }
    fn read_left(&self) -> usize {
        self.job
            .input
            .map_or(0, |i| i.bit_len())
            .saturating_sub(self.rpos)
    }
    fn seek_read(&mut self, pos: usize) {
        self.rpos = pos;
    }
    fn run(&mut self, _: &[FlatItem], _: u32, _: u32) -> Ran<LeafError> {
        Ran::Declined
    }
    fn elements(&mut self, _: Kind, _: Option<u64>, _: u32) -> Elements<LeafError> {
        Ok(None)
    }
}
