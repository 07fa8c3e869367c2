//! DroneCAN checksums: CRC-64-WE data type signatures and the CRC-16-CCITT-FALSE transfer CRC.

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
pub fn crc16(mut crc: u16, bytes: &[u8]) -> u16 {
    for &b in bytes {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// The seed of a multi-frame transfer's CRC: CRC-16-CCITT-FALSE over the data type
/// signature's 8 little-endian bytes.
pub fn transfer_crc_seed(signature: u64) -> u16 {
    crc16(0xFFFF, &signature.to_le_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_values() {
        // The standard check string of both CRCs.
        assert_eq!(dsdl_signature(b"123456789"), 0x62EC_59E3_F1A4_F00A);
        assert_eq!(crc16(0xFFFF, b"123456789"), 0x29B1);
        let mut s = Signature::default();
        s.add(b"123");
        s.add(b"456789");
        assert_eq!(s.value(), 0x62EC_59E3_F1A4_F00A);
        assert_eq!(data_type_signature(0x1234, &[]), 0x1234);
    }
}
