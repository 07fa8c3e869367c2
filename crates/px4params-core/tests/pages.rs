//! Stored values in fixed-size pages (`px4params_core::pages`): where they go, which pieces a
//! value is read from, and the pages refused. The values are three uint8 fields (three bytes
//! each, the fields' own bytes), so where each byte lands is plain to see.

mod common;

use common::VecStore;
use px4params_core::compile::OwnedLayout;
use px4params_core::layout::Role;
use px4params_core::pages::{read_paged_leaf, write_pages, PagedValue};
use px4params_core::scatter::Pieces;
use px4params_core::store::{ParamDef, StoreError, Which};
use px4params_core::{Cast, Scalar};

struct Fixture {
    layout: OwnedLayout,
    store: VecStore,
}

/// Parameter 0, 4 instances of `{uint8 a, uint8 b, uint8 c}`; instances 0, 1 and 3 present,
/// holding 1 2 3, 4 5 6 and 7 8 9.
fn fixture() -> Fixture {
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Cast::Saturated).unwrap();
    let triple = l
        .structure(&[
            ("a", u8_, Role::Data),
            ("b", u8_, Role::Data),
            ("c", u8_, Role::Data),
        ])
        .unwrap();
    let view = l.as_layout();
    let mut store = common::vec_store(&view, vec![ParamDef::instanced(triple, 4)]);
    for (instance, value) in [(0, [1, 2, 3]), (1, [4, 5, 6]), (3, [7, 8, 9])] {
        store.add(0, Some(instance)).unwrap();
        store
            .set_encoded(&view, 0, instance, Which::Value, &value)
            .unwrap();
    }
    Fixture { layout: l, store }
}

fn write(
    f: &Fixture,
    page: usize,
    pages: usize,
    index: usize,
) -> Result<(Vec<u8>, Vec<PagedValue>), StoreError> {
    let mut memory = vec![0u8; page * pages];
    let mut chunks: Vec<&mut [u8]> = memory.chunks_mut(page).collect();
    let mut entries = vec![PagedValue::default(); index];
    let n = write_pages(&f.store, Which::Value, &mut chunks, &mut entries)?;
    entries.truncate(n);
    Ok((memory, entries))
}

fn at(instance: u16, start: u32) -> PagedValue {
    PagedValue {
        param: 0,
        instance,
        start,
        len: 3,
    }
}

#[test]
fn values_lie_back_to_back_across_page_edges() {
    let f = fixture();
    let (memory, index) = write(&f, 4, 3, 8).unwrap();
    assert_eq!(memory, [1, 2, 3, 4, 5, 6, 7, 8, 9, 0, 0, 0]);
    assert_eq!(index, [at(0, 0), at(1, 3), at(3, 6)]);
    // Exactly as much room as the values need, in pages and in the index.
    let (memory, index) = write(&f, 3, 3, 3).unwrap();
    assert_eq!(memory, [1, 2, 3, 4, 5, 6, 7, 8, 9]);
    assert_eq!(index.len(), 3);
    let (memory, _) = write(&f, 9, 1, 3).unwrap();
    assert_eq!(memory, [1, 2, 3, 4, 5, 6, 7, 8, 9]);
    // Defaults instead of values: the zero value.
    let mut memory = [0xEEu8; 12];
    let mut pages: Vec<&mut [u8]> = memory.chunks_mut(4).collect();
    let mut index = [PagedValue::default(); 3];
    assert_eq!(
        write_pages(&f.store, Which::Default, &mut pages, &mut index),
        Ok(3)
    );
    assert_eq!(memory[..9], [0; 9]);
}

#[test]
fn pages_or_an_index_too_small_are_refused_and_nothing_is_written() {
    let f = fixture();
    let full = Err(StoreError::PagesFull {
        needed: 9,
        values: 3,
    });
    assert_eq!(write(&f, 4, 2, 8), full);
    assert_eq!(write(&f, 2, 4, 8), full);
    assert_eq!(write(&f, 8, 1, 8), full);
    assert_eq!(write(&f, 4, 3, 2), full);
    let mut memory = vec![0xEEu8; 8];
    let mut pages: Vec<&mut [u8]> = memory.chunks_mut(4).collect();
    let mut index = [PagedValue::default(); 3];
    assert!(write_pages(&f.store, Which::Value, &mut pages, &mut index).is_err());
    assert_eq!(memory, [0xEE; 8]);
    assert_eq!(index, [PagedValue::default(); 3]);
}

#[test]
fn pages_of_unequal_sizes_or_none_are_refused() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let def = f.store.def(0).unwrap();
    let mut index = [PagedValue::default(); 4];
    let (mut a, mut b) = ([0u8; 8], [0u8; 4]);
    let mut unequal: Vec<&mut [u8]> = vec![&mut a, &mut b];
    let e = write_pages(&f.store, Which::Value, &mut unequal, &mut index);
    assert_eq!(e, Err(StoreError::UnequalPages));
    let (mut a, mut b) = ([0u8; 8], [0u8; 16]);
    let mut unequal: Vec<&mut [u8]> = vec![&mut a, &mut b];
    let e = write_pages(&f.store, Which::Value, &mut unequal, &mut index);
    assert_eq!(e, Err(StoreError::UnequalPages));
    let mut none: Vec<&mut [u8]> = vec![];
    let e = write_pages(&f.store, Which::Value, &mut none, &mut index);
    assert_eq!(e, Err(StoreError::UnequalPages));
    let mut empty: Vec<&mut [u8]> = vec![&mut [], &mut []];
    let e = write_pages(&f.store, Which::Value, &mut empty, &mut index);
    assert_eq!(e, Err(StoreError::UnequalPages));
    // Reading too.
    let value = at(0, 0);
    let pages: [&[u8]; 2] = [&[1, 2, 3, 4], &[5, 6]];
    assert_eq!(
        read_paged_leaf(&layout, &def, &pages, &value, 0),
        Err(StoreError::UnequalPages)
    );
    let pages: [&[u8]; 2] = [&[1, 2], &[5, 6, 7]];
    assert_eq!(
        read_paged_leaf(&layout, &def, &pages, &value, 0),
        Err(StoreError::UnequalPages)
    );
    assert_eq!(
        read_paged_leaf(&layout, &def, &[], &value, 0),
        Err(StoreError::UnequalPages)
    );
}

#[test]
fn a_value_is_read_from_its_pieces_in_place() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let def = f.store.def(0).unwrap();
    let (memory, index) = write(&f, 4, 3, 8).unwrap();
    let pages: Vec<&[u8]> = memory.chunks(4).collect();
    // 4 5 6 from byte 3: the last byte of page 0, two of page 1.
    let pieces = index[1].pieces(&pages);
    assert_eq!(pieces.count(), 2);
    assert_eq!(
        (pieces.piece(0), pieces.piece(1)),
        (&[4u8][..], &[5u8, 6][..])
    );
    // 7 8 9 from byte 6: the end of page 1 and the start of page 2.
    let pieces = index[2].pieces(&pages);
    assert_eq!(pieces.count(), 2);
    assert_eq!(
        (pieces.piece(0), pieces.piece(1)),
        (&[7u8, 8][..], &[9u8][..])
    );
    let read = |value: &PagedValue, k| read_paged_leaf(&layout, &def, &pages, value, k);
    for (value, expected) in index.iter().zip([[1, 2, 3], [4, 5, 6], [7, 8, 9]]) {
        for (k, byte) in expected.into_iter().enumerate() {
            assert_eq!(read(value, k), Ok(Scalar::Uint(byte)));
        }
        assert!(matches!(read(value, 3), Err(StoreError::Codec(_))));
    }
    // A value over many pages: byte 5 to 14 in pages of 4 is pages 1, 2 and 3.
    let memory: Vec<u8> = (0..16).collect();
    let pages: Vec<&[u8]> = memory.chunks(4).collect();
    let long = PagedValue {
        param: 0,
        instance: 0,
        start: 5,
        len: 10,
    };
    let pieces = long.pieces(&pages);
    assert_eq!(pieces.count(), 3);
    let all: Vec<&[u8]> = (0..3).map(|i| pieces.piece(i)).collect();
    assert_eq!(
        all,
        [&[5u8, 6, 7][..], &[8, 9, 10, 11][..], &[12, 13, 14][..]]
    );
    // Starting on a page's first byte, and ending on its last.
    let aligned = PagedValue {
        start: 4,
        len: 8,
        ..long
    };
    assert_eq!(aligned.pieces(&pages).count(), 2);
    let empty = PagedValue { len: 0, ..long };
    assert_eq!(empty.pieces(&pages).count(), 0);
}
