//! Encoding and decoding whole values with the DroneCAN rules, driven by a [`Layout`].
//!
//! Values come from a [`Source`] and go to a [`Sink`], so the one loop ([`crate::interp`])
//! serves Python objects in the binding, flat leaf lists in firmware and anything else,
//! without allocating. Each operation here is a dispatcher: a plan answers or declines, and
//! the loop answers the rest and words every error.

use core::convert::Infallible;

use crate::bits::{to_stream, BitRead};
use crate::error::{Error, Step};
use crate::layout::{Kind, Layout, NodeId, Role};
use crate::plan::{Active, Plans};
pub(crate) use crate::rules::scalar_raw;
pub use crate::rules::{
    read_scalar, scalar_bits, ArrayLen, At, DecodeOptions, Decoded, EncodeOptions, LeafKind, Sink,
    Source, MAX_DEPTH,
};
use crate::scalar::{self, Scalar};
use crate::value::{LeafError, LeafSink, LeafSource};
use crate::{interp, straight, walk};

/// Encodes the value of type `root` from `source` into `out`; returns the length in bytes.
///
/// `out` needs [`Layout::max_bytes`] bytes at most; only the bytes returned are written.
// Inlined into the caller, so that a small value the straight plan answers costs no second
// call and no frame of the loop.
#[inline(always)]
pub fn encode<S: Source>(
    layout: &Layout<'_>,
    root: NodeId,
    source: &mut S,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<S::Error>> {
    encode_with::<Active, S>(layout, root, source, out, options)
}

/// [`encode`] with the plans `P`: the straight plan ([`Plans::STRAIGHT`]) answers or
/// declines, and the one loop ([`crate::interp`]) answers what it declines.
#[inline(always)]
pub fn encode_with<P: Plans, S: Source>(
    layout: &Layout<'_>,
    root: NodeId,
    source: &mut S,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<S::Error>> {
    if S::FLAT && P::STRAIGHT {
        if let Some(len) = straight::encode(layout, root, source, out, options) {
            return Ok(len);
        }
    }
    interp::encode::<P, S>(layout, root, source, out, options)
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
    decode_with::<Active, R, K>(layout, root, data, sink, options)
}

/// [`decode`] with the plans `P`: the straight plan answers or declines, and the one loop
/// ([`crate::interp`]) answers what it declines.
#[inline(always)]
pub fn decode_with<P: Plans, R: BitRead + ?Sized, K: Sink>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    sink: &mut K,
    options: DecodeOptions,
) -> Result<usize, Error<K::Error>> {
    if K::FLAT && P::STRAIGHT {
        if let Some(bits) = straight::decode(layout, root, data, sink, options) {
            return Ok(bits);
        }
    }
    interp::decode::<P, R, K>(layout, root, data, sink, options)
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

/// [`encode_leaves`] with the plans `P`: with [`Plans::FLAT`] (hosts), the straight plan, then
/// the one loop ([`crate::interp`], with the flat runs inside it), which words every error;
/// without (firmware), [`crate::walk`], which firmware runs for every other operation on
/// values too, so that it links one interpreter (the loop compiled for leaf lists beside it
/// would add 6.7 KB on a Cortex-M7). Both give the same bytes and errors (`tests/parity.rs`).
pub fn encode_leaves_with<P: Plans>(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<LeafError>> {
    if !P::FLAT {
        return walk::encode(layout, root, leaves, out, options);
    }
    encode_with::<P, _>(layout, root, &mut LeafSource::new(leaves), out, options)
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

/// [`decode_leaves`] with the plans `P`: with [`Plans::FLAT`] (hosts), the straight plan, then
/// the one loop ([`crate::interp`]), which words every error; without (firmware),
/// [`crate::walk`], as [`encode_leaves_with`] says.
pub fn decode_leaves_with<P: Plans, R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    leaves: &mut [Scalar],
    options: DecodeOptions,
) -> Result<Decoded, Error<LeafError>> {
    if !P::FLAT {
        return walk::decode(layout, root, data, leaves, options);
    }
    let mut sink = LeafSink::new(leaves);
    let bits = decode_with::<P, R, _>(layout, root, data, &mut sink, options)?;
    let leaves = sink.leaves().len();
    Ok(Decoded { bits, leaves })
}

/// Checks that `data` is exactly one value of `root` stored without tail array optimization
/// (as the store keeps values) whose `p_version` fields hold the type's version and whose
/// floats are finite (a store keeps no NaN or infinity), with the build's
/// [`crate::plan::Active`] plans: see [`check_stored_with`].
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
        let check = &mut VersionCheck { layout };
        if decode_with::<P, _, _>(layout, root, data, check, options).is_ok() {
            return Ok(());
        }
    }
    walk::check_stored(layout, root, data)
}

/// A sink that keeps nothing and refuses `p_version` fields that differ from the version, and
/// NaNs and infinities.
struct VersionCheck<'l, 'a> {
    layout: &'l Layout<'a>,
}

impl Sink for VersionCheck<'_, '_> {
    /// A `p_version` that is not the type's: the plan declines.
    type Error = ();

    fn scalar(&mut self, value: Scalar, at: At<'_>) -> Result<(), ()> {
        if let Scalar::Float(v) = value {
            return if v.is_finite() { Ok(()) } else { Err(()) };
        }
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
        to_stream(interp::fast_raw::<Active>(kind, value, saturate)?, bits),
        bits,
    ))
}
