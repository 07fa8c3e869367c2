//! The bit writer against DroneCAN's bit order (each byte filled most-significant bit first),
//! with the bytes and positions worked out by hand.

use px4params_core::bits::{zero_bits, BitWriter};

#[test]
fn bit_writer_position_counts_every_bit_written() {
    let mut out = [0u8; 16];
    let mut w = BitWriter::new(&mut out);
    assert_eq!(w.bit_pos(), 0);
    // A run of fields of 3, 12, 1, 33 and 7 bits: the position is the sum of their widths,
    // whether the bits wait in the writer or are already stored as bytes.
    let mut expected = 0;
    for (value, n) in [(0b101, 3), (0xABC, 12), (1, 1), (1 << 32, 33), (0x55, 7)] {
        w.write(value, n).unwrap();
        expected += n as usize;
        assert_eq!(w.bit_pos(), expected, "after a field of {n} bits");
    }
    assert_eq!(w.finish(), Ok(7)); // 56 bits
}

#[test]
fn bit_writer_fills_bytes_most_significant_bit_first() {
    // 1 (1 bit), 0b011 (3 bits), 0xF (4 bits), then 0x5 as 4 bits padded with zeros:
    // 1011 1111 | 0101 0000.
    let mut out = [0u8; 2];
    let mut w = BitWriter::new(&mut out);
    for (value, n) in [(1, 1), (0b011, 3), (0xF, 4), (0x5, 4)] {
        w.write(value, n).unwrap();
    }
    assert_eq!(w.bit_pos(), 12);
    assert_eq!(w.finish(), Ok(2));
    assert_eq!(out, [0b1011_1111, 0b0101_0000]);
}

#[test]
fn zero_bits_clears_exactly_the_bits_asked_for() {
    // 70 bits from bit 5 on (bits 5..75): of 10 bytes of ones, the first 5 and last 5 bits stay.
    let mut out = [0xFFu8; 10];
    zero_bits(&mut out, 5, 70);
    assert_eq!(out, [0b1111_1000, 0, 0, 0, 0, 0, 0, 0, 0, 0b0001_1111]);
}

#[test]
fn a_refused_aligned_slice_loses_no_bit() {
    // 16 bits into 1 byte of room: the first byte is stored and the second has nowhere to go.
    // The writer still holds all 16 bits, so finishing asks for 2 bytes rather than
    // reporting 1 byte as a whole message.
    let mut out = [0u8; 1];
    let mut w = BitWriter::new(&mut out);
    w.write(0xABCD, 16).unwrap();
    assert!(w.aligned_bytes(0).is_none());
    assert_eq!(w.bit_pos(), 16);
    assert_eq!(w.finish(), Err(2));
}
