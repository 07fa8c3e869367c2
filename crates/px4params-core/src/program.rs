//! Value programs: a type compiled once into flat lists of steps (which field, of which kind,
//! in which order; where nested structs begin and end; where arrays and unions go), run over a
//! caller's value representation through two small traits: [`ValueSource`] (read a value's
//! fields and items, for encoding) and [`ValueSink`] (build one, for decoding). The Python
//! binding implements them for Python objects, so that `encode` reads a dict and writes the
//! bits, and `decode` reads the bits and builds the dict, each in one pass, with no leaf list
//! and no walk in between.
//!
//! Programs cover every struct and union type: primitives, padding, versions, nested structs,
//! unions (the tag, then the one variant), arrays of primitives and arrays of composites
//! (static; dynamic with their length prefix; tail arrays without it, where tail array
//! optimization applies: the last field of the top-level value, elements of 8 bits or more).
//! Only a type nested deeper than the codec ever walks ([`MAX_DEPTH`]) has none.
//!
//! A program is a plan: it answers or declines, and never words an error. The bits come from
//! the codec's own conversions ([`scalar_stream`], [`read_scalar`]); whatever a program does
//! not take exactly as the codec would (a value the source declines, a missing or unknown
//! field, a number out of range, an array of another length, an unknown union variant, short
//! data, a bad tag, trailing bytes) makes it decline (`None`), and the caller then runs
//! [`crate::codec::encode`] or [`crate::codec::decode`], which answers or words the error.

use alloc::boxed::Box;
use alloc::vec::Vec;
use core::slice;

use crate::bits::{from_stream, read_bits, to_stream, BitWriter};
use crate::codec::{
    read_scalar, scalar_bits, scalar_stream, DecodeOptions, EncodeOptions, MAX_DEPTH,
};
use crate::layout::{Kind, Layout, NodeId, Role};
use crate::rules::{tail_elements, tail_goes_on, tail_qualifies};
use crate::scalar::Scalar;

/// Reads a value for [`Program::encode`]. Every method may decline (`None`): the value is not
/// one the program takes as the codec would (the caller's general path then decides).
pub trait ValueSource {
    /// A value borrowed from the value being encoded (or its root), valid while its
    /// container is read.
    type Item: Copy;
    /// A struct being read: its fields are asked for in field order.
    type Struct;
    /// An array being read (of primitives, or of composite items).
    type Array;

    /// Starts reading `item` as a struct.
    fn begin_struct(&mut self, item: Self::Item) -> Option<Self::Struct>;
    /// The field whose index in [`Layout::fields`] is `field`: `Some(None)` when absent.
    fn field(&mut self, fields: &mut Self::Struct, field: u32) -> Option<Option<Self::Item>>;
    /// The struct is read, `used` of its entries found as fields: declines when it holds
    /// others.
    fn end_struct(&mut self, fields: Self::Struct, used: usize) -> Option<()>;
    /// `item` as a union whose variants are the `count` fields from index `first` of
    /// [`Layout::fields`]: the selected variant (`0..count`) and its value.
    fn union(&mut self, item: Self::Item, first: u32, count: u32) -> Option<(u32, Self::Item)>;
    /// `item` as a primitive of `kind` (its value, not yet checked against the kind's range).
    fn scalar(&mut self, item: Self::Item, kind: Kind) -> Option<Scalar>;
    /// Starts reading `item` as an array of `elem` primitives: the array and its length.
    fn begin_array(&mut self, item: Self::Item, elem: Kind) -> Option<(Self::Array, usize)>;
    /// Element `index` (below the length) of an array, as a primitive of `elem`.
    fn element(&mut self, array: &Self::Array, index: usize, elem: Kind) -> Option<Scalar>;
    /// Element `index` of an array of `uint8`, when it is a value of 0 to 255: the bytes of a
    /// byte-aligned array are written straight.
    #[inline(always)]
    fn byte(&mut self, array: &Self::Array, index: usize, elem: Kind) -> Option<u8> {
        match self.element(array, index, elem)? {
            Scalar::Uint(v) => u8::try_from(v).ok(),
            _ => None,
        }
    }
    /// Starts reading `item` as an array of composite values (structs, unions, arrays): the
    /// array and its length.
    fn begin_items(&mut self, item: Self::Item) -> Option<(Self::Array, usize)>;
    /// Item `index` (below the length) of an array of composite values.
    fn item(&mut self, array: &Self::Array, index: usize) -> Option<Self::Item>;
}

/// Builds a value for [`Program::decode`]. Its errors are the sink's own (out of memory, say),
/// passed on unchanged.
pub trait ValueSink {
    /// A built value.
    type Value;
    /// A struct being built, its fields put in field order.
    type Struct;
    /// An array of composite values being built, its items pushed in order.
    type Items;
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
    /// A value of union `node` whose selected variant is field `field` of [`Layout::fields`],
    /// holding `value`.
    fn union(
        &mut self,
        node: NodeId,
        field: u32,
        value: Self::Value,
    ) -> Result<Self::Value, Self::Error>;
    /// A primitive's value.
    fn scalar(&mut self, value: Scalar) -> Result<Self::Value, Self::Error>;
    /// An array of `len` primitives, produced in order by `items`.
    fn list(
        &mut self,
        len: usize,
        items: impl Iterator<Item = Scalar>,
    ) -> Result<Self::Value, Self::Error>;
    /// Starts an array of composite values; `len` is its length, or for a tail array the most
    /// it can have.
    fn begin_items(&mut self, len: usize) -> Result<Self::Items, Self::Error>;
    /// Adds the next item.
    fn push(&mut self, items: &mut Self::Items, value: Self::Value) -> Result<(), Self::Error>;
    /// The array's value, every item pushed.
    fn end_items(&mut self, items: Self::Items) -> Result<Self::Value, Self::Error>;
}

/// One step of a struct's program, in the order of the bits. `field` is a field's index in
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
    /// A union or an array of composites: the program's value `value` ([`Program::values`]).
    Value { field: u32, value: u32 },
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

/// A value that is not a struct's field of its own: the root, a union's variant, an item of
/// an array, a union or array of composites in a struct ([`Step::Value`]).
#[derive(Debug)]
enum Value {
    /// A struct of type `node`: its steps, ending with [`Step::End`].
    Struct { node: NodeId, steps: Box<[Step]> },
    /// A primitive.
    Scalar(Kind),
    /// An array of primitives.
    Array { elem: Kind, len: Len },
    /// A union of type `node`, its variants the fields from `first`.
    Union {
        node: NodeId,
        first: u32,
        tag_bits: u8,
        variants: Box<[Value]>,
    },
    /// An array of composites: its items' program, and the last item's when the array ends
    /// the value (a tail array inside the last item may drop its prefix).
    Items {
        len: Len,
        item: Box<Value>,
        last: Option<Box<Value>>,
    },
}

/// A type's program.
#[derive(Debug)]
pub struct Program {
    root: NodeId,
    /// The root's program: a struct's or a union's.
    top: Value,
    /// Unions and arrays of composites in structs, by [`Step::Value`].
    values: Box<[Value]>,
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
    /// The fields of `steps` (a root struct's) when all are primitives and padding.
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
                Step::End | Step::Run { .. } => {}
                Step::Begin { .. } | Step::Array { .. } | Step::Value { .. } => return None,
            }
        }
        Some(Self {
            fields: fields.into(),
            bits: bits as usize,
        })
    }
}

impl Program {
    /// The program of struct or union type `root`; `None` for other nodes and for a type
    /// nested deeper than the codec walks.
    pub fn compile(layout: &Layout<'_>, root: NodeId) -> Option<Self> {
        if !matches!(
            layout.node(root).kind,
            Kind::Struct { .. } | Kind::Union { .. }
        ) {
            return None;
        }
        let mut compiler = Compiler {
            layout,
            values: Vec::new(),
        };
        let top = compiler.value(root, true, 1)?;
        let fixed = match &top {
            Value::Struct { steps, .. } => Fixed::of(steps),
            _ => None,
        };
        Some(Self {
            root,
            top,
            values: compiler.values.into(),
            fixed,
        })
    }

    /// The type the program is of.
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
            values: &self.values,
            tao: options.tao,
            saturate: options.saturate,
        };
        match &self.top {
            // The common case first: a struct's steps, with no dispatch.
            Value::Struct { steps, .. } => {
                let fields = encoder.source.begin_struct(value)?;
                encoder.fields(&mut steps.iter(), fields)?;
            }
            top => encoder.value(top, value)?,
        }
        encoder.out.finish().ok()
    }

    /// Decodes `data` into a value built by `sink`: `Ok(None)` to decline (the data is not a
    /// value the program reads as the codec would: short, too long, a bad tag, an array too
    /// long).
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
            values: &self.values,
            tao: options.tao,
        };
        let decoded = match &self.top {
            Value::Struct { steps, node } => decoder.fields(&mut steps.iter(), *node)?,
            top => decoder.value(top)?,
        };
        let Some(value) = decoded else {
            return Ok(None);
        };
        if !options.allow_trailing && len > decoder.pos.div_ceil(8) {
            return Ok(None);
        }
        Ok(Some(value))
    }
}

/// Compiles a type's values, collecting the unions and arrays of composites its structs hold.
struct Compiler<'l, 'a> {
    layout: &'l Layout<'a>,
    values: Vec<Value>,
}

impl Compiler<'_, '_> {
    /// The program of a value of node `id`; `tail` when it ends the top-level value, `depth`
    /// the codec's nesting at it (`None` beyond [`MAX_DEPTH`], or for padding as a value).
    fn value(&mut self, id: NodeId, tail: bool, depth: usize) -> Option<Value> {
        if depth > MAX_DEPTH {
            return None;
        }
        let layout = self.layout;
        Some(match layout.node(id).kind {
            kind if is_primitive(kind) => Value::Scalar(kind),
            Kind::Struct { first, count } => {
                let mut steps = Vec::new();
                self.fields(first, count, tail, depth, &mut steps)?;
                steps.push(Step::End);
                Value::Struct {
                    node: id,
                    steps: with_runs(&steps).into(),
                }
            }
            Kind::Union {
                first,
                count,
                tag_bits,
            } => {
                let variants = (first..first + count)
                    .map(|f| self.value(layout.fields[f as usize].node, tail, depth + 1))
                    .collect::<Option<_>>()?;
                Value::Union {
                    node: id,
                    first,
                    tag_bits,
                    variants,
                }
            }
            Kind::Array { elem, len } => self.array(elem, Len::Fixed(len), tail, depth)?,
            Kind::DynArray {
                elem,
                max,
                len_bits,
            } if len_bits > 0 => {
                let len = Len::Dynamic {
                    max,
                    len_bits,
                    tail: tail && tail_qualifies(layout.node(elem).min_bits),
                };
                self.array(elem, len, tail, depth)?
            }
            _ => return None,
        })
    }

    /// An array of `elem` values; its last item ends the value when the array does.
    fn array(&mut self, elem: NodeId, len: Len, tail: bool, depth: usize) -> Option<Value> {
        // Its elements are a level deeper, primitives too (as the walk counts them).
        if depth + 1 > MAX_DEPTH {
            return None;
        }
        if let Some(elem) = primitive(self.layout, elem) {
            return Some(Value::Array { elem, len });
        }
        let item = Box::new(self.value(elem, false, depth + 1)?);
        let last = match tail {
            true => Some(Box::new(self.value(elem, true, depth + 1)?)),
            false => None,
        };
        Some(Value::Items { len, item, last })
    }

    /// Appends the steps of a struct's fields; `tail` when the struct ends the value.
    fn fields(
        &mut self,
        first: u32,
        count: u32,
        tail: bool,
        depth: usize,
        steps: &mut Vec<Step>,
    ) -> Option<()> {
        let layout = self.layout;
        for field in first..first + count {
            // Every field is a level deeper, primitives and padding too (as the walk counts
            // them): a struct at the nesting bound holds none the walk takes.
            if depth + 1 > MAX_DEPTH {
                return None;
            }
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
                    self.fields(first, count, last, depth + 1, steps)?;
                    Step::End
                }
                (Role::Data, _) => match self.value(member.node, last, depth + 1)? {
                    Value::Array { elem, len } => Step::Array { field, elem, len },
                    value => {
                        self.values.push(value);
                        Step::Value {
                            field,
                            value: self.values.len() as u32 - 1,
                        }
                    }
                },
                _ => return None,
            };
            steps.push(step);
        }
        Some(())
    }
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

impl Len {
    /// Whether the array drops its length prefix (tail array optimization is on, `tao`).
    #[inline]
    fn tail(self, tao: bool) -> bool {
        matches!(self, Len::Dynamic { tail: true, .. }) && tao
    }
}

/// Which program an array's item `i` of `n` follows: the last item's when the array ends the
/// value and keeps its length prefix (a tail array's items never end the value).
#[inline]
fn item_of<'v>(
    item: &'v Value,
    last: Option<&'v Value>,
    len: Len,
    tao: bool,
    i: usize,
    n: usize,
) -> &'v Value {
    match last {
        Some(last) if i + 1 == n && !len.tail(tao) => last,
        _ => item,
    }
}

struct Encoder<'s, 'o, 'p, S> {
    source: &'s mut S,
    out: BitWriter<'o>,
    /// The length of `out`.
    room: usize,
    values: &'p [Value],
    tao: bool,
    saturate: bool,
}

impl<S: ValueSource> Encoder<'_, '_, '_, S> {
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
                Step::Value { field, value } => {
                    let item = self.source.field(&mut fields, field)??;
                    used += 1;
                    let values = self.values;
                    self.value(&values[value as usize], item)?;
                }
                // Only ever inside runs.
                Step::Leaf { .. } | Step::Version { .. } | Step::Pad { .. } => return None,
            }
        }
        self.source.end_struct(fields, used)
    }

    /// A value of its own (the root, a variant, an item).
    fn value(&mut self, value: &Value, item: S::Item) -> Option<()> {
        match value {
            Value::Struct { steps, .. } => {
                let fields = self.source.begin_struct(item)?;
                self.fields(&mut steps.iter(), fields)
            }
            &Value::Scalar(kind) => {
                let value = self.source.scalar(item, kind)?;
                let (stream, bits) = scalar_stream(kind, value, self.saturate).ok()?;
                self.out.write(stream, bits).ok()
            }
            &Value::Array { elem, len } => self.array(item, elem, len),
            Value::Union {
                first,
                tag_bits,
                variants,
                ..
            } => {
                let count = variants.len() as u32;
                let (tag, inner) = self.source.union(item, *first, count)?;
                let variant = variants.get(tag as usize)?;
                if *tag_bits > 0 {
                    let bits = u32::from(*tag_bits);
                    self.out.write(to_stream(tag.into(), bits), bits).ok()?;
                }
                self.value(variant, inner)
            }
            Value::Items {
                len,
                item: each,
                last,
            } => {
                let (array, n) = self.source.begin_items(item)?;
                self.length(*len, n)?;
                for i in 0..n {
                    let inner = self.source.item(&array, i)?;
                    let program = item_of(each, last.as_deref(), *len, self.tao, i, n);
                    self.value(program, inner)?;
                }
                Some(())
            }
        }
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

    // Inlined into the struct loop, where nearly every array is (as before unions and arrays
    // of composites gave it a second caller): a call here costs a plain struct's encode.
    #[inline(always)]
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
    #[inline(always)]
    fn length(&mut self, len: Len, n: usize) -> Option<()> {
        match len {
            Len::Fixed(len) => (n == len as usize).then_some(()),
            Len::Dynamic { max, .. } if n > max as usize => None,
            Len::Dynamic { tail: true, .. } if self.tao => Some(()),
            Len::Dynamic { len_bits, .. } => {
                let bits = u32::from(len_bits);
                self.out.write(to_stream(n as u64, bits), bits).ok()
            }
        }
    }
}

/// The primitive of `kind` at bit `offset` of `data`, which holds its bits.
#[inline(always)]
fn scalar_at(data: &[u8], offset: usize, kind: Kind) -> Scalar {
    match kind {
        // Unsigned fields, the most common, need no conversion.
        Kind::Uint { bits, .. } => Scalar::Uint(from_stream(
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

struct Decoder<'a, 'p, K> {
    sink: &'a mut K,
    /// The data, perhaps with zeros after it.
    data: &'a [u8],
    /// The data's own length in bits.
    bit_len: usize,
    /// The bit offset of the next read.
    pos: usize,
    values: &'p [Value],
    tao: bool,
}

impl<K: ValueSink> Decoder<'_, '_, K> {
    fn bits_left(&self) -> usize {
        self.bit_len - self.pos
    }

    /// The next `bits` bits as an unsigned number (1 to 64 bits); `None` past the data.
    fn uint(&mut self, bits: u8) -> Option<u64> {
        if usize::from(bits) > self.bits_left() {
            return None;
        }
        let n = from_stream(read_bits(self.data, self.pos, bits.into()), bits.into());
        self.pos += usize::from(bits);
        Some(n)
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
                Step::Value { field, value } => {
                    let values = self.values;
                    match self.value(&values[value as usize])? {
                        Some(inner) => (field, inner),
                        None => return Ok(None),
                    }
                }
            };
            self.sink.put(&mut built, field, item)?;
        }
        self.sink.end_struct(built, node).map(Some)
    }

    /// A value of its own (the root, a variant, an item).
    fn value(&mut self, value: &Value) -> Result<Option<K::Value>, K::Error> {
        match value {
            Value::Struct { node, steps } => self.fields(&mut steps.iter(), *node),
            &Value::Scalar(kind) => {
                let bits = scalar_bits(kind) as usize;
                if bits > self.bits_left() {
                    return Ok(None);
                }
                let value = scalar_at(self.data, self.pos, kind);
                self.pos += bits;
                self.sink.scalar(value).map(Some)
            }
            &Value::Array { elem, len } => self.array(elem, len),
            Value::Union {
                node,
                first,
                tag_bits,
                variants,
            } => {
                let tag = match *tag_bits {
                    0 => 0,
                    bits => match self.uint(bits) {
                        Some(tag) => tag as usize,
                        None => return Ok(None),
                    },
                };
                let Some(variant) = variants.get(tag) else {
                    return Ok(None);
                };
                let Some(inner) = self.value(variant)? else {
                    return Ok(None);
                };
                self.sink.union(*node, first + tag as u32, inner).map(Some)
            }
            Value::Items { len, item, last } => {
                let (n, max) = match *len {
                    Len::Fixed(n) => (Some(n as usize), n as usize),
                    Len::Dynamic { max, .. } if len.tail(self.tao) => (None, max as usize),
                    Len::Dynamic { max, len_bits, .. } => match self.uint(len_bits) {
                        Some(n) if n <= u64::from(max) => (Some(n as usize), n as usize),
                        _ => return Ok(None),
                    },
                };
                let mut items = self.sink.begin_items(n.unwrap_or(max))?;
                let mut i = 0;
                loop {
                    let more = match n {
                        Some(n) => i < n,
                        None => tail_goes_on(self.bits_left()),
                    };
                    if !more {
                        break;
                    }
                    if i == max {
                        return Ok(None);
                    }
                    let program = item_of(item, last.as_deref(), *len, self.tao, i, max);
                    let Some(value) = self.value(program)? else {
                        return Ok(None);
                    };
                    self.sink.push(&mut items, value)?;
                    i += 1;
                }
                self.sink.end_items(items).map(Some)
            }
        }
    }

    fn array(&mut self, elem: Kind, len: Len) -> Result<Option<K::Value>, K::Error> {
        let bits = scalar_bits(elem) as usize;
        let n = match len {
            Len::Fixed(len) => len as usize,
            Len::Dynamic { tail: true, .. } if self.tao => tail_elements(self.bits_left(), bits),
            Len::Dynamic { len_bits, .. } => match self.uint(len_bits) {
                Some(n) => n as usize,
                None => return Ok(None),
            },
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
