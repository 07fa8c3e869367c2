//! Descattering: reading a value whose bytes lie in several pieces (a transfer's head, pool
//! blocks and tail; CAN frame payloads; storage pages) without copying them together.
//!
//! [`Scattered`] implements [`BitRead`], so every decoder and leaf accessor reads from it as
//! from a flat buffer. It remembers the last piece it read from, so that the sequential reads
//! of a decoder cost a comparison each.

use core::cell::Cell;

use crate::bits::{read_bits, BitRead};

/// A sequence of byte pieces, in order.
pub trait Pieces {
    /// Number of pieces.
    fn count(&self) -> usize;
    /// Piece `i` (`i < count()`).
    fn piece(&self, i: usize) -> &[u8];
}

impl Pieces for [&[u8]] {
    #[inline]
    fn count(&self) -> usize {
        self.len()
    }
    #[inline]
    fn piece(&self, i: usize) -> &[u8] {
        self[i]
    }
}

/// The payload pieces of a DroneCAN transfer's CAN frames: each frame without its tail byte,
/// and the first without the two transfer-CRC bytes when there are several frames.
#[derive(Clone, Copy, Debug)]
pub struct FramePayloads<'f, 'a> {
    frames: &'f [&'a [u8]],
}

impl<'f, 'a> FramePayloads<'f, 'a> {
    /// Pieces over `frames` (each at least one byte long: the tail byte).
    pub fn new(frames: &'f [&'a [u8]]) -> Self {
        Self { frames }
    }
}

impl Pieces for FramePayloads<'_, '_> {
    #[inline]
    fn count(&self) -> usize {
        self.frames.len()
    }
    #[inline]
    fn piece(&self, i: usize) -> &[u8] {
        let frame = self.frames[i];
        let body = &frame[..frame.len().saturating_sub(1)];
        if i == 0 && self.frames.len() > 1 {
            body.get(2..).unwrap_or(&[])
        } else {
            body
        }
    }
}

/// The piece read last.
#[derive(Clone, Copy, Debug)]
struct Cursor<'p> {
    index: usize,
    /// Stream byte offset where the piece starts.
    start: usize,
    bytes: &'p [u8],
    /// A piece of at most 8 bytes (a CAN frame's payload) as one big-endian word, zero-filled:
    /// reads inside it are a shift.
    word: Option<u64>,
}

impl<'p> Cursor<'p> {
    fn at(index: usize, start: usize, bytes: &'p [u8]) -> Self {
        let word = (bytes.len() <= 8).then(|| word_of(bytes));
        Self {
            index,
            start,
            bytes,
            word,
        }
    }
}

/// Up to 8 bytes as a big-endian word, zero-filled at the end: two overlapping 4-byte loads
/// for the usual 4..8-byte pieces (CAN frame payloads), a byte loop below that.
#[inline]
fn word_of(bytes: &[u8]) -> u64 {
    let len = bytes.len();
    match (bytes.get(..4), bytes.get(len.saturating_sub(4)..)) {
        (Some(head), Some(tail)) if len >= 4 => {
            let hi = u64::from(u32::from_be_bytes([head[0], head[1], head[2], head[3]]));
            let lo = u64::from(u32::from_be_bytes([tail[0], tail[1], tail[2], tail[3]]));
            // The loads overlap for len < 8; the overlapping bytes are equal, so OR is exact.
            (hi << 32) | (lo << (8 * (8 - len)))
        }
        _ => bytes
            .iter()
            .enumerate()
            .fold(0u64, |w, (k, &b)| w | u64::from(b) << (56 - 8 * k)),
    }
}

/// A bit stream over scattered pieces.
#[derive(Debug)]
pub struct Scattered<'p, P: Pieces + ?Sized> {
    pieces: &'p P,
    bytes: usize,
    cursor: Cell<Cursor<'p>>,
}

impl<'p, P: Pieces + ?Sized> Scattered<'p, P> {
    /// A stream over `pieces`.
    pub fn new(pieces: &'p P) -> Self {
        let bytes = (0..pieces.count()).map(|i| pieces.piece(i).len()).sum();
        let first: &'p [u8] = if pieces.count() > 0 {
            pieces.piece(0)
        } else {
            &[]
        };
        Self {
            pieces,
            bytes,
            cursor: Cell::new(Cursor::at(0, 0, first)),
        }
    }

    /// Total length in bytes.
    pub fn len(&self) -> usize {
        self.bytes
    }

    /// Whether there are no bytes.
    pub fn is_empty(&self) -> bool {
        self.bytes == 0
    }

    /// The piece holding stream byte `byte`.
    #[inline]
    fn find(&self, byte: usize) -> Cursor<'p> {
        let c = self.cursor.get();
        if byte >= c.start && byte < c.start + c.bytes.len() {
            return c;
        }
        let (mut i, mut start, mut piece) = if byte < c.start {
            (0, 0, self.first())
        } else {
            (c.index, c.start, c.bytes)
        };
        let count = self.pieces.count();
        while byte >= start + piece.len() && i + 1 < count {
            start += piece.len();
            i += 1;
            piece = self.pieces.piece(i);
        }
        let c = Cursor::at(i, start, piece);
        self.cursor.set(c);
        c
    }

    fn first(&self) -> &'p [u8] {
        if self.pieces.count() > 0 {
            self.pieces.piece(0)
        } else {
            &[]
        }
    }

    /// [`BitRead::read_bits`] outside the current piece: move to the right one, or gather the
    /// bits from two or more.
    #[inline(never)]
    fn read_bits_elsewhere(&self, offset: usize, n: u32) -> u64 {
        let first = offset / 8;
        let last = (offset + n as usize - 1) / 8;
        let c = self.find(first);
        if last < c.start + c.bytes.len() {
            let local = offset - c.start * 8;
            return match c.word {
                Some(word) => (word << local) >> (64 - n),
                None => read_bits(c.bytes, local, n),
            };
        }
        self.read_across(c, offset, n)
    }

    /// Reads bits that start in `c`'s piece and end in a later one (at most 9 bytes), then
    /// leaves the cursor on the piece where they end: a decoder reads on from there.
    fn read_across(&self, c: Cursor<'p>, offset: usize, n: u32) -> u64 {
        let first = offset / 8;
        let need = (offset + n as usize - 1) / 8 - first + 1;
        let (mut acc, mut got) = (0u128, 0usize);
        let (mut i, mut start, mut piece) = (c.index, c.start, c.bytes);
        let mut skip = first - start;
        let count = self.pieces.count();
        loop {
            for &b in piece.get(skip..).unwrap_or(&[]) {
                if got == need {
                    break;
                }
                acc = (acc << 8) | u128::from(b);
                got += 1;
            }
            if got == need || i + 1 >= count {
                break;
            }
            start += piece.len();
            i += 1;
            piece = self.pieces.piece(i);
            skip = 0;
        }
        self.cursor.set(Cursor::at(i, start, piece));
        // `acc` holds `got` bytes: all of them, as callers read within the length.
        if got == 0 {
            return 0;
        }
        let bits = 8 * got as u32;
        ((acc << (128 - bits) << (offset % 8)) >> (128 - n)) as u64
    }

    /// Copies stream bytes from `byte` into `window` (as many as there are).
    fn gather(&self, byte: usize, window: &mut [u8]) {
        let c = self.find(byte);
        let (mut i, start) = (c.index, c.start);
        let mut skip = byte - start;
        let mut filled = 0;
        while filled < window.len() && i < self.pieces.count() {
            let piece = self.pieces.piece(i);
            let take = (piece.len() - skip.min(piece.len())).min(window.len() - filled);
            // Short copies: a byte loop beats a memcpy call here.
            for (w, &b) in window[filled..filled + take].iter_mut().zip(&piece[skip..]) {
                *w = b;
            }
            filled += take;
            skip = 0;
            i += 1;
        }
    }
}

impl<P: Pieces + ?Sized> BitRead for Scattered<'_, P> {
    #[inline]
    fn bit_len(&self) -> usize {
        self.bytes * 8
    }

    #[inline(always)]
    fn read_bits(&self, offset: usize, n: u32) -> u64 {
        let first = offset / 8;
        let last = (offset + n as usize - 1) / 8;
        let c = self.cursor.get();
        if first >= c.start && last < c.start + c.bytes.len() {
            // Within the current piece: read it in place.
            let local = offset - c.start * 8;
            if let Some(word) = c.word {
                return (word << local) >> (64 - n);
            }
            return read_bits(c.bytes, local, n);
        }
        self.read_bits_elsewhere(offset, n)
    }

    fn read_bytes(&self, byte: usize, out: &mut [u8]) -> bool {
        if byte + out.len() > self.bytes {
            return false;
        }
        self.gather(byte, out);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_across_pieces_like_the_flat_bytes() {
        let flat: [u8; 20] = core::array::from_fn(|i| (i as u8).wrapping_mul(37) ^ 0x5A);
        let splits: [&[u8]; 5] = [&flat[..1], &flat[1..8], &[], &flat[8..15], &flat[15..]];
        let s = Scattered::new(&splits[..]);
        assert_eq!(s.bit_len(), 160);
        for n in 1..=64u32 {
            // Forward and backward, so the cursor restarts too.
            for offset in (0..=(160 - n as usize)).chain((0..=(160 - n as usize)).rev()) {
                assert_eq!(
                    s.read_bits(offset, n),
                    read_bits(&flat, offset, n),
                    "{offset} {n}"
                );
            }
        }
    }

    #[test]
    fn frame_payloads_drop_tail_and_crc() {
        let frames: [&[u8]; 2] = [&[0xAA, 0xBB, 1, 2, 3, 4, 5, 0x80], &[6, 7, 0x60]];
        let p = FramePayloads::new(&frames);
        assert_eq!(p.piece(0), &[1, 2, 3, 4, 5]);
        assert_eq!(p.piece(1), &[6, 7]);
        let single: [&[u8]; 1] = [&[9, 8, 0xC0]];
        assert_eq!(FramePayloads::new(&single).piece(0), &[9, 8]);
    }
}
