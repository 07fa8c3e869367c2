//! A float field given an integer value (issue 40): DroneCAN's float16/32/64 fields hold the
//! number, so an unsigned integer is written as the float of the same value, held to the
//! field's range like any float. Expected bits are IEEE 754 patterns written out by hand.

use px4params_core::scalar::{float_raw, ScalarError};
use px4params_core::{Cast, Scalar};

#[test]
fn an_unsigned_integer_written_to_a_float_field_is_that_number() {
    let raw = |v: u64, bits: u32| float_raw(Scalar::Uint(v), bits, Cast::Saturated, false);
    // 3 = 1.5 * 2^1: binary16 0x4200, binary32 0x40400000, binary64 0x4008000000000000.
    assert_eq!(raw(3, 16), Ok(0x4200));
    assert_eq!(raw(3, 32), Ok(0x4040_0000));
    assert_eq!(raw(3, 64), Ok(0x4008_0000_0000_0000));
    // 1000000 = 0xF4240 = 1.9073486328125 * 2^19: binary32 0x49742400.
    assert_eq!(raw(1_000_000, 32), Ok(0x4974_2400));
    // 65504, the largest finite binary16: 0x7BFF.
    assert_eq!(raw(65504, 16), Ok(0x7BFF));
}

#[test]
fn an_unsigned_integer_beyond_a_float16_is_held_to_its_range() {
    assert_eq!(
        float_raw(Scalar::Uint(70000), 16, Cast::Saturated, false),
        Err(ScalarError::OutOfRange {
            value: Scalar::Uint(70000),
            min: Scalar::Float(-65504.0),
            max: Scalar::Float(65504.0),
        })
    );
    // Saturated on request: the largest finite; a truncated field overflows to infinity.
    assert_eq!(
        float_raw(Scalar::Uint(70000), 16, Cast::Saturated, true),
        Ok(0x7BFF)
    );
    assert_eq!(
        float_raw(Scalar::Uint(70000), 16, Cast::Truncated, false),
        Ok(0x7C00)
    );
}
