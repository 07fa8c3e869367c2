//! Value programs: a struct type compiled once into a flat list of steps (which field, of which
//! kind, in which order; where nested structs begin and end; where arrays go), run over a
//! caller's value representation through two small traits: [`ValueSource`] (read a value's
//! fields and items, for encoding) and [`ValueSink`] (build one, for decoding). The Python
//! binding implements them for Python objects, so that `encode` reads a dict and writes the
//! bits, and `decode` reads the bits and builds the dict, each in one pass, with no leaf list
//! and no walk in between.
//!
//! Programs cover the common shapes of parameters and messages: structs of primitives, nested
//! structs, padding, versions and arrays of primitives. A type with a union or an array of
//! composites inside has none.
//!
//! A program is a plan: it answers or declines, and never words an error. The bits come from
//! the codec's own conversions ([`scalar_stream`], [`read_scalar`]); whatever a program does
//! not take exactly as the codec would (a value the source declines, a missing or unknown
//! field, a number out of range, an array of another length, short data, trailing bytes)
//! makes it decline (`None`), and the caller then runs [`crate::codec::encode`] or
//! [`crate::codec::decode`], which answers or words the error.

use alloc::boxed::Box;
use alloc::vec::Vec;
use core::slice;

use crate::bits::{read_bits, BitWriter};
use crate::codec::{read_scalar, scalar_bits, scalar_stream, DecodeOptions, EncodeOptions};
use crate::layout::{Kind, Layout, NodeId, Role};
use crate::scalar::{self, Scalar};

/// Nesting beyond this has no program (the codec's own limit is far above; no real type
/// comes near either).
const MAX_NESTING: usize = 16;

/// Reads a value for [`Program::encode`]. Every method may decline (`None`): the value is not
/// one the program takes as the codec would (the caller's general path then decides).
pub trait ValueSource {
    /// A value borrowed from the value being encoded (or its root), valid while its
    /// container is read.
    type Item: Copy;
    /// A struct being read: its fields are asked for in field order.
    type Struct;
    /// An array of primitives being read.
    type Array;

    /// Starts reading `item` as a struct.
    fn begin_struct(&mut self, item: Self::Item) -> Option<Self::Struct>;
    /// The field whose index in [`Layout::fields`] is `field`: `Some(None)` when absent.
    fn field(&mut self, fields: &mut Self::Struct, field: u32) -> Option<Option<Self::Item>>;
    /// The struct is read, `used` of its entries found as fields: declines when it holds
    /// others.
    fn end_struct(&mut self, fields: Self::Struct, used: usize) -> Option<()>;
    /// `item` as a primitive of `kind` (its value, not yet checked against the kind's range).
    fn scalar(&mut self, item: Self::Item, kind: Kind) -> Option<Scalar>;
    /// Starts reading `item` as an array of `elem` primitives: the array and its length.
    fn begin_array(&mut self, item: Self::Item, elem: Kind) -> Option<(Self::Array, usize)>;
    /// Element `index` (below the length) of an array, as a primitive of `elem`.
    fn element(&mut self, array: &Self::Array, index: usize, elem: Kind) -> Option<Scalar>;
    /// Element `index` of an array of `uint8`, when it is a value of 0 to 255: the bytes of a
    /// byte-aligned array are written straight.
    #[inline]
    fn byte(&mut self, array: &Self::Array, index: usize, elem: Kind) -> Option<u8> {
        match self.element(array, index, elem)? {
            Scalar::Uint(v) => u8::try_from(v).ok(),
            _ => None,
        }
    }
}

/// Builds a value for [`Program::decode`]. Its errors are the sink's own (out of memory, say),
/// passed on unchanged.
pub trait ValueSink {
    /// A built value.
    type Value;
    /// A struct being built, its fields put in field order.
    type Struct;
    /// The sink's own error.
    type Error;

    /// Starts a value of struct `node`.
    fn begin_struct(&mut self, node: NodeId) -> Result<Self::Struct, Self::Error>;
    /// Adds the field whose index in [`Layout::fields`] is `field` (padding has none).
    fn put(
        &mut self,
        fields: &mut Self::Struct,
        field: u32,
        value: Self::Value,
    ) -> Result<(), Self::Error>;
    /// The struct's value, every field put.
    fn end_struct(
        &mut self,
        fields: Self::Struct,
        node: NodeId,
    ) -> Result<Self::Value, Self::Error>;
    /// A primitive's value.
    fn scalar(&mut self, value: Scalar) -> Result<Self::Value, Self::Error>;
    /// An array of `len` primitives, produced in order by `items`.
    fn list(
        &mut self,
        len: usize,
        items: impl Iterator<Item = Scalar>,
    ) -> Result<Self::Value, Self::Error>;
}

/// One step of a program, in the order of the bits. `field` is a field's index in
/// [`Layout::fields`].
#[derive(Clone, Copy, Debug)]
enum Step {
    /// A primitive field of the current struct.
    Leaf { field: u32, kind: Kind },
    /// The `p_version` field: the type's version, which the value may leave out.
    Version {
        field: u32,
        kind: Kind,
        version: u32,
    },
    /// Padding bits.
    Pad { bits: u8 },
    /// A struct field (of type `node`): the current struct until the matching [`Step::End`].
    Begin { field: u32, node: NodeId },
    /// The current struct ends.
    End,
    /// An array of primitives.
    Array { field: u32, elem: Kind, len: Len },
    /// The next `len` steps are primitives and padding, which the encoder writes in one run.
    Run { len: u32 },
}

/// An array's length rule.
#[derive(Clone, Copy, Debug)]
enum Len {
    /// `T[N]`.
    Fixed(u32),
    /// `T[<=max]` with a `len_bits` prefix; `tail` when the array ends the value and its
    /// elements have 8 bits or more, so that tail array optimization drops the prefix.
    Dynamic { max: u32, len_bits: u8, tail: bool },
}

/// A struct type's program.
#[derive(Debug)]
pub struct Program {
    root: NodeId,
    steps: Box<[Step]>,
    /// For a type of primitives and padding alone (NodeStatus, most small messages): each
    /// field at its bit offset, which is fixed, so that decoding interprets no steps.
    fixed: Option<Fixed>,
}

/// The fields of a type of primitives and padding alone, and its length in bits.
#[derive(Debug)]
struct Fixed {
    fields: Box<[FixedField]>,
    bits: usize,
}

/// A primitive field at a fixed bit offset.
#[derive(Clone, Copy, Debug)]
struct FixedField {
    field: u32,
    kind: Kind,
    offset: u32,
}

impl Fixed {
    /// The fields of `steps` (a root struct's, without runs) when all are primitives and
    /// padding.
    fn of(steps: &[Step]) -> Option<Self> {
        let mut fields = Vec::with_capacity(steps.len());
        let mut bits = 0u32;
        for &step in steps {
            match step {
                Step::Leaf { field, kind } | Step::Version { field, kind, .. } => {
                    fields.push(FixedField {
                        field,
                        kind,
                        offset: bits,
                    });
                    bits += scalar_bits(kind);
                }
                Step::Pad { bits: pad } => bits += u32::from(pad),
                Step::End => {}
                Step::Begin { .. } | Step::Array { .. } | Step::Run { .. } => return None,
            }
        }
        Some(Self {
            fields: fields.into(),
            bits: bits as usize,
        })
    }
}

impl Program {
    /// The program of struct `root`, or `None` for shapes programs do not cover.
    pub fn compile(layout: &Layout<'_>, root: NodeId) -> Option<Self> {
        let Kind::Struct { first, count } = layout.node(root).kind else {
            return None;
        };
        let mut steps = Vec::new();
        compile_struct(layout, first, count, true, 0, &mut steps)?;
        steps.push(Step::End);
        Some(Self {
            root,
            fixed: Fixed::of(&steps),
            steps: with_runs(&steps).into(),
        })
    }

    /// The struct type the program is of.
    pub fn root(&self) -> NodeId {
        self.root
    }

    /// Encodes `value` (read from `source`) into `out`: the length in bytes, or `None` to
    /// decline. `out` needs room for the type's largest value; what it held does not matter.
    #[inline]
    pub fn encode<S: ValueSource>(
        &self,
        source: &mut S,
        value: S::Item,
        out: &mut [u8],
        options: EncodeOptions,
    ) -> Option<usize> {
        let mut encoder = Encoder {
            source,
            room: out.len(),
            out: BitWriter::new(out),
            tao: options.tao,
            saturate: options.saturate,
        };
        let fields = encoder.source.begin_struct(value)?;
        encoder.fields(&mut self.steps.iter(), fields)?;
        encoder.out.finish().ok()
    }

    /// Decodes `data` into a value built by `sink`: `Ok(None)` to decline (the data is not a
    /// value the program reads as the codec would: short, too long, an array too long).
    #[inline]
    pub fn decode<K: ValueSink>(
        &self,
        sink: &mut K,
        data: &[u8],
        options: DecodeOptions,
    ) -> Result<Option<K::Value>, K::Error> {
        // The data is read from a copy with zero bytes after it, so that every read takes the
        // bit reader's whole-window path (the bounds are checked on the data's own length);
        // the copy's room is chosen by the data's length, so that a small message zeroes
        // little.
        let len = data.len();
        if len + 8 <= 32 {
            let mut window = [0u8; 32];
            window[..len].copy_from_slice(data);
            self.decode_window(sink, &window[..len + 8], len, options)
        } else if len + 8 <= 64 {
            let mut window = [0u8; 64];
            window[..len].copy_from_slice(data);
            self.decode_window(sink, &window[..len + 8], len, options)
        } else if len + 8 <= 256 {
            let mut window = [0u8; 256];
            window[..len].copy_from_slice(data);
            self.decode_window(sink, &window[..len + 8], len, options)
        } else {
            self.decode_window(sink, data, len, options)
        }
    }

    /// [`Program::decode`] over `window`, the data (`len` bytes) perhaps with zeros after it.
    #[inline]
    fn decode_window<K: ValueSink>(
        &self,
        sink: &mut K,
        window: &[u8],
        len: usize,
        options: DecodeOptions,
    ) -> Result<Option<K::Value>, K::Error> {
        if let Some(fixed) = &self.fixed {
            // Short data, or trailing bytes not allowed: the codec words the error.
            let fits =
                len * 8 >= fixed.bits && (options.allow_trailing || len == fixed.bits.div_ceil(8));
            if !fits {
                return Ok(None);
            }
            return fixed_struct(sink, window, &fixed.fields, self.root).map(Some);
        }
        let mut decoder = Decoder {
            sink,
            data: window,
            bit_len: len * 8,
            pos: 0,
            tao: options.tao,
        };
        let Some(value) = decoder.fields(&mut self.steps.iter(), self.root)? else {
            return Ok(None);
        };
        if !options.allow_trailing && len > decoder.pos.div_ceil(8) {
            return Ok(None);
        }
        Ok(Some(value))
    }
}

/// Appends the steps of a struct's fields; `tail` when the struct ends the value.
fn compile_struct(
    layout: &Layout<'_>,
    first: u32,
    count: u32,
    tail: bool,
    depth: usize,
    steps: &mut Vec<Step>,
) -> Option<()> {
    if depth > MAX_NESTING {
        return None;
    }
    for field in first..first + count {
        let member = layout.fields[field as usize];
        let last = tail && field + 1 == first + count;
        let kind = layout.node(member.node).kind;
        let step = match (member.role, kind) {
            (Role::Padding, Kind::Void { bits }) => Step::Pad { bits },
            (Role::Version(version), kind) if is_primitive(kind) => Step::Version {
                field,
                kind,
                version,
            },
            (Role::Data, kind) if is_primitive(kind) => Step::Leaf { field, kind },
            (Role::Data, Kind::Struct { first, count }) => {
                steps.push(Step::Begin {
                    field,
                    node: member.node,
                });
                compile_struct(layout, first, count, last, depth + 1, steps)?;
                Step::End
            }
            (Role::Data, Kind::Array { elem, len }) => Step::Array {
                field,
                elem: primitive(layout, elem)?,
                len: Len::Fixed(len),
            },
            (
                Role::Data,
                Kind::DynArray {
                    elem,
                    max,
                    len_bits,
                },
            ) if len_bits > 0 => Step::Array {
                field,
                elem: primitive(layout, elem)?,
                len: Len::Dynamic {
                    max,
                    len_bits,
                    tail: last && layout.node(elem).min_bits >= 8,
                },
            },
            _ => return None,
        };
        steps.push(step);
    }
    Some(())
}

/// `steps` with a [`Step::Run`] before each run of primitives and padding.
fn with_runs(steps: &[Step]) -> Vec<Step> {
    let mut marked = Vec::with_capacity(steps.len() * 2);
    let mut run = None;
    for &step in steps {
        if matches!(
            step,
            Step::Leaf { .. } | Step::Version { .. } | Step::Pad { .. }
        ) {
            let start = *run.get_or_insert(marked.len());
            if start == marked.len() {
                marked.push(Step::Run { len: 0 });
            }
            if let Step::Run { len } = &mut marked[start] {
                *len += 1;
            }
        } else {
            run = None;
        }
        marked.push(step);
    }
    marked
}

/// Whether `kind` is a primitive with a value (not padding, not a container).
fn is_primitive(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool
    )
}

/// The kind of node `id` when it is a primitive.
fn primitive(layout: &Layout<'_>, id: NodeId) -> Option<Kind> {
    let kind = layout.node(id).kind;
    is_primitive(kind).then_some(kind)
}

struct Encoder<'s, 'o, S> {
    source: &'s mut S,
    out: BitWriter<'o>,
    /// The length of `out`.
    room: usize,
    tao: bool,
    saturate: bool,
}

impl<S: ValueSource> Encoder<'_, '_, S> {
    /// The steps of one struct, up to its [`Step::End`], from `fields`.
    #[inline]
    fn fields(&mut self, steps: &mut slice::Iter<'_, Step>, mut fields: S::Struct) -> Option<()> {
        let mut used = 0;
        while let Some(&step) = steps.next() {
            match step {
                Step::Run { len } => {
                    let run = steps.as_slice().get(..len as usize)?.iter();
                    self.run(run, &mut fields, &mut used)?;
                    steps.nth(len as usize - 1);
                }
                Step::Begin { field, .. } => {
                    let item = self.source.field(&mut fields, field)??;
                    used += 1;
                    let inner = self.source.begin_struct(item)?;
                    self.fields(steps, inner)?;
                }
                Step::End => break,
                Step::Array { field, elem, len } => {
                    let item = self.source.field(&mut fields, field)??;
                    used += 1;
                    self.array(item, elem, len)?;
                }
                // Only ever inside runs.
                Step::Leaf { .. } | Step::Version { .. } | Step::Pad { .. } => return None,
            }
        }
        self.source.end_struct(fields, used)
    }

    /// A run of primitives and padding, written in one go (the writer's state stays in
    /// registers); `used` counts the fields found.
    #[inline]
    fn run(
        &mut self,
        mut run: slice::Iter<'_, Step>,
        fields: &mut S::Struct,
        used: &mut usize,
    ) -> Option<()> {
        let (source, saturate) = (&mut *self.source, self.saturate);
        let mut bits_of = |step: Step| -> Option<(u64, u32)> {
            let (kind, value) = match step {
                Step::Leaf { field, kind } => {
                    let item = source.field(fields, field)??;
                    *used += 1;
                    (kind, source.scalar(item, kind)?)
                }
                Step::Version {
                    field,
                    kind,
                    version,
                } => {
                    if let Some(item) = source.field(fields, field)? {
                        *used += 1;
                        // Any value but the type's version: the codec decides.
                        if source.scalar(item, kind)? != Scalar::Uint(version.into()) {
                            return None;
                        }
                    }
                    (kind, Scalar::Uint(version.into()))
                }
                Step::Pad { bits } => return Some((0, bits.into())),
                _ => return None,
            };
            scalar_stream(kind, value, saturate).ok()
        };
        let count = run.len();
        let written = self
            .out
            .write_run(count, |_| bits_of(*run.next().ok_or(())?).ok_or(()));
        written.ok()
    }

    fn array(&mut self, item: S::Item, elem: Kind, len: Len) -> Option<()> {
        let (array, n) = self.source.begin_array(item, elem)?;
        self.length(len, n)?;
        // Byte strings on a byte boundary (most names), with room for them: the bytes
        // themselves. (The room is checked first: a writer that runs out of room midway
        // through its pending bytes is not to be written on.)
        let pos = self.out.bit_pos();
        if matches!(elem, Kind::Uint { bits: 8, .. }) && pos % 8 == 0 && pos / 8 + n <= self.room {
            if let Some(bytes) = self.out.aligned_bytes(n) {
                for (i, byte) in bytes.iter_mut().enumerate() {
                    *byte = self.source.byte(&array, i, elem)?;
                }
                return Some(());
            }
        }
        for i in 0..n {
            let value = self.source.element(&array, i, elem)?;
            let (stream, bits) = scalar_stream(elem, value, self.saturate).ok()?;
            self.out.write(stream, bits).ok()?;
        }
        Some(())
    }

    /// Checks an array's length and writes its prefix.
    fn length(&mut self, len: Len, n: usize) -> Option<()> {
        match len {
            Len::Fixed(len) => (n == len as usize).then_some(()),
            Len::Dynamic { max, .. } if n > max as usize => None,
            Len::Dynamic { tail: true, .. } if self.tao => Some(()),
            Len::Dynamic { len_bits, .. } => {
                let bits = u32::from(len_bits);
                self.out.write(scalar::to_stream(n as u64, bits), bits).ok()
            }
        }
    }
}

/// The primitive of `kind` at bit `offset` of `data`, which holds its bits.
#[inline(always)]
fn scalar_at(data: &[u8], offset: usize, kind: Kind) -> Scalar {
    match kind {
        // Unsigned fields, the most common, need no conversion.
        Kind::Uint { bits, .. } => Scalar::Uint(scalar::from_stream(
            read_bits(data, offset, bits.into()),
            bits.into(),
        )),
        _ => read_scalar(data, offset, kind),
    }
}

/// A struct (of type `node`) of primitives and padding alone; `data` holds all of its bits.
#[inline]
fn fixed_struct<K: ValueSink>(
    sink: &mut K,
    data: &[u8],
    fields: &[FixedField],
    node: NodeId,
) -> Result<K::Value, K::Error> {
    let mut built = sink.begin_struct(node)?;
    for field in fields {
        let value = scalar_at(data, field.offset as usize, field.kind);
        let item = sink.scalar(value)?;
        sink.put(&mut built, field.field, item)?;
    }
    sink.end_struct(built, node)
}

struct Decoder<'a, K> {
    sink: &'a mut K,
    /// The data, perhaps with zeros after it.
    data: &'a [u8],
    /// The data's own length in bits.
    bit_len: usize,
    /// The bit offset of the next read.
    pos: usize,
    tao: bool,
}

impl<K: ValueSink> Decoder<'_, K> {
    fn bits_left(&self) -> usize {
        self.bit_len - self.pos
    }

    /// The steps of one struct (of type `node`), up to its [`Step::End`].
    fn fields(
        &mut self,
        steps: &mut slice::Iter<'_, Step>,
        node: NodeId,
    ) -> Result<Option<K::Value>, K::Error> {
        let mut built = self.sink.begin_struct(node)?;
        while let Some(&step) = steps.next() {
            let (field, item) = match step {
                Step::Leaf { field, kind } | Step::Version { field, kind, .. } => {
                    let bits = scalar_bits(kind) as usize;
                    if bits > self.bits_left() {
                        return Ok(None);
                    }
                    let value = scalar_at(self.data, self.pos, kind);
                    self.pos += bits;
                    (field, self.sink.scalar(value)?)
                }
                Step::Run { .. } => continue,
                Step::Pad { bits } => {
                    if usize::from(bits) > self.bits_left() {
                        return Ok(None);
                    }
                    self.pos += usize::from(bits);
                    continue;
                }
                Step::Begin { field, node } => match self.fields(steps, node)? {
                    Some(inner) => (field, inner),
                    None => return Ok(None),
                },
                Step::End => break,
                Step::Array { field, elem, len } => match self.array(elem, len)? {
                    Some(list) => (field, list),
                    None => return Ok(None),
                },
            };
            self.sink.put(&mut built, field, item)?;
        }
        self.sink.end_struct(built, node).map(Some)
    }

    fn array(&mut self, elem: Kind, len: Len) -> Result<Option<K::Value>, K::Error> {
        let bits = scalar_bits(elem) as usize;
        let n = match len {
            Len::Fixed(len) => len as usize,
            // Elements are read while a whole byte is left.
            Len::Dynamic { tail: true, .. } if self.tao => match self.bits_left() {
                left @ 8.. => (left - 8) / bits + 1,
                _ => 0,
            },
            Len::Dynamic { len_bits, .. } => {
                if usize::from(len_bits) > self.bits_left() {
                    return Ok(None);
                }
                let n = scalar::from_stream(
                    read_bits(self.data, self.pos, len_bits.into()),
                    len_bits.into(),
                );
                self.pos += usize::from(len_bits);
                n as usize
            }
        };
        let too_long = matches!(len, Len::Dynamic { max, .. } if n > max as usize);
        if too_long || n * bits > self.bits_left() {
            return Ok(None);
        }
        let (data, start) = (self.data, self.pos);
        self.pos += n * bits;
        let items = (0..n).map(|i| read_scalar(data, start + i * bits, elem));
        self.sink.list(n, items).map(Some)
    }
}
