//! What a translation reports (issue 40): each field of the new type is said kept (carried
//! over from the old value) or new (taken from the base), and each field of the old type the
//! new one lacks is said dropped, by its dotted path. The values are worked out by hand.

use px4params_core::compile::OwnedLayout;
use px4params_core::layout::Role;
use px4params_core::translate::{translate, Change};
use px4params_core::Cast;

#[test]
fn a_translation_says_which_fields_were_kept_added_and_dropped() {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let u16_ = l.uint(16, Cast::Saturated).unwrap();
    let inner_old = l
        .structure(&[("x", u8_, Role::Data), ("gone", u8_, Role::Data)])
        .unwrap();
    let inner_new = l.structure(&[("x", u8_, Role::Data)]).unwrap();
    let old = l
        .structure(&[
            ("a", u8_, Role::Data),
            ("b", u8_, Role::Data),
            ("inner", inner_old, Role::Data),
        ])
        .unwrap();
    let new = l
        .structure(&[
            ("a", u8_, Role::Data),
            ("c", u16_, Role::Data),
            ("inner", inner_new, Role::Data),
        ])
        .unwrap();
    let layout = l.as_layout();
    // old: a = 7, b = 9, inner.x = 5, inner.gone = 6; the base (a value of new): a = 1,
    // c = 0x0302 (little-endian bytes 02 03), inner.x = 4.
    let old_data = [7u8, 9, 5, 6];
    let base = [1u8, 0x02, 0x03, 4];
    let mut out = [0u8; 8];
    let mut said: Vec<String> = Vec::new();
    let n = translate(
        &layout,
        old,
        &old_data[..],
        new,
        &base[..],
        &mut out,
        &mut |c| {
            said.push(match c {
                Change::Kept(p) => format!("kept {p}"),
                Change::New(p) => format!("new {p}"),
                Change::Dropped(p) => format!("dropped {p}"),
            })
        },
    )
    .unwrap();
    // a and inner.x from the old value, c from the base.
    assert_eq!(&out[..n], [7, 0x02, 0x03, 5]);
    said.sort();
    assert_eq!(
        said,
        [
            "dropped b",
            "dropped inner.gone",
            "kept a",
            "kept inner.x",
            "new c"
        ],
    );
}

/// A translation keeps a frame for each field and two for each array (the array, then the
/// element): a type as deep as the codec follows (`MAX_DEPTH` nodes, here fixed arrays of one
/// inside a struct) translates with its report, as the codec encodes it; the report names
/// the array once, as kept.
#[test]
fn a_type_as_deep_as_the_codec_follows_is_translated_with_its_report() {
    use px4params_core::rules::MAX_DEPTH;
    let mut l = OwnedLayout::default();
    let mut node = l.uint(8, Cast::Saturated).unwrap();
    for _ in 2..MAX_DEPTH {
        node = l.array(node, 1).unwrap();
    }
    let root = l.structure(&[("x", node, Role::Data)]).unwrap();
    let layout = l.as_layout();
    let mut out = [0u8; 2];
    let mut said: Vec<String> = Vec::new();
    let n = translate(
        &layout,
        root,
        &[0x5Au8][..],
        root,
        &[0x11u8][..],
        &mut out,
        &mut |c| {
            if let Change::Kept(p) = c {
                said.push(p.to_string());
            }
        },
    )
    .expect("as deep as the codec follows");
    assert_eq!(&out[..n], [0x5A], "the old value's byte, not the base's");
    // the array is kept whole: nothing inside its elements is reported on its own
    assert_eq!(said, ["x"]);
}
