//! The scalar casts against DroneCAN's serialization rules, with answers written out from the
//! rules (IEEE 754 bit patterns by hand), not computed by the product: saturated integers and
//! floats clamp to the field's range or report it, truncated floats overflow to infinities of
//! the value's sign, and the largest finite value of a field is in range.

use px4params_core::scalar::{float_raw, int_raw, raw_is_finite, uint_raw, ScalarError};
use px4params_core::{Cast, Scalar};

/// IEEE 754 binary32 bit patterns.
const F32_MAX: u64 = 0x7F7F_FFFF;
const F32_NEG_MAX: u64 = 0xFF7F_FFFF;
const F32_INF: u64 = 0x7F80_0000;
const F32_NEG_INF: u64 = 0xFF80_0000;
/// IEEE 754 binary16 bit patterns: ±65504 (the largest finite) and ±infinity.
const F16_MAX: u64 = 0x7BFF;
const F16_NEG_MAX: u64 = 0xFBFF;
const F16_INF: u64 = 0x7C00;
const F16_NEG_INF: u64 = 0xFC00;

#[test]
fn out_of_range_names_the_fields_range_in_its_kind_of_number() {
    // uint8 holds 0..=255, as unsigned numbers.
    assert_eq!(
        uint_raw(Scalar::Uint(300), 8, Cast::Saturated, false),
        Err(ScalarError::OutOfRange {
            value: Scalar::Uint(300),
            min: Scalar::Uint(0),
            max: Scalar::Uint(255),
        })
    );
    // int4 holds -8..=7 (two's complement), as signed numbers.
    assert_eq!(
        int_raw(Scalar::Int(100), 4, Cast::Saturated, false),
        Err(ScalarError::OutOfRange {
            value: Scalar::Int(100),
            min: Scalar::Int(-8),
            max: Scalar::Int(7),
        })
    );
    // float16 holds -65504..=65504; float32 -f32::MAX..=f32::MAX.
    assert_eq!(
        float_raw(Scalar::Float(-1e6), 16, Cast::Saturated, false),
        Err(ScalarError::OutOfRange {
            value: Scalar::Float(-1e6),
            min: Scalar::Float(-65504.0),
            max: Scalar::Float(65504.0),
        })
    );
    assert_eq!(
        float_raw(Scalar::Float(1e39), 32, Cast::Saturated, false),
        Err(ScalarError::OutOfRange {
            value: Scalar::Float(1e39),
            min: Scalar::Float(-3.4028234663852886e38),
            max: Scalar::Float(3.4028234663852886e38),
        })
    );
}

#[test]
fn saturated_float32_clamps_to_the_largest_finite_float32() {
    // 1e39 is beyond f32::MAX (about 3.4e38): saturation keeps it finite, of its sign.
    let sat = Cast::Saturated;
    assert_eq!(float_raw(Scalar::Float(1e39), 32, sat, true), Ok(F32_MAX));
    assert_eq!(
        float_raw(Scalar::Float(-1e39), 32, sat, true),
        Ok(F32_NEG_MAX)
    );
}

#[test]
fn saturated_float16_clamps_negative_values_to_minus_65504() {
    let sat = Cast::Saturated;
    assert_eq!(
        float_raw(Scalar::Float(-1e6), 16, sat, true),
        Ok(F16_NEG_MAX)
    );
    assert_eq!(
        float_raw(Scalar::Int(-70000), 16, sat, true),
        Ok(F16_NEG_MAX)
    );
}

#[test]
fn truncated_floats_overflow_to_the_infinity_of_their_sign() {
    let trunc = Cast::Truncated;
    assert_eq!(float_raw(Scalar::Float(1e6), 16, trunc, false), Ok(F16_INF));
    assert_eq!(
        float_raw(Scalar::Float(-1e6), 16, trunc, false),
        Ok(F16_NEG_INF)
    );
    assert_eq!(
        float_raw(Scalar::Float(1e39), 32, trunc, false),
        Ok(F32_INF)
    );
    assert_eq!(
        float_raw(Scalar::Float(-1e39), 32, trunc, false),
        Ok(F32_NEG_INF)
    );
}

#[test]
fn the_largest_finite_value_of_a_float_field_is_in_range() {
    // Exactly ±65504 fits float16 whatever the cast mode: it is neither clamped, refused nor
    // turned into an infinity. Likewise ±f32::MAX for float32.
    for cast in [Cast::Saturated, Cast::Truncated] {
        assert_eq!(
            float_raw(Scalar::Float(65504.0), 16, cast, false),
            Ok(F16_MAX)
        );
        assert_eq!(
            float_raw(Scalar::Float(-65504.0), 16, cast, false),
            Ok(F16_NEG_MAX)
        );
        let max = f64::from(f32::MAX);
        assert_eq!(float_raw(Scalar::Float(max), 32, cast, false), Ok(F32_MAX));
        assert_eq!(
            float_raw(Scalar::Float(-max), 32, cast, false),
            Ok(F32_NEG_MAX)
        );
    }
}

/// The bits of IEEE 754 binary16, binary32 and binary64 (the standard's own encodings: an
/// exponent of all ones is an infinity or a NaN), told finite or not, each sign.
#[test]
fn raw_float_bits_are_finite_unless_their_exponent_is_all_ones() {
    let cases: [(u32, u64, bool); 15] = [
        (16, 0x3C00, true),                 // 1.0
        (16, 0x7BFF, true),                 // 65504, the largest finite
        (16, 0x0001, true),                 // the smallest subnormal
        (16, 0x7C00, false),                // +inf
        (16, 0xFE00, false),                // a negative NaN
        (32, 0x3F80_0000, true),            // 1.0
        (32, 0x7F7F_FFFF, true),            // f32::MAX
        (32, 0xFF80_0000, false),           // -inf
        (32, 0x7FC0_0000, false),           // NaN
        (64, 0x3FF0_0000_0000_0000, true),  // 1.0
        (64, 0x7FEF_FFFF_FFFF_FFFF, true),  // f64::MAX
        (64, 0x0000_0000_7FF0_0000, true),  // a subnormal whose low word looks like an exponent
        (64, 0x7FF0_0000_0000_0000, false), // +inf
        (64, 0xFFF8_0000_0000_0000, false), // a negative NaN
        (64, 0x7FF0_0000_0000_0001, false), // a signalling NaN
    ];
    for (bits, raw, finite) in cases {
        assert_eq!(raw_is_finite(raw, bits), finite, "{bits} bits: {raw:#x}");
    }
    for v in [0.5f64, f64::MAX, f64::MIN_POSITIVE, f64::INFINITY, f64::NAN] {
        assert_eq!(raw_is_finite(v.to_bits(), 64), v.is_finite(), "{v}");
    }
}
