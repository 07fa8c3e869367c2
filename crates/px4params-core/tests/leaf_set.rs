//! Writing a primitive leaf in encoded data (`leaf::set_leaf_at`): the data is copied as it
//! is and only the leaf's bits change (padding bits and bytes after the value stay); a value
//! that does not fit its field, or an output too small for the copy, is refused with its
//! position and path. Both plan sets alike: the seek's leaf and the walk's are written by one
//! code, so `tests/parity.rs` cannot tell it wrong; these answers are worked out by hand.

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::Role;
use px4params_core::leaf::set_leaf_at_with;
use px4params_core::plan::{HostPlans, NoPlans, Plans};
use px4params_core::{Cast, EncodeOptions, Error, ErrorKind, NodeId, Path, Scalar};

/// `uint8 a`, `void4`, `uint4 b`: `b` is leaf [1], bits 12..16, the low nibble of byte 1
/// (DroneCAN fills each byte from its most significant bit).
fn padded(l: &mut OwnedLayout) -> NodeId {
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let pad = l.void(4).unwrap();
    let u4 = l.uint(4, Cast::Saturated).unwrap();
    let fields = [
        ("a", u8_, Role::Data),
        ("", pad, Role::Padding),
        ("b", u4, Role::Data),
    ];
    l.structure(&fields).unwrap()
}

const OPTIONS: EncodeOptions = EncodeOptions {
    tao: false,
    saturate: false,
    keep_versions: false,
};

/// Leaf [1] (`b`) of `data` set to `value`, into an output of `room` bytes (0xEE each).
fn set_b<P: Plans>(data: &[u8], value: u64, room: usize) -> Result<Vec<u8>, String> {
    let mut l = OwnedLayout::default();
    let root = padded(&mut l);
    let layout = l.as_layout();
    let mut out = vec![0xEE; room];
    match set_leaf_at_with::<P, _>(
        &layout,
        root,
        data,
        1,
        Scalar::Uint(value),
        &mut out,
        OPTIONS,
    ) {
        Ok(n) => Ok(out[..n].to_vec()),
        Err(e) => Err(worded(&l, &e)),
    }
}

fn worded(l: &OwnedLayout, e: &Error<core::convert::Infallible>) -> String {
    format!("{} (bit {})", e.display(&l.as_layout()), e.bit_offset)
}

#[test]
fn only_the_leaf_s_bits_change_padding_and_trailing_bytes_stay() {
    for set in [set_b::<HostPlans>, set_b::<NoPlans>] {
        // a = 0x11, padding 0xF (set, as a sender may leave it), b = 2; then 0xAA after.
        assert_eq!(set(&[0x11, 0xF2], 5, 2), Ok(vec![0x11, 0xF5]));
        assert_eq!(set(&[0x11, 0xF2, 0xAA], 15, 3), Ok(vec![0x11, 0xFF, 0xAA]));
        assert_eq!(set(&[0x11, 0x02, 0xAA], 0, 8), Ok(vec![0x11, 0x00, 0xAA]));
    }
}

#[test]
fn a_value_over_the_field_is_refused_at_the_leaf() {
    for set in [set_b::<HostPlans>, set_b::<NoPlans>] {
        assert_eq!(
            set(&[0x11, 0xF2], 16, 2),
            Err("b: value 16 is out of range (expected 0 to 15) (bit 12)".into())
        );
    }
}

#[test]
fn an_output_shorter_than_the_data_is_refused_with_the_data_s_length() {
    let mut l = OwnedLayout::default();
    let root = padded(&mut l);
    let layout = l.as_layout();
    let data = [0x11, 0xF2, 0xAA];
    for plans in [true, false] {
        let mut out = [0xEE; 2];
        let set = match plans {
            true => set_leaf_at_with::<HostPlans, [u8]>,
            false => set_leaf_at_with::<NoPlans, [u8]>,
        };
        let e = set(&layout, root, &data, 1, Scalar::Uint(5), &mut out, OPTIONS).unwrap_err();
        assert_eq!(e.kind, ErrorKind::BufferTooSmall { needed: 3 });
        assert_eq!((e.bit_offset, e.path), (0, Path::default()));
        assert_eq!(out, [0xEE; 2], "nothing written");
    }
}
