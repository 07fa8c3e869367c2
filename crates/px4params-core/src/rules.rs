//! The DroneCAN rules' shared vocabulary: what the one walk ([`crate::walk`]), the plans and
//! the operations ([`crate::codec`], [`crate::leaf`], [`crate::translate`]) all speak, so that
//! none of them imports another for it (the core's modules import each other in one
//! direction: `rules` below them all). Each item is re-exported where it was first defined.

use core::convert::Infallible;
use core::fmt;

use crate::bits::{from_stream, BitRead};
use crate::error::{Error, Path};
use crate::layout::{Field, Kind, Layout, NodeId};
use crate::plan::{Active, Plans};
use crate::scalar::{self, Scalar};

// From `codec`.

/// Nesting deeper than this is refused (DSDL cannot express recursion; a corrupt static
/// layout could).
pub const MAX_DEPTH: usize = 64;

/// Options for encoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncodeOptions {
    /// Tail array optimization (on for classic CAN and for parameter storage, off for CAN FD).
    pub tao: bool,
    /// Clamp out-of-range values of `saturated` fields instead of refusing them.
    pub saturate: bool,
    /// Write `p_version` fields as given (re-encoding stored data of another version) instead
    /// of refusing any value but the type's version.
    pub keep_versions: bool,
}

impl Default for EncodeOptions {
    fn default() -> Self {
        Self {
            tao: true,
            saturate: false,
            keep_versions: false,
        }
    }
}

/// Options for decoding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DecodeOptions {
    /// Tail array optimization (see [`EncodeOptions::tao`]).
    pub tao: bool,
    /// Accept whole bytes after the value (CAN FD frames are padded to their DLC).
    pub allow_trailing: bool,
}

impl Default for DecodeOptions {
    fn default() -> Self {
        Self {
            tao: true,
            allow_trailing: false,
        }
    }
}

/// What kind of leaf a position holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeafKind {
    /// A primitive field: one of [`Kind::Uint`], [`Kind::Int`], [`Kind::Float`], [`Kind::Bool`].
    Scalar(Kind),
    /// A union's tag.
    Tag {
        /// Tag width in bits.
        bits: u8,
        /// The union node.
        union: NodeId,
    },
    /// A dynamic array's length (encoded in `bits` bits; 0 when tail-array optimized).
    Len {
        /// Prefix width in bits, 0 under tail array optimization.
        bits: u8,
        /// The array node.
        array: NodeId,
    },
}

/// The length of an array as the decoder announces it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArrayLen {
    /// A static array of this length (its length is not a leaf).
    Fixed(usize),
    /// A dynamic array whose length prefix says this.
    Prefixed(usize),
    /// A tail-optimized dynamic array: its length is known when it ends.
    Tail,
}

/// Where the decoder is when it hands a leaf to a [`Sink`].
#[derive(Clone, Copy, Debug)]
pub struct At<'a> {
    /// Field path of the leaf.
    pub path: &'a Path,
    /// Bit offset of the leaf in the data.
    pub bit_offset: usize,
    /// What the leaf is.
    pub kind: LeafKind,
}

/// Supplies a value to the encoder, which asks for it in serialization order.
pub trait Source {
    /// The source's own error (e.g. "expected a dict, got str").
    type Error;
    /// Whether the source is a flat leaf list that supports [`Source::leaf_run`]: the encoder
    /// then skips the struct calls and takes fixed-shape runs of leaves at once.
    const FLAT: bool = false;
    /// The next `n` leaves, for flat sources; `None` for others. An error (fewer than `n`
    /// left) must leave the source where it was: the encoder then takes the leaves one by one
    /// and names the first one missing.
    #[inline]
    fn leaf_run(&mut self, _n: usize) -> Option<Result<&[Scalar], Self::Error>> {
        None
    }
    /// For flat sources, the leaves not taken yet, without taking them (`None` for others):
    /// a plan reads them first and takes them ([`Source::leaf_run`]) only when it answers,
    /// so that declining leaves the source where it was.
    #[inline]
    fn pending_leaves(&self) -> Option<&[Scalar]> {
        None
    }
    /// The primitive at the current position; `kind` is the field's type.
    fn scalar(&mut self, kind: Kind) -> Result<Scalar, Self::Error>;
    /// The current position must hold a struct.
    fn begin_struct(&mut self) -> Result<(), Self::Error>;
    /// Moves to field `name` (at `index` in [`Layout::fields`]) of the current struct;
    /// `Ok(false)` when the input lacks it.
    fn field(&mut self, index: u32, name: &str) -> Result<bool, Self::Error>;
    /// Leaves the field entered by a successful [`Source::field`].
    fn end_field(&mut self);
    /// Ends the struct whose members are `fields`; `used` of them were present in the input,
    /// so any further input field is unknown.
    fn end_struct(
        &mut self,
        layout: &Layout<'_>,
        fields: &[Field],
        used: usize,
    ) -> Result<(), Self::Error>;
    /// The current position must hold a union: returns the index of the selected variant among
    /// `variants` and moves into it.
    fn begin_union(&mut self, layout: &Layout<'_>, variants: &[Field]) -> Result<u32, Self::Error>;
    /// Leaves the union.
    fn end_union(&mut self);
    /// The current position must hold an array: returns its length. `fixed` is the declared
    /// length of a static array, `None` for a dynamic one.
    fn begin_array(&mut self, fixed: Option<u32>) -> Result<usize, Self::Error>;
    /// Moves to element `index` of the current array.
    fn element(&mut self, index: usize) -> Result<(), Self::Error>;
    /// Leaves the element.
    fn end_element(&mut self);
    /// Leaves the array.
    fn end_array(&mut self);
}

/// Receives a decoded value, in serialization order.
pub trait Sink {
    /// The sink's own error.
    type Error;
    /// Whether the sink is a flat leaf list that supports [`Sink::leaf_slots`]: the decoder
    /// then skips the struct calls and fills fixed-shape runs of leaves at once.
    const FLAT: bool = false;
    /// Room for the next `n` leaves, for flat sinks; `None` for others.
    #[inline]
    fn leaf_slots(&mut self, _n: usize) -> Option<Result<&mut [Scalar], Self::Error>> {
        None
    }
    /// A primitive field's value.
    fn scalar(&mut self, value: Scalar, at: At<'_>) -> Result<(), Self::Error>;
    /// A struct begins; `field` announces each member before its value.
    fn begin_struct(&mut self, fields: usize) -> Result<(), Self::Error>;
    /// The next value is field `name` (at `index` in [`Layout::fields`]) of the current struct.
    fn field(&mut self, index: u32, name: &str) -> Result<(), Self::Error>;
    /// The struct ends.
    fn end_struct(&mut self) -> Result<(), Self::Error>;
    /// A union begins with variant `name` (tag `tag`, at `index` in [`Layout::fields`])
    /// selected; its value follows.
    fn begin_union(
        &mut self,
        tag: u32,
        index: u32,
        name: &str,
        at: At<'_>,
    ) -> Result<(), Self::Error>;
    /// The union ends.
    fn end_union(&mut self) -> Result<(), Self::Error>;
    /// An array begins.
    fn begin_array(&mut self, len: ArrayLen, at: At<'_>) -> Result<(), Self::Error>;
    /// The array ends with `len` elements.
    fn end_array(&mut self, len: usize) -> Result<(), Self::Error>;
}

/// A value decoded into a flat leaf list: the bits it took and the leaves written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Decoded {
    /// Bits the value took.
    pub bits: usize,
    /// Leaves written to the front of the list.
    pub leaves: usize,
}

/// Whether a dynamic array with element `elem` drops its length prefix when it is last (not
/// where the layout lacks the node: the walk refuses it where it comes to it).
#[inline]
pub(crate) fn tail_optimized(layout: &Layout<'_>, elem: NodeId, tao: bool) -> bool {
    tao && layout
        .nodes
        .get(elem as usize)
        .is_some_and(|n| tail_qualifies(n.min_bits))
}

// Tail array optimization, the rule itself: the walk and every plan ask these three.

/// Whether an array whose elements take at least `elem_min_bits` bits drops its length
/// prefix when it ends the value (with the optimization on): elements of 8 bits or more.
#[inline(always)]
pub(crate) const fn tail_qualifies(elem_min_bits: u64) -> bool {
    elem_min_bits >= 8
}

/// Whether a tail array's next element begins with `bits_left` bits left: while a whole byte
/// is left (fewer bits are the padding of the last byte).
#[inline(always)]
pub(crate) const fn tail_goes_on(bits_left: usize) -> bool {
    bits_left >= 8
}

/// How many elements of `elem_bits` bits each (8 or more) a tail array has with `bits_left`
/// bits left: as many as [`tail_goes_on`] begins. The last may run past the end, which the
/// walk refuses (a plan declines it).
#[inline(always)]
pub(crate) const fn tail_elements(bits_left: usize, elem_bits: usize) -> usize {
    if !tail_goes_on(bits_left) {
        0
    } else if elem_bits == 8 {
        // Bytes, the common case, without a division.
        bits_left / 8
    } else {
        (bits_left - 8) / elem_bits + 1
    }
}

/// A scalar from its raw bits.
#[inline(always)]
pub(crate) fn scalar_of(kind: Kind, raw: u64) -> Scalar {
    match kind {
        Kind::Uint { .. } => Scalar::Uint(raw),
        Kind::Int { bits, .. } => Scalar::Int(scalar::sign_extend(raw, bits.into())),
        Kind::Float { bits, .. } => Scalar::Float(scalar::float_from_raw(raw, bits.into())),
        Kind::Bool => Scalar::Bool(raw != 0),
        _ => Scalar::Uint(0),
    }
}

/// Reads a scalar leaf's value at `bit_offset`, as the decoder does.
///
/// # Panics
/// If the leaf's bits lie outside `data` (callers check the length first).
#[inline(always)]
pub fn read_scalar<R: BitRead + ?Sized>(data: &R, bit_offset: usize, kind: Kind) -> Scalar {
    let bits = scalar_bits(kind);
    if bits == 0 {
        return Scalar::Uint(0);
    }
    scalar_of(kind, from_stream(data.read_bits(bit_offset, bits), bits))
}

/// The bit width of a scalar kind (0 for containers).
#[inline(always)]
pub fn scalar_bits(kind: Kind) -> u32 {
    match kind {
        Kind::Uint { bits, .. } | Kind::Int { bits, .. } | Kind::Float { bits, .. } => bits.into(),
        Kind::Bool => 1,
        Kind::Void { bits } => bits.into(),
        _ => 0,
    }
}

/// Raw bits of `value` for a scalar kind, honouring the cast mode.
#[cfg_attr(not(feature = "compact"), inline)]
#[cfg_attr(feature = "compact", inline(never))]
pub(crate) fn scalar_raw(
    kind: Kind,
    value: Scalar,
    saturate: bool,
) -> Result<u64, scalar::ScalarError> {
    // Hosts only (firmware keeps this function small): a signed value in range, which
    // sign-extending from the field's width gives back, needs no casting rules. Here rather
    // than in `fast_raw`, whose every unsigned field it would slow.
    if Active::FLAT {
        if let (Kind::Int { bits, .. }, Scalar::Int(v)) = (kind, value) {
            if scalar::sign_extend(v as u64, bits.into()) == v {
                return Ok(v as u64 & crate::bits::field_mask(bits.into()));
            }
        }
    }
    match kind {
        Kind::Uint { bits, cast } => scalar::uint_raw(value, bits.into(), cast, saturate),
        Kind::Int { bits, cast } => scalar::int_raw(value, bits.into(), cast, saturate),
        Kind::Float { bits, cast } => scalar::float_raw(value, bits.into(), cast, saturate),
        _ => match value {
            Scalar::Bool(b) => Ok(u64::from(b)),
            Scalar::Uint(v @ (0 | 1)) => Ok(v),
            Scalar::Int(v @ (0 | 1)) => Ok(v as u64),
            _ => Err(scalar::ScalarError::WrongKind {
                expected: "a boolean",
            }),
        },
    }
}

// From `leaf`.

/// Which leaf to access.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target<'p> {
    /// Leaf `[k]`.
    Index(usize),
    /// A dotted path such as `bus.i2c.address` or `cells[3]`; `_tag` names a union's tag
    /// (`bus._tag`) and `_len` a dynamic array's length (`cells._len`).
    Path(&'p str),
}

/// A located leaf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leaf {
    /// Its number `[k]`.
    pub index: usize,
    /// Where its bits start.
    pub bit_offset: usize,
    /// What it is.
    pub kind: LeafKind,
    /// Its field path.
    pub path: Path,
}

/// Codec errors of leaf access (no value source or sink involved).
pub type LeafAccessError = Error<Infallible>;

/// Where leaf `[k]` of a value encoded without tail array optimization is, found by
/// [`crate::leaf::seek`]: cheaper than [`crate::leaf::locate`] because it keeps no field path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Position {
    /// Where its bits start.
    pub bit_offset: usize,
    /// What it is.
    pub kind: LeafKind,
    /// The leaf is a `p_version` field.
    pub version: bool,
}

impl Position {
    /// Reads the leaf's value (a tag or length as [`Scalar::Uint`]).
    pub fn read<R: BitRead + ?Sized>(&self, data: &R) -> Scalar {
        match self.kind {
            LeafKind::Scalar(kind) => read_scalar(data, self.bit_offset, kind),
            LeafKind::Tag { bits, .. } | LeafKind::Len { bits, .. } => {
                Scalar::Uint(read_uint(data, self.bit_offset, bits.into()))
            }
        }
    }
}

pub(crate) fn read_uint<R: BitRead + ?Sized>(data: &R, offset: usize, bits: u32) -> u64 {
    from_stream(data.read_bits(offset, bits), bits)
}

// From `translate`.

/// Longest field path translation handles.
pub const PATH_MAX: usize = 192;

/// Why a value could not be translated (besides the codec's own errors).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum TranslateError {
    /// A field path longer than [`crate::translate::PATH_MAX`] bytes.
    PathTooLong,
    /// The old data or the base could not be read at a path.
    Unreadable,
}

impl fmt::Display for TranslateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TranslateError::PathTooLong => write!(f, "a field path over {PATH_MAX} bytes"),
            TranslateError::Unreadable => f.write_str("the stored value cannot be read"),
        }
    }
}

// From `value`.

/// Why a leaf list could not be read or written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum LeafError {
    /// The list ended before the value did.
    Exhausted,
    /// The storage for decoded leaves is full.
    Full,
    /// A union tag or array length leaf that is not a non-negative integer.
    NotACount,
}

impl fmt::Display for LeafError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Exhausted => "the leaf list ends before the value",
            Self::Full => "too many leaves for the storage",
            Self::NotACount => "a union tag or array length must be a non-negative integer",
        })
    }
}
