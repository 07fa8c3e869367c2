//! Bit-level access in DroneCAN order: bits fill each byte most-significant-bit first.
//!
//! Everything here works on *stream values*: an `n`-bit number whose most significant bit is the
//! first bit in the stream. The little-endian byte order of multi-byte scalars is applied on top
//! of this by [`crate::scalar`].

use crate::plan::{Active, Plans};

/// A read-only bit stream. Implemented for contiguous bytes here; the trait lets the same
/// decoders read payloads that lie in several pieces (descattering).
pub trait BitRead {
    /// Reads the stream from one position on (see [`BitRead::reader`]).
    type Reader<'r>: BitReader + Copy
    where
        Self: 'r;

    /// Total number of bits available.
    fn bit_len(&self) -> usize;

    /// Reads `n` bits (`1..=64`) starting at bit `offset` as a big-endian stream value.
    ///
    /// The caller guarantees `offset + n <= self.bit_len()`.
    fn read_bits(&self, offset: usize, n: u32) -> u64;

    /// A reader of the bits from `offset` on, one field after another: what a decoder uses,
    /// as it reads forwards. It gives the same bits as [`BitRead::read_bits`].
    fn reader(&self, offset: usize) -> Self::Reader<'_>;

    /// Byte `index` (`index < self.bit_len() / 8`), as the small walk ([`crate::walk`]) reads.
    fn byte(&self, index: usize) -> u8 {
        self.read_bits(index * 8, 8) as u8
    }

    /// The bits as one run of bytes when they are one (`None` for payloads in pieces): what
    /// a plan that reads whole bytes at a time needs (see [`crate::straight`]).
    #[inline]
    fn contiguous(&self) -> Option<&[u8]> {
        None
    }
}

/// Reads a [`BitRead`] forwards from a position; made by [`BitRead::reader`]. The caller
/// checks against [`BitRead::bit_len`] that the bits it reads exist.
pub trait BitReader {
    /// The next `n` bits (`1..=64`) as a big-endian stream value.
    fn read(&mut self, n: u32) -> u64;

    /// The next `out.len()` bytes, the reader standing on a byte boundary (byte strings are
    /// copied, not shifted bit by bit).
    fn read_bytes(&mut self, out: &mut [u8]);

    /// Skips `n` bits.
    fn skip(&mut self, n: usize);

    /// The bit offset of the next read.
    fn position(&self) -> usize;
}

/// [`BitReader`] over contiguous bytes: a position.
#[derive(Clone, Copy, Debug)]
pub struct SliceReader<'d> {
    data: &'d [u8],
    pos: usize,
}

impl BitReader for SliceReader<'_> {
    #[inline(always)]
    fn read(&mut self, n: u32) -> u64 {
        let value = read_bits(self.data, self.pos, n);
        self.pos += n as usize;
        value
    }

    #[inline]
    fn read_bytes(&mut self, out: &mut [u8]) {
        let start = self.pos / 8;
        out.copy_from_slice(&self.data[start..start + out.len()]);
        self.pos += 8 * out.len();
    }

    #[inline(always)]
    fn skip(&mut self, n: usize) {
        self.pos += n;
    }

    #[inline(always)]
    fn position(&self) -> usize {
        self.pos
    }
}

impl BitRead for [u8] {
    type Reader<'r> = SliceReader<'r>;

    #[inline]
    fn bit_len(&self) -> usize {
        self.len() * 8
    }

    #[inline(always)]
    fn read_bits(&self, offset: usize, n: u32) -> u64 {
        read_bits(self, offset, n)
    }

    #[inline(always)]
    fn reader(&self, offset: usize) -> SliceReader<'_> {
        SliceReader {
            data: self,
            pos: offset,
        }
    }

    #[inline]
    fn byte(&self, index: usize) -> u8 {
        self[index]
    }

    #[inline]
    fn contiguous(&self) -> Option<&[u8]> {
        Some(self)
    }
}

/// Mask of the low `n` bits, `n <= 64`.
#[inline(always)]
pub const fn mask(n: u32) -> u64 {
    // Branch-free: this runs several times per encoded field.
    ((1u128 << (n & 127)) - 1) as u64
}

/// [`mask`] for `1 <= n <= 64` (a field's width), in one shift.
#[inline(always)]
pub(crate) const fn field_mask(n: u32) -> u64 {
    debug_assert!(n >= 1 && n <= 64);
    if cfg!(target_pointer_width = "32") {
        field_mask_halves(n)
    } else {
        u64::MAX >> (64 - n)
    }
}

/// [`field_mask`] in 32-bit halves, as 32-bit cores take it: a 64-bit shift by a variable
/// amount is a routine call there (`__aeabi_llsr`).
#[inline(always)]
const fn field_mask_halves(n: u32) -> u64 {
    let low = if n >= 32 { u32::MAX } else { !(u32::MAX << n) };
    let high = if n > 32 { u32::MAX >> (64 - n) } else { 0 };
    (high as u64) << 32 | low as u64
}

/// Reads `n` bits (`1..=64`) at bit `offset` from `data` as a big-endian stream value.
///
/// # Panics
/// If the bits lie outside `data` (callers check the length first).
#[inline(always)]
pub fn read_bits(data: &[u8], offset: usize, n: u32) -> u64 {
    debug_assert!((1..=64).contains(&n));
    let first = offset / 8;
    let shift = (offset % 8) as u32;
    let last = (offset + n as usize - 1) / 8;
    // Fast path: the bits (plus the leading skipped bits) fit a 64-bit window; near the end
    // of the data the window is zero-filled. Without plans (firmware) the loop alone runs.
    if Active::WINDOWED_BITS && shift + n <= 64 {
        let word = if let Some(bytes) = data.get(first..first + 8) {
            let mut window = [0u8; 8];
            window.copy_from_slice(bytes);
            u64::from_be_bytes(window)
        } else {
            // Near the end of the data (or of a short piece): only the bytes needed.
            let mut word = 0u64;
            for (k, &b) in data[first..=last].iter().enumerate() {
                word |= u64::from(b) << (56 - 8 * k);
            }
            word
        };
        return (word << shift) >> (64 - n);
    }
    let mut acc: u128 = 0;
    for &byte in &data[first..=last] {
        acc = (acc << 8) | u128::from(byte);
    }
    let total = ((last - first + 1) * 8) as u32;
    ((acc >> (total - shift - n)) as u64) & mask(n)
}

/// Writes the low `n` bits (`1..=64`) of `value` at bit `offset`, most significant first,
/// replacing whatever bits were there and leaving all others untouched.
///
/// # Panics
/// If the bits lie outside `out` (callers check the length first).
#[inline]
pub fn write_bits(out: &mut [u8], offset: usize, value: u64, n: u32) {
    debug_assert!((1..=64).contains(&n));
    let first = offset / 8;
    let shift = (offset % 8) as u32;
    // Fast path: read-modify-write one 64-bit window holding all the bits (not in firmware
    // builds, `compact`, which take the loop alone).
    if Active::WINDOWED_BITS && shift + n <= 64 && first + 8 <= out.len() {
        let mut window = [0u8; 8];
        window.copy_from_slice(&out[first..first + 8]);
        let word = u64::from_be_bytes(window);
        let place = 64 - shift - n;
        let field = mask(n) << place;
        let word = (word & !field) | ((value & mask(n)) << place);
        out[first..first + 8].copy_from_slice(&word.to_be_bytes());
        return;
    }
    let mut remaining = n;
    let mut pos = offset;
    while remaining > 0 {
        let byte = pos / 8;
        let used = (pos % 8) as u32;
        let room = 8 - used;
        let take = room.min(remaining);
        let chunk = ((value >> (remaining - take)) & mask(take)) as u8;
        let shift = room - take;
        let keep = !((mask(take) as u8) << shift);
        out[byte] = (out[byte] & keep) | (chunk << shift);
        pos += take as usize;
        remaining -= take;
    }
}

/// Writes bits one after another into a byte buffer. Unfinished bits wait in a 64-bit register
/// and go out 32 at a time, so a field costs a shift and an or, and fields do not wait on
/// each other's byte stores.
#[derive(Debug)]
pub struct BitWriter<'o> {
    out: &'o mut [u8],
    /// Bytes completed in `out`.
    bytes: usize,
    /// Pending bits, right-aligned; fewer than 32 between writes.
    acc: u64,
    pending: u32,
}

impl<'o> BitWriter<'o> {
    /// A writer at the start of `out`.
    pub fn new(out: &'o mut [u8]) -> Self {
        Self {
            out,
            bytes: 0,
            acc: 0,
            pending: 0,
        }
    }

    /// Bits written so far.
    #[inline]
    pub fn bit_pos(&self) -> usize {
        self.bytes * 8 + self.pending as usize
    }

    /// Appends the low `n` bits (`1..=64`) of a big-endian stream value; `Err(needed_bytes)`
    /// when `out` is too small.
    #[inline(always)]
    pub fn write(&mut self, value: u64, n: u32) -> Result<(), usize> {
        let value = value & field_mask(n);
        match self.write_run(1, |_| Ok::<_, ()>((value, n))) {
            Ok(()) => Ok(()),
            Err(Err(needed)) => Err(needed),
            Err(Ok(())) => Ok(()),
        }
    }

    /// Appends `count` values produced by `next(i)` as `(stream value, bit length)` (the value
    /// must fit its length, as [`crate::scalar::to_stream`] makes it), keeping the writer's
    /// state in registers for the whole run. Stops at the first error of `next` (`Err(Ok(e))`)
    /// or when `out` is full (`Err(Err(needed_bytes))`), with the values before it written.
    #[inline(always)]
    pub fn write_run<E>(
        &mut self,
        count: usize,
        mut next: impl FnMut(usize) -> Result<(u64, u32), E>,
    ) -> Result<(), Result<E, usize>> {
        let (mut acc, mut pending, mut bytes) = (self.acc, self.pending, self.bytes);
        let out = &mut *self.out;
        let mut result = Ok(());
        for i in 0..count {
            let (value, n) = match next(i) {
                Ok(v) => v,
                Err(e) => {
                    result = Err(Ok(e));
                    break;
                }
            };
            debug_assert!(n <= 64 && value & !mask(n) == 0);
            let stored = if !Active::WINDOWED_BITS {
                // Firmware (built for size): one copy of `put`, taking both halves; the high
                // one is empty for values of up to 32 bits.
                [
                    (value >> 32, n.saturating_sub(32)),
                    (value & mask(32), n.min(32)),
                ]
                .into_iter()
                .try_for_each(|(half, k)| put(out, &mut acc, &mut pending, &mut bytes, half, k))
            } else if n > 32 {
                // Over 32 bits: two halves, so that pending (< 32) + n stays within 64.
                put(out, &mut acc, &mut pending, &mut bytes, value >> 32, n - 32).and_then(|()| {
                    put(
                        out,
                        &mut acc,
                        &mut pending,
                        &mut bytes,
                        value & mask(32),
                        32,
                    )
                })
            } else {
                put(out, &mut acc, &mut pending, &mut bytes, value, n)
            };
            if let Err(needed) = stored {
                result = Err(Err(needed));
                break;
            }
        }
        (self.acc, self.pending, self.bytes) = (acc, pending, bytes);
        result
    }

    /// Stores the pending whole bytes; `Err(needed_bytes)` when `out` is too small.
    fn flush_bytes(&mut self) -> Result<(), usize> {
        while self.pending >= 8 {
            // Room first: a refused byte stays pending, so the writer's position (and what
            // `finish` asks for) still counts it.
            let Some(slot) = self.out.get_mut(self.bytes) else {
                return Err(self.bytes + 1);
            };
            self.pending -= 8;
            *slot = (self.acc >> self.pending) as u8;
            self.bytes += 1;
        }
        self.acc &= mask(self.pending);
        Ok(())
    }

    /// When the writer stands on a byte boundary with `n` bytes of room: those bytes, to be
    /// filled by the caller (the writer moves past them).
    #[inline]
    pub fn aligned_bytes(&mut self, n: usize) -> Option<&mut [u8]> {
        if self.pending % 8 != 0 {
            return None;
        }
        self.flush_bytes().ok()?;
        let start = self.bytes;
        let bytes = self.out.get_mut(start..start + n)?;
        self.bytes += n;
        Some(bytes)
    }

    /// Pads the last byte with zeros; returns the length in bytes.
    pub fn finish(mut self) -> Result<usize, usize> {
        let pad = (8 - self.pending % 8) % 8;
        self.acc <<= pad;
        self.pending += pad;
        self.flush_bytes()?;
        Ok(self.bytes)
    }
}

/// Appends `n <= 32` bits to an accumulator holding fewer than 32, storing 32 at a time.
#[inline(always)]
fn put(
    out: &mut [u8],
    acc: &mut u64,
    pending: &mut u32,
    bytes: &mut usize,
    value: u64,
    n: u32,
) -> Result<(), usize> {
    *acc = (*acc << n) | value;
    *pending += n;
    if *pending >= 32 {
        *pending -= 32;
        let word = ((*acc >> *pending) as u32).to_be_bytes();
        match out.get_mut(*bytes..*bytes + 4) {
            Some(slot) => slot.copy_from_slice(&word),
            None => {
                // Near the end of a short buffer: store what fits, report the rest.
                let room = out.len().saturating_sub(*bytes);
                if let Some(slot) = out.get_mut(*bytes..) {
                    slot.copy_from_slice(&word[..room]);
                }
                return Err(*bytes + 4);
            }
        }
        *bytes += 4;
        *acc &= mask(*pending);
    }
    Ok(())
}

/// Copies `n` bits from `src` at `src_offset` to `dst` at `dst_offset`.
pub fn copy_bits<R: BitRead + ?Sized>(
    src: &R,
    src_offset: usize,
    dst: &mut [u8],
    dst_offset: usize,
    n: usize,
) {
    let mut done = 0;
    while done < n {
        let chunk = (n - done).min(56) as u32;
        let bits = src.read_bits(src_offset + done, chunk);
        write_bits(dst, dst_offset + done, bits, chunk);
        done += chunk as usize;
    }
}

/// Writes `n` zero bits at `offset`.
pub fn zero_bits(out: &mut [u8], offset: usize, n: usize) {
    let mut done = 0;
    while done < n {
        let chunk = (n - done).min(64) as u32;
        write_bits(out, offset + done, 0, chunk);
        done += chunk as usize;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks_of_every_width() {
        assert_eq!(mask(0), 0);
        assert_eq!(mask(64), u64::MAX);
        for n in 1..=64u32 {
            // Against the arithmetic definition, 2^n - 1.
            assert_eq!(u128::from(mask(n)), (1u128 << n) - 1, "n={n}");
            assert_eq!(u128::from(field_mask(n)), (1u128 << n) - 1, "n={n}");
            assert_eq!(field_mask_halves(n), field_mask(n), "n={n}");
        }
    }

    #[test]
    fn write_then_read_at_every_offset() {
        for n in 1..=64u32 {
            for offset in 0..17usize {
                let value = 0xA5C3_0F96_5AF0_3C69u64 & mask(n);
                let mut buf = [0xFFu8; 16];
                write_bits(&mut buf, offset, value, n);
                assert_eq!(read_bits(&buf, offset, n), value, "n={n} offset={offset}");
                // Neighbouring bits are untouched.
                if offset > 0 {
                    assert_eq!(read_bits(&buf, 0, offset as u32), mask(offset as u32));
                }
            }
        }
    }

    #[test]
    fn msb_first_within_a_byte() {
        let mut buf = [0u8; 2];
        write_bits(&mut buf, 0, 0b1, 1);
        write_bits(&mut buf, 7, 0b11, 2);
        assert_eq!(buf, [0b1000_0001, 0b1000_0000]);
    }

    #[test]
    fn bit_writer_matches_write_bits() {
        let widths = [3u32, 12, 1, 64, 7, 33, 8, 57, 2];
        let mut expected = [0u8; 32];
        let mut buf = [0xAAu8; 32];
        let mut w = BitWriter::new(&mut buf);
        let mut pos = 0;
        for (i, &n) in widths.iter().enumerate() {
            let v = 0x9E37_79B9_7F4A_7C15u64.rotate_left(i as u32 * 7) & mask(n);
            write_bits(&mut expected, pos, v, n);
            w.write(v, n).unwrap();
            pos += n as usize;
        }
        let len = w.finish().unwrap();
        assert_eq!(len, pos.div_ceil(8));
        assert_eq!(buf[..len], expected[..len]);
        let mut small = [0u8; 2];
        let mut w = BitWriter::new(&mut small);
        w.write(0x00FF_FFFF, 24).unwrap();
        assert_eq!(w.finish(), Err(3));
        let mut small = [0u8; 2];
        let mut w = BitWriter::new(&mut small);
        assert_eq!(w.write(0x00FF_FFFF_FFFF, 40), Err(4));
    }

    #[test]
    fn copy_bits_across_unaligned_offsets() {
        let src = [0xDEu8, 0xAD, 0xBE, 0xEF, 0x01, 0x23, 0x45, 0x67, 0x89];
        for src_off in 0..8 {
            for dst_off in 0..8 {
                let n = 60;
                let mut dst = [0u8; 10];
                copy_bits(&src[..], src_off, &mut dst, dst_off, n);
                for i in 0..n {
                    assert_eq!(
                        read_bits(&dst, dst_off + i, 1),
                        read_bits(&src, src_off + i, 1)
                    );
                }
            }
        }
    }
}
