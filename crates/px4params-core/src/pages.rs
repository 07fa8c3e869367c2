//! Stored values in fixed-size pages, read where they lie.
//!
//! Firmware often keeps parameters in flash or EEPROM pages that are not one contiguous
//! buffer. [`write_pages`] lays a store's values out back to back over such pages (a value may
//! cross page boundaries) and records where each one is; [`PagedValue::pieces`] gives the
//! pieces of one value so that [`Scattered`] reads it in place: the decoders and leaf
//! accessors work on it unchanged, without copying the value together. This is the talk's
//! use of libcanard's descattering for parameter storage.

use crate::layout::Layout;
use crate::leaf::{self, Target};
use crate::scalar::Scalar;
use crate::scatter::{Pieces, Scattered};
use crate::store::{ParamDef, Slot, Store, StoreError, Which};

/// Where one stored value lies in the pages.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct PagedValue {
    /// The parameter.
    pub param: u32,
    /// The instance.
    pub instance: u16,
    /// First byte, counted over all pages.
    pub start: u32,
    /// Length in bytes.
    pub len: u32,
}

impl PagedValue {
    /// The pieces of `pages` this value occupies.
    pub fn pieces<'p, 'a>(&self, pages: &'p [&'a [u8]]) -> PagePieces<'p, 'a> {
        PagePieces {
            pages,
            start: self.start as usize,
            len: self.len as usize,
        }
    }
}

/// One value's pieces in fixed-size pages (all pages as long as the first).
#[derive(Clone, Copy, Debug)]
pub struct PagePieces<'p, 'a> {
    pages: &'p [&'a [u8]],
    start: usize,
    len: usize,
}

impl PagePieces<'_, '_> {
    fn page_size(&self) -> usize {
        self.pages.first().map_or(1, |p| p.len().max(1))
    }
}

impl Pieces for PagePieces<'_, '_> {
    fn count(&self) -> usize {
        if self.len == 0 {
            return 0;
        }
        let size = self.page_size();
        (self.start + self.len - 1) / size - self.start / size + 1
    }

    fn piece(&self, i: usize) -> &[u8] {
        let size = self.page_size();
        let page = self.start / size + i;
        let from = if i == 0 { self.start % size } else { 0 };
        let end = (self.start + self.len - page * size).min(size);
        self.pages
            .get(page)
            .and_then(|p| p.get(from..end))
            .unwrap_or(&[])
    }
}

/// Writes the values (or defaults) of every existing instance of `store` back to back over
/// `pages` (all of one size), recording each in `index`. Returns the number of values written.
/// Nothing is written when they do not fit ([`StoreError::PagesFull`]).
pub fn write_pages<D, S, B, T>(
    store: &Store<D, S, B, T>,
    which: Which,
    pages: &mut [&mut [u8]],
    index: &mut [PagedValue],
) -> Result<usize, StoreError>
where
    D: AsRef<[ParamDef]>,
    S: AsRef<[Slot]> + AsMut<[Slot]>,
    B: AsRef<[u8]> + AsMut<[u8]>,
    T: AsRef<[crate::table::LeafSlot]> + AsMut<[crate::table::LeafSlot]>,
{
    let size = pages.first().map_or(0, |p| p.len());
    if size == 0 || pages.iter().any(|p| p.len() != size) {
        return Err(StoreError::UnequalPages);
    }
    let values = || {
        store
            .defs()
            .iter()
            .enumerate()
            .flat_map(move |(param, def)| {
                (0..def.instances).filter_map(move |instance| {
                    let data = store.get(param as u32, instance, which).ok()?; // absent: skipped
                    Some((param as u32, instance, data))
                })
            })
    };
    let (needed, count) = values().fold((0, 0), |(b, n), (_, _, data)| (b + data.len(), n + 1));
    if needed > size * pages.len() || count > index.len() {
        return Err(StoreError::PagesFull {
            needed,
            values: count,
        });
    }
    let mut at = 0usize;
    for (slot, (param, instance, data)) in index.iter_mut().zip(values()) {
        for (k, &byte) in data.iter().enumerate() {
            let pos = at + k;
            pages[pos / size][pos % size] = byte;
        }
        *slot = PagedValue {
            param,
            instance,
            start: at as u32,
            len: data.len() as u32,
        };
        at += data.len();
    }
    Ok(count)
}

/// Reads leaf `[k]` of a value kept in pages (all of one size), in place.
pub fn read_paged_leaf(
    layout: &Layout<'_>,
    def: &ParamDef,
    pages: &[&[u8]],
    value: &PagedValue,
    k: usize,
) -> Result<Scalar, StoreError> {
    let size = pages.first().map_or(0, |p| p.len());
    if size == 0 || pages.iter().any(|p| p.len() != size) {
        return Err(StoreError::UnequalPages);
    }
    let pieces = value.pieces(pages);
    let data = Scattered::new(&pieces);
    match leaf::seek(layout, def.root, &data, k) {
        Some(found) => Ok(found.read(&data)),
        None => Ok(leaf::get_leaf(layout, def.root, &data, Target::Index(k), false)?.1),
    }
}
