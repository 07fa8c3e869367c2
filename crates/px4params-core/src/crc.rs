//! DroneCAN checksums: CRC-64-WE data type signatures and the CRC-16-CCITT-FALSE transfer CRC;
//! and the store file's CRC-32.

use crate::plan::{Active, Plans};

/// A running CRC-64-WE (poly `0x42F0E1EBA9EA3693`, init and final xor all ones), the DSDL
/// signature hash.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Signature(u64);

const POLY64: u64 = 0x42F0_E1EB_A9EA_3693;

impl Default for Signature {
    fn default() -> Self {
        Self(u64::MAX)
    }
}

impl Signature {
    /// A hash that continues from a previous signature `value`.
    pub const fn extend_from(value: u64) -> Self {
        Self(value ^ u64::MAX)
    }

    /// Feeds bytes.
    pub fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b) << 56;
            for _ in 0..8 {
                self.0 = if self.0 & (1 << 63) != 0 {
                    (self.0 << 1) ^ POLY64
                } else {
                    self.0 << 1
                };
            }
        }
    }

    /// The signature so far.
    pub const fn value(&self) -> u64 {
        self.0 ^ u64::MAX
    }
}

/// The DSDL signature of a normalized definition text.
pub fn dsdl_signature(normalized: &[u8]) -> u64 {
    let mut s = Signature::default();
    s.add(normalized);
    s.value()
}

/// The data type signature: the DSDL signature extended, for each nested composite field in
/// order, with that field's data type signature and then the value so far (both 8 bytes,
/// little-endian).
pub fn data_type_signature(dsdl_signature: u64, nested: &[u64]) -> u64 {
    let mut s = Signature::extend_from(dsdl_signature);
    for &field in nested {
        let so_far = s.value();
        s.add(&field.to_le_bytes());
        s.add(&so_far.to_le_bytes());
    }
    s.value()
}

/// CRC-16-CCITT-FALSE (poly `0x1021`, no reflection, no final xor) continuing from `crc`.
///
/// Eight bytes at a time on hosts ("slicing by 8"): the table lookups of a step do not depend
/// on each other, so they overlap, where byte at a time (or bit by bit) every step waits for
/// the one before. The tables (4 KB) are read-only data computed at compile time. Without
/// plans (firmware, [`crate::plan`]) half a byte at a time from a 32-byte table, as
/// [`crc32`] goes: flash matters more there than a frame's few dozen cycles.
pub fn crc16(mut crc: u16, bytes: &[u8]) -> u16 {
    if SLICES == 0 {
        for &b in bytes {
            crc = crc16_nibble(crc, b >> 4);
            crc = crc16_nibble(crc, b & 15);
        }
        return crc;
    }
    let t: &[[u16; 256]] = &CRC16_TABLES;
    // The first `len % 8` bytes as a step of their own, so that the rest are whole steps.
    let (head, body) = bytes.split_at(bytes.len() % 8);
    if let [first, rest @ ..] = head {
        // The head as the last bytes of a step whose bytes before them are zero (they look
        // up zero); the register is xored onto its first two. Byte loads, not one word: a
        // payload just gathered lies in 8-byte stores that a word would straddle (one made
        // BatteryInfo's `receive` 12% slower).
        let n = head.len();
        crc = match rest {
            [] => (crc << 8) ^ t[0][usize::from((crc >> 8) as u8 ^ first)],
            [second, rest @ ..] => {
                let mut others = 0;
                for (k, &b) in (2..).zip(rest) {
                    others ^= t[n - 1 - k][usize::from(b)];
                }
                t[n - 1][usize::from((crc >> 8) as u8 ^ first)]
                    ^ t[n - 2][usize::from(crc as u8 ^ second)]
                    ^ others
            }
        };
    }
    // A step waits for the one before only through its first two bytes' lookups. The six
    // others are taken a step ahead and carried over: written in one piece, the compiler
    // xors all eight in one chain after the two, and each step waits for that chain.
    let mut chunks = body
        .chunks_exact(8)
        .filter_map(|c| <&[u8; 8]>::try_from(c).ok());
    if let Some(mut x) = chunks.next() {
        let mut six = crc16_last_six(t, x);
        for next in chunks {
            let next_six = crc16_last_six(t, next);
            crc = crc16_first_two(t, crc, x) ^ six;
            (x, six) = (next, next_six);
        }
        crc = crc16_first_two(t, crc, x) ^ six;
    }
    crc
}

/// The lookups of a slicing-by-8 step for the first two of its bytes `x`, onto which the
/// register `crc` is xored.
#[inline(always)]
fn crc16_first_two(t: &[[u16; 256]], crc: u16, x: &[u8; 8]) -> u16 {
    let high = (crc >> 8) as u8 ^ x[0];
    let low = crc as u8 ^ x[1];
    t[7][usize::from(high)] ^ t[6][usize::from(low)]
}

/// The lookups of a slicing-by-8 step for the last six of its bytes `x`, which do not
/// depend on the register.
#[inline(always)]
fn crc16_last_six(t: &[[u16; 256]], x: &[u8; 8]) -> u16 {
    (t[5][usize::from(x[2])] ^ t[4][usize::from(x[3])])
        ^ (t[3][usize::from(x[4])] ^ t[2][usize::from(x[5])])
        ^ (t[1][usize::from(x[6])] ^ t[0][usize::from(x[7])])
}

/// Four bits of [`crc16`]: `nibble` (below 16) shifted through the register.
#[inline(always)]
fn crc16_nibble(crc: u16, nibble: u8) -> u16 {
    (crc << 4) ^ CRC16_NIBBLES[usize::from(((crc >> 12) as u8 ^ nibble) & 15)]
}

/// [`crc16`] over `pieces` as if they were one run of bytes (a transfer's CAN frames carry 7
/// payload bytes each: a step each).
pub fn crc16_pieces<'a>(mut crc: u16, pieces: impl IntoIterator<Item = &'a [u8]>) -> u16 {
    for piece in pieces {
        crc = crc16(crc, piece);
    }
    crc
}

/// Bytes per step of [`crc16`] (and tables); 0: half a byte per step (firmware).
const SLICES: usize = Active::CRC_SLICES;

/// `CRC16_TABLES[k][n]`: the CRC register after shifting byte `n` and then `k` zero bytes
/// through it from zero.
static CRC16_TABLES: [[u16; 256]; SLICES] = crc16_tables();

/// `CRC16_NIBBLES[n]`: the CRC register after shifting the four bits `n` through it from zero.
static CRC16_NIBBLES: [u16; 16] = {
    let mut table = [0u16; 16];
    let mut n = 0;
    while n < 16 {
        table[n] = crc16_shifted((n as u16) << 12, 4);
        n += 1;
    }
    table
};

/// `crc` with `bits` zero bits shifted through it, bit by bit (the definition).
const fn crc16_shifted(mut crc: u16, bits: u32) -> u16 {
    let mut bit = 0;
    while bit < bits {
        crc = if crc & 0x8000 != 0 {
            (crc << 1) ^ 0x1021
        } else {
            crc << 1
        };
        bit += 1;
    }
    crc
}

const fn crc16_tables() -> [[u16; 256]; SLICES] {
    let mut first = [0u16; 256];
    let mut n = 0;
    while n < 256 {
        first[n] = crc16_shifted((n as u16) << 8, 8);
        n += 1;
    }
    // Table k from table k - 1 (k a variable: with no tables, no index is out of range; the
    // bound is the array's length, not `SLICES`, which clippy finds always 0 in firmware).
    let mut tables = [[0u16; 256]; SLICES];
    let mut k = 0;
    while k < tables.len() {
        let mut n = 0;
        while n < 256 {
            tables[k][n] = if k == 0 {
                first[n]
            } else {
                let prev = tables[k - 1][n];
                (prev << 8) ^ first[(prev >> 8) as usize]
            };
            n += 1;
        }
        k += 1;
    }
    tables
}

/// The seed of a multi-frame transfer's CRC: CRC-16-CCITT-FALSE over the data type
/// signature's 8 little-endian bytes.
pub fn transfer_crc_seed(signature: u64) -> u16 {
    crc16(0xFFFF, &signature.to_le_bytes())
}

/// CRC-32 (IEEE 802.3, zlib's `crc32`: reflected poly `0xEDB88320`, init and final xor all
/// ones) continuing from `crc` (0 to start), as the store file's trailer uses it.
///
/// Four bits at a time from a 64-byte table: a store file is read once at boot, so size
/// matters more here than speed.
pub fn crc32(crc: u32, bytes: &[u8]) -> u32 {
    let mut crc = !crc;
    for &b in bytes {
        crc ^= u32::from(b);
        crc = (crc >> 4) ^ CRC32_NIBBLES[(crc & 15) as usize];
        crc = (crc >> 4) ^ CRC32_NIBBLES[(crc & 15) as usize];
    }
    !crc
}

const CRC32_NIBBLES: [u32; 16] = {
    let mut table = [0u32; 16];
    let mut i = 0;
    while i < 16 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 4 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_values() {
        // The standard check string of both CRCs.
        assert_eq!(dsdl_signature(b"123456789"), 0x62EC_59E3_F1A4_F00A);
        assert_eq!(crc16(0xFFFF, b"123456789"), 0x29B1);
        assert_eq!(crc32(0, b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(crc32(0, b"1234"), b"56789"), 0xCBF4_3926);
        assert_eq!(crc32(0, b""), 0);
        let mut s = Signature::default();
        s.add(b"123");
        s.add(b"456789");
        assert_eq!(s.value(), 0x62EC_59E3_F1A4_F00A);
        assert_eq!(data_type_signature(0x1234, &[]), 0x1234);
    }

    /// The tables against the bit-by-bit definition, for every byte and running value.
    #[test]
    fn tables_match_the_bitwise_definition() {
        fn bitwise(mut crc: u16, byte: u8) -> u16 {
            crc ^= u16::from(byte) << 8;
            for _ in 0..8 {
                crc = if crc & 0x8000 != 0 {
                    (crc << 1) ^ 0x1021
                } else {
                    crc << 1
                };
            }
            crc
        }
        for start in [0u16, 0xFFFF, 0x1234, 0x8000, 0x00FF] {
            for byte in 0..=255u8 {
                assert_eq!(crc16(start, &[byte]), bitwise(start, byte));
            }
        }
        // Every length around the eight-byte steps and the last shorter one.
        let data: std::vec::Vec<u8> = (0..67u32).map(|i| (i * 37 + 11) as u8).collect();
        for len in 0..data.len() {
            let expected = data[..len].iter().fold(0xFFFF, |crc, &b| bitwise(crc, b));
            assert_eq!(crc16(0xFFFF, &data[..len]), expected, "length {len}");
        }
        // Pieces of every size, as frames cut a payload, give the CRC of the whole.
        let whole = crc16(0xBEEF, &data);
        for size in 1..10 {
            assert_eq!(
                crc16_pieces(0xBEEF, data.chunks(size)),
                whole,
                "pieces of {size}"
            );
        }
        let uneven: [&[u8]; 4] = [&data[..1], &data[1..1], &data[1..9], &data[9..]];
        assert_eq!(crc16_pieces(0xBEEF, uneven), whole);
    }
}
