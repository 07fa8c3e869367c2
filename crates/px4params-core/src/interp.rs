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

use crate::bits::{BitRead, BitReader, BitWriter};
use crate::error::{Error, ErrorKind, Path, Step};
use crate::layout::{FlatItem, Kind, Layout, NodeId, Role, Segment, Span};
use crate::plan::Plans;
use crate::rules::{
    scalar_bits, scalar_of, scalar_raw, tail_optimized, ArrayLen, At, DecodeOptions, EncodeOptions,
    LeafKind, Sink, Source, MAX_DEPTH,
};
use crate::scalar::{self, Scalar};

/// The loop stopped: the error waits in [`Run::error`] (results stay register-sized).
pub(crate) struct Stop;

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

    /// The fault a method stopped at (each keeps it, so that results stay register-sized).
    fn fault(&mut self) -> Option<ErrorKind<Self::Error>>;
    /// Bits read or written so far.
    fn pos(&self) -> usize;
    /// A primitive value.
    fn scalar(&mut self, kind: Kind, path: &Path) -> Result<(), Stop>;
    /// A `p_version` field the input has (decoding: a primitive like any other).
    fn version(&mut self, kind: Kind, version: u32, path: &Path) -> Result<(), Stop>;
    /// A `p_version` field the input leaves out (encoding only): the type's version.
    fn absent_version(&mut self, kind: Kind, version: u32) -> Result<(), Stop>;
    /// `bits` zero bits.
    fn void(&mut self, bits: u32) -> Result<(), Stop>;
    fn begin_struct(&mut self, count: u32) -> Result<(), Stop>;
    /// Field `index`; whether the input has it.
    fn field(&mut self, index: u32, name: &str) -> Result<bool, Stop>;
    fn end_field(&mut self);
    fn end_struct(&mut self, layout: &Layout<'_>, id: NodeId, used: usize) -> Result<(), Stop>;
    /// A union's tag, read or given (unchecked).
    fn tag(&mut self, layout: &Layout<'_>, id: NodeId, bits: u8) -> Result<u64, Stop>;
    /// The tag, checked, selects variant `index` (`name`): written, or told to the sink.
    fn variant(&mut self, tag: u64, index: u32, name: &str, at: At<'_>) -> Result<(), Stop>;
    fn end_union(&mut self) -> Result<(), Stop>;
    /// A static array of `len` elements begins.
    fn fixed(&mut self, len: u32, at: At<'_>) -> Result<(), Stop>;
    /// A dynamic array's length, read (from a prefix of `bits`) or given; `None` for a tail
    /// array read, whose elements are counted as they come.
    fn length(&mut self, bits: u8, tail: bool) -> Result<Option<u64>, Stop>;
    /// The length, checked, begins the array: its prefix written (none for a tail array), or
    /// told to the sink.
    fn prefix(&mut self, n: Option<u64>, at: At<'_>) -> Result<(), Stop>;
    /// Whether element `i` is there: below the length, or for a tail array read, while
    /// whole bytes remain.
    fn more(&self, i: u64, n: Option<u64>) -> bool;
    fn element(&mut self, i: u64) -> Result<(), Stop>;
    fn end_element(&mut self);
    fn end_array(&mut self, n: u64) -> Result<(), Stop>;
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
    path: Path,
    depth: usize,
    pub(crate) error: Option<Error<P::Error>>,
}

impl<'l, P: Pass> Run<'l, P> {
    pub(crate) fn new(layout: &'l Layout<'l>, pass: P) -> Self {
        Run {
            layout,
            pass,
            path: Path::default(),
            depth: 0,
            error: None,
        }
    }

    /// The error the loop stopped at.
    #[cold]
    pub(crate) fn stopped(&mut self) -> Error<P::Error> {
        // Every Stop is made by `fail_at`, which fills the slot first.
        self.error.take().unwrap_or(Error {
            kind: ErrorKind::TooDeep,
            bit_offset: 0,
            path: Path::default(),
        })
    }

    #[cold]
    #[inline(never)]
    fn fail_at(&mut self, bit_offset: usize, kind: ErrorKind<P::Error>) -> Stop {
        self.error = Some(Error {
            kind,
            bit_offset,
            path: self.path,
        });
        Stop
    }

    #[cold]
    #[inline(never)]
    fn fail(&mut self, kind: ErrorKind<P::Error>) -> Stop {
        let at = self.pass.pos();
        self.fail_at(at, kind)
    }

    #[inline(always)]
    fn ok<T>(&mut self, r: Result<T, Stop>) -> Result<T, Stop> {
        match r {
            Ok(v) => Ok(v),
            Err(Stop) => Err(self.refused()),
        }
    }

    /// Words the fault the pass stopped at.
    #[cold]
    #[inline(never)]
    fn refused(&mut self) -> Stop {
        let kind = self.pass.fault().unwrap_or(ErrorKind::TooDeep);
        self.fail(kind)
    }

    /// A primitive (a field, an element or a variant), one past the nesting bound refused.
    #[inline]
    fn scalar(&mut self, kind: Kind) -> Result<(), Stop> {
        if self.depth >= MAX_DEPTH {
            return Err(self.fail(ErrorKind::TooDeep));
        }
        let r = self.pass.scalar(kind, &self.path);
        self.ok(r)
    }

    /// Walks node `id`; `tao`: it ends the value (tail array optimization applies to it).
    pub(crate) fn node(&mut self, id: NodeId, tao: bool) -> Result<(), Stop> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.fail(ErrorKind::TooDeep));
        }
        let layout = self.layout;
        let at_pos = self.pass.pos();
        // An array's elements: walked after the match, from one place in the code.
        let mut array = None;
        match layout.node(id).kind {
            kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool) => {
                let r = self.pass.scalar(kind, &self.path);
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
                        used += self.field(i, tao && i + 1 == first + count)?;
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
                let r = self.pass.tag(layout, id, tag_bits);
                let tag = self.ok(r)?;
                // The rule: the tag selects one of the variants.
                if tag >= u64::from(count) {
                    let bad = ErrorKind::BadUnionTag {
                        tag,
                        variants: count,
                    };
                    return Err(self.fail_at(at_pos, bad));
                }
                let index = first + tag as u32;
                let variant = layout.fields[index as usize];
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
                self.path.push(Step::Field(index));
                self.node(variant.node, tao)?;
                self.path.pop();
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
                array = Some((elem, Some(len.into()), len, tao));
            }
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => {
                // The rule: the last array of a value, of elements of a byte or more, has no
                // prefix and takes the remaining whole bytes.
                let tail = tail_optimized(layout, elem, tao);
                let r = self.pass.length(len_bits, tail);
                let n = self.ok(r)?;
                // The rule: at most `max` elements.
                if let Some(n) = n.filter(|&n| n > u64::from(max)) {
                    return Err(self.fail_at(at_pos, ErrorKind::ArrayTooLong { len: n, max }));
                }
                let at = At {
                    path: &self.path,
                    bit_offset: at_pos,
                    kind: LeafKind::Len {
                        bits: if tail { 0 } else { len_bits },
                        array: id,
                    },
                };
                let r = self.pass.prefix(n, at);
                self.ok(r)?;
                array = Some((elem, n, max, tao && !tail));
            }
        }
        if let Some((elem, n, max, tao)) = array {
            self.elements(elem, n, max, tao)?;
        }
        self.depth -= 1;
        Ok(())
    }

    #[inline(always)]
    /// The elements of an array (`n`: its length, `None` for a tail array read: as many as
    /// whole bytes remain for, at most `max`).
    fn elements(&mut self, elem: NodeId, n: Option<u64>, max: u32, tao: bool) -> Result<(), Stop> {
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
                let too_long = ErrorKind::ArrayTooLong { len: i + 1, max };
                return Err(self.fail(too_long));
            }
            self.path.push(Step::Index(i as u32));
            let r = self.pass.element(i);
            self.ok(r)?;
            if scalar {
                self.scalar(kind)?;
            } else {
                self.node(elem, tao && Some(i + 1) == n)?;
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
    fn field(&mut self, index: u32, last: bool) -> Result<usize, Stop> {
        let layout = self.layout;
        let field = layout.fields[index as usize];
        if field.role == Role::Padding {
            self.node(field.node, last)?;
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
        let role = if P::ENCODES { field.role } else { Role::Data };
        let used = match (present, role) {
            (true, role) => {
                match role {
                    Role::Version(v) if is_scalar(kind) => {
                        if self.depth >= MAX_DEPTH {
                            return Err(self.fail(ErrorKind::TooDeep));
                        }
                        let r = self.pass.version(kind, v, &self.path);
                        self.ok(r)?;
                    }
                    _ if is_scalar(kind) => self.scalar(kind)?,
                    _ => self.node(field.node, last)?,
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

    /// A struct's fields by its segments: fixed-shape runs in one piece where the pass takes
    /// them, other fields one by one (`end`: one past its last field).
    fn runs(&mut self, id: NodeId, end: u32, tao: bool) -> Result<(), Stop> {
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
                                self.field(i, tao && i + 1 == end)?;
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
                    self.field(i, tao && i + 1 == end)?;
                }
            }
        }
        Ok(())
    }

    /// A run the input has too few leaves for: its fields one by one, to fail at the first
    /// leaf missing.
    #[cold]
    #[inline(never)]
    fn missing_leaf(&mut self, fields: Span, end: u32, tao: bool) -> Stop {
        for i in fields.first..fields.first + fields.count {
            if let Err(stop) = self.field(i, tao && i + 1 == end) {
                return stop;
            }
        }
        // The leaves were there after all: the input is inconsistent.
        self.fail(ErrorKind::MissingField)
    }
}

/// Extends `path` to leaf `leaf` of a run of fixed-shape `fields`.
#[cold]
fn push_flat_path(layout: &Layout<'_>, fields: Span, leaf: u32, path: &mut Path) {
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
    if run.node(root, options.tao).is_err() {
        return Err(run.stopped());
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
    if run.node(root, options.tao).is_err() {
        return Err(run.stopped());
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
            .write(scalar::to_stream(raw, bits), bits)
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

    fn fault(&mut self) -> Option<ErrorKind<S::Error>> {
        self.fault.take()
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
    fn tag(&mut self, layout: &Layout<'_>, id: NodeId, _bits: u8) -> Result<u64, Stop> {
        let tag = self.source.begin_union(layout, layout.members(id));
        tag.map(u64::from)
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
    fn prefix(&mut self, n: Option<u64>, at: At<'_>) -> Result<(), Stop> {
        match (at.kind, n) {
            (LeafKind::Len { bits, .. }, Some(n)) if bits > 0 => self.write(n, bits.into()),
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
        Ok(scalar::from_stream(stream, bits))
    }
}

impl<'d, P: Plans, R: BitRead + ?Sized + 'd, K: Sink> Pass for Decode<'d, P, R, K> {
    type Error = K::Error;
    const RUNS: bool = K::FLAT && P::FLAT;
    const ENCODES: bool = false;

    fn fault(&mut self) -> Option<ErrorKind<K::Error>> {
        self.fault.take()
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
    fn tag(&mut self, _: &Layout<'_>, _: NodeId, bits: u8) -> Result<u64, Stop> {
        self.read(bits.into())
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
    fn prefix(&mut self, n: Option<u64>, at: At<'_>) -> Result<(), Stop> {
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
            None => self.remaining() >= 8,
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
            // A tail array: as many elements as whole bytes remain for.
            None if self.remaining() >= 8 => (self.remaining() / 8 * 8) / bits,
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
                        *slot = scalar_of(kind, scalar::from_stream(reader.read(bits), bits));
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
                    *slot = scalar_of(kind, scalar::from_stream(raw, bits));
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
        Ok((scalar::to_stream(raw, bits), bits))
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
        Ok((scalar::to_stream(raw, bits), bits))
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
