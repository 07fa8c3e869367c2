//! The casting rules a leaf's value meets on its way into the bit stream, and the rules
//! module's own words (issue 40: survivors of the run over rules.rs). Answers from the
//! DroneCAN specification's casting modes ("saturated": clamped to the field's range,
//! "truncated": the low bits kept) and from DSDL's `bool`, which the value lists of the
//! binding and the store give as 0 or 1 as well as true or false.

use px4params_core::codec::encode_leaves_with;
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::Role;
use px4params_core::plan::{Active, NoPlans, Plans};
use px4params_core::rules::{scalar_bits, TranslateError, PATH_MAX};
use px4params_core::scalar::ScalarError;
use px4params_core::{Cast, EncodeOptions, ErrorKind, Kind, Scalar};

fn options(saturate: bool) -> EncodeOptions {
    EncodeOptions {
        tao: true,
        saturate,
        keep_versions: false,
    }
}

/// The one byte of a struct holding one field built by `field`, from the leaf `value`; or
/// the error's kind and words.
fn encode_one<P: Plans>(
    field: impl Fn(&mut OwnedLayout) -> u32,
    value: Scalar,
    saturate: bool,
) -> Result<u8, String> {
    let mut l = OwnedLayout::default();
    let node = field(&mut l);
    let root = l.structure(&[("v", node, Role::Data)]).unwrap();
    let layout = l.as_layout();
    let mut out = [0u8; 2];
    match encode_leaves_with::<P>(&layout, root, &[value], &mut out, options(saturate)) {
        Ok(1) => Ok(out[0]),
        Ok(n) => panic!("{n} bytes for one 8-bit field"),
        Err(e) => Err(match e.kind {
            ErrorKind::Scalar(ScalarError::OutOfRange { .. }) => "out of range".into(),
            ErrorKind::Scalar(ScalarError::WrongKind { expected }) => format!("not {expected}"),
            other => format!("{other:?}"),
        }),
    }
}

fn int8(cast: Cast) -> impl Fn(&mut OwnedLayout) -> u32 {
    move |l| l.int(8, cast).unwrap()
}

fn both<T: PartialEq + core::fmt::Debug>(run: impl Fn(bool) -> T) -> T {
    // Hosts' plans and firmware's walk: the same answer.
    let host = run(true);
    assert_eq!(host, run(false), "the host's plans and the walk differ");
    host
}

fn int8_of(cast: Cast, value: i64, saturate: bool) -> Result<u8, String> {
    both(|host| {
        let v = Scalar::Int(value);
        if host {
            encode_one::<Active>(int8(cast), v, saturate)
        } else {
            encode_one::<NoPlans>(int8(cast), v, saturate)
        }
    })
}

#[test]
fn a_signed_value_in_range_is_its_twos_complement() {
    assert_eq!(int8_of(Cast::Saturated, -5, false), Ok(0xFB));
    assert_eq!(int8_of(Cast::Saturated, 127, false), Ok(0x7F));
    assert_eq!(int8_of(Cast::Saturated, -128, false), Ok(0x80));
}

#[test]
fn a_signed_value_out_of_range_is_refused_clamped_or_truncated_as_its_cast_says() {
    // saturated, without saturation asked for: refused, never wrapped
    assert_eq!(
        int8_of(Cast::Saturated, 200, false),
        Err("out of range".into())
    );
    assert_eq!(
        int8_of(Cast::Saturated, -129, false),
        Err("out of range".into())
    );
    // saturated and asked for: the nearest end of -128..=127
    assert_eq!(int8_of(Cast::Saturated, 200, true), Ok(0x7F));
    assert_eq!(int8_of(Cast::Saturated, -200, true), Ok(0x80));
    // truncated: the low 8 bits (200 = 0xC8; -200 = ...FF38)
    assert_eq!(int8_of(Cast::Truncated, 200, false), Ok(0xC8));
    assert_eq!(int8_of(Cast::Truncated, -200, false), Ok(0x38));
}

#[test]
fn a_boolean_is_true_false_or_the_integers_one_and_zero() {
    let bool_of = |value: Scalar| {
        both(|host| {
            let field = |l: &mut OwnedLayout| l.boolean();
            if host {
                encode_one::<Active>(field, value, false)
            } else {
                encode_one::<NoPlans>(field, value, false)
            }
        })
    };
    // one bit, the first of the stream: the byte's most significant
    for (value, byte) in [
        (Scalar::Bool(true), 0x80),
        (Scalar::Uint(1), 0x80),
        (Scalar::Int(1), 0x80),
        (Scalar::Bool(false), 0x00),
        (Scalar::Uint(0), 0x00),
        (Scalar::Int(0), 0x00),
    ] {
        assert_eq!(bool_of(value), Ok(byte), "{value:?}");
    }
    for value in [Scalar::Uint(2), Scalar::Int(-1), Scalar::Float(1.0)] {
        assert_eq!(bool_of(value), Err("not a boolean".into()), "{value:?}");
    }
}

#[test]
fn a_scalar_kind_s_width_is_its_bits_and_padding_s_too() {
    let mut l = OwnedLayout::default();
    let pad = l.void(3).unwrap();
    let word = l.uint(12, Cast::Saturated).unwrap();
    let flag = l.boolean();
    let half = l.float(16, Cast::Saturated).unwrap();
    let whole = l.structure(&[("w", word, Role::Data)]).unwrap();
    let layout = l.as_layout();
    let width = |id: u32| scalar_bits(layout.node(id).kind);
    assert_eq!(
        [
            width(pad),
            width(word),
            width(flag),
            width(half),
            width(whole)
        ],
        [3, 12, 1, 16, 0]
    );
    assert!(matches!(layout.node(pad).kind, Kind::Void { bits: 3 }));
}

#[test]
fn a_translation_s_own_refusals_are_worded() {
    assert_eq!(PATH_MAX, 192);
    assert_eq!(
        TranslateError::PathTooLong.to_string(),
        "a field path over 192 bytes"
    );
    assert_eq!(
        TranslateError::Unreadable.to_string(),
        "the stored value cannot be read"
    );
}
