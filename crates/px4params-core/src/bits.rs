//! Where a scalar's bits go in a DroneCAN stream, in one place: a value's bytes least
//! significant first (the last holding its top `bits % 8` bits), each byte's bits most
//! significant first. No other module of the core says it (`tests/rule_home.rs` checks).
//!
//! A *stream value* is an `n`-bit number whose most significant bit is the first in the
//! stream; [`to_stream`] and [`from_stream`] turn values into stream values and back
//! (`Order` does it for a width known ahead). Around them, side by side, the ways the codec
//! moves stream bits, each for its own case and all held to the rule by the tests below:
//!
//! - at any offset: [`read_bits`] and [`write_bits`], a 64-bit window (firmware: a loop);
//! - one field after another: [`BitWriter`] over the `Pending` register, the `Ahead`
//!   register that readers gather bytes into, and `load_word`/`store_word` for whole words;
//! - a byte at a time, as firmware's walk reads and writes: `read_scalar`/`put_scalar`.

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

// ---- Byte order: a value's bytes least significant first, its top `bits % 8` bits last.

/// Puts a value's bytes in DroneCAN stream order: the whole low bytes first, then the top
/// `bits % 8` bits, as one big-endian stream value of `bits` bits.
#[inline(always)]
pub fn to_stream(value: u64, bits: u32) -> u64 {
    let whole = bits / 8;
    let rest = bits % 8;
    if whole == 0 {
        return value & mask(rest);
    }
    let low = value & field_mask(whole * 8);
    let swapped = low.swap_bytes() >> (64 - whole * 8);
    if rest == 0 {
        swapped
    } else {
        (swapped << rest) | ((value >> (whole * 8)) & field_mask(rest))
    }
}

/// Inverse of [`to_stream`].
#[inline(always)]
pub fn from_stream(stream: u64, bits: u32) -> u64 {
    let whole = bits / 8;
    let rest = bits % 8;
    if whole == 0 {
        return stream;
    }
    let bytes = if rest == 0 { stream } else { stream >> rest };
    let low = (bytes << (64 - whole * 8)).swap_bytes();
    if rest == 0 {
        low
    } else {
        low | ((stream & mask(rest)) << (whole * 8))
    }
}

/// How a value's bits become stream bits, known ahead (a plan's step keeps it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(u8)]
pub(crate) enum Order {
    /// At most 8 bits: as they are.
    #[default]
    Same,
    /// Whole bytes: the bytes reversed.
    Bytes,
    /// Whole bytes and some bits more: the general rule.
    Mixed,
}

impl Order {
    /// The order of a value of `bits` bits (`1..=64`).
    pub(crate) const fn of(bits: u32) -> Self {
        match bits {
            ..=8 => Self::Same,
            _ if bits % 8 == 0 => Self::Bytes,
            _ => Self::Mixed,
        }
    }

    /// [`to_stream`] for a value of this order.
    #[inline(always)]
    pub(crate) fn stream(self, raw: u64, bits: u32) -> u64 {
        match self {
            Self::Same => raw,
            // 16 to 64 bits: the shift is at most 48.
            Self::Bytes => raw.swap_bytes() >> (64 - bits),
            Self::Mixed => to_stream(raw, bits),
        }
    }

    /// The stream value `acc` followed by the value `raw` of `bits` bits (`1..=64`; `acc` is 0
    /// where `bits` is 64).
    // [`join`] of the stream value, with `acc` shifted first: through `join` the small plans'
    // encode took 8 more instructions (NodeStatus, 290 -> 298).
    #[inline(always)]
    pub(crate) fn append(self, acc: u64, raw: u64, bits: u32) -> u64 {
        acc.wrapping_shl(bits) | self.stream(raw, bits)
    }

    /// [`from_stream`] for a value of this order.
    #[inline(always)]
    pub(crate) fn raw(self, stream: u64, bits: u32) -> u64 {
        match self {
            Self::Same => stream,
            Self::Bytes => (stream << (64 - bits)).swap_bytes(),
            Self::Mixed => from_stream(stream, bits),
        }
    }
}

// ---- Bit order: each byte's most significant bit first.

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
        return bits_at(load_word(&data[first..]), shift, n);
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

/// Bits on their way out, most significant first, in a register: the oldest go out as
/// big-endian bytes, 32 at a time or a byte at a time. Bits older than the waiting ones may
/// stay above them in the register; they are shifted out, never stored.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Pending {
    acc: u64,
    /// How many of the lowest bits of `acc` wait (`<= 64`).
    count: u32,
}

impl Pending {
    /// The low `count` (`<= 64`) bits of `acc` waiting, the oldest highest.
    #[inline(always)]
    pub(crate) const fn new(acc: u64, count: u32) -> Self {
        Self { acc, count }
    }

    /// How many bits wait.
    #[inline(always)]
    pub(crate) const fn count(&self) -> u32 {
        self.count
    }

    /// Appends `n` bits (`count + n <= 64`) of a stream value that fits them; when 32 or
    /// more wait then, gives the oldest 32 as they go out.
    #[inline(always)]
    pub(crate) fn push(&mut self, value: u64, n: u32) -> Option<[u8; 4]> {
        self.acc = (self.acc << n) | value;
        self.count += n;
        if self.count < 32 {
            return None;
        }
        self.count -= 32;
        Some(((self.acc >> self.count) as u32).to_be_bytes())
    }

    /// The oldest byte; 8 bits or more wait.
    #[inline(always)]
    pub(crate) fn pop_byte(&mut self) -> u8 {
        debug_assert!(self.count >= 8);
        self.count -= 8;
        (self.acc >> self.count) as u8
    }

    /// The waiting bits (at most 32) as they end a stream: at the top of 4 bytes, zeros
    /// after them, and how many of the bytes they reach.
    #[inline(always)]
    pub(crate) fn last_bytes(&self) -> ([u8; 4], usize) {
        debug_assert!(self.count <= 32);
        let word = ((self.acc << (32 - self.count)) as u32).to_be_bytes();
        (word, self.count.div_ceil(8) as usize)
    }
}

/// Writes bits one after another into a byte buffer. Unfinished bits wait in a register
/// and go out 32 at a time, so a field costs a shift and an or, and fields do
/// not wait on each other's byte stores.
#[derive(Debug)]
pub struct BitWriter<'o> {
    out: &'o mut [u8],
    /// Bytes completed in `out`.
    bytes: usize,
    /// Fewer than 32 between writes.
    pending: Pending,
}

impl<'o> BitWriter<'o> {
    /// A writer at the start of `out`.
    pub fn new(out: &'o mut [u8]) -> Self {
        Self {
            out,
            bytes: 0,
            pending: Pending::default(),
        }
    }

    /// Bits written so far.
    #[inline]
    pub fn bit_pos(&self) -> usize {
        self.bytes * 8 + self.pending.count() as usize
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
    /// must fit its length, as [`to_stream`] makes it), keeping the writer's state in
    /// registers for the whole run. Stops at the first error of `next` (`Err(Ok(e))`) or when
    /// `out` is full (`Err(Err(needed_bytes))`), with the values before it written.
    #[inline(always)]
    pub fn write_run<E>(
        &mut self,
        count: usize,
        mut next: impl FnMut(usize) -> Result<(u64, u32), E>,
    ) -> Result<(), Result<E, usize>> {
        let (mut pending, mut bytes) = (self.pending, self.bytes);
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
                // Firmware (built for size): one copy of `put`, taking both halves; the first
                // one is empty for values of up to 32 bits.
                halves(value, n)
                    .into_iter()
                    .try_for_each(|(half, k)| put(out, &mut pending, &mut bytes, half, k))
            } else if n > 32 {
                // Over 32 bits: two halves, so that pending (< 32) + n stays within 64.
                let [(first, k), (rest, _)] = halves(value, n);
                put(out, &mut pending, &mut bytes, first, k)
                    .and_then(|()| put(out, &mut pending, &mut bytes, rest, 32))
            } else {
                put(out, &mut pending, &mut bytes, value, n)
            };
            if let Err(needed) = stored {
                result = Err(Err(needed));
                break;
            }
        }
        (self.pending, self.bytes) = (pending, bytes);
        result
    }

    /// Stores the pending whole bytes; `Err(needed_bytes)` when `out` is too small.
    fn flush_bytes(&mut self) -> Result<(), usize> {
        while self.pending.count() >= 8 {
            // Room first: a refused byte stays pending, so the writer's position (and what
            // `finish` asks for) still counts it.
            let Some(slot) = self.out.get_mut(self.bytes) else {
                return Err(self.bytes + 1);
            };
            *slot = self.pending.pop_byte();
            self.bytes += 1;
        }
        Ok(())
    }

    /// When the writer stands on a byte boundary with `n` bytes of room: those bytes, to be
    /// filled by the caller (the writer moves past them).
    #[inline]
    pub fn aligned_bytes(&mut self, n: usize) -> Option<&mut [u8]> {
        if self.pending.count() % 8 != 0 {
            return None;
        }
        self.flush_bytes().ok()?;
        let start = self.bytes;
        let bytes = self.out.get_mut(start..start + n)?;
        self.bytes += n;
        Some(bytes)
    }

    /// Pads the last byte with zeros; returns the length in bytes, or `Err(needed_bytes)`
    /// when `out` is too small (then nothing more is stored).
    pub fn finish(self) -> Result<usize, usize> {
        let (word, n) = self.pending.last_bytes();
        let end = self.bytes + n;
        let slot = self.out.get_mut(self.bytes..end).ok_or(end)?;
        slot.copy_from_slice(&word[..n]);
        Ok(end)
    }
}

/// Appends `n <= 32` bits to a register holding fewer than 32, storing 32 at a time.
#[inline(always)]
fn put(
    out: &mut [u8],
    pending: &mut Pending,
    bytes: &mut usize,
    value: u64,
    n: u32,
) -> Result<(), usize> {
    let Some(word) = pending.push(value, n) else {
        return Ok(());
    };
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
    Ok(())
}

// ---- Stream words: stream bits in a register, the first highest.

/// The first 8 bytes of `bytes` (fewer where it is shorter, zeros after them) as a stream
/// word: the first byte highest.
#[inline(always)]
pub(crate) fn load_word(bytes: &[u8]) -> u64 {
    if let Some(eight) = bytes.first_chunk::<8>() {
        return u64::from_be_bytes(*eight);
    }
    let len = bytes.len();
    if let (Some(head), Some(tail)) = (bytes.first_chunk::<4>(), bytes.last_chunk::<4>()) {
        // 4 to 7 bytes: two loads, which overlap; the bytes they share are equal, so the
        // or is exact.
        let high = u64::from(u32::from_be_bytes(*head)) << 32;
        return high | u64::from(u32::from_be_bytes(*tail)) << (8 * (8 - len));
    }
    // Fewer than 4: 2 and 1 at a time, as the length's bits say.
    let (mut word, mut at) = (0u64, 0);
    if let Some(two) = bytes.first_chunk::<2>() {
        word = u64::from(u16::from_be_bytes(*two)) << 48;
        at = 2;
    }
    if let Some(&one) = bytes.get(at) {
        word |= u64::from(one) << (56 - 8 * at);
    }
    word
}

/// Stores the low `bits` (`1..=64`) bits of `acc` at the start of `out` as stream bits,
/// zeros after them, filling `out` up to its 8th byte (which the bits need, or which the
/// caller writes next): one to four stores, without a count of bytes.
#[inline(always)]
pub(crate) fn store_word(out: &mut [u8], acc: u64, bits: u32) {
    let bytes = acc.wrapping_shl(64 - bits).to_be_bytes();
    let n = out.len();
    if let Some(word) = out.first_chunk_mut::<8>() {
        *word = bytes;
    } else if n >= 4 {
        // 4 to 7 bytes: the first four and the last four (overlapping).
        out[..4].copy_from_slice(&bytes[..4]);
        out[n - 4..].copy_from_slice(&bytes[n - 4..n]);
    } else if n >= 2 {
        out[..2].copy_from_slice(&bytes[..2]);
        if let Some(third) = out.get_mut(2) {
            *third = bytes[2];
        }
    } else if let Some(first) = out.first_mut() {
        *first = bytes[0];
    }
}

/// Bits `skip..skip + n` (`n` in `1..=64`, `skip + n <= 64`) of a stream word.
#[inline(always)]
pub(crate) const fn bits_at(word: u64, skip: u32, n: u32) -> u64 {
    (word << skip) >> (64 - n)
}

/// A stream word's bytes after its first `n` (`0..=7`), zeros after them.
#[inline(always)]
pub(crate) const fn after_bytes(word: u64, n: u32) -> u64 {
    word << (8 * n)
}

/// A stream word's first `n` (`1..=8`) bytes, zeros after them.
#[inline(always)]
pub(crate) const fn first_bytes(word: u64, n: u32) -> u64 {
    (word >> (64 - 8 * n)) << (64 - 8 * n)
}

/// The stream value `first` followed by the `n` bits (`0..=64`) of the stream value `next`
/// (`first` is 0 where `n` is 64; the bits lost above 64 are the caller's to know).
#[inline(always)]
pub(crate) const fn join(first: u64, next: u64, n: u32) -> u64 {
    first.wrapping_shl(n) | next
}

/// A stream value of `bits` bits (`0..=64`) as two of at most 32: its first `bits - 32` (none
/// for up to 32 bits) and the rest, in the order they go out.
#[inline(always)]
pub(crate) const fn halves(stream: u64, bits: u32) -> [(u64, u32); 2] {
    [
        (stream >> 32, bits.saturating_sub(32)),
        (stream & 0xFFFF_FFFF, if bits < 32 { bits } else { 32 }),
    ]
}

/// Clears the bits of `out`'s byte holding bit `end` from that bit on: the padding after a
/// value that ends there.
#[inline(always)]
pub(crate) fn clear_after(out: &mut [u8], end: usize) {
    if end % 8 != 0 {
        if let Some(byte) = out.get_mut(end / 8) {
            *byte &= 0xFF << (8 - end % 8);
        }
    }
}

/// Stream bits read ahead of their use: the next `count` bits, the first highest in `word`.
/// After them the word holds zeros or the stream's own next bits, except after
/// [`Ahead::drop`] of 64 bits.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Ahead {
    word: u64,
    count: u32,
}

impl Ahead {
    /// The first `count` bits of the stream word `word`.
    #[inline(always)]
    pub(crate) const fn new(word: u64, count: u32) -> Self {
        Self { word, count }
    }

    /// How many bits are ahead.
    #[inline(always)]
    pub(crate) const fn count(&self) -> u32 {
        self.count
    }

    /// The next `n` bits (`1..=64`, at most those ahead) as a stream value.
    #[inline(always)]
    pub(crate) fn take(&mut self, n: u32) -> u64 {
        let value = self.word >> (64 - n);
        self.drop(n);
        value
    }

    /// Passes over the next `n` bits (`0..=64`, at most those ahead).
    #[inline(always)]
    pub(crate) fn drop(&mut self, n: u32) {
        // A shift by 64 leaves the word as it was: nothing is ahead then.
        self.word = self.word.wrapping_shl(n);
        self.count = self.count.saturating_sub(n);
    }

    /// All the bits ahead (fewer than 64) as a stream value, leaving none.
    #[inline(always)]
    pub(crate) fn take_all(&mut self) -> u64 {
        let value = (self.word >> 1) >> (63 - self.count);
        self.count = 0;
        value
    }

    /// Appends the first `bytes` bytes of the stream word `word` (those ahead and these fill
    /// at most 64 bits; the word after those ahead holds zeros or these bits).
    #[inline(always)]
    pub(crate) fn append(&mut self, word: u64, bytes: u32) {
        self.word |= word >> self.count;
        self.count += 8 * bytes;
    }

    /// The bits ahead as bytes: whole bytes first when a byte boundary is next.
    #[inline(always)]
    pub(crate) const fn bytes(&self) -> [u8; 8] {
        self.word.to_be_bytes()
    }
}

/// Up to 16 stream bytes in a register, the first highest: what a window over pieces holds.
pub(crate) mod wide {
    /// `word` with the stream word `next` appended after its first `len` bytes (`len <= 16`;
    /// the bytes after them are zero).
    #[inline(always)]
    pub(crate) fn append(word: u128, len: usize, next: u64) -> u128 {
        word | (u128::from(next) << 64) >> (8 * len)
    }

    /// `word` without its first `n` bytes (`n <= 16`; zero when none are left).
    #[inline(always)]
    pub(crate) fn after_bytes(word: u128, n: usize) -> u128 {
        word.checked_shl(8 * n as u32).unwrap_or(0)
    }

    /// Bits `skip..skip + n` of `word` (`n` in `1..=64`, `skip + n <= 128`).
    #[inline(always)]
    pub(crate) fn bits_at(word: u128, skip: u32, n: u32) -> u64 {
        ((word << skip) >> (128 - n)) as u64
    }
}

// ---- Both at once, a byte at a time: what firmware's walk reads and writes with.

/// Writes the low `bits` bits of `raw` at bit `pos` of `out` as a DroneCAN scalar (its bytes
/// least significant first, the top bits last, each most significant bit first), a byte at a
/// time into the two bytes it may span; the caller checks that `out` holds them.
#[inline(never)]
pub(crate) fn put_scalar(out: &mut [u8], mut pos: usize, raw: u64, bits: u32) {
    let (mut value, end) = (raw, pos + bits as usize);
    // A caller's mistake shows in tests, where release builds would write short.
    debug_assert!(end <= out.len() * 8, "put beyond the output: bit {end}");
    while pos < end {
        let n = (end - pos).min(8) as u32;
        let (i, s) = (pos / 8, (pos % 8) as u32);
        let place = 16 - n - s;
        let bits = ((value as u32) & ((1 << n) - 1)) << place;
        let keep = !(((1u32 << n) - 1) << place);
        // (Checked reaches: the caller has checked them, and firmware links no panic here.)
        if let Some(byte) = out.get_mut(i) {
            *byte = (u32::from(*byte) & (keep >> 8)) as u8 | (bits >> 8) as u8;
        }
        if s + n > 8 {
            if let Some(byte) = out.get_mut(i + 1) {
                *byte = (u32::from(*byte) & keep) as u8 | bits as u8;
            }
        }
        value >>= 8;
        pos += n as usize;
    }
}

/// Two bytes as [`read_scalar`] takes them: a stream word, the first highest.
#[inline(always)]
pub(crate) const fn pair_word(bytes: [u8; 2]) -> u16 {
    (bytes[0] as u16) << 8 | bytes[1] as u16
}

/// Reads a DroneCAN scalar from bit `pos` to bit `end` (1 to 64 bits) as [`put_scalar`] writes
/// it, a byte at a time: `pair(i)` gives bytes `i` and `i + 1` as [`pair_word`] makes them
/// (the caller checks that the bits lie in the data). (Gathered as bytes: a 64-bit shift by a
/// variable amount is a call on 32-bit targets.)
#[inline(always)]
pub(crate) fn read_scalar(pair: impl Fn(usize) -> u16, mut pos: usize, end: usize) -> u64 {
    let (mut bytes, mut k) = ([0u8; 8], 0);
    while pos < end {
        let n = (end - pos).min(8) as u32;
        let (i, s) = (pos / 8, (pos % 8) as u32);
        let window = u32::from(pair(i)) << s;
        bytes[k & 7] = ((window >> (16 - n)) & ((1 << n) - 1)) as u8;
        k += 1;
        pos += n as usize;
    }
    u64::from_le_bytes(bytes)
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
    fn stream_order_round_trips() {
        for bits in 1..=64 {
            let v = 0x0123_4567_89AB_CDEFu64 & field_mask(bits);
            assert_eq!(from_stream(to_stream(v, bits), bits), v, "bits={bits}");
        }
        // 0xEDA as 12 bits: low byte DA first, then the top nibble E.
        assert_eq!(to_stream(0xEDA, 12), 0xDAE);
    }

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

    /// The rule as the DroneCAN specification words it, bit by bit, independently of the
    /// code above: a value's bytes least significant first, the last one holding the top
    /// `bits % 8` bits, each byte's bits most significant first. Bit `j` of the stream
    /// lands in byte `(pos + j) / 8` at bit `7 - (pos + j) % 8`.
    fn write_by_the_rule(out: &mut [u8], pos: usize, raw: u64, bits: u32) {
        let (whole, rest) = (bits / 8, bits % 8);
        let value_bits = (0..whole)
            .flat_map(|k| (0..8).rev().map(move |b| 8 * k + b))
            .chain((0..rest).rev().map(|b| 8 * whole + b));
        for (j, bit) in (pos..).zip(value_bits) {
            let one = (raw >> bit) & 1 == 1;
            let mask = 0x80u8 >> (j % 8);
            out[j / 8] = if one {
                out[j / 8] | mask
            } else {
                out[j / 8] & !mask
            };
        }
    }

    fn load_by_the_rule(bytes: &[u8]) -> u64 {
        (0..8).fold(0u64, |w, k| {
            w << 8 | u64::from(bytes.get(k).copied().unwrap_or(0))
        })
    }

    extern crate std;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn scalar() -> impl Strategy<Value = (u32, u64, usize, Vec<u8>)> {
        (
            1u32..=64,
            any::<u64>(),
            0usize..24,
            proptest::collection::vec(any::<u8>(), 12..14),
        )
            .prop_map(|(bits, raw, pos, background)| {
                (bits, raw & field_mask(bits), pos, background)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(3000))]

        /// Every writer and reader of a scalar here agrees with the rule: the byte-at-a-time
        /// pair, the stream value through the windowed access, and the per-step order.
        #[test]
        fn every_scalar_path_follows_the_rule((bits, raw, pos, background) in scalar()) {
            let mut expected = background.clone();
            write_by_the_rule(&mut expected, pos, raw, bits);

            let mut put = background.clone();
            put_scalar(&mut put, pos, raw, bits);
            prop_assert_eq!(&put, &expected);

            let mut windowed = background.clone();
            write_bits(&mut windowed, pos, to_stream(raw, bits), bits);
            prop_assert_eq!(&windowed, &expected);

            let order = Order::of(bits);
            prop_assert_eq!(order.stream(raw, bits), to_stream(raw, bits));
            prop_assert_eq!(order.raw(to_stream(raw, bits), bits), raw);
            prop_assert_eq!(order.append(0b101, raw, bits), join(0b101, to_stream(raw, bits), bits));

            prop_assert_eq!(from_stream(read_bits(&expected, pos, bits), bits), raw);
            let pair = |i: usize| pair_word([expected[i], expected.get(i + 1).copied().unwrap_or(0)]);
            prop_assert_eq!(read_scalar(pair, pos, pos + bits as usize), raw);
        }

        /// The registers: a run of fields written through [`Pending`] (as [`BitWriter`]) and
        /// read back through [`Ahead`] (as the straight plan gathers bytes) give the rule's
        /// bytes and values.
        #[test]
        fn registers_follow_the_rule(fields in proptest::collection::vec((1u32..=64, any::<u64>()), 1..12)) {
            let total: usize = fields.iter().map(|&(n, _)| n as usize).sum();
            let mut expected = std::vec![0u8; total.div_ceil(8)];
            let mut out = std::vec![0xA5u8; total.div_ceil(8)];
            let mut writer = BitWriter::new(&mut out);
            let mut pos = 0;
            for &(n, v) in &fields {
                let raw = v & field_mask(n);
                write_by_the_rule(&mut expected, pos, raw, n);
                writer.write(to_stream(raw, n), n).unwrap();
                pos += n as usize;
            }
            prop_assert_eq!(writer.finish(), Ok(expected.len()));
            prop_assert_eq!(&out, &expected);

            let (mut ahead, mut next, mut pos) = (Ahead::default(), 0usize, 0usize);
            for &(n, v) in &fields {
                let raw = v & field_mask(n);
                // Fields of over 32 bits in two takes, as the straight plan reads them.
                let mut value = 0;
                for (_, k) in halves(0, n) {
                    if k == 0 {
                        continue;
                    }
                    if k > ahead.count() {
                        let rest = &expected[next..];
                        let whole = ((64 - ahead.count()) / 8).min(rest.len() as u32);
                        ahead.append(load_word(rest), whole);
                        next += whole as usize;
                    }
                    value = join(value, ahead.take(k), k);
                }
                prop_assert_eq!(from_stream(value, n), raw);
                prop_assert_eq!(value, read_bits(&expected, pos, n));
                pos += n as usize;
            }
        }
    }

    #[test]
    fn stream_words_by_the_rule() {
        let bytes: [u8; 10] = core::array::from_fn(|i| 0x11 * (i as u8 + 1));
        for len in 0..=10 {
            assert_eq!(
                load_word(&bytes[..len]),
                load_by_the_rule(&bytes[..len]),
                "len={len}"
            );
        }
        for bits in 1..=64 {
            for len in 1..=8 {
                let mut out = [0xFFu8; 8];
                store_word(
                    &mut out[..len],
                    0x0123_4567_89AB_CDEF & field_mask(bits),
                    bits,
                );
                let mut expected = [0xFFu8; 8];
                expected[..len].fill(0);
                let stream = 0x0123_4567_89AB_CDEF & field_mask(bits);
                for (j, b) in (0..bits).rev().enumerate() {
                    if j / 8 < len && (stream >> b) & 1 == 1 {
                        expected[j / 8] |= 0x80 >> (j % 8);
                    }
                }
                assert_eq!(out, expected, "bits={bits} len={len}");
            }
        }
        let word = 0x0102_0304_0506_0708u64;
        assert_eq!(first_bytes(word, 7), 0x0102_0304_0506_0700);
        assert_eq!(after_bytes(word, 2), 0x0304_0506_0708_0000);
        assert_eq!(bits_at(word, 12, 8), 0x20);
        assert_eq!(wide::bits_at(u128::from(word) << 64, 12, 8), 0x20);
        assert_eq!(
            wide::append(0xAB << 120, 1, word) >> 64,
            0xAB01_0203_0405_0607
        );
        assert_eq!(wide::after_bytes(u128::MAX, 16), 0);
        assert_eq!(halves(0x1_2345_6789, 33), [(1, 1), (0x2345_6789, 32)]);
        assert_eq!(halves(0x5A, 7), [(0, 0), (0x5A, 7)]);
        assert_eq!(join(0b1, 0b01, 2), 0b101);
        assert_eq!(pair_word([0x12, 0x34]), 0x1234);
        let mut out = [0xFFu8; 2];
        clear_after(&mut out, 11);
        assert_eq!(out, [0xFF, 0b1110_0000]);
        clear_after(&mut out, 16);
        assert_eq!(out, [0xFF, 0b1110_0000]);
    }
}
