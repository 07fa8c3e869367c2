//! DroneCAN scalars: integer and float conversions, cast modes, float16 (where a value's bits
//! go in the stream is [`crate::bits`]').

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
    /// A value a store would keep as a NaN or an infinity: a non-finite float, or a finite
    /// one a truncated float field turns into an infinity. Stores keep finite numbers only
    /// (the codec itself encodes both).
    NotFinite {
        /// The value, as given or read.
        value: Scalar,
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

/// Encodes an unsigned integer field of `bits` bits to raw bits.
#[inline]
pub fn uint_raw(value: Scalar, bits: u32, cast: Cast, saturate: bool) -> Result<u64, ScalarError> {
    if let (Scalar::Bool(b), 1) = (value, bits) {
        return Ok(u64::from(b));
    }
    integer_raw(value, bits, false, cast, saturate)
}

/// Encodes a signed integer field of `bits` bits to raw (two's complement) bits.
#[inline]
pub fn int_raw(value: Scalar, bits: u32, cast: Cast, saturate: bool) -> Result<u64, ScalarError> {
    integer_raw(value, bits, true, cast, saturate)
}

/// An integer `value` for a field of `bits` bits (two's complement when `signed`), cast as
/// `cast` says where it is out of range (clamped only when `saturate`). In 64-bit arithmetic
/// (no `i128`: on 32-bit cores every 128-bit compare is a run of instructions).
fn integer_raw(
    value: Scalar,
    bits: u32,
    signed: bool,
    cast: Cast,
    saturate: bool,
) -> Result<u64, ScalarError> {
    // The mask here, once for both kinds of integer.
    let mask = crate::bits::field_mask(bits);
    // The field holds min..=max: 0..=mask unsigned, -(mask/2)-1..=mask/2 signed.
    let max = if signed { mask >> 1 } else { mask };
    let min = if signed { !max as i64 } else { 0 };
    let (raw, below) = match value {
        Scalar::Uint(v) => (v, false),
        Scalar::Int(v) => (v as u64, v < min),
        _ => {
            return Err(ScalarError::WrongKind {
                expected: "an integer",
            })
        }
    };
    // Above the range: a value over `max` that is not a negative `Int`.
    let above = raw > max && !matches!(value, Scalar::Int(v) if v < 0);
    let raw = match cast {
        _ if !below && !above => raw,
        Cast::Truncated => raw,
        Cast::Saturated if saturate && below => min as u64,
        Cast::Saturated if saturate => max,
        Cast::Saturated => {
            // The range as the field's kind of number: unsigned from 0, signed otherwise.
            let (min, max) = match signed {
                false => (Scalar::Uint(0), Scalar::Uint(max)),
                true => (Scalar::Int(min), Scalar::Int(max as i64)),
            };
            return Err(ScalarError::OutOfRange { value, min, max });
        }
    };
    Ok(raw & mask)
}

/// `v` as the nearest float (`v as f64`). On 32-bit cores from its magnitude (see
/// [`uint_to_f64`]): rounding to nearest is the same for `-v` as for `v`, so the magnitude's
/// float with `v`'s sign is `v`'s.
#[inline]
fn int_to_f64(v: i64) -> f64 {
    if cfg!(target_pointer_width = "32") {
        int_to_f64_halves(v)
    } else {
        v as f64
    }
}

/// [`int_to_f64`] as 32-bit cores do it (a function of its own, so that hosts test it).
#[inline(always)]
fn int_to_f64_halves(v: i64) -> f64 {
    uint_to_f64_bits(v.unsigned_abs(), v < 0)
}

/// `v` as the nearest float (`v as f64`). 32-bit cores convert a 64-bit integer by a library
/// routine (`__aeabi_ul2d`, 136 bytes on Cortex-M); there it is done in integer arithmetic
/// instead, in less code and without the FPU (a Cortex-M4F's is single precision).
#[inline]
fn uint_to_f64(v: u64) -> f64 {
    if cfg!(target_pointer_width = "32") {
        uint_to_f64_bits(v, false)
    } else {
        v as f64
    }
}

/// [`uint_to_f64`] by the bits of IEEE 754 binary64: the value shifted up until its top bit is
/// set, whose top 53 bits are the significand, rounded to nearest (ties to even) by the 11
/// below them; negated where `negative` (its sign bit: one conversion for both signs).
#[inline(never)]
fn uint_to_f64_bits(v: u64, negative: bool) -> f64 {
    let (top, zeros) = shift_top(v);
    // The significand's leading 1 lands on the exponent's lowest bit and adds 1: the biased
    // exponent 1023 + (63 - zeros) is stored less 1.
    let mut bits = (u64::from(1085 - zeros) << 52) + (top >> 11);
    let dropped = top & 0x7FF;
    if dropped > 0x400 || (dropped == 0x400 && bits & 1 == 1) {
        // A carry out of the significand moves to the next power of two, as it should.
        bits += 1;
    }
    f64::from_bits(if v == 0 { 0 } else { bits } | u64::from(negative) << 63)
}

/// `v` shifted up until its top bit is set, and by how many bits (its leading zeros; 0 stays
/// 0), in 32-bit halves: a 64-bit shift by a variable amount is a routine call on 32-bit cores
/// (`__aeabi_llsl`, 44 bytes).
#[inline(always)]
fn shift_top(v: u64) -> (u64, u32) {
    let (high, low) = ((v >> 32) as u32, v as u32);
    // A high half of zeros: the low half moves up whole.
    let (high, low, whole) = if high == 0 {
        (low, 0, 32)
    } else {
        (high, low, 0)
    };
    let zeros = high.leading_zeros();
    let s = zeros & 31;
    // The low half's top `s` bits join the high half (none for `s` 0: two shifts, not 32).
    let high = (high << s) | ((low >> 1) >> (31 - s));
    (u64::from(high) << 32 | u64::from(low << s), whole + zeros)
}

/// Encodes a float field of 16, 32 or 64 bits to raw bits.
#[inline]
pub fn float_raw(value: Scalar, bits: u32, cast: Cast, saturate: bool) -> Result<u64, ScalarError> {
    let v = match value {
        Scalar::Float(v) => v,
        Scalar::Int(v) => int_to_f64(v),
        Scalar::Uint(v) => uint_to_f64(v),
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
    // Finite and beyond the limit, compared as bits: the bits of non-negative floats order as
    // their values do (a Cortex-M4F compares doubles by a library routine).
    let magnitude = v.abs().to_bits();
    let v = if magnitude < f64::INFINITY.to_bits() && magnitude > limit.to_bits() {
        match cast {
            Cast::Truncated => f64::INFINITY.copysign(v),
            Cast::Saturated if saturate => limit.copysign(v),
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
    if cfg!(target_pointer_width = "32") {
        sign_extend_halves(raw, bits)
    } else {
        let shift = 64 - bits;
        ((raw << shift) as i64) >> shift
    }
}

/// [`sign_extend`] in 32-bit halves, as 32-bit cores take it: a 64-bit shift by a variable
/// amount is a routine call there (`__aeabi_llsl`, `__aeabi_lasr`).
#[inline(always)]
fn sign_extend_halves(raw: u64, bits: u32) -> i64 {
    if bits > 32 {
        let shift = 64 - bits;
        let high = (((raw >> 32) as u32 as i32) << shift) >> shift;
        i64::from(high) << 32 | i64::from(raw as u32)
    } else {
        let shift = 32 - bits;
        i64::from(((raw as u32 as i32) << shift) >> shift)
    }
}

/// Whether raw float bits of 16, 32 or 64 bits are a finite number: their exponent is not all
/// ones, which marks infinities and NaNs. (Masks at fixed places, in 32 bits: a 64-bit shift
/// by a variable amount is a routine call on 32-bit cores.)
#[inline]
pub fn raw_is_finite(raw: u64, bits: u32) -> bool {
    let (word, exponent) = match bits {
        16 => (raw as u32, 0x7C00),
        32 => (raw as u32, 0x7F80_0000),
        _ => ((raw >> 32) as u32, 0x7FF0_0000),
    };
    word & exponent != exponent
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
    fn integers_convert_to_floats_from_their_magnitudes_as_casts_do() {
        // 32-bit cores' conversion (hosts cast): exact below 2^53, rounded to nearest even
        // above, halfway cases included (2^53 + 1 lies between two floats), either sign.
        let mut values = std::vec![0i64, 1, -1, i64::MIN, i64::MAX, i64::MIN + 1];
        values.extend([(1 << 53) + 1, (1 << 53) + 3, -(1 << 53) - 1, -(1 << 53) - 3]);
        values.extend(
            (0..63)
                .map(|k| 1i64 << k)
                .flat_map(|p| [p, p - 1, p + 1, p | 0x401]),
        );
        values.extend((1..2000u64).map(|k| k.wrapping_mul(0x9E37_79B9_7F4A_7C15) as i64));
        for v in values {
            for v in [v, v.wrapping_neg()] {
                assert_eq!(int_to_f64(v).to_bits(), (v as f64).to_bits(), "{v}");
                assert_eq!(int_to_f64_halves(v).to_bits(), (v as f64).to_bits(), "{v}");
                let u = v as u64;
                assert_eq!(
                    uint_to_f64_bits(u, false).to_bits(),
                    (u as f64).to_bits(),
                    "{u}"
                );
                let negated = uint_to_f64_bits(u, true).to_bits();
                assert_eq!(negated, (-(u as f64)).to_bits(), "-{u}");
            }
        }
    }

    #[test]
    fn sign_extension_in_halves_is_the_shifts_of_64_bits() {
        let raws = [
            0u64,
            1,
            u64::MAX,
            0x8000_0000,
            0x7FFF_FFFF,
            0x0123_4567_89AB_CDEF,
        ];
        for bits in 1..=64u32 {
            for raw in raws
                .iter()
                .flat_map(|&r| [r, !r, r >> (64 - bits), 1 << (bits - 1)])
            {
                // Bits above the field's too: both drop them.
                let shift = 64 - bits;
                let by_shifts = ((raw << shift) as i64) >> shift;
                assert_eq!(sign_extend_halves(raw, bits), by_shifts, "{raw:#x} {bits}");
                assert_eq!(sign_extend(raw, bits), by_shifts);
            }
        }
    }

    #[test]
    fn integer_casts_at_the_edges_of_every_width() {
        let (sat, trunc) = (Cast::Saturated, Cast::Truncated);
        for bits in 1..=64u32 {
            let mask = crate::bits::field_mask(bits);
            let (smax, smin) = ((mask >> 1) as i64, !((mask >> 1) as i64));
            // In range: the value's bits.
            assert_eq!(uint_raw(Scalar::Uint(mask), bits, sat, false), Ok(mask));
            assert_eq!(uint_raw(Scalar::Int(0), bits, sat, false), Ok(0));
            assert_eq!(
                int_raw(Scalar::Int(smin), bits, sat, false),
                Ok(smin as u64 & mask)
            );
            assert_eq!(
                int_raw(Scalar::Uint(smax as u64), bits, sat, false),
                Ok(smax as u64)
            );
            // Below: clamped to the minimum, or its low bits.
            assert_eq!(uint_raw(Scalar::Int(-1), bits, sat, true), Ok(0));
            assert_eq!(uint_raw(Scalar::Int(-1), bits, trunc, false), Ok(mask));
            let out = uint_raw(Scalar::Int(-1), bits, sat, false);
            let (min, max) = (Scalar::Uint(0), Scalar::Uint(mask));
            let value = Scalar::Int(-1);
            assert_eq!(out, Err(ScalarError::OutOfRange { value, min, max }));
            if bits < 64 {
                let low = Scalar::Int(smin - 1);
                assert_eq!(int_raw(low, bits, sat, true), Ok(smin as u64 & mask));
                let (min, max) = (Scalar::Int(smin), Scalar::Int(smax));
                let out = int_raw(low, bits, sat, false);
                assert_eq!(
                    out,
                    Err(ScalarError::OutOfRange {
                        value: low,
                        min,
                        max
                    })
                );
                // Above: clamped to the maximum, or its low bits.
                let high = Scalar::Uint(mask + 1);
                assert_eq!(uint_raw(high, bits, sat, true), Ok(mask));
                assert_eq!(uint_raw(high, bits, trunc, false), Ok(0));
            }
            let high = Scalar::Uint(u64::MAX);
            assert_eq!(int_raw(high, bits, sat, true), Ok(smax as u64));
            assert_eq!(int_raw(high, bits, trunc, false), Ok(mask));
            let (min, max) = (Scalar::Int(smin), Scalar::Int(smax));
            let out = int_raw(high, bits, sat, false);
            assert_eq!(
                out,
                Err(ScalarError::OutOfRange {
                    value: high,
                    min,
                    max
                })
            );
        }
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
