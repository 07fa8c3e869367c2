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

use crate::bits::{BitRead, BitReader};
use crate::layout::{FlatItem, Kind, Layout, NodeId, Role, Segment};
use crate::rules::{
    scalar_bits, scalar_of, scalar_raw, DecodeOptions, EncodeOptions, Sink, Source,
};
use crate::scalar::{self, Scalar};

/// The dynamic array of primitives that may end a straight-line type.
#[derive(Clone, Copy, Debug)]
struct Tail<'l> {
    /// The element's kind (a primitive).
    elem: &'l Kind,
    /// Its width in bits.
    elem_bits: u32,
    /// Largest length.
    max: u32,
    /// Width of the length prefix (written unless `tail_optimized`).
    len_bits: u32,
    /// Tail array optimization: no prefix, the array takes the remaining whole bytes.
    tail_optimized: bool,
}

impl Tail<'_> {
    /// Bits of the length prefix as encoded.
    #[inline(always)]
    fn prefix(&self) -> usize {
        if self.tail_optimized {
            0
        } else {
            self.len_bits as usize
        }
    }
}

/// A type the plan answers for: its fixed run, then perhaps one array.
#[derive(Clone, Copy, Debug)]
struct Shape<'l> {
    /// The fixed run's items, in stream order (empty when the struct is the array alone).
    items: &'l [FlatItem],
    /// Leaves of the fixed run.
    leaves: usize,
    /// Bits of the fixed run.
    bits: usize,
    tail: Option<Tail<'l>>,
}

impl<'l> Shape<'l> {
    /// The shape of `root` when the plan answers for it, as a value encoded with or without
    /// tail array optimization (`tao`). The layout's compiled segments are the plan: a struct
    /// of one flat segment, and/or a last field that is a dynamic array of primitives.
    #[inline(always)]
    fn of(layout: &Layout<'l>, root: NodeId, tao: bool) -> Option<Self> {
        let node = layout.nodes.get(root as usize)?;
        let Kind::Struct { first, count } = node.kind else {
            return None;
        };
        // The compiler splits a struct's fields into segments in order (as the flat codec
        // trusts): a flat run, then perhaps one field of another shape.
        let (flat, last) = match node.segments.of(layout.segments) {
            [Segment::Flat {
                items,
                leaves,
                bits,
                ..
            }] => (Some((items, leaves, bits)), None),
            [Segment::Flat {
                items,
                leaves,
                bits,
                ..
            }, Segment::Field(i)] => (Some((items, leaves, bits)), Some(*i)),
            [Segment::Field(i)] => (None, Some(*i)),
            [] => (None, None),
            _ => return None,
        };
        let mut shape = Shape {
            items: &[],
            leaves: 0,
            bits: 0,
            tail: None,
        };
        if let Some((items, leaves, bits)) = flat {
            shape.items = items.of(layout.flat);
            if shape.items.len() != items.count as usize {
                return None;
            }
            shape.leaves = *leaves as usize;
            shape.bits = *bits as usize;
        }
        if let Some(i) = last {
            // The array must be the last field (it alone may be tail-optimized) and data.
            if u64::from(i) + 1 != u64::from(first) + u64::from(count) {
                return None;
            }
            let field = layout.fields.get(i as usize)?;
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
            shape.tail = Some(Tail {
                elem: &elem_node.kind,
                elem_bits,
                max,
                len_bits: len_bits.into(),
                tail_optimized: tao && elem_node.min_bits >= 8,
            });
        }
        Some(shape)
    }
}

/// The bits of `value` for a primitive `kind` in stream order, and how many; `None` where
/// the general path has something to say (out of range, wrong kind, a rejected cast).
#[inline(always)]
fn stream_of(kind: &Kind, value: &Scalar, saturate: bool) -> Option<(u64, u32)> {
    // The common cases without the casting rules: an integer in range, a float that is finite
    // and in range (NaN compares false and takes the general rules, as do infinities).
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
        _ => return cast(*kind, *value, saturate),
    };
    Some((scalar::to_stream(raw, bits), bits))
}

/// [`stream_of`] by the casting rules (saturation, truncation, the other kinds of value).
#[cold]
#[inline(never)]
fn cast(kind: Kind, value: Scalar, saturate: bool) -> Option<(u64, u32)> {
    let raw = scalar_raw(kind, value, saturate).ok()?;
    let bits = scalar_bits(kind);
    Some((scalar::to_stream(raw, bits), bits))
}

/// A `p_version` leaf: the type's own version unless versions are kept as given (the
/// general path words a mismatch).
#[cold]
#[inline(never)]
fn version_stream(
    kind: Kind,
    value: Scalar,
    version: u32,
    options: EncodeOptions,
) -> Option<(u64, u32)> {
    if options.keep_versions {
        stream_of(&kind, &value, options.saturate)
    } else if scalar::same_integer(value, version) {
        stream_of(&kind, &Scalar::Uint(version.into()), false)
    } else {
        None
    }
}

/// Bits going out most significant first into a buffer holding exactly the value: fewer than
/// 32 wait in a register between fields, 32 are stored at a time.
struct Out<'o> {
    out: &'o mut [u8],
    at: usize,
    acc: u64,
    pending: u32,
}

impl Out<'_> {
    /// Appends `bits` (`<= 64`) bits of a stream value that fits them.
    #[inline(always)]
    fn put(&mut self, stream: u64, bits: u32) {
        if bits > 32 {
            self.put32(stream >> 32, bits - 32);
            self.put32(stream & 0xFFFF_FFFF, 32);
        } else {
            self.put32(stream, bits);
        }
    }

    #[inline(always)]
    fn put32(&mut self, stream: u64, bits: u32) {
        // Bits above `pending` may hold older bits: they are shifted out, never stored.
        self.acc = (self.acc << bits) | stream;
        self.pending += bits;
        if self.pending >= 32 {
            self.pending -= 32;
            let word = ((self.acc >> self.pending) as u32).to_be_bytes();
            if let Some(slot) = self.out.get_mut(self.at..self.at + 4) {
                slot.copy_from_slice(&word);
            }
            self.at += 4;
        }
    }

    /// Stores the pending bits, the last byte padded with zeros.
    #[inline(always)]
    fn finish(mut self) {
        let pad = (8 - self.pending % 8) % 8;
        self.acc <<= pad;
        self.pending += pad;
        while self.pending >= 8 {
            self.pending -= 8;
            if let Some(slot) = self.out.get_mut(self.at) {
                *slot = (self.acc >> self.pending) as u8;
            }
            self.at += 1;
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
    let shape = Shape::of(layout, root, options.tao)?;
    let leaves = source.pending_leaves()?;
    let fixed = leaves.get(..shape.leaves)?;
    let mut taken = shape.leaves;
    let mut bits = shape.bits;
    let mut elements: &[Scalar] = &[];
    if let Some(tail) = shape.tail {
        let n = count_of(*leaves.get(shape.leaves)?)?;
        if n > tail.max as usize {
            return None;
        }
        elements = leaves.get(shape.leaves + 1..shape.leaves + 1 + n)?;
        taken += 1 + n;
        bits += tail.prefix() + n * tail.elem_bits as usize;
    }
    let len = bits.div_ceil(8);
    let mut out = Out {
        out: out.get_mut(..len)?,
        at: 0,
        acc: 0,
        pending: 0,
    };
    let saturate = options.saturate;
    let mut values = fixed.iter();
    for item in shape.items {
        let (stream, bits) = match item {
            FlatItem::Pad(bits) => (0, u32::from(*bits)),
            FlatItem::Leaf(kind) => stream_of(kind, values.next()?, saturate)?,
            FlatItem::Version(kind, version) => {
                version_stream(*kind, *values.next()?, *version, options)?
            }
        };
        out.put(stream, bits);
    }
    if let Some(tail) = shape.tail {
        if tail.prefix() != 0 {
            out.put(elements.len() as u64, tail.len_bits);
        }
        write_elements(&mut out, tail.elem, elements, saturate)?;
    }
    out.finish();
    // Take what was used, as the general path does (leaves after the value stay).
    source.leaf_run(taken)?.ok()?;
    Some(len)
}

/// The elements of the ending array; byte strings on a byte boundary as plain bytes.
#[inline(always)]
fn write_elements(
    out: &mut Out<'_>,
    kind: &Kind,
    elements: &[Scalar],
    saturate: bool,
) -> Option<()> {
    if elements.is_empty() {
        return Some(());
    }
    if matches!(kind, Kind::Uint { bits: 8, .. }) && out.pending % 8 == 0 {
        // Store the whole bytes pending, then the string.
        while out.pending >= 8 {
            out.pending -= 8;
            *out.out.get_mut(out.at)? = (out.acc >> out.pending) as u8;
            out.at += 1;
        }
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
/// shape, data in pieces, a sink that is not a flat leaf list or has too little room, data cut short or with
/// bytes after the value (unless allowed), an array longer than its maximum.
#[inline(never)]
pub fn decode<R: BitRead + ?Sized, K: Sink>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    sink: &mut K,
    options: DecodeOptions,
) -> Option<usize> {
    let shape = Shape::of(layout, root, options.tao)?;
    // Payloads in pieces are the general decoder's (its reader follows the pieces).
    let data = data.contiguous()?;
    let bit_len = data.bit_len();
    let rest = bit_len.checked_sub(shape.bits)?;
    // The array's length and where the value ends, before the sink is asked for anything.
    let (n, end) = match shape.tail {
        None => (0, shape.bits),
        Some(tail) if tail.tail_optimized => {
            // The array takes every remaining whole byte: whole elements, fewer than 8 bits
            // left over.
            let width = tail.elem_bits as usize;
            let n = rest / width;
            if rest - n * width >= 8 || n > tail.max as usize {
                return None;
            }
            (n, shape.bits + n * width)
        }
        Some(tail) => {
            let prefix = tail.prefix();
            if rest < prefix {
                return None;
            }
            let n = if prefix == 0 {
                0
            } else {
                scalar::from_stream(data.read_bits(shape.bits, tail.len_bits), tail.len_bits)
            };
            let n = usize::try_from(n)
                .ok()
                .filter(|&n| n <= tail.max as usize)?;
            let end = shape.bits + prefix + n * tail.elem_bits as usize;
            if end > bit_len {
                return None;
            }
            (n, end)
        }
    };
    if !options.allow_trailing && bit_len / 8 > end.div_ceil(8) {
        return None;
    }
    let total = shape.leaves + shape.tail.map_or(0, |_| 1 + n);
    let slots = sink.leaf_slots(total)?.ok()?;
    let (fixed, slots) = slots.split_at_mut(shape.leaves);
    let mut bits_in = In {
        data,
        next: 0,
        acc: 0,
        avail: 0,
    };
    let mut fixed = fixed.iter_mut();
    for item in shape.items {
        match item {
            FlatItem::Pad(bits) => {
                bits_in.take(u32::from(*bits));
            }
            FlatItem::Leaf(kind) | FlatItem::Version(kind, _) => {
                let bits = scalar_bits(*kind);
                let raw = bits_in.take(bits);
                if let Some(slot) = fixed.next() {
                    *slot = scalar_of(*kind, scalar::from_stream(raw, bits));
                }
            }
        }
    }
    if let (Some(tail), [len, elements @ ..]) = (shape.tail, slots) {
        *len = Scalar::Uint(n as u64);
        let mut reader = data.reader(shape.bits + tail.prefix());
        read_elements(&mut reader, tail.elem, elements);
    }
    Some(end)
}

/// Bits coming in most significant first from data the caller has measured: whole bytes
/// gathered into a register ahead of the fields, so that a small value is read in a few
/// loads without a bounds check per field.
struct In<'d, R: BitRead + ?Sized> {
    data: &'d R,
    /// The next byte to gather.
    next: usize,
    /// Gathered bits, left-aligned.
    acc: u64,
    avail: u32,
}

impl<R: BitRead + ?Sized> In<'_, R> {
    /// The next `bits` (`0..=64`) bits as a stream value.
    #[inline(always)]
    fn take(&mut self, bits: u32) -> u64 {
        if bits > 32 {
            let high = self.take32(bits - 32);
            return (high << 32) | self.take32(32);
        }
        self.take32(bits)
    }

    #[inline(always)]
    fn take32(&mut self, bits: u32) -> u64 {
        if bits == 0 {
            return 0;
        }
        if bits > self.avail {
            // Up to 57 bits or the end of the data (which holds the value: measured first).
            let len = self.data.bit_len() / 8;
            if self.next + 8 <= len {
                // A whole window: the bits after the gathered ones (those past the last
                // whole byte counted are the stream's own, gathered again next time).
                let word = self.data.read_bits(self.next * 8, 64);
                self.acc |= word >> self.avail;
                let whole = (64 - self.avail) / 8;
                self.next += whole as usize;
                self.avail += 8 * whole;
            }
            while self.avail <= 56 && self.next < len {
                self.acc |= u64::from(self.data.byte(self.next)) << (56 - self.avail);
                self.avail += 8;
                self.next += 1;
            }
        }
        let value = self.acc >> (64 - bits);
        self.acc <<= bits;
        self.avail = self.avail.saturating_sub(bits);
        value
    }
}

/// The elements of the ending array (the data holds them all); byte strings on a byte
/// boundary as plain bytes.
#[inline(always)]
fn read_elements<B: BitReader>(reader: &mut B, kind: &Kind, slots: &mut [Scalar]) {
    if slots.is_empty() {
        return;
    }
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
        *slot = scalar_of(*kind, scalar::from_stream(reader.read(bits), bits));
    }
}
