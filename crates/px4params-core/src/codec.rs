//! Encoding and decoding whole values with the DroneCAN rules, driven by a [`Layout`].
//!
//! Values come from a [`Source`] and go to a [`Sink`], so the same walk serves Python objects
//! in the binding, flat leaf lists in firmware and anything else, without allocating.

use core::convert::Infallible;

use crate::bits::{BitRead, BitReader, BitWriter};
use crate::error::{Error, ErrorKind, Path, Step};
use crate::layout::{FlatItem, Kind, Layout, NodeId, Role, Segment, Span};
use crate::plan::{Active, Plans};
pub use crate::rules::{
    read_scalar, scalar_bits, ArrayLen, At, DecodeOptions, Decoded, EncodeOptions, LeafKind, Sink,
    Source, MAX_DEPTH,
};
pub(crate) use crate::rules::{scalar_of, scalar_raw, tail_optimized};
use crate::scalar::{self, Scalar};
use crate::value::{LeafError, LeafSink, LeafSource};
use crate::{straight, walk};

/// Encodes the value of type `root` from `source` into `out`; returns the length in bytes.
///
/// `out` needs [`Layout::max_bytes`] bytes at most; only the bytes returned are written.
// Inlined into the caller, so that a small value the straight plan answers costs no second
// call and no frame of the general encoder.
#[inline(always)]
pub fn encode<S: Source>(
    layout: &Layout<'_>,
    root: NodeId,
    source: &mut S,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<S::Error>> {
    if S::FLAT && Active::STRAIGHT {
        if let Some(len) = straight::encode(layout, root, source, out, options) {
            return Ok(len);
        }
    }
    encode_general(layout, root, source, out, options)
}

/// [`encode`] by the general encoder.
#[inline(never)]
fn encode_general<S: Source>(
    layout: &Layout<'_>,
    root: NodeId,
    source: &mut S,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<S::Error>> {
    let mut enc = Encoder {
        layout,
        out: BitWriter::new(out),
        path: Path::default(),
        source,
        saturate: options.saturate,
        keep_versions: options.keep_versions,
        depth: 0,
        error: None,
    };
    if enc.node(root, options.tao).is_err() {
        return Err(stopped(enc.error));
    }
    let pos = enc.out.bit_pos();
    enc.out.finish().map_err(|needed| Error {
        kind: ErrorKind::BufferTooSmall { needed },
        bit_offset: pos,
        path: Path::default(),
    })
}

/// Decodes a value of type `root` from `data` into `sink`; returns the bits used.
// Inlined into the caller, as `encode` is.
#[inline(always)]
pub fn decode<R: BitRead + ?Sized, K: Sink>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    sink: &mut K,
    options: DecodeOptions,
) -> Result<usize, Error<K::Error>> {
    if K::FLAT && Active::STRAIGHT {
        if let Some(bits) = straight::decode(layout, root, data, sink, options) {
            return Ok(bits);
        }
    }
    decode_general(layout, root, data, sink, options)
}

/// [`decode`] by the general decoder.
#[inline(never)]
fn decode_general<R: BitRead + ?Sized, K: Sink>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    sink: &mut K,
    options: DecodeOptions,
) -> Result<usize, Error<K::Error>> {
    let mut dec: Decoder<'_, '_, R, K> = Decoder {
        layout,
        reader: data.reader(0),
        bit_len: data.bit_len(),
        path: Path::default(),
        sink,
        depth: 0,
        error: None,
    };
    if dec.node(root, options.tao).is_err() {
        return Err(stopped(dec.error));
    }
    let end = dec.pos();
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

/// Encodes the value given as a flat leaf list (see [`crate::value`]) into `out`; returns the
/// length in bytes. With the build's [`crate::plan::Active`] plans: see [`encode_leaves_with`].
pub fn encode_leaves(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<LeafError>> {
    encode_leaves_with::<Active>(layout, root, leaves, out, options)
}

/// [`encode_leaves`] with the plans `P`: the flat encoder ([`Plans::FLAT`]) answers or
/// declines, and [`crate::walk`] answers what it declines: the same bytes, and every error
/// worded by the walk.
pub fn encode_leaves_with<P: Plans>(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<LeafError>> {
    if P::FLAT {
        // The plan answers or declines: any fault is worded by the walk.
        if let Ok(n) = encode(layout, root, &mut LeafSource::new(leaves), out, options) {
            return Ok(n);
        }
    }
    walk::encode(layout, root, leaves, out, options)
}

/// Decodes a value of type `root` from `data` into the flat leaf list `leaves`, with the
/// build's [`crate::plan::Active`] plans: see [`decode_leaves_with`].
pub fn decode_leaves<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    leaves: &mut [Scalar],
    options: DecodeOptions,
) -> Result<Decoded, Error<LeafError>> {
    decode_leaves_with::<Active, R>(layout, root, data, leaves, options)
}

/// [`decode_leaves`] with the plans `P`: the flat decoder ([`Plans::FLAT`]) answers or
/// declines, and [`crate::walk`] answers what it declines (every error worded by the walk).
pub fn decode_leaves_with<P: Plans, R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    leaves: &mut [Scalar],
    options: DecodeOptions,
) -> Result<Decoded, Error<LeafError>> {
    if P::FLAT {
        // The plan answers or declines: any fault is worded by the walk.
        let mut sink = LeafSink::new(leaves);
        if let Ok(bits) = decode(layout, root, data, &mut sink, options) {
            let leaves = sink.leaves().len();
            return Ok(Decoded { bits, leaves });
        }
    }
    walk::decode(layout, root, data, leaves, options)
}

/// Checks that `data` is exactly one value of `root` stored without tail array optimization
/// (as the store keeps values) whose `p_version` fields hold the type's version, with the
/// build's [`crate::plan::Active`] plans: see [`check_stored_with`].
pub fn check_stored(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
) -> Result<(), Error<Infallible>> {
    check_stored_with::<Active>(layout, root, data)
}

/// [`check_stored`] with the plans `P`: the decoder into a sink that keeps nothing
/// ([`Plans::TRANSLATE`]) answers or declines, and [`crate::walk`] answers what it declines
/// (every error worded by the walk).
pub fn check_stored_with<P: Plans>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
) -> Result<(), Error<Infallible>> {
    if P::TRANSLATE {
        let options = DecodeOptions {
            tao: false,
            allow_trailing: false,
        };
        if decode(layout, root, data, &mut VersionCheck { layout }, options).is_ok() {
            return Ok(());
        }
    }
    walk::check_versions(layout, root, data)
}

/// A sink that keeps nothing and refuses `p_version` fields that differ from the version.
struct VersionCheck<'l, 'a> {
    layout: &'l Layout<'a>,
}

impl Sink for VersionCheck<'_, '_> {
    /// A `p_version` that is not the type's: the plan declines.
    type Error = ();

    fn scalar(&mut self, value: Scalar, at: At<'_>) -> Result<(), ()> {
        if let Some(Step::Field(f)) = at.path.last() {
            if let Some(Role::Version(expected)) =
                self.layout.fields.get(f as usize).map(|f| f.role)
            {
                if value != Scalar::Uint(expected.into()) {
                    return Err(());
                }
            }
        }
        Ok(())
    }
    fn begin_struct(&mut self, _fields: usize) -> Result<(), ()> {
        Ok(())
    }
    fn field(&mut self, _index: u32, _name: &str) -> Result<(), ()> {
        Ok(())
    }
    fn end_struct(&mut self) -> Result<(), ()> {
        Ok(())
    }
    fn begin_union(&mut self, _: u32, _: u32, _: &str, _: At<'_>) -> Result<(), ()> {
        Ok(())
    }
    fn end_union(&mut self) -> Result<(), ()> {
        Ok(())
    }
    fn begin_array(&mut self, _len: ArrayLen, _at: At<'_>) -> Result<(), ()> {
        Ok(())
    }
    fn end_array(&mut self, _len: usize) -> Result<(), ()> {
        Ok(())
    }
}

/// Internal failure marker: the error itself waits in the walker's slot, so that results stay
/// small enough to travel in registers through the recursion.
pub(crate) struct Stop(());

/// The error a walker stored when it stopped.
#[cold]
fn stopped<E>(slot: Option<Error<E>>) -> Error<E> {
    // Every Stop is made by a walker's `fail`, which fills the slot first.
    slot.unwrap_or(Error {
        kind: ErrorKind::TooDeep,
        bit_offset: 0,
        path: Path::default(),
    })
}

struct Encoder<'l, 'o, S: Source> {
    layout: &'l Layout<'l>,
    out: BitWriter<'o>,
    path: Path,
    source: &'o mut S,
    saturate: bool,
    keep_versions: bool,
    depth: usize,
    error: Option<Error<S::Error>>,
}

impl<S: Source> Encoder<'_, '_, S> {
    #[cold]
    #[inline(never)]
    fn fail(&mut self, kind: ErrorKind<S::Error>) -> Stop {
        self.error = Some(Error {
            kind,
            bit_offset: self.out.bit_pos(),
            path: self.path,
        });
        Stop(())
    }

    // One out-of-line copy in firmware builds (feature `compact`): every kind of node writes.
    #[cfg_attr(not(feature = "compact"), inline(always))]
    #[cfg_attr(feature = "compact", inline(never))]
    fn write(&mut self, raw: u64, bits: u32) -> Result<(), Stop> {
        self.out
            .write(scalar::to_stream(raw, bits), bits)
            .map_err(|needed| self.fail(ErrorKind::BufferTooSmall { needed }))
    }

    #[inline(never)]
    fn scalar(&mut self, kind: Kind, value: Scalar) -> Result<(), Stop> {
        let raw =
            fast_raw(kind, value, self.saturate).map_err(|e| self.fail(ErrorKind::Scalar(e)))?;
        self.write(raw, scalar_bits(kind))
    }

    #[inline(always)]
    fn value<T>(&mut self, r: Result<T, S::Error>) -> Result<T, Stop> {
        match r {
            Ok(v) => Ok(v),
            Err(e) => Err(self.fail(ErrorKind::Value(e))),
        }
    }

    fn node(&mut self, id: NodeId, tao: bool) -> Result<(), Stop> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.fail(ErrorKind::TooDeep));
        }
        let layout = self.layout;
        match layout.node(id).kind {
            kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool) => {
                let v = self.source.scalar(kind);
                let v = self.value(v)?;
                self.scalar(kind, v)?;
            }
            Kind::Void { bits } => self.write(0, bits.into())?,
            Kind::Struct { first, count } => {
                if S::FLAT && Active::FLAT {
                    self.flat_struct(id, first, count, tao)?;
                } else {
                    let r = self.source.begin_struct();
                    self.value(r)?;
                    let mut used = 0;
                    for i in 0..count {
                        used += self.field(first + i, tao && i + 1 == count)?;
                    }
                    let r = self.source.end_struct(layout, layout.members(id), used);
                    self.value(r)?;
                }
            }
            Kind::Union {
                first,
                count,
                tag_bits,
            } => {
                let variants = layout.members(id);
                let tag = self.source.begin_union(layout, variants);
                let tag = self.value(tag)?;
                if tag >= count {
                    return Err(self.fail(ErrorKind::BadUnionTag {
                        tag: tag.into(),
                        variants: count,
                    }));
                }
                self.write(tag.into(), tag_bits.into())?;
                self.path.push(Step::Field(first + tag));
                self.node(variants[tag as usize].node, tao)?;
                self.path.pop();
                self.source.end_union();
            }
            Kind::Array { elem, len } => {
                let n = self.source.begin_array(Some(len));
                let n = self.value(n)?;
                if n != len as usize {
                    return Err(self.fail(ErrorKind::WrongArrayLength {
                        len: n as u64,
                        expected: len,
                    }));
                }
                self.elements(elem, n, tao)?;
            }
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => {
                let n = self.source.begin_array(None);
                let n = self.value(n)?;
                if n > max as usize {
                    return Err(self.fail(ErrorKind::ArrayTooLong { len: n as u64, max }));
                }
                if tail_optimized(layout, elem, tao) {
                    self.elements(elem, n, false)?;
                } else {
                    self.write(n as u64, len_bits.into())?;
                    self.elements(elem, n, tao)?;
                }
            }
        }
        self.depth -= 1;
        Ok(())
    }

    /// Encodes field `index`; returns 1 when the input had it (0 for padding and filled-in
    /// versions), so that the struct can tell unknown input fields.
    #[cfg_attr(feature = "compact", inline(never))]
    fn field(&mut self, index: u32, last: bool) -> Result<usize, Stop> {
        let layout = self.layout;
        let field = layout.fields[index as usize];
        if field.role == Role::Padding {
            self.node(field.node, last)?;
            return Ok(0);
        }
        self.path.push(Step::Field(index));
        let present = self.source.field(index, layout.name(&field));
        let used = if self.value(present)? {
            let kind = layout.node(field.node).kind;
            // A field one past the bound: `node` refuses it, as the walk does.
            let deep = self.depth >= MAX_DEPTH;
            if field.role == Role::Data && is_scalar(kind) && !deep {
                // Primitive fields are the common case: no recursion.
                let v = self.source.scalar(kind);
                let v = self.value(v)?;
                self.scalar(kind, v)?;
            } else if let (Role::Version(version), false, false) =
                (field.role, self.keep_versions, deep)
            {
                let given = self.source.scalar(kind);
                let given = self.value(given)?;
                if !scalar::same_integer(given, version) {
                    return Err(self.fail(ErrorKind::VersionMismatch {
                        given,
                        expected: version,
                    }));
                }
                self.scalar(kind, Scalar::Uint(version.into()))?;
            } else {
                self.node(field.node, last)?;
            }
            self.source.end_field();
            1
        } else if let Role::Version(version) = field.role {
            self.scalar(layout.node(field.node).kind, Scalar::Uint(version.into()))?;
            0
        } else {
            return Err(self.fail(ErrorKind::MissingField));
        };
        self.path.pop();
        Ok(used)
    }

    /// A flat run the source has too few leaves for: its fields one by one, to fail at the
    /// first leaf missing.
    #[cold]
    #[inline(never)]
    fn missing_leaf(&mut self, fields: Span, end: u32, tao: bool) -> Stop {
        for i in fields.first..fields.first + fields.count {
            if let Err(stop) = self.field(i, tao && i + 1 == end) {
                return stop;
            }
        }
        // The leaves were there after all: the source is inconsistent.
        self.fail(ErrorKind::MissingField)
    }

    /// A struct from a flat source: fixed-shape runs of fields in one tight loop each.
    fn flat_struct(&mut self, id: NodeId, first: u32, count: u32, tao: bool) -> Result<(), Stop> {
        let layout = self.layout;
        for segment in layout.node(id).segments.of(layout.segments) {
            match *segment {
                Segment::Flat {
                    fields,
                    items,
                    leaves,
                    height,
                    ..
                } => {
                    let saturate = self.saturate;
                    let keep = self.keep_versions;
                    // Deeper than the walk follows: field by field, which refuses the type.
                    let run = if self.depth + height as usize > MAX_DEPTH {
                        None
                    } else {
                        self.source.leaf_run(leaves as usize)
                    };
                    let outcome = match run {
                        Some(Ok(run)) => {
                            encode_items(&mut self.out, items.of(layout.flat), run, saturate, keep)
                        }
                        // Not enough leaves (nothing was taken): field by field, which names
                        // the first leaf missing, as a build without this fast path does.
                        Some(Err(_)) => {
                            return Err(self.missing_leaf(fields, first + count, tao));
                        }
                        None => {
                            for i in fields.first..fields.first + fields.count {
                                self.field(i, tao && i + 1 == first + count)?;
                            }
                            continue;
                        }
                    };
                    if let Err((leaf, kind)) = outcome {
                        push_flat_path(layout, fields, leaf, &mut self.path);
                        return Err(self.fail(kind.into_kind()));
                    }
                }
                Segment::Field(i) => {
                    self.field(i, tao && i + 1 == first + count)?;
                }
            }
        }
        Ok(())
    }

    fn elements(&mut self, elem: NodeId, n: usize, tao: bool) -> Result<(), Stop> {
        let kind = self.layout.node(elem).kind;
        if S::FLAT && Active::FLAT && is_scalar(kind) {
            let saturate = self.saturate;
            let outcome = match self.source.leaf_run(n) {
                Some(Ok(run)) => Some(encode_scalars(&mut self.out, kind, run, saturate)),
                // Not enough leaves: element by element names the first one missing.
                Some(Err(_)) | None => None,
            };
            match outcome {
                Some(Ok(())) => {
                    self.source.end_array();
                    return Ok(());
                }
                Some(Err((i, fail))) => {
                    self.path.push(Step::Index(i as u32));
                    return Err(self.fail(fail.into_kind()));
                }
                None => {}
            }
        }
        if is_scalar(kind) {
            // Arrays of primitives (strings, covariances) skip the per-element recursion.
            for i in 0..n {
                self.path.push(Step::Index(i as u32));
                let r = self.source.element(i);
                self.value(r)?;
                let v = self.source.scalar(kind);
                let v = self.value(v)?;
                self.scalar(kind, v)?;
                self.source.end_element();
                self.path.pop();
            }
            self.source.end_array();
            return Ok(());
        }
        for i in 0..n {
            self.path.push(Step::Index(i as u32));
            let r = self.source.element(i);
            self.value(r)?;
            self.node(elem, tao && i + 1 == n)?;
            self.source.end_element();
            self.path.pop();
        }
        self.source.end_array();
        Ok(())
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
fn encode_items(
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
                    fast_raw(kind, v, saturate).map_err(FlatFail::Scalar)?,
                    scalar_bits(kind),
                )
            }
            FlatItem::Version(kind, version) => {
                let v = leaves.next().unwrap_or(Scalar::Uint(0));
                let raw = if keep_versions {
                    fast_raw(kind, v, saturate).map_err(FlatFail::Scalar)?
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
fn encode_scalars(
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
        let raw = fast_raw(kind, run[i], saturate).map_err(FlatFail::Scalar)?;
        Ok((scalar::to_stream(raw, bits), bits))
    });
    written.map_err(|e| (at, e.unwrap_or_else(FlatFail::Buffer)))
}

/// The bits the encoder writes for a primitive `value` of `kind`, in stream order, and how
/// many: what a binding that walks a type its own way (see `px4params-py`'s programs) writes,
/// so that its bytes are the encoder's.
#[inline(always)]
pub fn scalar_stream(
    kind: Kind,
    value: Scalar,
    saturate: bool,
) -> Result<(u64, u32), scalar::ScalarError> {
    let bits = scalar_bits(kind);
    Ok((
        scalar::to_stream(fast_raw(kind, value, saturate)?, bits),
        bits,
    ))
}

/// [`scalar_raw`] with the in-range unsigned case first.
#[inline(always)]
fn fast_raw(kind: Kind, value: Scalar, saturate: bool) -> Result<u64, scalar::ScalarError> {
    if !Active::FLAT {
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
fn is_scalar(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool
    )
}

struct Decoder<'l, 'd, R: BitRead + ?Sized + 'd, K: Sink> {
    layout: &'l Layout<'l>,
    /// Where the decoder stands: it reads forwards only.
    reader: R::Reader<'d>,
    bit_len: usize,
    path: Path,
    sink: &'d mut K,
    depth: usize,
    error: Option<Error<K::Error>>,
}

impl<'d, R: BitRead + ?Sized + 'd, K: Sink> Decoder<'_, 'd, R, K> {
    /// The bit offset of the next read.
    #[inline(always)]
    fn pos(&self) -> usize {
        self.reader.position()
    }

    /// Bits left to read.
    #[inline(always)]
    fn remaining(&self) -> usize {
        self.bit_len.saturating_sub(self.pos())
    }

    #[cold]
    #[inline(never)]
    fn fail(&mut self, kind: ErrorKind<K::Error>) -> Stop {
        let at = self.pos();
        self.fail_at(at, kind)
    }

    /// Fails pointing at `bit_offset` (the start of what was found wrong).
    #[cold]
    #[inline(never)]
    fn fail_at(&mut self, bit_offset: usize, kind: ErrorKind<K::Error>) -> Stop {
        self.error = Some(Error {
            kind,
            bit_offset,
            path: self.path,
        });
        Stop(())
    }

    #[inline]
    fn read(&mut self, bits: u32) -> Result<u64, Stop> {
        let needed = self.pos() + bits as usize;
        if needed > self.bit_len {
            return Err(self.fail(ErrorKind::Truncated {
                needed_bits: needed,
                available_bits: self.bit_len,
            }));
        }
        let stream = self.reader.read(bits);
        Ok(scalar::from_stream(stream, bits))
    }

    #[inline(always)]
    fn sunk<T>(&mut self, r: Result<T, K::Error>) -> Result<T, Stop> {
        match r {
            Ok(v) => Ok(v),
            Err(e) => Err(self.fail(ErrorKind::Value(e))),
        }
    }

    fn node(&mut self, id: NodeId, tao: bool) -> Result<(), Stop> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.fail(ErrorKind::TooDeep));
        }
        let layout = self.layout;
        let at_pos = self.pos();
        match layout.node(id).kind {
            kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool) => {
                self.leaf(kind)?;
            }
            Kind::Void { bits } => {
                self.read(bits.into())?;
            }
            Kind::Struct { first, count } => {
                if K::FLAT && Active::FLAT {
                    self.flat_struct(id, first, count, tao)?;
                } else {
                    let r = self.sink.begin_struct(count as usize);
                    self.sunk(r)?;
                    for i in 0..count {
                        self.field(first + i, tao && i + 1 == count)?;
                    }
                    let r = self.sink.end_struct();
                    self.sunk(r)?;
                }
            }
            Kind::Union {
                first,
                count,
                tag_bits,
            } => {
                let tag = self.read(tag_bits.into())?;
                if tag >= u64::from(count) {
                    return Err(self.fail_at(
                        at_pos,
                        ErrorKind::BadUnionTag {
                            tag,
                            variants: count,
                        },
                    ));
                }
                let variant = layout.fields[(first + tag as u32) as usize];
                let at = At {
                    path: &self.path,
                    bit_offset: at_pos,
                    kind: LeafKind::Tag {
                        bits: tag_bits,
                        union: id,
                    },
                };
                let r = self.sink.begin_union(
                    tag as u32,
                    first + tag as u32,
                    layout.name(&variant),
                    at,
                );
                self.sunk(r)?;
                self.path.push(Step::Field(first + tag as u32));
                self.node(variant.node, tao)?;
                self.path.pop();
                let r = self.sink.end_union();
                self.sunk(r)?;
            }
            Kind::Array { elem, len } => {
                let at = At {
                    path: &self.path,
                    bit_offset: at_pos,
                    kind: LeafKind::Len { bits: 0, array: id },
                };
                let r = self.sink.begin_array(ArrayLen::Fixed(len as usize), at);
                self.sunk(r)?;
                for i in 0..len {
                    self.path.push(Step::Index(i));
                    self.node(elem, tao && i + 1 == len)?;
                    self.path.pop();
                }
                let r = self.sink.end_array(len as usize);
                self.sunk(r)?;
            }
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } => {
                if tail_optimized(layout, elem, tao) {
                    let at = At {
                        path: &self.path,
                        bit_offset: at_pos,
                        kind: LeafKind::Len { bits: 0, array: id },
                    };
                    let r = self.sink.begin_array(ArrayLen::Tail, at);
                    self.sunk(r)?;
                    // The array takes every remaining whole byte.
                    let mut n = 0usize;
                    let elem_kind = layout.node(elem).kind;
                    if is_scalar(elem_kind) {
                        // Primitive elements of 8+ bits: their count is known up front.
                        let bits = scalar_bits(elem_kind) as usize;
                        let count = (self.remaining() / 8 * 8) / bits;
                        let whole = self.remaining() >= 8;
                        if whole && count <= max as usize && self.flat_elements(elem_kind, count)? {
                            n = count;
                        }
                    }
                    while self.remaining() >= 8 {
                        if n == max as usize {
                            return Err(self.fail(ErrorKind::ArrayTooLong {
                                len: n as u64 + 1,
                                max,
                            }));
                        }
                        self.element(elem, n as u32, false)?;
                        n += 1;
                    }
                    let r = self.sink.end_array(n);
                    self.sunk(r)?;
                } else {
                    let n = self.read(len_bits.into())?;
                    if n > u64::from(max) {
                        return Err(self.fail_at(at_pos, ErrorKind::ArrayTooLong { len: n, max }));
                    }
                    let at = At {
                        path: &self.path,
                        bit_offset: at_pos,
                        kind: LeafKind::Len {
                            bits: len_bits,
                            array: id,
                        },
                    };
                    let r = self.sink.begin_array(ArrayLen::Prefixed(n as usize), at);
                    self.sunk(r)?;
                    let elem_kind = layout.node(elem).kind;
                    let done = is_scalar(elem_kind) && self.flat_elements(elem_kind, n as usize)?;
                    for i in (if done { n as u32 } else { 0 })..n as u32 {
                        self.element(elem, i, tao && u64::from(i) + 1 == n)?;
                    }
                    let r = self.sink.end_array(n as usize);
                    self.sunk(r)?;
                }
            }
        }
        self.depth -= 1;
        Ok(())
    }

    /// Element `i` of a dynamic array (primitive elements without recursion).
    #[cfg_attr(feature = "compact", inline(never))]
    fn element(&mut self, elem: NodeId, i: u32, last: bool) -> Result<(), Stop> {
        self.path.push(Step::Index(i));
        let kind = self.layout.node(elem).kind;
        if is_scalar(kind) {
            self.leaf(kind)?;
        } else {
            self.node(elem, last)?;
        }
        self.path.pop();
        Ok(())
    }

    fn field(&mut self, index: u32, last: bool) -> Result<(), Stop> {
        let layout = self.layout;
        let field = layout.fields[index as usize];
        if field.role == Role::Padding {
            return self.node(field.node, last);
        }
        let r = self.sink.field(index, layout.name(&field));
        self.sunk(r)?;
        self.path.push(Step::Field(index));
        let kind = layout.node(field.node).kind;
        // A field one past the bound goes to `node`, which refuses it as the walk does.
        if is_scalar(kind) && self.depth < MAX_DEPTH {
            // Primitive fields are the common case: no recursion.
            self.leaf(kind)?;
        } else {
            self.node(field.node, last)?;
        }
        self.path.pop();
        Ok(())
    }

    /// A struct into a flat sink: fixed-shape runs of fields in one tight loop each.
    fn flat_struct(&mut self, id: NodeId, first: u32, count: u32, tao: bool) -> Result<(), Stop> {
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
                    // Enough data for the whole run means no read inside it can fail; if
                    // not, the field-by-field walk finds where exactly it ends (and refuses a
                    // run deeper than the walk follows).
                    let fits = bits as usize <= self.remaining()
                        && self.depth + height as usize <= MAX_DEPTH;
                    let slots = if fits {
                        self.sink.leaf_slots(leaves as usize)
                    } else {
                        None
                    };
                    match slots {
                        Some(Ok(slots)) => {
                            // A local copy of the reader stays in registers for the run.
                            let mut reader = self.reader;
                            decode_items(&mut reader, items.of(layout.flat), slots);
                            self.reader = reader;
                        }
                        Some(Err(e)) => return Err(self.fail(ErrorKind::Value(e))),
                        None => {
                            for i in fields.first..fields.first + fields.count {
                                self.field(i, tao && i + 1 == first + count)?;
                            }
                        }
                    }
                }
                Segment::Field(i) => self.field(i, tao && i + 1 == first + count)?,
            }
        }
        Ok(())
    }

    /// Decodes `n` primitive elements of `kind` into a flat sink when there is one.
    /// Returns false when the sink is not flat or the data is too short (walk instead).
    fn flat_elements(&mut self, kind: Kind, n: usize) -> Result<bool, Stop> {
        let bits = scalar_bits(kind);
        if !(K::FLAT && Active::FLAT) || (bits as usize).saturating_mul(n) > self.remaining() {
            return Ok(false);
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
                    for slot in slots.iter_mut() {
                        *slot = scalar_of(kind, scalar::from_stream(reader.read(bits), bits));
                    }
                }
                self.reader = reader;
                Ok(true)
            }
            Some(Err(e)) => Err(self.fail(ErrorKind::Value(e))),
            None => Ok(false),
        }
    }

    /// Reads a primitive and hands it to the sink.
    #[inline]
    fn leaf(&mut self, kind: Kind) -> Result<(), Stop> {
        let at_pos = self.pos();
        let value = self.scalar(kind)?;
        let at = At {
            path: &self.path,
            bit_offset: at_pos,
            kind: LeafKind::Scalar(kind),
        };
        let r = self.sink.scalar(value, at);
        self.sunk(r)
    }

    /// A primitive's value from its bits, by the one holder of the rule ([`scalar_of`]).
    #[inline]
    fn scalar(&mut self, kind: Kind) -> Result<Scalar, Stop> {
        Ok(scalar_of(kind, self.read(scalar_bits(kind))?))
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
