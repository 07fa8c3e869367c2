//! One small walk over a value, for firmware: it reads a value, writes one, or both at once,
//! and hands every leaf to a [`Visit`] that watches, supplies or replaces it.
//!
//! Every operation on values is one walk with its own visit: decoding into a flat leaf list
//! ([`decode`]), encoding from one ([`encode`]), finding leaf `[k]` ([`locate`]), rewriting a
//! value with a new union tag or array length ([`transcode`]), a type's default
//! ([`encode_default`]), checking a stored value's `p_version` fields ([`check_versions`]) and
//! translating a value of an older type version ([`translate`]). Firmware builds (feature
//! `compact`) do all of these through this one interpreter of the DroneCAN rules, which is
//! why it is here: one walk in the code instead of one per operation.
//!
//! Hosts keep faster walks for most of them (the codec's encoder and decoder, leaf tables,
//! seeks), which tests hold to this one, and use this one where a write changes a value's
//! shape ([`transcode`], [`encode_default`]). Reads go through [`Input`], so the same code
//! reads contiguous bytes and scattered pieces alike.

use core::convert::Infallible;

use crate::bits::BitRead;
use crate::error::{Error, ErrorKind, Path, Step};
use crate::layout::{Kind, Layout, NodeId, Role};
use crate::rules::{
    scalar_bits, scalar_of, scalar_raw, tail_optimized, DecodeOptions, Decoded, EncodeOptions,
    Leaf, LeafAccessError, LeafError, LeafKind, Position, TranslateError, MAX_DEPTH,
};
use crate::scalar::{self, Scalar, ScalarError};

/// Bits a walk reads: [`BitRead`] behind a pointer, so that one walk serves every kind of data.
pub(crate) trait Input {
    /// Total number of bits.
    fn bit_len(&self) -> usize;
    /// Bytes `index` and `index + 1` as a big-endian pair, 0 for the second one where it
    /// lies beyond the end; the caller checks that the first one does not.
    fn pair(&self, index: usize) -> u16;
}

/// Any [`BitRead`] as an [`Input`] (a pointer to it: the data itself may be unsized).
struct Bits<'d, R: ?Sized>(&'d R);

impl<R: BitRead + ?Sized> Input for Bits<'_, R> {
    fn bit_len(&self) -> usize {
        self.0.bit_len()
    }
    fn pair(&self, index: usize) -> u16 {
        let next = match index + 1 < self.0.bit_len() / 8 {
            true => self.0.byte(index + 1),
            false => 0,
        };
        u16::from(self.0.byte(index)) << 8 | u16::from(next)
    }
}

/// A leaf as a walk hands it to its [`Visit`].
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

/// Why a [`Visit`] stops its walk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Halt {
    /// What the visit looked for is found: the walk ends without error.
    Found,
    /// The walk fails at the leaf, with the error [`Visit::refusal`] gives (results stay
    /// small enough for registers).
    Refused,
}

/// What a walk does at each leaf, besides reading and writing it.
pub(crate) trait Visit {
    /// Leaf `at`, whose value read is `old` (`None` when the walk reads nothing there).
    /// Returns the value to write in its place (`None`: the value read, or when nothing is
    /// read, the default: zero, or the type's version for `p_version`).
    fn leaf(&mut self, at: &LeafAt<'_>, old: Option<Scalar>) -> Result<Option<Scalar>, Halt>;

    /// The error of the last [`Halt::Refused`]. The visits' own errors are those of leaf
    /// lists (a translation's is one: a leaf it cannot read).
    fn refusal(&self) -> ErrorKind<LeafError> {
        ErrorKind::TooDeep
    }

    /// A static array of `len` elements is about to be written at `path` from given values
    /// (its length is not a leaf).
    fn fixed_len(&mut self, _path: &Path, _len: u32) -> Result<(), Halt> {
        Ok(())
    }
}

/// Where a part of the value comes from.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
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
    fn reads(self) -> bool {
        matches!(self, Mode::Data | Mode::Skip)
    }

    fn visits(self) -> bool {
        matches!(self, Mode::Data | Mode::Given)
    }
}

/// How a part of the value is walked: where its values come from, and whether it ends the
/// value read and the value written (tail array optimization applies to its last field).
#[derive(Clone, Copy)]
struct How {
    mode: Mode,
    rtao: bool,
    wtao: bool,
}

impl How {
    /// For a member: tail array optimization only for the `last` one.
    fn within(self, last: bool) -> How {
        How {
            mode: self.mode,
            rtao: self.rtao && last,
            wtao: self.wtao && last,
        }
    }

    fn with(self, mode: Mode) -> How {
        How { mode, ..self }
    }
}

/// The walk failed: the error waits in [`Walk::error`] (results stay register-sized).
struct Stop;

struct Walk<'w> {
    layout: &'w Layout<'w>,
    input: Option<&'w dyn Input>,
    rpos: usize,
    out: &'w mut [u8],
    writing: bool,
    wpos: usize,
    leaves: usize,
    /// Reading only, fixed-shape parts whose leaves all come before this one are passed over
    /// unread (finding leaf `[k]`).
    skip_below: Option<usize>,
    saturate: bool,
    keep_versions: bool,
    path: Path,
    depth: usize,
    visit: &'w mut dyn Visit,
    /// The error a walk stopped at (none when it stopped because its visit found its leaf).
    error: Option<Error<LeafError>>,
    /// The output is too small: the walk goes on without writing, to tell how small.
    overflow: bool,
}

/// What a walk is asked to do.
struct Job<'w> {
    input: Option<&'w dyn Input>,
    out: &'w mut [u8],
    writing: bool,
    skip_below: Option<usize>,
    options: EncodeOptions,
}

impl<'w> Job<'w> {
    /// A walk that reads `input` and writes nothing (`skip_below`: see [`Walk::skip_below`]).
    fn reading(input: &'w dyn Input, tao: bool, skip_below: Option<usize>) -> Self {
        Job {
            input: Some(input),
            out: &mut [],
            writing: false,
            skip_below,
            options: EncodeOptions {
                tao,
                ..EncodeOptions::default()
            },
        }
    }
}

/// Where a walk ended.
struct Walked {
    /// Bits read.
    read: usize,
    /// Bits written.
    written: usize,
    /// Leaves visited (with those passed over unread).
    leaves: usize,
}

/// Runs a walk over `root`.
fn run(
    layout: &Layout<'_>,
    root: NodeId,
    job: Job<'_>,
    visit: &mut dyn Visit,
) -> Result<Walked, Error<LeafError>> {
    let mode = if job.input.is_some() {
        Mode::Data
    } else {
        Mode::Given
    };
    let mut walk = Walk {
        layout,
        input: job.input,
        rpos: 0,
        out: job.out,
        writing: job.writing,
        wpos: 0,
        leaves: 0,
        skip_below: job.skip_below,
        saturate: job.options.saturate,
        keep_versions: job.options.keep_versions,
        path: Path::default(),
        depth: 0,
        visit,
        error: None,
        overflow: false,
    };
    let tao = job.options.tao;
    let how = How {
        mode,
        rtao: tao,
        wtao: tao,
    };
    let stopped = walk.node(root, None, how).is_err();
    match walk.error {
        Some(error) if stopped => Err(error),
        _ if walk.overflow => Err(Error {
            kind: ErrorKind::BufferTooSmall {
                needed: walk.wpos.div_ceil(8),
            },
            bit_offset: walk.wpos,
            path: Path::default(),
        }),
        _ => Ok(Walked {
            read: walk.rpos,
            written: walk.wpos,
            leaves: walk.leaves,
        }),
    }
}

impl Walk<'_> {
    /// The position errors and leaves are reported at: in the data read, if any.
    fn pos(&self) -> usize {
        if self.input.is_some() {
            self.rpos
        } else {
            self.wpos
        }
    }

    #[cold]
    #[inline(never)]
    fn fail_at(&mut self, bit_offset: usize, kind: ErrorKind<LeafError>) -> Stop {
        self.error = Some(Error {
            kind,
            bit_offset,
            path: self.path,
        });
        Stop
    }

    fn fail(&mut self, kind: ErrorKind<LeafError>) -> Stop {
        self.fail_at(self.pos(), kind)
    }

    /// Reads `bits` bits where `mode` reads (0 elsewhere).
    fn read(&mut self, bits: u32, mode: Mode) -> Result<u64, Stop> {
        let Some(input) = self.input.filter(|_| bits > 0 && mode.reads()) else {
            return Ok(0);
        };
        let (needed, available) = (self.rpos + bits as usize, input.bit_len());
        if needed > available {
            return Err(self.fail(ErrorKind::Truncated {
                needed_bits: needed,
                available_bits: available,
            }));
        }
        // The value's bytes, least significant first (its top bits last), each read most
        // significant bit first: a byte at a time, from the pair of bytes it may span.
        let (mut raw, mut shift) = (0, 0);
        while self.rpos < needed {
            let n = (needed - self.rpos).min(8) as u32;
            let (i, s) = (self.rpos / 8, (self.rpos % 8) as u32);
            let window = u32::from(input.pair(i)) << s;
            raw |= u64::from((window >> (16 - n)) & ((1 << n) - 1)) << shift;
            shift += 8;
            self.rpos += n as usize;
        }
        Ok(raw)
    }

    fn write(&mut self, raw: u64, bits: u32, mode: Mode) -> Result<(), Stop> {
        if !self.writing || mode == Mode::Skip || bits == 0 {
            return Ok(());
        }
        let end = self.wpos + bits as usize;
        // A value too long for the output is still walked to its end (its faults come first).
        self.overflow |= end > self.out.len() * 8;
        if self.overflow {
            self.wpos = end;
            return Ok(());
        }
        put(self.out, self.wpos, raw, bits);
        self.wpos = end;
        Ok(())
    }

    fn visit(
        &mut self,
        kind: LeafKind,
        version: Option<u32>,
        bit_offset: usize,
        old: Option<Scalar>,
    ) -> Result<Option<Scalar>, Stop> {
        let at = LeafAt {
            index: self.leaves,
            kind,
            version,
            bit_offset,
            path: &self.path,
        };
        self.leaves += 1;
        match self.visit.leaf(&at, old) {
            Ok(v) => Ok(v),
            Err(halt) => Err(self.halt(halt)),
        }
    }

    #[cold]
    fn halt(&mut self, halt: Halt) -> Stop {
        match halt {
            Halt::Found => Stop,
            Halt::Refused => {
                let kind = self.visit.refusal();
                self.fail(kind)
            }
        }
    }

    /// A union tag or array length given as a leaf value.
    fn count(&mut self, value: Scalar) -> Result<u64, Stop> {
        match value {
            Scalar::Uint(n) => Ok(n),
            Scalar::Int(n) if n >= 0 => Ok(n as u64),
            _ => Err(self.fail(ErrorKind::Value(LeafError::NotACount))),
        }
    }

    /// Passes over a fixed-shape part by its length, unread, where the walk looks for a leaf
    /// after it; says whether it did.
    fn passed_over(&mut self, id: NodeId, mode: Mode) -> bool {
        let node = self.layout.node(id);
        let Some(n) = node.fixed_leaves() else {
            return false;
        };
        let before = self
            .skip_below
            .is_some_and(|k| self.leaves + n as usize <= k);
        if mode == Mode::Data && !self.writing && before {
            self.rpos += node.min_bits as usize;
            self.leaves += n as usize;
            return true;
        }
        false
    }

    /// Walks node `id`, reached by `via` (a step on the path while inside; none for padding
    /// and the root).
    fn node(&mut self, id: NodeId, via: Option<Step>, how: How) -> Result<(), Stop> {
        let mode = how.mode;
        if self.passed_over(id, mode) {
            return Ok(());
        }
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.fail(ErrorKind::TooDeep));
        }
        let layout = self.layout;
        let mut version = None;
        if let Some(step) = via {
            if let Step::Field(f) = step {
                if let Role::Version(v) = layout.fields[f as usize].role {
                    version = Some(v);
                }
            }
            self.path.push(step);
        }
        match layout.node(id).kind {
            Kind::Void { bits } => {
                self.read(bits.into(), mode)?;
                self.write(0, bits.into(), mode)?;
            }
            Kind::Struct { first, count } => {
                for i in first..first + count {
                    let field = layout.fields[i as usize];
                    let via = (field.role != Role::Padding).then_some(Step::Field(i));
                    self.node(field.node, via, how.within(i + 1 == first + count))?;
                }
            }
            Kind::Union {
                first,
                count,
                tag_bits,
            } => {
                let kind = LeafKind::Tag {
                    bits: tag_bits,
                    union: id,
                };
                let (old, tag) = self.count_leaf(kind, count.into(), None, mode)?;
                self.write(tag, tag_bits.into(), mode)?;
                let variant = |t: u64| {
                    (
                        first + t as u32,
                        layout.fields[(first + t as u32) as usize].node,
                    )
                };
                let (index, node) = variant(tag);
                let mut how = how;
                if mode == Mode::Data && tag != old {
                    // The old variant is passed over, the new one written with its default.
                    let (old_index, old_node) = variant(old);
                    self.node(old_node, Some(Step::Field(old_index)), how.with(Mode::Skip))?;
                    how = how.with(Mode::Default);
                }
                self.node(node, Some(Step::Field(index)), how)?;
            }
            Kind::Array { elem, len } => {
                if mode == Mode::Given {
                    let r = self.visit.fixed_len(&self.path, len);
                    r.map_err(|halt| self.halt(halt))?;
                }
                for i in 0..len {
                    self.node(elem, Some(Step::Index(i)), how.within(i + 1 == len))?;
                }
            }
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => self.dyn_array(id, elem, max, len_bits, how)?,
            kind => self.scalar(kind, version, mode)?,
        }
        if via.is_some() {
            self.path.pop();
        }
        self.depth -= 1;
        Ok(())
    }

    fn scalar(&mut self, kind: Kind, version: Option<u32>, mode: Mode) -> Result<(), Stop> {
        let bits = scalar_bits(kind);
        let at = self.pos();
        let mut raw = if mode.reads() {
            self.read(bits, mode)?
        } else {
            version.unwrap_or(0).into()
        };
        if mode.visits() {
            let old = mode.reads().then(|| scalar_of(kind, raw));
            if let Some(v) = self.visit(LeafKind::Scalar(kind), version, at, old)? {
                raw = match version {
                    Some(expected) if mode == Mode::Given && !self.keep_versions => {
                        if !scalar::same_integer(v, expected) {
                            return Err(
                                self.fail(ErrorKind::VersionMismatch { given: v, expected })
                            );
                        }
                        expected.into()
                    }
                    _ => match scalar_raw(kind, v, self.saturate) {
                        Ok(raw) => raw,
                        Err(e) => return Err(self.fail(ErrorKind::Scalar(e))),
                    },
                };
            }
        }
        self.write(raw, bits, mode)
    }

    /// A union tag or dynamic array length (`kind`): read where the mode reads (a tail
    /// array's elements counted, `tail`), visited, then checked against `limit` (the number
    /// of variants, or the maximum length plus one). Returns the count read and the new one.
    fn count_leaf(
        &mut self,
        kind: LeafKind,
        limit: u64,
        tail: Option<(NodeId, u32)>,
        mode: Mode,
    ) -> Result<(u64, u64), Stop> {
        let at = self.pos();
        let (bits, tag) = match kind {
            LeafKind::Tag { bits, .. } => (bits, true),
            LeafKind::Len { bits, .. } => (bits, false),
            LeafKind::Scalar(_) => (0, false),
        };
        let old = match tail {
            Some((elem, max)) if mode.reads() => self.tail_count(elem, max)?,
            _ => self.read(bits.into(), mode)?,
        };
        let mut new = old;
        if mode.visits() {
            // Visited before it is checked: a bad one can be looked at.
            let read = mode.reads().then_some(Scalar::Uint(old));
            if let Some(v) = self.visit(kind, None, at, read)? {
                new = self.count(v)?;
                if tag {
                    new = new.min(u32::MAX.into());
                }
            }
        }
        let (n, at) = match (old, new) {
            (old, _) if old >= limit && mode.reads() => (old, at),
            (_, new) if new >= limit => (new, self.pos()),
            _ => return Ok((old, new)),
        };
        let fault = if tag {
            ErrorKind::BadUnionTag {
                tag: n,
                variants: limit as u32,
            }
        } else {
            ErrorKind::ArrayTooLong {
                len: n,
                max: (limit - 1) as u32,
            }
        };
        Err(self.fail_at(at, fault))
    }

    fn dyn_array(
        &mut self,
        id: NodeId,
        elem: NodeId,
        max: u32,
        len_bits: u8,
        how: How,
    ) -> Result<(), Stop> {
        let mode = how.mode;
        let rtail = tail_optimized(self.layout, elem, how.rtao) && mode.reads();
        let wtail = tail_optimized(self.layout, elem, how.wtao);
        let tail = if mode.reads() { rtail } else { wtail };
        let kind = LeafKind::Len {
            bits: if tail { 0 } else { len_bits },
            array: id,
        };
        let counted = rtail.then_some((elem, max));
        let (old, n) = self.count_leaf(kind, u64::from(max) + 1, counted, mode)?;
        if !wtail {
            self.write(n, len_bits.into(), mode)?;
        }
        let (old, n) = (old as u32, n as u32);
        for i in 0..n.max(old) {
            let part = How {
                mode: match mode {
                    _ if i >= n => Mode::Skip,
                    Mode::Data if i >= old => Mode::Default,
                    mode => mode,
                },
                rtao: !rtail && how.rtao && i + 1 == old,
                wtao: !wtail && how.wtao && i + 1 == n,
            };
            self.node(elem, Some(Step::Index(i)), part)?;
        }
        Ok(())
    }

    /// The number of elements of a tail-optimized array from here: as many as there are whole
    /// bytes left for. Elements of variable shape are read ahead (every bit, so that a fault
    /// is found where decoding them in order finds it), then read again; fixed-shape ones are
    /// counted by their length.
    fn tail_count(&mut self, elem: NodeId, max: u32) -> Result<u64, Stop> {
        let start = self.rpos;
        let len = self.input.map_or(0, |i| i.bit_len());
        let mut n = 0;
        while len.saturating_sub(self.rpos) >= 8 {
            if n == max {
                let too_long = ErrorKind::ArrayTooLong {
                    len: u64::from(n) + 1,
                    max,
                };
                return Err(self.fail(too_long));
            }
            let node = self.layout.node(elem);
            if node.fixed_leaves().is_some() {
                // Any fault in it is found when it is read.
                self.rpos += node.min_bits as usize;
            } else {
                let skip = How {
                    mode: Mode::Skip,
                    rtao: false,
                    wtao: false,
                };
                self.node(elem, Some(Step::Index(n)), skip)?;
            }
            n += 1;
        }
        self.rpos = start;
        Ok(n.into())
    }
}

/// Writes the low `bits` bits of `raw` at bit `pos` of `out` as a DroneCAN scalar (its bytes
/// least significant first, the top bits last, each most significant bit first), a byte at a
/// time into the two bytes it may span; the caller checks that `out` holds them.
pub(crate) fn put(out: &mut [u8], mut pos: usize, raw: u64, bits: u32) {
    let (mut value, end) = (raw, pos + bits as usize);
    while pos < end {
        let n = (end - pos).min(8) as u32;
        let (i, s) = (pos / 8, (pos % 8) as u32);
        let place = 16 - n - s;
        let bits = ((value as u32) & ((1 << n) - 1)) << place;
        let keep = !(((1u32 << n) - 1) << place);
        out[i] = (u32::from(out[i]) & (keep >> 8)) as u8 | (bits >> 8) as u8;
        if s + n > 8 {
            out[i + 1] = (u32::from(out[i + 1]) & keep) as u8 | bits as u8;
        }
        value >>= 8;
        pos += n as usize;
    }
}

/// The error of a walk whose visit refuses nothing.
fn plain(e: Error<LeafError>) -> LeafAccessError {
    Error {
        kind: e.kind.map_value(|_| ErrorKind::TooDeep),
        bit_offset: e.bit_offset,
        path: e.path,
    }
}

/// Collects the leaves read.
struct Collect<'s> {
    leaves: &'s mut [Scalar],
    len: usize,
}

impl Visit for Collect<'_> {
    fn leaf(&mut self, _: &LeafAt<'_>, old: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        let slot = self.leaves.get_mut(self.len).ok_or(Halt::Refused)?;
        *slot = old.unwrap_or(Scalar::Uint(0));
        self.len += 1;
        Ok(None)
    }

    fn refusal(&self) -> ErrorKind<LeafError> {
        ErrorKind::Value(LeafError::Full)
    }
}

/// Supplies the leaves written, in order.
struct Supply<'s> {
    leaves: &'s [Scalar],
    next: usize,
}

impl Visit for Supply<'_> {
    fn leaf(&mut self, _: &LeafAt<'_>, _: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        let v = *self.leaves.get(self.next).ok_or(Halt::Refused)?;
        self.next += 1;
        Ok(Some(v))
    }

    fn refusal(&self) -> ErrorKind<LeafError> {
        ErrorKind::Value(LeafError::Exhausted)
    }
}

/// Decodes a value of type `root` from `data` into the flat leaf list `leaves` (what
/// [`crate::codec::decode`] with a [`crate::value::LeafSink`] gives).
pub fn decode<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    leaves: &mut [Scalar],
    options: DecodeOptions,
) -> Result<Decoded, Error<LeafError>> {
    let mut collect = Collect { leaves, len: 0 };
    let bits = Bits(data);
    let job = Job::reading(&bits, options.tao, None);
    let end = run(layout, root, job, &mut collect)?.read;
    let (used, len) = (end.div_ceil(8), BitRead::bit_len(data) / 8);
    if !options.allow_trailing && len > used {
        return Err(Error {
            kind: ErrorKind::TrailingBytes { used, len },
            bit_offset: end,
            path: Path::default(),
        });
    }
    Ok(Decoded {
        bits: end,
        leaves: collect.len,
    })
}

/// Encodes the value of type `root` given as the flat leaf list `leaves` into `out`; returns
/// its length in bytes (what [`crate::codec::encode`] with a [`crate::value::LeafSource`]
/// gives).
pub fn encode(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<LeafError>> {
    let mut supply = Supply { leaves, next: 0 };
    write_whole(layout, root, None, out, options, &mut supply)
}

/// A walk that writes a whole value into `out` (reading `input` if any); its length in bytes,
/// the last byte's unused bits zero.
fn write_whole(
    layout: &Layout<'_>,
    root: NodeId,
    input: Option<&dyn Input>,
    out: &mut [u8],
    options: EncodeOptions,
    visit: &mut dyn Visit,
) -> Result<usize, Error<LeafError>> {
    let job = Job {
        input,
        out: &mut *out,
        writing: true,
        skip_below: None,
        options,
    };
    let end = run(layout, root, job, visit)?.written;
    let bytes = end.div_ceil(8);
    if end % 8 != 0 {
        // The last byte's unused bits.
        out[end / 8] &= 0xFF << (8 - end % 8);
    }
    Ok(bytes)
}

/// Finds a leaf: by number, or (when `path` is set) by field path and kind of leaf.
struct Find<'p> {
    /// The data's length in bits.
    bit_len: usize,
    /// Where a leaf that lies beyond the data starts.
    beyond: usize,
    k: usize,
    path: Option<(&'p Path, LeafClass)>,
    found: Option<(Leaf, Scalar, bool)>,
}

/// Which leaf of a node a path names: the node itself, or its tag or length.
#[derive(Clone, Copy, PartialEq, Eq)]
enum LeafClass {
    Scalar,
    Tag,
    Len,
}

fn class(kind: LeafKind) -> LeafClass {
    match kind {
        LeafKind::Scalar(_) => LeafClass::Scalar,
        LeafKind::Tag { .. } => LeafClass::Tag,
        LeafKind::Len { .. } => LeafClass::Len,
    }
}

impl Visit for Find<'_> {
    fn leaf(&mut self, at: &LeafAt<'_>, old: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        let hit = match self.path {
            Some((path, leaf)) => at.path == path && class(at.kind) == leaf,
            None => at.index == self.k,
        };
        if !hit {
            return Ok(None);
        }
        if at.bit_offset > self.bit_len {
            // A tail array's length, after parts passed over unread that end beyond the data.
            self.beyond = at.bit_offset;
            return Err(Halt::Refused);
        }
        let leaf = Leaf {
            index: at.index,
            bit_offset: at.bit_offset,
            kind: at.kind,
            path: *at.path,
        };
        self.found = Some((leaf, old.unwrap_or(Scalar::Uint(0)), at.version.is_some()));
        Err(Halt::Found)
    }

    fn refusal(&self) -> ErrorKind<LeafError> {
        ErrorKind::Truncated {
            needed_bits: self.beyond,
            available_bits: self.bit_len,
        }
    }
}

fn find<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    find: &mut Find<'_>,
    tao: bool,
) -> Result<(Leaf, Scalar, bool), LeafAccessError> {
    let skip_below = find.path.is_none().then_some(find.k);
    let bits = Bits(data);
    let job = Job::reading(&bits, tao, skip_below);
    let walked = run(layout, root, job, find).map_err(plain)?;
    find.found.ok_or(Error {
        kind: ErrorKind::NoSuchLeaf {
            index: find.k,
            count: walked.leaves,
        },
        bit_offset: walked.read,
        path: Path::default(),
    })
}

/// Finds leaf `[k]` of `data`, a value of type `root`, and reads it (what
/// [`crate::leaf::get_leaf`] gives for [`crate::leaf::Target::Index`]).
pub fn locate<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    let mut found = Find {
        bit_len: BitRead::bit_len(data),
        beyond: 0,
        k,
        path: None,
        found: None,
    };
    let (leaf, value, _) = find(layout, root, data, &mut found, tao)?;
    Ok((leaf, value))
}

/// Where leaf `[k]` is (what [`crate::leaf::seek`] gives); `None` where [`locate`] fails.
pub fn seek<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
) -> Option<Position> {
    let mut found = Find {
        bit_len: BitRead::bit_len(data),
        beyond: 0,
        k,
        path: None,
        found: None,
    };
    let (leaf, _, version) = find(layout, root, data, &mut found, false).ok()?;
    Some(Position {
        bit_offset: leaf.bit_offset,
        kind: leaf.kind,
        version: version && matches!(leaf.kind, LeafKind::Scalar(_)),
    })
}

/// Replaces leaf `[k]` and checks its new value.
struct Edit<'l> {
    layout: &'l Layout<'l>,
    k: usize,
    value: Scalar,
    /// The number of variants, or the array's maximum plus one, the value is not below.
    limit: u64,
}

impl Visit for Edit<'_> {
    fn leaf(&mut self, at: &LeafAt<'_>, _: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        if at.index != self.k {
            return Ok(None);
        }
        // A tag or length must select a variant or fit the array.
        let limit = match at.kind {
            LeafKind::Tag { union, .. } => match self.layout.node(union).kind {
                Kind::Union { count, .. } => u64::from(count),
                _ => 0,
            },
            LeafKind::Len { array, .. } => match self.layout.node(array).kind {
                Kind::DynArray { max, .. } => u64::from(max) + 1,
                _ => 0,
            },
            LeafKind::Scalar(_) => return Ok(Some(self.value)),
        };
        self.limit = limit;
        match self.value {
            Scalar::Uint(v) if v < limit => Ok(Some(self.value)),
            Scalar::Int(v) if v >= 0 && (v as u64) < limit => Ok(Some(self.value)),
            _ => Err(Halt::Refused),
        }
    }

    fn refusal(&self) -> ErrorKind<LeafError> {
        ErrorKind::Scalar(ScalarError::OutOfRange {
            value: self.value,
            min: Scalar::Uint(0),
            max: Scalar::Uint(self.limit.saturating_sub(1)),
        })
    }
}

/// Re-encodes `data` (a value of `root`) into `out` with leaf `[k]` set to `value`: a new
/// union tag selects that variant with its default value, a new array length drops elements
/// at the end or appends default ones. Returns the new length in bytes.
pub fn transcode<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    value: Scalar,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, LeafAccessError> {
    let mut edit = Edit {
        layout,
        k,
        value,
        limit: 0,
    };
    write_whole(layout, root, Some(&Bits(data)), out, options, &mut edit).map_err(plain)
}

/// Writes the default value of `root` into `out`: zeros, `p_version` set to the type's
/// version, the first union variant, empty dynamic arrays. Returns the length in bytes.
pub fn encode_default(
    layout: &Layout<'_>,
    root: NodeId,
    out: &mut [u8],
    tao: bool,
) -> Result<usize, LeafAccessError> {
    struct Defaults;
    impl Visit for Defaults {
        fn leaf(&mut self, _: &LeafAt<'_>, _: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
            Ok(None)
        }
    }
    let options = EncodeOptions {
        tao,
        ..EncodeOptions::default()
    };
    write_whole(layout, root, None, out, options, &mut Defaults).map_err(plain)
}

/// Checks that `data` is exactly one value of `root` stored without tail array optimization
/// whose `p_version` fields hold the type's version.
pub fn check_versions(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
) -> Result<(), Error<Infallible>> {
    struct Versions(Scalar, u32);
    impl Visit for Versions {
        fn leaf(&mut self, at: &LeafAt<'_>, old: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
            match (at.version, old) {
                (Some(expected), Some(given)) if !scalar::same_integer(given, expected) => {
                    *self = Versions(given, expected);
                    Err(Halt::Refused)
                }
                _ => Ok(None),
            }
        }

        fn refusal(&self) -> ErrorKind<LeafError> {
            ErrorKind::VersionMismatch {
                given: self.0,
                expected: self.1,
            }
        }
    }
    let bits = Bits(data);
    let job = Job::reading(&bits, false, None);
    let end = run(layout, root, job, &mut Versions(Scalar::Uint(0), 0))
        .map_err(plain)?
        .read;
    let (used, len) = (end.div_ceil(8), data.len());
    if len > used {
        return Err(Error {
            kind: ErrorKind::TrailingBytes { used, len },
            bit_offset: end,
            path: Path::default(),
        });
    }
    Ok(())
}

/// Reads the leaf at `path` (its node's own value, tag or length) of `data`, a value of
/// `root` stored without tail array optimization.
fn read_at<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    path: &Path,
    leaf: LeafClass,
) -> Result<Scalar, Halt> {
    let mut found = Find {
        bit_len: BitRead::bit_len(data),
        beyond: 0,
        k: 0,
        path: Some((path, leaf)),
        found: None,
    };
    // Not there: the stored value holds less than the walk asks of it.
    match find(layout, root, data, &mut found, false) {
        Ok((_, value, _)) => Ok(value),
        Err(_) => Err(Halt::Refused),
    }
}

/// What a node holds, for telling a field that changed its kind of value.
fn shape(layout: &Layout<'_>, id: NodeId) -> u8 {
    match layout.node(id).kind {
        Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool => 0,
        Kind::Struct { .. } => 1,
        Kind::Union { .. } => 2,
        Kind::Array { .. } | Kind::DynArray { .. } => 3,
        Kind::Void { .. } => 4,
    }
}

/// Supplies the leaves of the new version of a value: each from the old value where it has
/// the same field (by name, holding the same kind of value), else from the base.
struct Carry<'a, R: ?Sized, B: ?Sized> {
    layout: &'a Layout<'a>,
    old_root: NodeId,
    old_data: &'a R,
    new_root: NodeId,
    base: &'a B,
    /// A static array the old value has with another length: that length, and the new one.
    wrong_len: Option<(u64, u32)>,
}

impl<R: BitRead + ?Sized, B: BitRead + ?Sized> Carry<'_, R, B> {
    /// The old value's node at `path` of the new type, with its path in the old value.
    fn old_at(&self, path: &Path) -> Result<(Option<NodeId>, Path), Halt> {
        let layout = self.layout;
        let (mut new, mut old) = (self.new_root, Some(self.old_root));
        let mut steps = Path::default();
        for step in path.steps() {
            let (next, carried) = match step {
                Step::Field(f) => {
                    let field = layout.fields[f as usize];
                    let name = layout.name(&field);
                    let member = match (layout.node(new).kind, old) {
                        // A union keeps the old value's variant only where the old value
                        // selects one of that name.
                        (Kind::Union { .. }, Some(o)) => {
                            let tag = read_at(
                                layout,
                                self.old_root,
                                self.old_data,
                                &steps,
                                LeafClass::Tag,
                            )?;
                            let selected = match (layout.node(o).kind, tag) {
                                (Kind::Union { first, .. }, Scalar::Uint(t)) => layout
                                    .members(o)
                                    .get(t as usize)
                                    .map(|v| (first + t as u32, v)),
                                _ => None,
                            };
                            selected
                                .filter(|(_, v)| layout.name(v) == name)
                                .map(|(i, _)| i)
                        }
                        (_, Some(o)) => layout.member_index(o, name),
                        (_, None) => None,
                    };
                    let carried = member
                        .map(|i| (i, layout.fields[i as usize].node))
                        .filter(|&(_, node)| shape(layout, node) == shape(layout, field.node));
                    if let Some((i, _)) = carried {
                        steps.push(Step::Field(i));
                    }
                    (field.node, carried.map(|(_, node)| node))
                }
                Step::Index(i) => {
                    let elem = |id: NodeId| match layout.node(id).kind {
                        Kind::Array { elem, .. } | Kind::DynArray { elem, .. } => Some(elem),
                        _ => None,
                    };
                    let carried = old.and_then(elem);
                    if carried.is_some() {
                        steps.push(Step::Index(i));
                    }
                    (elem(new).unwrap_or(new), carried)
                }
            };
            (new, old) = (next, carried);
        }
        Ok((old, steps))
    }

    /// The old value's length of the array at `path`, if it has an array there.
    fn old_len(&self, old: Option<NodeId>, steps: &Path) -> Result<Option<u64>, Halt> {
        Ok(match old.map(|o| self.layout.node(o).kind) {
            Some(Kind::Array { len, .. }) => Some(len.into()),
            Some(Kind::DynArray { .. }) => {
                let len = read_at(
                    self.layout,
                    self.old_root,
                    self.old_data,
                    steps,
                    LeafClass::Len,
                )?;
                match len {
                    Scalar::Uint(n) => Some(n),
                    _ => None,
                }
            }
            _ => None,
        })
    }
}

impl<R: BitRead + ?Sized, B: BitRead + ?Sized> Visit for Carry<'_, R, B> {
    fn leaf(&mut self, at: &LeafAt<'_>, _: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        if let Some(version) = at.version {
            return Ok(Some(Scalar::Uint(version.into())));
        }
        let layout = self.layout;
        let (old, steps) = self.old_at(at.path)?;
        let carried = match (at.kind, old) {
            (LeafKind::Scalar(_), Some(o)) if shape(layout, o) == 0 => Some(read_at(
                layout,
                self.old_root,
                self.old_data,
                &steps,
                LeafClass::Scalar,
            )?),
            (LeafKind::Tag { union, .. }, Some(o)) => {
                // The old variant, where the new type has one of that name and kind.
                let tag = read_at(layout, self.old_root, self.old_data, &steps, LeafClass::Tag)?;
                let variant = match tag {
                    Scalar::Uint(t) => layout.members(o).get(t as usize),
                    _ => None,
                };
                variant.and_then(|v| {
                    layout
                        .members(union)
                        .iter()
                        .position(|n| {
                            layout.name(n) == layout.name(v)
                                && shape(layout, n.node) == shape(layout, v.node)
                        })
                        .map(|i| Scalar::Uint(i as u64))
                })
            }
            (LeafKind::Len { .. }, old) => self.old_len(old, &steps)?.map(Scalar::Uint),
            _ => None,
        };
        match carried {
            Some(value) => Ok(Some(value)),
            None => read_at(layout, self.new_root, self.base, at.path, class(at.kind)).map(Some),
        }
    }

    fn fixed_len(&mut self, path: &Path, len: u32) -> Result<(), Halt> {
        let (old, steps) = self.old_at(path)?;
        match self.old_len(old, &steps)? {
            Some(n) if n != u64::from(len) => {
                self.wrong_len = Some((n, len));
                Err(Halt::Refused)
            }
            _ => Ok(()),
        }
    }

    fn refusal(&self) -> ErrorKind<LeafError> {
        match self.wrong_len {
            Some((len, expected)) => ErrorKind::WrongArrayLength { len, expected },
            // A leaf the old value or the base does not hold (TranslateError::Unreadable).
            None => ErrorKind::Value(LeafError::Exhausted),
        }
    }
}

/// Encodes into `out` the value of type `new` that `old_data` (a value of type `old`, stored
/// without tail array optimization) becomes, with what `new` added taken from `base` (a value
/// of `new`, same encoding): what [`crate::translate::translate`] writes, without its report.
/// Returns the length in bytes.
pub fn translate<R: BitRead + ?Sized, B: BitRead + ?Sized>(
    layout: &Layout<'_>,
    old: NodeId,
    old_data: &R,
    new: NodeId,
    base: &B,
    out: &mut [u8],
) -> Result<usize, Error<TranslateError>> {
    let mut carry = Carry {
        layout,
        old_root: old,
        old_data,
        new_root: new,
        base,
        wrong_len: None,
    };
    let options = EncodeOptions {
        tao: false,
        saturate: false,
        keep_versions: false,
    };
    let written = write_whole(layout, new, None, out, options, &mut carry);
    written.map_err(|e| Error {
        kind: e
            .kind
            .map_value(|_| ErrorKind::Value(TranslateError::Unreadable)),
        bit_offset: e.bit_offset,
        path: e.path,
    })
}
