//! Descattering: reading a value whose bytes lie in several pieces (a transfer's head, pool
//! blocks and tail; CAN frame payloads; storage pages) without copying them together.
//!
//! [`Scattered`] implements [`BitRead`], so every decoder and leaf accessor reads from it as
//! from a flat buffer, and nothing is gathered into one:
//! - decoders read forwards through a [`ScatteredReader`], which keeps the next bits of the
//!   stream in a register and takes the next piece's bytes (one load for a CAN frame) when
//!   they run out; byte strings are moved from the pieces a word at a time;
//! - reads at any offset (leaf access) go through a window of up to 16 bytes that moves with
//!   them.
//!
//! A piece gives its bytes up to 8 at a time ([`Pieces::chunk`]); fields span pieces freely.
//!
//! ```
//! use px4params_core::bits::{BitRead, BitReader};
//! use px4params_core::scatter::Scattered;
//! use px4params_core::transfer::{frames, receive};
//!
//! let payload: Vec<u8> = (0..20).collect();
//! let sent: Vec<Vec<u8>> = frames(&payload, 0x1234, 5, false)
//!     .map(|f| f.as_bytes().to_vec())
//!     .collect();
//! let sent: Vec<&[u8]> = sent.iter().map(Vec::as_slice).collect();
//! let received = receive(&sent, 0x1234).unwrap();
//! let stream = Scattered::new(&received.payload);
//! assert_eq!(stream.len(), 20);
//! // Bytes 4..8 lie in the first and second frames.
//! let mut reader = stream.reader(4 * 8);
//! assert_eq!(reader.read(32), 0x0405_0607);
//! assert_eq!(stream.read_bits(8 * 19, 8), 19);
//! ```

use core::cell::Cell;

use crate::bits::{after_bytes, first_bytes, join, load_word, wide, Ahead, BitRead, BitReader};
use crate::plan::{Active, Plans};

/// Up to 8 bytes of a piece, as [`Pieces::chunk`] gives them. `len` is 0 only where the piece
/// has no bytes left (`left` is 0 then), and the word is zero after the `len` bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chunk {
    /// The bytes as a big-endian word, left-aligned and zero-filled.
    pub word: u64,
    /// How many bytes (`0..=8`).
    pub len: usize,
    /// Bytes of the piece after these.
    pub left: usize,
}

impl Chunk {
    /// The first (up to) 8 bytes of `bytes`.
    #[inline(always)]
    pub fn of(bytes: &[u8]) -> Self {
        Self {
            word: load_word(bytes),
            len: bytes.len().min(8),
            left: bytes.len().saturating_sub(8),
        }
    }
}

/// A sequence of byte pieces, in order.
pub trait Pieces {
    /// Number of pieces.
    fn count(&self) -> usize;

    /// Piece `i` (`i < count()`).
    fn piece(&self, i: usize) -> &[u8];

    /// Total length of the pieces in bytes (override when known without visiting them).
    fn total_len(&self) -> usize {
        (0..self.count()).map(|i| self.piece(i).len()).sum()
    }

    /// Up to 8 bytes of piece `i` from its byte `skip` (`skip` at most its length): how the
    /// readers take bytes. Override when a word loads more cheaply; the result must be what
    /// [`Chunk::of`] gives for the piece's bytes from `skip` on.
    #[inline]
    fn chunk(&self, i: usize, skip: usize) -> Chunk {
        chunk_of_piece(self, i, skip)
    }

    /// The pieces as one run of bytes, where they are one or a copy of them is at hand
    /// (`None` otherwise): what [`Scattered`] answers to [`BitRead::contiguous`].
    #[inline]
    fn contiguous(&self) -> Option<&[u8]> {
        None
    }

    /// Fills `out` with the bytes from piece `at.index`, byte `at.skip`, on, and returns
    /// where they end. Where the pieces end first, the rest of `out` is unspecified. Override
    /// to move short pieces a word at a time.
    fn copy_out(&self, mut at: Place, out: &mut [u8]) -> Place {
        let mut done = 0;
        while done < out.len() && at.index < self.count() {
            let rest = self.piece(at.index).get(at.skip..).unwrap_or(&[]);
            let n = rest.len().min(out.len() - done);
            out[done..done + n].copy_from_slice(&rest[..n]);
            done += n;
            at.step(n, n == rest.len());
        }
        at
    }
}

/// [`Pieces::chunk`] from [`Pieces::piece`].
#[inline(always)]
fn chunk_of_piece<P: Pieces + ?Sized>(pieces: &P, i: usize, skip: usize) -> Chunk {
    Chunk::of(pieces.piece(i).get(skip..).unwrap_or(&[]))
}

/// A place in [`Pieces`]: piece `index`, from its byte `skip` (at most the piece's length).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Place {
    /// The piece.
    pub index: usize,
    /// Bytes of it already passed.
    pub skip: usize,
}

impl Place {
    /// Moves on by `n` bytes of the current piece, to the next piece if they were its last.
    #[inline(always)]
    pub fn step(&mut self, n: usize, last: bool) {
        if last {
            self.index += 1;
            self.skip = 0;
        } else {
            self.skip += n;
        }
    }

    /// Moves past `chunk`, just taken from here; returns the length of the piece it ended.
    #[inline(always)]
    fn pass(&mut self, chunk: &Chunk) -> Option<usize> {
        let ended = chunk.left == 0;
        let length = self.skip + chunk.len;
        self.step(chunk.len, ended);
        ended.then_some(length)
    }
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
///
/// [`crate::transfer::receive`] gathers a short multi-frame payload into one run to check its
/// CRC (hosts only: [`crate::plan::Plans::GATHERED_CRC`]); the run is kept here, so that a
/// plan that reads whole bytes ([`crate::straight`]) decodes from it as from flat bytes,
/// through [`Pieces::contiguous`]. A single frame's payload is one run as it lies.
#[derive(Clone, Copy, Debug)]
pub struct FramePayloads<'f, 'a> {
    frames: &'f [&'a [u8]],
    /// The payload gathered into one run: its first `gathered` bytes (none when 0, where
    /// there is nothing to gather or it was not gathered).
    run: [u8; RUN],
    gathered: usize,
}

/// Bytes of a gathered payload that [`FramePayloads`] keeps (none without the plan).
pub(crate) const RUN: usize = if Active::GATHERED_CRC { 64 } else { 0 };

impl<'f, 'a> FramePayloads<'f, 'a> {
    /// Pieces over `frames` (each at least one byte long: the tail byte).
    pub fn new(frames: &'f [&'a [u8]]) -> Self {
        Self {
            frames,
            run: [0; RUN],
            gathered: 0,
        }
    }

    /// Gathers the payload into the run kept with it, which must hold it (`len`, its length
    /// in bytes, is at most [`RUN`]), and returns the run.
    #[inline]
    pub(crate) fn gather(&mut self, len: usize) -> &[u8] {
        let run = &mut self.run[..len];
        gather(self.frames, run);
        self.gathered = len;
        run
    }

    /// The run, for the payload to be gathered into by other means than [`Self::gather`];
    /// [`Self::set_gathered`] then says how much of it is the payload.
    #[inline(always)]
    pub(crate) fn run_mut(&mut self) -> &mut [u8] {
        &mut self.run
    }

    /// Marks the run's first `len` bytes the gathered payload (written through
    /// [`Self::run_mut`]), and returns them.
    #[inline(always)]
    pub(crate) fn set_gathered(&mut self, len: usize) -> &[u8] {
        self.gathered = len;
        &self.run[..len]
    }

    /// Bytes before frame `i`'s payload: the transfer CRC in the first of several frames.
    #[inline(always)]
    fn head(&self, i: usize) -> usize {
        head(self.frames, i)
    }

    /// [`Pieces::chunk`] of a frame other than a full 8-byte one: the last frame, a CAN FD
    /// frame, or a malformed short one (kept out of line: it is rare).
    #[inline(never)]
    fn odd_chunk(&self, i: usize, skip: usize) -> Chunk {
        chunk_of_piece(self, i, skip)
    }
}

impl Pieces for FramePayloads<'_, '_> {
    #[inline]
    fn count(&self) -> usize {
        self.frames.len()
    }

    #[inline]
    fn piece(&self, i: usize) -> &[u8] {
        piece(self.frames, i)
    }

    #[inline]
    fn total_len(&self) -> usize {
        if self.gathered > 0 {
            return self.gathered;
        }
        let bodies: usize = self.frames.iter().map(|f| f.len().saturating_sub(1)).sum();
        let crc = self
            .frames
            .first()
            .map_or(0, |first| first.len().saturating_sub(1).min(self.head(0)));
        bodies - crc
    }

    #[inline]
    fn contiguous(&self) -> Option<&[u8]> {
        match self.frames {
            [_] => Some(self.piece(0)),
            _ => self.run.get(..self.gathered).filter(|run| !run.is_empty()),
        }
    }

    #[inline(always)]
    fn chunk(&self, i: usize, skip: usize) -> Chunk {
        let frame = self.frames[i];
        if let Ok(eight) = <[u8; 8]>::try_from(frame) {
            // A full classic CAN frame: one load; the tail byte and what is skipped are
            // shifted out.
            let from = (self.head(i) + skip).min(7);
            let word = after_bytes(first_bytes(load_word(&eight), 7), from as u32);
            return Chunk {
                word,
                len: 7 - from,
                left: 0,
            };
        }
        self.odd_chunk(i, skip)
    }

    fn copy_out(&self, mut at: Place, out: &mut [u8]) -> Place {
        let mut done = 0;
        while done < out.len() && at.index < self.frames.len() {
            if at.skip == 0 && at.index > 0 {
                // Whole classic frames after the first: the 7 payload bytes and the tail byte
                // in one 8-byte move; the tail byte is overwritten by the next.
                while let (Some(frame), Some(dst)) =
                    (self.frames.get(at.index), out.get_mut(done..done + 8))
                {
                    let Ok(eight) = <&[u8; 8]>::try_from(*frame) else {
                        break;
                    };
                    dst.copy_from_slice(eight);
                    done += 7;
                    at.index += 1;
                }
                if at.index >= self.frames.len() {
                    break;
                }
            }
            // The rest of the first frame, a short or CAN FD frame, or the last few bytes.
            let rest = self.piece(at.index).get(at.skip..).unwrap_or(&[]);
            let n = rest.len().min(out.len() - done);
            copy_few(&mut out[done..done + n], &rest[..n]);
            done += n;
            at.step(n, n == rest.len());
        }
        at
    }
}

/// Bytes before frame `i`'s payload: the transfer CRC in the first of several frames.
#[inline(always)]
fn head(frames: &[&[u8]], i: usize) -> usize {
    if i == 0 && frames.len() > 1 {
        2
    } else {
        0
    }
}

/// Frame `i`'s payload: without its tail byte, and the transfer CRC in the first of several.
#[inline]
fn piece<'a>(frames: &[&'a [u8]], i: usize) -> &'a [u8] {
    let frame = frames[i];
    let body = &frame[..frame.len().saturating_sub(1)];
    body.get(head(frames, i)..).unwrap_or(&[])
}

/// Copies the payloads of `frames` (each at least its tail byte) one after another into
/// `out`, which is exactly their length.
#[inline(always)]
pub(crate) fn gather(frames: &[&[u8]], out: &mut [u8]) {
    let Some((first, rest)) = frames.split_first() else {
        return;
    };
    let head = if rest.is_empty() { 0 } else { 2 };
    let piece = first
        .get(head..first.len().saturating_sub(1))
        .unwrap_or(&[]);
    let mut at = piece.len();
    copy_few(&mut out[..at], piece);
    for &frame in rest {
        if let (Ok(eight), Some(room)) = (<&[u8; 8]>::try_from(frame), out.get_mut(at..at + 8)) {
            // A full classic frame: its 7 payload bytes and the tail byte in one 8-byte
            // store; the tail byte lies within `out`, where the next piece overwrites it.
            room.copy_from_slice(eight);
            at += 7;
            continue;
        }
        let piece = &frame[..frame.len().saturating_sub(1)];
        copy_few(&mut out[at..at + piece.len()], piece);
        at += piece.len();
    }
}

/// `dst.copy_from_slice(src)`, without a call for up to 8 bytes (a short last frame).
#[inline(always)]
pub(crate) fn copy_few(dst: &mut [u8], src: &[u8]) {
    let n = src.len();
    match (src.get(..4), src.get(n.saturating_sub(4)..)) {
        (Some(head), Some(tail)) if n <= 8 && dst.len() == n => {
            // Two 4-byte moves, overlapping for fewer than 8 bytes.
            dst[..4].copy_from_slice(head);
            dst[n - 4..].copy_from_slice(tail);
        }
        _ if n < 4 && dst.len() == n => {
            for (d, &s) in dst.iter_mut().zip(src) {
                *d = s;
            }
        }
        _ => dst.copy_from_slice(src),
    }
}

/// Where stream byte `byte` lies (in the last piece if beyond), walking from `from`, a place
/// whose piece starts at stream byte `start`; returns the place and its piece's start.
fn seek<P: Pieces + ?Sized>(pieces: &P, from: Place, start: usize, byte: usize) -> (Place, usize) {
    if byte == start + from.skip {
        return (from, start);
    }
    let (mut index, mut start) = (from.index, start);
    while byte < start && index > 0 {
        index -= 1;
        start -= pieces.piece(index).len();
    }
    let count = pieces.count();
    while index + 1 < count {
        let end = start + pieces.piece(index).len();
        if byte < end {
            break;
        }
        (index, start) = (index + 1, end);
    }
    // Past the end: the end of the last piece (or of none, where `from` was already there).
    let length = if index < count {
        pieces.piece(index).len()
    } else {
        0
    };
    let skip = byte.saturating_sub(start).min(length);
    (Place { index, skip }, start)
}

/// The window of [`BitRead::read_bits`]: the bytes it holds ([`Held`]; none until the first
/// read at an offset, or after a byte read from firmware's [`BitRead::byte`]) and where the
/// stream goes on after them (`next`, in a piece that starts at stream byte `next_start`).
// The held bytes are an `Option` so that an empty window is made by four stores (the tag and
// the place), not by clearing a 48-byte struct (a `memset` call in firmware).
#[derive(Clone, Copy, Debug)]
struct Window {
    held: Option<Held>,
    next: Place,
    next_start: usize,
}

/// Stream bytes from bit `start_bit` (a byte boundary), left-aligned in `word` (zero after the
/// `len` ones). Once filled, a window holds at least [`REFILLED`] bytes or all there are, so
/// its top 64 bits are the stream's.
#[derive(Clone, Copy, Debug)]
struct Held {
    start_bit: usize,
    len: usize,
    word: u128,
}

/// Bytes a filled window holds unless the stream ends first: enough for any read of up to 64
/// bits that starts in its first byte.
const REFILLED: usize = 9;

impl Window {
    /// `n` bits at `offset`, if they are among the top 64 of a filled window.
    #[inline(always)]
    fn read(&self, offset: usize, n: u32) -> Option<u64> {
        let held = self.held.as_ref()?;
        // Offsets behind the window wrap around to huge ones.
        let local = offset.wrapping_sub(held.start_bit);
        (local <= (64 - n) as usize && held.len > 0)
            .then(|| wide::bits_at(held.word, local as u32, n))
    }

    /// Moves the window to the byte holding bit `offset` and reads `n` bits there. Keeps the
    /// bytes it holds from that byte on and appends from the pieces after them.
    fn refill_read<P: Pieces + ?Sized>(&mut self, pieces: &P, offset: usize, n: u32) -> u64 {
        let byte = offset / 8;
        let kept = self.held.and_then(|held| {
            let drop = byte.wrapping_sub(held.start_bit / 8);
            (held.len > 0 && drop <= held.len).then(|| Held {
                start_bit: byte * 8,
                len: held.len - drop,
                word: wide::after_bytes(held.word, drop),
            })
        });
        let mut held = kept.unwrap_or_else(|| {
            (self.next, self.next_start) = seek(pieces, self.next, self.next_start, byte);
            Held {
                start_bit: byte * 8,
                len: 0,
                word: 0,
            }
        });
        while held.len < REFILLED && self.next.index < pieces.count() {
            let chunk = pieces.chunk(self.next.index, self.next.skip);
            held.word = wide::append(held.word, held.len, chunk.word);
            held.len += chunk.len;
            if let Some(length) = self.next.pass(&chunk) {
                self.next_start += length;
            }
        }
        self.held = Some(held);
        // Up to 71 bits from the top: the window holds 9 bytes or all there are.
        wide::bits_at(held.word, (offset % 8) as u32, n)
    }
}

/// A bit stream over scattered pieces.
///
/// Decoders read it forwards through a [`ScatteredReader`]; reads at any offset
/// ([`BitRead::read_bits`], for leaf access) go through a window of the bytes last read.
#[derive(Debug)]
pub struct Scattered<'p, P: Pieces + ?Sized> {
    pieces: &'p P,
    bytes: usize,
    window: Cell<Window>,
}

impl<'p, P: Pieces + ?Sized> Scattered<'p, P> {
    /// A stream over `pieces`.
    pub fn new(pieces: &'p P) -> Self {
        Self {
            pieces,
            bytes: pieces.total_len(),
            // Nothing yet: every read misses it. Written out field by field: as a constant the
            // whole struct would be cleared (its padding too), a `memset` call in firmware.
            window: Cell::new(Window {
                held: None,
                next: Place::default(),
                next_start: 0,
            }),
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

    #[inline(never)]
    fn read_bits_refilled(&self, offset: usize, n: u32) -> u64 {
        let mut w = self.window.get();
        let value = w.refill_read(self.pieces, offset, n);
        self.window.set(w);
        value
    }
}

impl<'p, P: Pieces + ?Sized> BitRead for Scattered<'p, P> {
    type Reader<'r>
        = ScatteredReader<'r, P>
    where
        Self: 'r;

    #[inline]
    fn bit_len(&self) -> usize {
        self.bytes * 8
    }

    #[inline(always)]
    fn read_bits(&self, offset: usize, n: u32) -> u64 {
        match self.window.get().read(offset, n) {
            Some(value) => value,
            None => self.read_bits_refilled(offset, n),
        }
    }

    #[inline]
    fn contiguous(&self) -> Option<&[u8]> {
        self.pieces.contiguous()
    }

    /// Firmware builds (`compact`) find the byte's piece from the place of the byte read
    /// before, without the window's code.
    #[inline]
    fn byte(&self, index: usize) -> u8 {
        if Active::WINDOWED_BITS {
            return self.read_bits(index * 8, 8) as u8;
        }
        // From the piece of the byte read before (remembered as the window's next place,
        // the window emptied), or from the first when the byte lies before it.
        let w = self.window.get();
        let (mut i, mut start) = match index >= w.next_start {
            true => (w.next.index, w.next_start),
            false => (0, 0),
        };
        while i < self.pieces.count() {
            let piece = self.pieces.piece(i);
            if let Some(&byte) = piece.get(index - start) {
                let next = Place { index: i, skip: 0 };
                self.window.set(Window {
                    held: None,
                    next,
                    next_start: start,
                });
                return byte;
            }
            (i, start) = (i + 1, start + piece.len());
        }
        0
    }

    #[inline]
    fn reader(&self, offset: usize) -> ScatteredReader<'_, P> {
        let w = self.window.get();
        let (next, _) = seek(self.pieces, w.next, w.next_start, offset / 8);
        let mut reader = ScatteredReader {
            pieces: self.pieces,
            ahead: Ahead::default(),
            next,
            pos: offset / 8 * 8,
        };
        if offset % 8 != 0 {
            reader.read((offset % 8) as u32);
        }
        reader
    }
}

/// [`BitReader`] over scattered pieces: the next bits wait in a register, topped up from the
/// next piece as they run out (once per CAN frame), so reading a field costs a shift.
#[derive(Debug)]
pub struct ScatteredReader<'p, P: Pieces + ?Sized> {
    pieces: &'p P,
    /// The next bits of the stream.
    ahead: Ahead,
    /// Where the bytes after those start.
    next: Place,
    /// The bit offset of the next read.
    pos: usize,
}

impl<P: Pieces + ?Sized> Clone for ScatteredReader<'_, P> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<P: Pieces + ?Sized> Copy for ScatteredReader<'_, P> {}

impl<P: Pieces + ?Sized> ScatteredReader<'_, P> {
    /// Reads `n` bits when fewer are ahead: those, then the rest from the next pieces.
    #[inline(always)]
    fn read_topped_up(&mut self, n: u32) -> u64 {
        let mut missing = n - self.ahead.count();
        let mut value = self.ahead.take_all();
        while self.next.index < self.pieces.count() {
            let chunk = self.pieces.chunk(self.next.index, self.next.skip);
            self.next.pass(&chunk);
            let mut got = Ahead::new(chunk.word, 8 * chunk.len as u32);
            if got.count() >= missing {
                // `missing` is 64 only when `value` is 0.
                value = join(value, got.take(missing), missing);
                self.ahead = got;
                return value;
            }
            if got.count() > 0 {
                let all = got.count();
                value = join(value, got.take(all), all);
                missing -= all;
            }
        }
        // Past the end (callers do not read there): zeros.
        join(value, 0, missing)
    }
}

impl<P: Pieces + ?Sized> BitReader for ScatteredReader<'_, P> {
    #[inline(always)]
    fn read(&mut self, n: u32) -> u64 {
        self.pos += n as usize;
        if n <= self.ahead.count() {
            return self.ahead.take(n);
        }
        self.read_topped_up(n)
    }

    fn read_bytes(&mut self, out: &mut [u8]) {
        self.pos += 8 * out.len();
        // On a byte boundary the bits ahead are whole bytes (at most 7): those first, then
        // the pieces. Bytes written past the end of a step are rewritten by the next one.
        let done = (self.ahead.count() as usize / 8).min(out.len());
        let ahead = self.ahead.bytes();
        match out.get_mut(..8) {
            Some(room) => room.copy_from_slice(&ahead),
            None => {
                for (slot, b) in out[..done].iter_mut().zip(ahead) {
                    *slot = b;
                }
            }
        }
        self.ahead.drop(8 * done as u32);
        if done < out.len() {
            self.next = self.pieces.copy_out(self.next, &mut out[done..]);
        }
    }

    #[inline]
    fn skip(&mut self, mut n: usize) {
        while n > 0 {
            let step = n.min(64);
            self.read(step as u32);
            n -= step;
        }
    }

    #[inline(always)]
    fn position(&self) -> usize {
        self.pos
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bits::read_bits;
    extern crate std;

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

    /// A full first frame (transfer CRC, 5 payload bytes), a full one, a CAN FD one, a short
    /// last one; each ends with its tail byte.
    const FRAMES: [&[u8]; 4] = [
        &[0xAA, 0xBB, 1, 2, 3, 4, 5, 0x80],
        &[6, 7, 8, 9, 10, 11, 12, 0x20],
        &[13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 0x00],
        &[24, 25, 26, 0x60],
    ];

    #[test]
    fn frame_chunks_are_their_payload_bytes() {
        let [full, next, fd, short] = FRAMES;
        let runs: [&[&[u8]]; 5] = [
            &[full, next, fd, short],
            &[full],
            &[short],
            &[&[0xAA, 0xBB, 0x80], &[0x40]],
            &[&[0x80], next, &[0x60]],
        ];
        for frames in runs {
            let p = FramePayloads::new(frames);
            let pieces: usize = (0..p.count()).map(|i| p.piece(i).len()).sum();
            assert_eq!(p.total_len(), pieces);
            for i in 0..p.count() {
                for skip in 0..=p.piece(i).len() {
                    let expected = Chunk::of(&p.piece(i)[skip..]);
                    assert_eq!(p.chunk(i, skip), expected, "frame {i} from {skip}");
                }
            }
        }
    }

    #[test]
    fn frame_payloads_copy_out_their_payload_bytes() {
        let [full, next, fd, short] = FRAMES;
        let frames: [&[u8]; 5] = [full, next, fd, &[0x20], short];
        let p = FramePayloads::new(&frames);
        let joined: std::vec::Vec<u8> = (0..p.count()).flat_map(|i| p.piece(i).to_vec()).collect();
        assert_eq!(joined.len(), p.total_len());
        let mut starts = std::vec::Vec::new();
        for i in 0..p.count() {
            for skip in 0..=p.piece(i).len() {
                starts.push((Place { index: i, skip }, starts_at(&p, i) + skip));
            }
        }
        for (at, byte) in starts {
            for len in 0..=joined.len() - byte {
                let mut out = [0xEEu8; 40];
                let end = p.copy_out(at, &mut out[..len]);
                assert_eq!(
                    out[..len],
                    joined[byte..byte + len],
                    "from {at:?}, {len} bytes"
                );
                // It ends where the bytes after the copied ones are.
                assert_eq!(starts_at(&p, end.index) + end.skip, byte + len);
            }
        }
    }

    fn starts_at<P: Pieces + ?Sized>(p: &P, i: usize) -> usize {
        (0..i).map(|k| p.piece(k).len()).sum()
    }

    #[test]
    fn a_read_past_the_end_does_not_disturb_later_reads() {
        let bytes: [u8; 12] = core::array::from_fn(|i| i as u8);
        let pieces: [&[u8]; 12] = core::array::from_fn(|i| &bytes[i..=i]);
        let s = Scattered::new(&pieces[..]);
        // Out of contract (callers check the length first), but no panic and no lasting harm,
        // also when the window has just taken the last piece.
        assert_eq!(s.read_bits(88, 8), 11);
        s.read_bits(160, 8);
        s.read_bits(96, 8);
        assert_eq!(s.read_bits(0, 8), 0);
        assert_eq!(s.read_bits(80, 8), 10);
        assert_eq!(s.read_bits(8, 16), 0x0102);
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
