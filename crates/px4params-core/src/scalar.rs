//! DroneCAN scalars: integer and float conversions, cast modes, float16, byte order.

/// How an out-of-range value is brought into a field (DSDL `saturated` / `truncated`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Cast {
    /// Clamp integers to the field's range; clamp finite floats to the largest finite value.
    Saturated,
    /// Keep the low bits of integers; out-of-range floats become infinities.
    Truncated,
}

/// A primitive value as the codec sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scalar {
    /// An unsigned integer, a union tag or an array length.
    Uint(u64),
    /// A signed integer.
    Int(i64),
    /// A floating-point number of any width.
    Float(f64),
    /// A boolean.
    Bool(bool),
}

/// Why a scalar could not be stored in a field.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ScalarError {
    /// The value is outside the field's range and saturation was not requested.
    OutOfRange {
        /// The value, as given.
        value: Scalar,
        /// Smallest value the field holds.
        min: Scalar,
        /// Largest value the field holds.
        max: Scalar,
    },
    /// A float or bool was given for an integer field, or similar.
    WrongKind {
        /// What the field holds.
        expected: &'static str,
    },
}

/// The largest finite float16 value.
pub const FLOAT16_MAX: f64 = 65504.0;

/// Converts a float to IEEE 754 binary16 bits as libuavcan, libcanard and pydronecan do:
/// round to nearest with ties away from zero, overflow to infinity, NaN as `0x7FFF`.
#[inline]
pub fn f16_from_f32(value: f32) -> u16 {
    const F32_INF: u32 = 255 << 23;
    const F16_INF: u32 = 31 << 23;
    const ROUND_MASK: u32 = !0xFFF;
    let magic = f32::from_bits(15 << 23);
    let mut bits = value.to_bits();
    let sign = bits & 0x8000_0000;
    bits ^= sign;
    let out = if bits >= F32_INF {
        if bits > F32_INF {
            0x7FFF
        } else {
            0x7C00
        }
    } else {
        // Drop the bits below half a float16 ulp, rescale the exponent, then add half an ulp
        // (the unsigned subtraction of ROUND_MASK adds 0x1000): ties round away from zero.
        let scaled = (f32::from_bits(bits & ROUND_MASK) * magic).to_bits();
        let rounded = scaled.wrapping_sub(ROUND_MASK).min(F16_INF);
        (rounded >> 13) as u16
    };
    out | (sign >> 16) as u16
}

/// Converts IEEE 754 binary16 bits to a float, exactly.
#[inline]
pub fn f32_from_f16(half: u16) -> f32 {
    let magic = f32::from_bits((254 - 15) << 23);
    let was_inf_nan = f32::from_bits((127 + 16) << 23);
    let mut out = f32::from_bits(u32::from(half & 0x7FFF) << 13) * magic;
    if out >= was_inf_nan {
        out = f32::from_bits(out.to_bits() | (255 << 23));
    }
    f32::from_bits(out.to_bits() | (u32::from(half & 0x8000) << 16))
}

/// Puts a value's bytes in DroneCAN stream order: the whole low bytes first, then the top
/// `bits % 8` bits, as one big-endian stream value of `bits` bits.
#[inline(always)]
pub fn to_stream(value: u64, bits: u32) -> u64 {
    let whole = bits / 8;
    let rest = bits % 8;
    if whole == 0 {
        return value & crate::bits::mask(rest);
    }
    let low = value & crate::bits::field_mask(whole * 8);
    let swapped = low.swap_bytes() >> (64 - whole * 8);
    if rest == 0 {
        swapped
    } else {
        (swapped << rest) | ((value >> (whole * 8)) & crate::bits::field_mask(rest))
    }
}

/// Inverse of [`to_stream`].
#[inline(always)]
pub fn from_stream(stream: u64, bits: u32) -> u64 {
    let whole = bits / 8;
    let rest = bits % 8;
    if whole == 0 {
        return stream;
    }
    let bytes = if rest == 0 { stream } else { stream >> rest };
    let low = (bytes << (64 - whole * 8)).swap_bytes();
    if rest == 0 {
        low
    } else {
        low | ((stream & crate::bits::mask(rest)) << (whole * 8))
    }
}

/// Encodes an unsigned integer field of `bits` bits to raw bits.
#[inline]
pub fn uint_raw(value: Scalar, bits: u32, cast: Cast, saturate: bool) -> Result<u64, ScalarError> {
    if let (Scalar::Bool(b), 1) = (value, bits) {
        return Ok(u64::from(b));
    }
    let max = crate::bits::field_mask(bits);
    integer_raw(value, 0, i128::from(max), max, cast, saturate)
}

/// Encodes a signed integer field of `bits` bits to raw (two's complement) bits.
#[inline]
pub fn int_raw(value: Scalar, bits: u32, cast: Cast, saturate: bool) -> Result<u64, ScalarError> {
    let mask = crate::bits::field_mask(bits);
    let max = i128::from(mask >> 1);
    integer_raw(value, -max - 1, max, mask, cast, saturate)
}

/// An integer `value` for a field holding `min..=max` in the bits of `mask`, cast as `cast`
/// says where it is out of range (clamped only when `saturate`).
fn integer_raw(
    value: Scalar,
    min: i128,
    max: i128,
    mask: u64,
    cast: Cast,
    saturate: bool,
) -> Result<u64, ScalarError> {
    let v = match value {
        Scalar::Uint(v) => i128::from(v),
        Scalar::Int(v) => i128::from(v),
        _ => {
            return Err(ScalarError::WrongKind {
                expected: "an integer",
            })
        }
    };
    let raw = match cast {
        _ if (min..=max).contains(&v) => v,
        Cast::Truncated => v,
        Cast::Saturated if saturate => v.clamp(min, max),
        Cast::Saturated => {
            // The range as the field's kind of number: unsigned from 0, signed otherwise.
            let bound = |b: i128| match min {
                0 => Scalar::Uint(b as u64),
                _ => Scalar::Int(b as i64),
            };
            return Err(ScalarError::OutOfRange {
                value,
                min: bound(min),
                max: bound(max),
            });
        }
    };
    Ok(raw as u64 & mask)
}

/// Encodes a float field of 16, 32 or 64 bits to raw bits.
#[inline]
pub fn float_raw(value: Scalar, bits: u32, cast: Cast, saturate: bool) -> Result<u64, ScalarError> {
    let v = match value {
        Scalar::Float(v) => v,
        Scalar::Int(v) => v as f64,
        Scalar::Uint(v) => v as f64,
        Scalar::Bool(_) => {
            return Err(ScalarError::WrongKind {
                expected: "a number",
            })
        }
    };
    let limit = match bits {
        16 => FLOAT16_MAX,
        32 => f64::from(f32::MAX),
        _ => f64::MAX,
    };
    let v = if v.is_finite() && v.abs() > limit {
        match cast {
            Cast::Truncated => v.signum() * f64::INFINITY,
            Cast::Saturated if saturate => v.signum() * limit,
            Cast::Saturated => {
                return Err(ScalarError::OutOfRange {
                    value,
                    min: Scalar::Float(-limit),
                    max: Scalar::Float(limit),
                })
            }
        }
    } else {
        v
    };
    Ok(match bits {
        16 => u64::from(f16_from_f32(v as f32)),
        32 => u64::from((v as f32).to_bits()),
        _ => v.to_bits(),
    })
}

/// Sign-extends the low `bits` bits of `raw`.
#[inline]
pub fn sign_extend(raw: u64, bits: u32) -> i64 {
    let shift = 64 - bits;
    ((raw << shift) as i64) >> shift
}

/// Decodes raw float bits of 16, 32 or 64 bits.
#[inline]
pub fn float_from_raw(raw: u64, bits: u32) -> f64 {
    match bits {
        16 => f64::from(f32_from_f16(raw as u16)),
        32 => f64::from(f32::from_bits(raw as u32)),
        _ => f64::from_bits(raw),
    }
}

/// Whether `given` is the integer `version` (a `p_version` field's value: a float never is).
pub(crate) fn same_integer(given: Scalar, version: u32) -> bool {
    match given {
        Scalar::Uint(v) => v == u64::from(version),
        Scalar::Int(v) => v == i64::from(version),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stream_order_round_trips() {
        for bits in 1..=64 {
            let v = 0x0123_4567_89AB_CDEFu64 & crate::bits::field_mask(bits);
            assert_eq!(from_stream(to_stream(v, bits), bits), v, "bits={bits}");
        }
        // 0xEDA as 12 bits: low byte DA first, then the top nibble E.
        assert_eq!(to_stream(0xEDA, 12), 0xDAE);
    }

    #[test]
    fn float16_known_values() {
        assert_eq!(f16_from_f32(1.0), 0x3C00);
        assert_eq!(f16_from_f32(-2.0), 0xC000);
        assert_eq!(f16_from_f32(65504.0), 0x7BFF);
        assert_eq!(f16_from_f32(f32::INFINITY), 0x7C00);
        assert_eq!(f16_from_f32(f32::NAN), 0x7FFF);
        assert_eq!(f16_from_f32(1e6), 0x7C00);
        // 1 + 2^-11 lies exactly between two float16 values: ties go away from zero.
        assert_eq!(f16_from_f32(1.0 + 1.0 / 2048.0), 0x3C01);
        assert_eq!(f16_from_f32(-(1.0 + 1.0 / 2048.0)), 0xBC01);
        assert_eq!(f32_from_f16(0x3C01), 1.0 + 1.0 / 1024.0);
        assert_eq!(f32_from_f16(0x0001), 2f32.powi(-24));
        assert!(f32_from_f16(0x7FFF).is_nan());
        assert_eq!(f32_from_f16(0xFC00), f32::NEG_INFINITY);
    }

    #[test]
    fn float16_round_trips_every_finite_value() {
        for half in 0..=u16::MAX {
            let f = f32_from_f16(half);
            if f.is_nan() {
                continue;
            }
            assert_eq!(f16_from_f32(f), half, "half={half:#06x}");
        }
    }

    #[test]
    fn integer_casts() {
        let sat = Cast::Saturated;
        let trunc = Cast::Truncated;
        assert_eq!(uint_raw(Scalar::Uint(0xBEDA), 12, trunc, false), Ok(0xEDA));
        assert_eq!(uint_raw(Scalar::Uint(300), 8, sat, true), Ok(255));
        assert_eq!(uint_raw(Scalar::Int(-1), 8, sat, true), Ok(0));
        assert!(matches!(
            uint_raw(Scalar::Uint(300), 8, sat, false),
            Err(ScalarError::OutOfRange { .. })
        ));
        assert_eq!(int_raw(Scalar::Int(-5), 4, sat, false), Ok(0b1011));
        assert_eq!(int_raw(Scalar::Int(-100), 4, sat, true), Ok(0b1000));
        assert_eq!(int_raw(Scalar::Int(100), 4, trunc, false), Ok(100 & 0xF));
        assert_eq!(sign_extend(0b1011, 4), -5);
        assert_eq!(
            uint_raw(Scalar::Float(1.0), 8, sat, false),
            Err(ScalarError::WrongKind {
                expected: "an integer"
            })
        );
    }

    #[test]
    fn float_casts() {
        let sat = Cast::Saturated;
        assert_eq!(float_raw(Scalar::Float(1e6), 16, sat, true), Ok(0x7BFF));
        assert!(float_raw(Scalar::Float(1e6), 16, sat, false).is_err());
        assert_eq!(
            float_raw(Scalar::Float(1e6), 16, Cast::Truncated, false),
            Ok(0x7C00)
        );
        // Infinities are kept in saturated mode (pydronecan clamps them; the spec does not).
        assert_eq!(
            float_raw(Scalar::Float(f64::NEG_INFINITY), 16, sat, false),
            Ok(0xFC00)
        );
        assert_eq!(
            float_raw(Scalar::Float(1.5), 32, sat, false),
            Ok(u64::from(1.5f32.to_bits()))
        );
    }
}
