//! Bit-level access in DroneCAN order: bits fill each byte most-significant-bit first.
//!
//! Everything here works on *stream values*: an `n`-bit number whose most significant bit is the
//! first bit in the stream. The little-endian byte order of multi-byte scalars is applied on top
//! of this by [`crate::scalar`].

/// A read-only bit stream. Implemented for contiguous bytes here; the trait lets the same
/// decoders read payloads that lie in several pieces (descattering).
pub trait BitRead {
    /// Total number of bits available.
    fn bit_len(&self) -> usize;

    /// Reads `n` bits (`1..=64`) starting at bit `offset` as a big-endian stream value.
    ///
    /// The caller guarantees `offset + n <= self.bit_len()`.
    fn read_bits(&self, offset: usize, n: u32) -> u64;
}

impl BitRead for [u8] {
    #[inline]
    fn bit_len(&self) -> usize {
        self.len() * 8
    }

    #[inline]
    fn read_bits(&self, offset: usize, n: u32) -> u64 {
        read_bits(self, offset, n)
    }
}

/// Mask of the low `n` bits, `n <= 64`.
#[inline]
pub const fn mask(n: u32) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1u64 << n) - 1
    }
}

/// Reads `n` bits (`1..=64`) at bit `offset` from `data` as a big-endian stream value.
///
/// # Panics
/// If the bits lie outside `data` (callers check the length first).
#[inline]
pub fn read_bits(data: &[u8], offset: usize, n: u32) -> u64 {
    debug_assert!((1..=64).contains(&n));
    let first = offset / 8;
    let shift = (offset % 8) as u32;
    let last = (offset + n as usize - 1) / 8;
    // Fast path: the bits (plus the leading skipped bits) fit a 64-bit window.
    if shift + n <= 64 && first + 8 <= data.len() {
        let mut window = [0u8; 8];
        window.copy_from_slice(&data[first..first + 8]);
        let word = u64::from_be_bytes(window);
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
    // Fast path: read-modify-write one 64-bit window holding all the bits.
    if shift + n <= 64 && first + 8 <= out.len() {
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

/// Writes bits one after another into a byte buffer, keeping the unfinished bits in a register
/// so that each write costs a shift and an or, plus a store per whole byte.
#[derive(Debug)]
pub struct BitWriter<'o> {
    out: &'o mut [u8],
    /// Bytes completed in `out`.
    bytes: usize,
    /// Pending bits, right-aligned; fewer than 8 between writes.
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
        debug_assert!((1..=64).contains(&n));
        let value = value & mask(n);
        if n > 56 {
            // Keep the accumulator within 64 bits: split very wide values.
            self.push(value >> 32, n - 32)?;
            return self.push(value & mask(32), 32);
        }
        self.push(value, n)
    }

    /// Appends `n <= 56` bits (more would overflow the accumulator's 7 pending bits).
    #[inline(always)]
    fn push(&mut self, value: u64, n: u32) -> Result<(), usize> {
        self.acc = (self.acc << n) | value;
        self.pending += n;
        while self.pending >= 8 {
            self.pending -= 8;
            let byte = (self.acc >> self.pending) as u8;
            match self.out.get_mut(self.bytes) {
                Some(slot) => *slot = byte,
                None => return Err(self.bytes + 1),
            }
            self.bytes += 1;
        }
        // pending < 8 here: keep only those bits (no branch needed for the mask).
        self.acc &= (1u64 << self.pending) - 1;
        Ok(())
    }

    /// Pads the last byte with zeros; returns the length in bytes.
    pub fn finish(mut self) -> Result<usize, usize> {
        if self.pending > 0 {
            let pad = 8 - self.pending;
            self.write(0, pad)?;
        }
        Ok(self.bytes)
    }
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
        assert_eq!(w.write(0x00FF_FFFF, 24), Err(3));
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
