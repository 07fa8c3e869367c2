//! The straight-line plan for small fixed-shape types: a struct whose fields are a run of
//! fixed-offset primitives (the layout's one flat segment), optionally ended by a dynamic
//! array of primitives: `uavcan.protocol.NodeStatus`, a `uavcan.protocol.file.Read`
//! response, `BatteryInfo`.
//!
//! Such a value is encoded and decoded in one pass over the segment's compiled items, without
//! the walk's per-node dispatch, path keeping or source and sink calls per field: what
//! remains per call is the few checks that decide whether the plan can answer at all. A plan
//! answers or declines ([`None`]); it never words an error. It looks before it writes
//! anything to the caller: the leaves are read before any is taken from the source, the data
//! is measured before the sink gives its slots, so that on a decline the dispatcher
//! ([`crate::codec::encode`], [`crate::codec::decode`]) runs the general path from where the
//! call began, and that path words the error. Firmware (`NoPlans`) does not run this plan
//! ([`crate::plan::Plans::STRAIGHT`]).

use crate::bits::{
    self, from_stream, halves, join, load_word, store_word, to_stream, Ahead, BitRead, BitReader,
    Order, Pending,
};
use crate::layout::{FlatItem, Kind, Layout, NodeId, Role, Segment, Span};
use crate::rules::{
    scalar_bits, scalar_of, scalar_raw, tail_elements, tail_qualifies, DecodeOptions,
    EncodeOptions, Sink, Source, MAX_DEPTH,
};
use crate::scalar::{self, Scalar};

pub use crate::layout::Straight;
use crate::layout::{Op, Small, Step, Tail, SMALL_STEPS};

/// The straight-line plan of `root` in `layout`, where the plan answers for it. The
/// compiler splits a struct's fields into segments in field order (as the flat codec
/// trusts): a flat run, then perhaps one field of another shape, which must be the last
/// field and a dynamic array of primitives (it alone may be tail-optimized).
pub fn compile(layout: &Layout<'_>, root: NodeId) -> Option<Straight> {
    let node = layout.nodes.get(root as usize)?;
    let Kind::Struct { first, count } = node.kind else {
        return None;
    };
    let mut plan = Straight {
        items: Span::default(),
        leaves: 0,
        bits: 0,
        tail: None,
        small: None,
    };
    let last = match node.segments.of(layout.segments) {
        [Segment::Flat {
            items,
            leaves,
            bits,
            height,
            ..
        }, rest @ ..] => {
            // The root is at depth 1: a run deeper than the walk follows is the walk's to
            // refuse.
            if items.of(layout.flat).len() != items.count as usize
                || 1 + *height as usize > MAX_DEPTH
            {
                return None;
            }
            plan.items = *items;
            plan.leaves = *leaves;
            plan.bits = *bits;
            plan.small = small(items.of(layout.flat), *bits);
            match rest {
                [] => return Some(plan),
                [Segment::Field(i)] => *i,
                _ => return None,
            }
        }
        [Segment::Field(i)] => {
            plan.small = small(&[], 0);
            *i
        }
        [] => return Some(plan),
        _ => return None,
    };
    if u64::from(last) + 1 != u64::from(first) + u64::from(count) {
        return None;
    }
    let field = layout.fields.get(last as usize)?;
    let Kind::DynArray {
        elem,
        max,
        len_bits,
    } = layout.nodes.get(field.node as usize)?.kind
    else {
        return None;
    };
    let elem_node = layout.nodes.get(elem as usize)?;
    let elem_bits = match elem_node.kind {
        Kind::Uint { bits, .. } | Kind::Int { bits, .. } | Kind::Float { bits, .. } => {
            u32::from(bits)
        }
        Kind::Bool => 1,
        _ => return None,
    };
    if elem_bits == 0 || field.role != Role::Data {
        return None;
    }
    plan.tail = Some(Tail {
        elem: elem_node.kind,
        elem_bits,
        max,
        prefixes: [
            len_bits,
            if tail_qualifies(elem_node.min_bits) {
                0
            } else {
                len_bits
            },
        ],
        bytes: matches!(elem_node.kind, Kind::Uint { bits: 8, .. }),
    });
    Some(plan)
}

/// The steps of a fixed run of `bits` bits, where it has at most [`SMALL_STEPS`] items and
/// 64 bits.
fn small(items: &[FlatItem], bits: u32) -> Option<Small> {
    if bits > 64 || items.len() > SMALL_STEPS {
        return None;
    }
    let mut small = Small {
        steps: [Step::default(); SMALL_STEPS],
        version: 0,
    };
    let mut versions = 0;
    for (step, item) in small.steps.iter_mut().zip(items) {
        *step = match *item {
            FlatItem::Pad(bits) => Step {
                op: Op::Pad,
                bits,
                order: Order::Same,
            },
            // One version that fits its field: others are the general path's.
            FlatItem::Version(Kind::Uint { bits, .. }, version)
                if versions == 0 && u64::from(version) <= u64::MAX >> (64 - u32::from(bits)) =>
            {
                versions += 1;
                small.version = version;
                Step {
                    op: Op::Version,
                    bits,
                    order: Order::Same,
                }
            }
            FlatItem::Version(..) => return None,
            FlatItem::Leaf(kind) => {
                let op = match kind {
                    Kind::Uint { .. } => Op::Uint,
                    Kind::Int { .. } => Op::Int,
                    Kind::Float { bits: 16, .. } => Op::Float16,
                    Kind::Float { bits: 32, .. } => Op::Float32,
                    Kind::Float { .. } => Op::Float64,
                    Kind::Bool => Op::Bool,
                    _ => return None,
                };
                Step {
                    op,
                    bits: scalar_bits(kind) as u8,
                    order: Order::Same,
                }
            }
        };
        if step.bits == 0 {
            return None;
        }
        step.order = Order::of(step.bits.into());
    }
    Some(small)
}

/// The raw bits of `value` for a primitive `kind` (in the kind's width); `None` where the
/// general path has something to say (out of range, wrong kind, a rejected cast).
#[inline(always)]
fn raw_of(kind: &Kind, value: &Scalar, saturate: bool) -> Option<u64> {
    // The common cases without the casting rules: an integer in range, a float that is finite
    // and in range (NaN compares false and takes the general rules, as do infinities).
    match (kind, value) {
        (&Kind::Uint { bits, .. }, &Scalar::Uint(v)) if v <= u64::MAX >> (64 - u32::from(bits)) => {
            Some(v)
        }
        (&Kind::Int { bits, .. }, &Scalar::Int(v))
            if scalar::sign_extend(v as u64, bits.into()) == v =>
        {
            Some(v as u64 & (u64::MAX >> (64 - u32::from(bits))))
        }
        (&Kind::Float { bits: 16, .. }, &Scalar::Float(v)) if v.abs() <= scalar::FLOAT16_MAX => {
            Some(u64::from(scalar::f16_from_f32(v as f32)))
        }
        (&Kind::Float { bits: 32, .. }, &Scalar::Float(v)) if v.abs() <= f64::from(f32::MAX) => {
            Some(u64::from((v as f32).to_bits()))
        }
        (&Kind::Bool, &Scalar::Bool(b)) => Some(u64::from(b)),
        _ => cast(*kind, *value, saturate),
    }
}

/// [`raw_of`] by the casting rules (saturation, truncation, the other kinds of value).
#[cold]
#[inline(never)]
fn cast(kind: Kind, value: Scalar, saturate: bool) -> Option<u64> {
    scalar_raw(kind, value, saturate).ok()
}

/// A `p_version` leaf's raw bits: the type's own version unless versions are kept as given
/// (the general path words a mismatch).
#[cold]
#[inline(never)]
fn version_raw(kind: Kind, value: Scalar, version: u32, options: EncodeOptions) -> Option<u64> {
    if options.keep_versions {
        raw_of(&kind, &value, options.saturate)
    } else if scalar::same_integer(value, version) {
        raw_of(&kind, &Scalar::Uint(version.into()), false)
    } else {
        None
    }
}

/// The bits of `value` for a primitive `kind` in stream order, and how many; `None` where
/// the general path has something to say (out of range, wrong kind, a rejected cast). Each
/// kind's own width, so that the byte order's shifts are constants.
#[inline(always)]
fn stream_of(kind: &Kind, value: &Scalar, saturate: bool) -> Option<(u64, u32)> {
    let (raw, bits) = match (kind, value) {
        (&Kind::Uint { bits, .. }, &Scalar::Uint(v)) if v <= u64::MAX >> (64 - u32::from(bits)) => {
            (v, u32::from(bits))
        }
        (&Kind::Int { bits, .. }, &Scalar::Int(v))
            if scalar::sign_extend(v as u64, bits.into()) == v =>
        {
            (
                v as u64 & (u64::MAX >> (64 - u32::from(bits))),
                u32::from(bits),
            )
        }
        (&Kind::Float { bits: 16, .. }, &Scalar::Float(v)) if v.abs() <= scalar::FLOAT16_MAX => {
            (u64::from(scalar::f16_from_f32(v as f32)), 16)
        }
        (&Kind::Float { bits: 32, .. }, &Scalar::Float(v)) if v.abs() <= f64::from(f32::MAX) => {
            (u64::from((v as f32).to_bits()), 32)
        }
        (&Kind::Bool, &Scalar::Bool(b)) => (u64::from(b), 1),
        _ => return cast_stream(*kind, *value, saturate),
    };
    Some((to_stream(raw, bits), bits))
}

/// [`stream_of`] by the casting rules (saturation, truncation, the other kinds of value).
#[cold]
#[inline(never)]
fn cast_stream(kind: Kind, value: Scalar, saturate: bool) -> Option<(u64, u32)> {
    let bits = scalar_bits(kind);
    Some((to_stream(cast(kind, value, saturate)?, bits), bits))
}

/// Bits going out most significant first into a buffer holding exactly the value: fewer than
/// 32 wait in a register ([`Pending`]) between fields, 32 are stored at a time.
struct Out<'o> {
    out: &'o mut [u8],
    at: usize,
    pending: Pending,
}

impl Out<'_> {
    /// Appends `bits` (`<= 64`) bits of a stream value that fits them.
    #[inline(always)]
    fn put(&mut self, stream: u64, bits: u32) {
        if bits > 32 {
            let [(first, k), (rest, _)] = halves(stream, bits);
            self.put32(first, k);
            self.put32(rest, 32);
        } else {
            self.put32(stream, bits);
        }
    }

    #[inline(always)]
    fn put32(&mut self, stream: u64, bits: u32) {
        if let Some(word) = self.pending.push(stream, bits) {
            if let Some(slot) = self.out.get_mut(self.at..self.at + 4) {
                slot.copy_from_slice(&word);
            }
            self.at += 4;
        }
    }

    /// Stores the whole bytes pending (none left over), for bytes copied after them.
    #[inline(always)]
    fn flush_bytes(&mut self) {
        while self.pending.count() >= 8 {
            let byte = self.pending.pop_byte();
            if let Some(slot) = self.out.get_mut(self.at) {
                *slot = byte;
            }
            self.at += 1;
        }
    }

    /// Stores 32 of the pending bits when 32 or more are pending (at most 64), so that
    /// [`Out::put`] and [`Out::finish`] find fewer.
    #[inline(always)]
    fn spill(&mut self) {
        self.put32(0, 0);
    }

    /// Stores the pending bits (at most 32), the last byte padded with zeros: one store
    /// of one to four bytes.
    #[inline(always)]
    fn finish(self) {
        let (word, n) = self.pending.last_bytes();
        let at = self.at;
        let out = self.out;
        match n {
            0 => {}
            1 => {
                if let Some(b) = out.get_mut(at) {
                    *b = word[0];
                }
            }
            2 => {
                if let Some(b) = out.get_mut(at..at + 2) {
                    b.copy_from_slice(&word[..2]);
                }
            }
            3 => {
                if let Some(b) = out.get_mut(at..at + 3) {
                    b.copy_from_slice(&word[..3]);
                }
            }
            _ => {
                if let Some(b) = out.get_mut(at..at + 4) {
                    b.copy_from_slice(&word);
                }
            }
        }
    }
}

/// A dynamic array's length leaf, as a flat leaf list gives it (a non-negative integer).
#[inline(always)]
fn count_of(leaf: Scalar) -> Option<usize> {
    match leaf {
        Scalar::Uint(v) => usize::try_from(v).ok(),
        Scalar::Int(v) => usize::try_from(v).ok(),
        _ => None,
    }
}

/// Encodes the value of `root` from a flat `source` into `out` when the plan answers for
/// it: the length in bytes, the leaves taken from the source as the general path takes
/// them. `None` (nothing taken, nothing to report) for anything else: a type of another
/// shape, a source that is not a flat leaf list, too few leaves, a value the DroneCAN rules
/// refuse or would cast, a buffer too small.
#[inline(never)]
pub fn encode<S: Source>(
    layout: &Layout<'_>,
    root: NodeId,
    source: &mut S,
    out: &mut [u8],
    options: EncodeOptions,
) -> Option<usize> {
    let plan = layout.straight.get(root as usize)?.as_ref()?;
    let leaves = source.pending_leaves()?;
    let (len, taken) = match &plan.small {
        Some(small) => encode_small(plan, small, leaves, out, options)?,
        None => encode_leaves(plan, plan.items.of(layout.flat), leaves, out, options)?,
    };
    // Take what was used, as the general path does (leaves after the value stay).
    source.leaf_run(taken)?.ok()?;
    Some(len)
}

/// [`encode`] of a small plan from its leaves: the length in bytes and the leaves used.
#[inline(always)]
fn encode_small(
    plan: &Straight,
    small: &Small,
    leaves: &[Scalar],
    out: &mut [u8],
    options: EncodeOptions,
) -> Option<(usize, usize)> {
    let fixed_leaves = plan.leaves as usize;
    let mut values = leaves.get(..fixed_leaves)?.iter();
    let mut acc = 0u64;
    let keep_versions = options.keep_versions;
    for step in &small.steps {
        let bits = u32::from(step.bits);
        if bits == 0 {
            break;
        }
        let raw = match step.op {
            Op::Pad => 0,
            op => step_raw(op, bits, values.next()?, small.version, keep_versions)?,
        };
        // A 64-bit step is the run's only one: nothing to shift out.
        acc = step.order.append(acc, raw, bits);
    }
    let Some(tail) = &plan.tail else {
        let len = (plan.bits as usize).div_ceil(8);
        store_word(out.get_mut(..len)?, acc, plan.bits);
        return Some((len, fixed_leaves));
    };
    let n = count_of(*leaves.get(fixed_leaves)?)?;
    if n > tail.max as usize {
        return None;
    }
    let prefix = tail.prefix(options.tao);
    let elements = leaves.get(fixed_leaves + 1..fixed_leaves + 1 + n)?;
    let head = plan.bits + prefix;
    let len = (head as usize + n * tail.elem_bits as usize).div_ceil(8);
    let out = out.get_mut(..len)?;
    if head <= 64 && (n == 0 || (tail.bytes && head % 8 == 0)) {
        // The run and the length in one store, then the bytes.
        if prefix != 0 {
            acc = join(acc, n as u64, prefix);
        }
        store_word(out, acc, head);
        if n != 0 {
            copy_bytes(out.get_mut(head as usize / 8..)?, elements)?;
        }
    } else {
        encode_tail(plan, tail, acc, prefix, elements, out, options.saturate)?;
    }
    Some((len, fixed_leaves + 1 + n))
}

/// The raw bits of a leaf for a [`Step`] of `bits` bits where they need no casting rules;
/// `None` for the others (the general path casts, or words why not).
#[inline(always)]
fn step_raw(op: Op, bits: u32, value: &Scalar, version: u32, keep_versions: bool) -> Option<u64> {
    // The common cases without the casting rules, as in `raw_of`.
    match (op, *value) {
        (Op::Uint, Scalar::Uint(v)) if v <= u64::MAX >> (64 - bits) => Some(v),
        (Op::Int, Scalar::Int(v)) if scalar::sign_extend(v as u64, bits) == v => {
            Some(v as u64 & (u64::MAX >> (64 - bits)))
        }
        (Op::Bool, Scalar::Bool(b)) => Some(u64::from(b)),
        (Op::Float16 | Op::Float32 | Op::Float64, Scalar::Float(v)) => float_raw(op, v),
        (Op::Version, value) => version_step(bits, value, version, keep_versions),
        _ => None,
    }
}

/// [`step_raw`] of a float that needs no cast: in range, infinite or NaN (out of line: most
/// small types have none, and their constants would load on every call). A finite value
/// out of range is the casting rules'.
#[inline(never)]
fn float_raw(op: Op, v: f64) -> Option<u64> {
    match op {
        Op::Float16 if v.abs() <= scalar::FLOAT16_MAX || !v.is_finite() => {
            Some(u64::from(scalar::f16_from_f32(v as f32)))
        }
        Op::Float32 if v.abs() <= f64::from(f32::MAX) || !v.is_finite() => {
            Some(u64::from((v as f32).to_bits()))
        }
        Op::Float64 => Some(v.to_bits()),
        _ => None,
    }
}

/// [`step_raw`] of a `p_version` field: the type's version (which fits the field) where the
/// value is it, or the value kept as given where it fits.
#[cold]
#[inline(never)]
fn version_step(bits: u32, value: Scalar, version: u32, keep_versions: bool) -> Option<u64> {
    match value {
        Scalar::Uint(v) if keep_versions => (v <= u64::MAX >> (64 - bits)).then_some(v),
        _ if keep_versions => None,
        _ => scalar::same_integer(value, version).then_some(version.into()),
    }
}

/// Bytes given as leaves into `out` (which has room for them); `None` for a leaf that is
/// not a byte.
#[inline(always)]
fn copy_bytes(out: &mut [u8], elements: &[Scalar]) -> Option<()> {
    for (byte, v) in out.iter_mut().zip(elements) {
        match *v {
            Scalar::Uint(b) if b <= 0xFF => *byte = b as u8,
            _ => return None,
        }
    }
    Some(())
}

/// The ending array of a small plan in the general way: `acc` holds the fixed run.
#[inline(never)]
fn encode_tail(
    plan: &Straight,
    tail: &Tail,
    acc: u64,
    prefix: u32,
    elements: &[Scalar],
    out: &mut [u8],
    saturate: bool,
) -> Option<()> {
    let mut out = Out {
        out,
        at: 0,
        pending: Pending::new(acc, plan.bits),
    };
    out.spill();
    if prefix != 0 {
        out.put(elements.len() as u64, prefix);
    }
    if !elements.is_empty() {
        write_elements(&mut out, &tail.elem, elements, saturate)?;
    }
    out.finish();
    Some(())
}

/// [`encode`] of a plan from its leaves: the length in bytes and the leaves used.
#[inline(never)]
fn encode_leaves(
    plan: &Straight,
    items: &[FlatItem],
    leaves: &[Scalar],
    out: &mut [u8],
    options: EncodeOptions,
) -> Option<(usize, usize)> {
    let fixed_leaves = plan.leaves as usize;
    let fixed = leaves.get(..fixed_leaves)?;
    let (bits, prefix, elements) = match &plan.tail {
        None => (plan.bits as usize, 0, &[][..]),
        Some(tail) => {
            let n = count_of(*leaves.get(fixed_leaves)?)?;
            if n > tail.max as usize {
                return None;
            }
            let prefix = tail.prefix(options.tao);
            (
                plan.bits as usize + prefix as usize + n * tail.elem_bits as usize,
                prefix,
                leaves.get(fixed_leaves + 1..fixed_leaves + 1 + n)?,
            )
        }
    };
    let len = bits.div_ceil(8);
    let mut out = Out {
        out: out.get_mut(..len)?,
        at: 0,
        pending: Pending::default(),
    };
    let saturate = options.saturate;
    // As many items as leaves and pads: the zip never stops short of a leaf item.
    let mut values = fixed.iter();
    for item in items {
        let (stream, bits) = item_stream(item, &mut values, options)?;
        out.put(stream, bits);
    }
    if let Some(tail) = &plan.tail {
        if prefix != 0 {
            out.put(elements.len() as u64, prefix);
        }
        if !elements.is_empty() {
            write_elements(&mut out, &tail.elem, elements, saturate)?;
        }
    }
    out.finish();
    Some((
        len,
        fixed_leaves + plan.tail.map_or(0, |_| 1 + elements.len()),
    ))
}

/// The stream bits of one item of the fixed run and how many, its leaf (if it has one)
/// taken from `values`.
#[inline(always)]
fn item_stream(
    item: &FlatItem,
    values: &mut core::slice::Iter<'_, Scalar>,
    options: EncodeOptions,
) -> Option<(u64, u32)> {
    match item {
        FlatItem::Leaf(kind) => stream_of(kind, values.next()?, options.saturate),
        FlatItem::Pad(bits) => Some((0, u32::from(*bits))),
        FlatItem::Version(kind, version) => {
            let bits = scalar_bits(*kind);
            let raw = version_raw(*kind, *values.next()?, *version, options)?;
            Some((to_stream(raw, bits), bits))
        }
    }
}

/// The elements of the ending array; byte strings on a byte boundary as plain bytes.
#[inline(always)]
fn write_elements(
    out: &mut Out<'_>,
    kind: &Kind,
    elements: &[Scalar],
    saturate: bool,
) -> Option<()> {
    if matches!(kind, Kind::Uint { bits: 8, .. }) && out.pending.count() % 8 == 0 {
        // Store the whole bytes pending, then the string.
        out.flush_bytes();
        let bytes = out.out.get_mut(out.at..out.at + elements.len())?;
        for (byte, v) in bytes.iter_mut().zip(elements) {
            match *v {
                Scalar::Uint(b) if b <= 0xFF => *byte = b as u8,
                _ => return None,
            }
        }
        out.at += elements.len();
        return Some(());
    }
    for v in elements {
        let (stream, bits) = stream_of(kind, v, saturate)?;
        out.put(stream, bits);
    }
    Some(())
}

/// Decodes the value of `root` from `data` into a flat `sink` when the plan answers for it:
/// the bits the value took, the sink holding its leaves as the general path leaves them.
/// `None` (the sink untouched, nothing to report) for anything else: a type of another
/// shape, data in pieces, a sink that is not a flat leaf list or has too little room, data
/// cut short or with bytes after the value (unless allowed), an array longer than its
/// maximum.
#[inline(never)]
pub fn decode<R: BitRead + ?Sized, K: Sink>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    sink: &mut K,
    options: DecodeOptions,
) -> Option<usize> {
    let plan = layout.straight.get(root as usize)?.as_ref()?;
    // Payloads in pieces are the general decoder's (its reader follows the pieces).
    let data = data.contiguous()?;
    let prefix = plan.tail.map_or(0, |t| t.prefix(options.tao));
    let (n, end) = measure(plan, prefix, data)?;
    if !options.allow_trailing && data.len() > end.div_ceil(8) {
        return None;
    }
    let fixed_leaves = plan.leaves as usize;
    let total = fixed_leaves + plan.tail.map_or(0, |_| 1 + n);
    let slots = sink.leaf_slots(total)?.ok()?;
    let (fixed, rest) = slots.split_at_mut_checked(fixed_leaves)?;
    match &plan.small {
        // The whole run from one load (the data holds it: measured).
        Some(small) => decode_small(small, load_word(data), fixed),
        None => decode_run(plan.items.of(layout.flat), data, fixed),
    }
    if let (Some(tail), [len, elements @ ..]) = (&plan.tail, rest) {
        *len = Scalar::Uint(n as u64);
        if !elements.is_empty() {
            let mut reader = data.reader(plan.bits as usize + prefix as usize);
            read_elements(&mut reader, &tail.elem, elements);
        }
    }
    Some(end)
}

/// The length of the ending array (0 without one) and where the value ends in `data`, which
/// holds it all, with a length prefix of `prefix` bits; `None` where it does not.
#[inline(always)]
fn measure(plan: &Straight, prefix: u32, data: &[u8]) -> Option<(usize, usize)> {
    let bits = plan.bits as usize;
    let bit_len = data.len() * 8;
    let rest = bit_len.checked_sub(bits)?;
    let Some(tail) = &plan.tail else {
        return Some((0, bits));
    };
    let width = tail.elem_bits as usize;
    if prefix == 0 {
        // Tail-optimized: one whose last element runs past the end is the walk's to refuse.
        let n = tail_elements(rest, width);
        if n * width > rest || n > tail.max as usize {
            return None;
        }
        return Some((n, bits + n * width));
    }
    let prefix_bits = prefix as usize;
    if rest < prefix_bits {
        return None;
    }
    let n = from_stream(bits::read_bits(data, bits, prefix), prefix);
    let n = usize::try_from(n)
        .ok()
        .filter(|&n| n <= tail.max as usize)?;
    let end = bits + prefix_bits + n * width;
    (end <= bit_len).then_some((n, end))
}

/// Fills `slots` with the leaves of a small plan's fixed run held in `word` (its first bit
/// the highest).
#[inline(always)]
fn decode_small(small: &Small, word: u64, slots: &mut [Scalar]) {
    let mut word = Ahead::new(word, 64);
    let mut slots = slots.iter_mut();
    for step in &small.steps {
        let bits = u32::from(step.bits);
        if bits == 0 {
            break;
        }
        // Steps have 1 to 64 bits; a 64-bit one is the run's only one.
        let raw = step.order.raw(word.take(bits), bits);
        let value = match step.op {
            Op::Pad => continue,
            Op::Uint | Op::Version => Scalar::Uint(raw),
            Op::Int => Scalar::Int(scalar::sign_extend(raw, bits)),
            Op::Float16 => Scalar::Float(f64::from(scalar::f32_from_f16(raw as u16))),
            Op::Float32 => Scalar::Float(f64::from(f32::from_bits(raw as u32))),
            Op::Float64 => Scalar::Float(f64::from_bits(raw)),
            Op::Bool => Scalar::Bool(raw != 0),
        };
        if let Some(slot) = slots.next() {
            *slot = value;
        }
    }
}

/// Fills `slots` with the leaves of a fixed run from `data`, measured to hold it. Out of
/// line: one copy of the leaf conversions per function keeps them inlined in both paths.
#[inline(never)]
fn decode_run(items: &[FlatItem], data: &[u8], slots: &mut [Scalar]) {
    let mut bits_in = In {
        data,
        next: 0,
        ahead: Ahead::default(),
    };
    let mut slots = slots.iter_mut();
    for item in items {
        match item {
            FlatItem::Leaf(kind) | FlatItem::Version(kind, _) => {
                let bits = scalar_bits(*kind);
                let raw = bits_in.take(bits);
                if let Some(slot) = slots.next() {
                    *slot = scalar_of(*kind, from_stream(raw, bits));
                }
            }
            FlatItem::Pad(bits) => {
                bits_in.take(u32::from(*bits));
            }
        }
    }
}

/// Bits coming in most significant first from data the caller has measured: whole bytes
/// gathered into a register ([`Ahead`]) ahead of the fields, so that a small value is read in
/// a few loads without a bounds check per field.
struct In<'d> {
    data: &'d [u8],
    /// The next byte to gather.
    next: usize,
    ahead: Ahead,
}

impl In<'_> {
    /// The next `bits` (`0..=64`) bits as a stream value.
    #[inline(always)]
    fn take(&mut self, bits: u32) -> u64 {
        if bits > 32 {
            let first = self.take32(bits - 32);
            return join(first, self.take32(32), 32);
        }
        self.take32(bits)
    }

    #[inline(always)]
    fn take32(&mut self, bits: u32) -> u64 {
        if bits == 0 {
            return 0;
        }
        if bits > self.ahead.count() {
            self.refill();
        }
        self.ahead.take(bits)
    }

    /// Gathers up to 57 bits or up to the end of the data (which holds the value: measured
    /// first). The bits after the last whole byte counted are the stream's own, gathered
    /// again next time.
    #[inline(always)]
    fn refill(&mut self) {
        let rest = self.data.get(self.next..).unwrap_or_default();
        let whole = ((64 - self.ahead.count()) / 8).min(rest.len() as u32);
        self.ahead.append(load_word(rest), whole);
        self.next += whole as usize;
    }
}

/// The elements of the ending array (the data holds them all); byte strings on a byte
/// boundary as plain bytes.
#[inline(always)]
fn read_elements<B: BitReader>(reader: &mut B, kind: &Kind, slots: &mut [Scalar]) {
    if matches!(kind, Kind::Uint { bits: 8, .. }) && reader.position() % 8 == 0 {
        let mut chunk = [0u8; 32];
        for group in slots.chunks_mut(chunk.len()) {
            let bytes = &mut chunk[..group.len()];
            reader.read_bytes(bytes);
            for (slot, &b) in group.iter_mut().zip(bytes.iter()) {
                *slot = Scalar::Uint(b.into());
            }
        }
        return;
    }
    let bits = scalar_bits(*kind);
    for slot in slots {
        *slot = scalar_of(*kind, from_stream(reader.read(bits), bits));
    }
}
