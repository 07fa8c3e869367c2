//! Store files built byte by byte from docs/store-format.md, with CRCs computed bit by bit here
//! (checked against the CRC catalogue's check values), for the tests of the core's file format
//! and of the C ABI (crates/px4params-ffi/tests/c_abi.rs includes this file).
#![allow(dead_code)]

/// CRC-16-CCITT-FALSE: polynomial 0x1021, initial value `crc`, no reflection, no final xor.
pub fn crc16_from(mut crc: u16, data: &[u8]) -> u16 {
    for &b in data {
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

/// CRC-16-CCITT-FALSE from its initial value 0xFFFF.
pub fn crc16(data: &[u8]) -> u16 {
    crc16_from(0xFFFF, data)
}

/// CRC-32 as zlib computes it (IEEE 802.3, reflected, polynomial 0xEDB88320).
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// The check values of the catalogue of parametrised CRC algorithms (CRC-16/IBM-3740, also
/// called CRC-16-CCITT-FALSE, and CRC-32/ISO-HDLC): what "123456789" hashes to.
pub fn assert_catalogue_check_values() {
    assert_eq!(crc16(b"123456789"), 0x29B1);
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
}

/// `chunk` followed by its CRC-16, little-endian.
pub fn with_crc16(chunk: &[u8]) -> Vec<u8> {
    let mut out = chunk.to_vec();
    out.extend(crc16(chunk).to_le_bytes());
    out
}

/// A store file of format `version`: header (magic, version, flags 0, the fingerprint: the
/// CRC-32 of the table's lines joined with `\n`), the table (format 2 only), each record
/// followed by its CRC-16, the CRC-32 trailer. Tables and records here are under 128 entries
/// and bytes, so every varint is one byte.
pub fn store_file(version: u8, table: &[&str], records: &[&[u8]]) -> Vec<u8> {
    let mut file = b"PX4P".to_vec();
    file.extend([version, 0]);
    file.extend(crc32(table.join("\n").as_bytes()).to_le_bytes());
    if version >= 2 {
        file.extend(with_crc16(&table_record(table)));
    }
    for record in records {
        file.extend(with_crc16(record));
    }
    file.extend(crc32(&file).to_le_bytes());
    file
}

/// The parameter table without its CRC: kind 3, the count, each line's length and bytes.
pub fn table_record(table: &[&str]) -> Vec<u8> {
    let mut t = vec![3, table.len() as u8];
    for line in table {
        t.push(line.len() as u8);
        t.extend(line.as_bytes());
    }
    t
}

/// A classic record holding a value (kind 2, flag 0x20), without its CRC: an int32 (format
/// 3), or of the reader's type (format 2).
pub fn classic_record(name: &str, value: i32) -> Vec<u8> {
    let mut r = vec![0x22, name.len() as u8];
    r.extend(name.as_bytes());
    r.extend(value.to_le_bytes());
    r
}

/// A format 3 classic record holding a float32 value (kind 2, flags 0x20 and 0x40), without
/// its CRC.
pub fn float_record(name: &str, value: f32) -> Vec<u8> {
    let mut r = vec![0x62, name.len() as u8];
    r.extend(name.as_bytes());
    r.extend(value.to_le_bytes());
    r
}

/// A structured record (kind 1) holding `default` (flag 0x10) and `value` (flag 0x20) when
/// given, without its CRC.
pub fn structured_record(
    index: u8,
    instance: u8,
    default: Option<&[u8]>,
    value: Option<&[u8]>,
) -> Vec<u8> {
    let flags = if default.is_some() { 0x10 } else { 0 } | if value.is_some() { 0x20 } else { 0 };
    let mut r = vec![0x01 | flags, index, instance];
    for payload in [default, value].into_iter().flatten() {
        r.push(payload.len() as u8);
        r.extend(payload);
    }
    r
}
