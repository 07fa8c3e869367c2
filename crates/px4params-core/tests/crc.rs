//! DroneCAN's checksums (`px4params_core::crc`) against the rules, computed bit by bit here:
//! CRC-16-CCITT-FALSE (the transfer CRC, seeded with the data type signature's 8 bytes,
//! little-endian), CRC-64-WE (the DSDL signature, extended with each nested type's
//! signature and the value so far, as pydronecan's `get_data_type_signature` does), and
//! zlib's CRC-32 (the store file's trailer).

#[path = "support/store_file.rs"]
mod store_file;

use px4params_core::crc::{
    crc16, crc16_pieces, crc32, data_type_signature, dsdl_signature, transfer_crc_seed, Signature,
};
use store_file::crc16_from;

/// CRC-64-WE: polynomial 0x42F0E1EBA9EA3693, initial value and final xor all ones.
fn crc64_we_from(mut crc: u64, data: &[u8]) -> u64 {
    crc ^= u64::MAX;
    for &b in data {
        crc ^= u64::from(b) << 56;
        for _ in 0..8 {
            crc = if crc & (1 << 63) != 0 {
                (crc << 1) ^ 0x42F0_E1EB_A9EA_3693
            } else {
                crc << 1
            };
        }
    }
    crc ^ u64::MAX
}

/// Bytes that are not a pattern a wrong table could match by chance.
fn bytes(n: usize) -> Vec<u8> {
    (0..n as u32)
        .map(|i| ((i * 151 + 7) ^ (i >> 3)) as u8)
        .collect()
}

#[test]
fn the_check_values_of_the_catalogue() {
    store_file::assert_catalogue_check_values();
    assert_eq!(crc64_we_from(0, b"123456789"), 0x62EC_59E3_F1A4_F00A);
    assert_eq!(dsdl_signature(b"123456789"), 0x62EC_59E3_F1A4_F00A);
    assert_eq!(crc16(0xFFFF, b"123456789"), 0x29B1);
    assert_eq!(crc32(0, b"123456789"), 0xCBF4_3926);
}

#[test]
fn a_transfer_crc_starts_from_the_signature_bytes() {
    // uavcan.protocol.NodeStatus and GetNodeInfo's data type signatures (libcanard's
    // examples, pydronecan).
    for signature in [0x0F08_68D0_C1A7_C6F1u64, 0xEE46_8A81_21C4_6A9E, 0, u64::MAX] {
        let seed = crc16_from(0xFFFF, &signature.to_le_bytes());
        assert_eq!(transfer_crc_seed(signature), seed, "{signature:#x}");
        let payload = bytes(40);
        assert_eq!(crc16(seed, &payload), crc16_from(seed, &payload));
    }
    // The two byte orders differ: the seed is over the little-endian bytes.
    let s = 0x0F08_68D0_C1A7_C6F1u64;
    assert_ne!(transfer_crc_seed(s), crc16_from(0xFFFF, &s.to_be_bytes()));
}

#[test]
fn crc16_continues_from_any_value_over_any_length() {
    let data = bytes(70);
    for start in [0u16, 0xFFFF, 0x29B1, 0x8001] {
        for len in 0..data.len() {
            let expected = crc16_from(start, &data[..len]);
            assert_eq!(crc16(start, &data[..len]), expected, "{start:#x} {len}");
            // And over pieces as CAN frames cut it: 7 bytes, and uneven cuts.
            let frames = data[..len].chunks(7);
            assert_eq!(crc16_pieces(start, frames), expected, "{start:#x} {len}");
            let (a, rest) = data[..len].split_at(len / 3);
            let (b, c) = rest.split_at(rest.len() / 2);
            let pieces: [&[u8]; 5] = [a, &[], b, c, &[]];
            assert_eq!(crc16_pieces(start, pieces), expected, "{start:#x} {len}");
        }
    }
    assert_eq!(crc16_pieces(0xFFFF, std::iter::empty()), 0xFFFF);
}

#[test]
fn crc32_continues_across_calls() {
    let data = bytes(33);
    let whole = crc32(0, &data);
    for cut in 0..data.len() {
        assert_eq!(crc32(crc32(0, &data[..cut]), &data[cut..]), whole);
    }
    assert_eq!(crc32(0, b""), 0);
    assert_eq!(crc32(0, b"a"), 0xE8B7_BE43);
    assert_eq!(crc32(0xFFFF_FFFF, b""), 0xFFFF_FFFF);
}

#[test]
fn a_data_type_signature_extends_the_dsdl_signature_with_each_nested_one() {
    let dsdl = crc64_we_from(0, b"uint8 a\nuavcan.protocol.NodeStatus status");
    assert_eq!(
        dsdl_signature(b"uint8 a\nuavcan.protocol.NodeStatus status"),
        dsdl
    );
    assert_eq!(data_type_signature(dsdl, &[]), dsdl);
    let nested = [0x0F08_68D0_C1A7_C6F1u64, 0xEE46_8A81_21C4_6A9E];
    let mut expected = dsdl;
    for field in nested {
        let so_far = expected;
        expected = crc64_we_from(expected, &field.to_le_bytes());
        expected = crc64_we_from(expected, &so_far.to_le_bytes());
    }
    assert_eq!(data_type_signature(dsdl, &nested), expected);
    assert_ne!(data_type_signature(dsdl, &nested[..1]), expected);
    // The running hash: fed in pieces, or continued from a value.
    let mut s = Signature::default();
    s.add(b"uint8 a\n");
    s.add(b"uavcan.protocol.NodeStatus status");
    assert_eq!(s.value(), dsdl);
    let mut s = Signature::extend_from(dsdl);
    s.add(&nested[0].to_le_bytes());
    assert_eq!(s.value(), crc64_we_from(dsdl, &nested[0].to_le_bytes()));
    assert_eq!(Signature::default().value(), 0);
    assert_eq!(Signature::extend_from(0x1234).value(), 0x1234);
}
