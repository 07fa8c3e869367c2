//! Descattering (`px4params_core::scatter`) against its documented behaviour: a value whose
//! bytes lie in pieces (a transfer's frames, storage pages) reads exactly as the same bytes
//! joined, whatever the pieces' sizes and whatever order the reads come in; DroneCAN frames
//! give their payload without the tail byte, and the first of several frames without the two
//! transfer-CRC bytes. The bits are compared with a reader written here from DroneCAN's bit
//! order (a stream of bytes, each read from its most significant bit), not with the core's
//! (issue 40).

use px4params_core::bits::{BitRead, BitReader};
use px4params_core::scatter::{Chunk, FramePayloads, Pieces, Place, Scattered};

/// `n` bits at bit `offset` of `bytes`, most significant first, one bit at a time.
fn bits(bytes: &[u8], offset: usize, n: u32) -> u64 {
    (offset..offset + n as usize).fold(0, |v, i| {
        (v << 1) | u64::from(bytes[i / 8] >> (7 - i % 8) & 1)
    })
}

/// Bytes no wrong shift reproduces by chance.
fn stream(n: usize) -> Vec<u8> {
    (0..n)
        .map(|i| (i as u32 * 167 + 89) as u8 ^ (i >> 2) as u8)
        .collect()
}

/// `bytes` cut at `cuts` (ascending byte offsets; repeats make empty pieces).
fn pieces<'a>(bytes: &'a [u8], cuts: &[usize]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut from = 0;
    for &c in cuts {
        out.push(&bytes[from..c]);
        from = c;
    }
    out.push(&bytes[from..]);
    out
}

/// A small deterministic sequence (xorshift), for access orders no test writer picked.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n as u64) as usize
    }
}

/// Ways to cut 40 bytes: single bytes, empty pieces, pieces longer than a word, one piece.
fn splits() -> Vec<Vec<usize>> {
    vec![
        vec![],
        (1..40).collect(),
        vec![0, 0, 7, 7, 14, 30, 40, 40],
        vec![3, 11, 12, 13, 21, 29, 37],
        vec![8, 16, 24, 32],
        vec![9, 18, 27, 36],
        vec![2, 20, 38, 39],
    ]
}

#[test]
fn reads_at_any_offset_and_width_give_the_joined_bytes() {
    let flat = stream(40);
    for cuts in splits() {
        let p = pieces(&flat, &cuts);
        let s = Scattered::new(&p[..]);
        assert_eq!((s.len(), s.bit_len(), s.is_empty()), (40, 320, false));
        for n in 1..=64u32 {
            for offset in 0..=320 - n as usize {
                assert_eq!(
                    s.read_bits(offset, n),
                    bits(&flat, offset, n),
                    "{cuts:?}: {offset}+{n}"
                );
            }
            for offset in (0..=320 - n as usize).rev() {
                assert_eq!(
                    s.read_bits(offset, n),
                    bits(&flat, offset, n),
                    "{cuts:?}: {offset}+{n}"
                );
            }
        }
        for (i, &b) in flat.iter().enumerate().chain(flat.iter().enumerate().rev()) {
            assert_eq!(s.byte(i), b, "{cuts:?}: byte {i}");
        }
    }
}

#[test]
fn reads_in_any_order_give_the_joined_bytes() {
    let flat = stream(40);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for cuts in splits() {
        let p = pieces(&flat, &cuts);
        let s = Scattered::new(&p[..]);
        for _ in 0..3000 {
            let n = 1 + rng.below(64) as u32;
            let offset = rng.below(321 - n as usize);
            assert_eq!(
                s.read_bits(offset, n),
                bits(&flat, offset, n),
                "{cuts:?}: {offset}+{n}"
            );
            let i = rng.below(40);
            assert_eq!(s.byte(i), flat[i], "{cuts:?}: byte {i}");
            // A reader made between reads starts where it is asked to.
            if rng.below(8) == 0 {
                let at = rng.below(320);
                let m = 1 + rng.below((320 - at).min(64)) as u32;
                assert_eq!(
                    s.reader(at).read(m),
                    bits(&flat, at, m),
                    "{cuts:?}: reader {at}+{m}"
                );
            }
        }
    }
}

#[test]
fn a_reader_reads_fields_one_after_another_as_the_joined_bytes() {
    let flat = stream(40);
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    for cuts in splits() {
        let p = pieces(&flat, &cuts);
        let s = Scattered::new(&p[..]);
        for start in 0..320 {
            // Widths from 1 to 64 bits, including whole words, to the end of the stream.
            let mut r = s.reader(start);
            let mut at = start;
            assert_eq!(r.position(), at);
            while at < 320 {
                let n = match rng.below(4) {
                    0 => 64,
                    1 => 8,
                    _ => 1 + rng.below(64),
                }
                .min(320 - at) as u32;
                assert_eq!(
                    r.read(n),
                    bits(&flat, at, n),
                    "{cuts:?}: from {start}, {at}+{n}"
                );
                at += n as usize;
                assert_eq!(r.position(), at);
            }
        }
    }
}

#[test]
fn byte_strings_and_skips_leave_the_reader_where_the_bytes_end() {
    let flat = stream(40);
    for cuts in splits() {
        let p = pieces(&flat, &cuts);
        let s = Scattered::new(&p[..]);
        for start in 0..40 {
            for len in 0..=40 - start {
                // Some bits held first (a field read before the string), or none.
                for before in [0usize, 8, 16, 24, 56] {
                    if start * 8 < before {
                        continue;
                    }
                    let mut r = s.reader(start * 8 - before);
                    if before > 0 {
                        r.read(before as u32);
                    }
                    let mut out = vec![0xEEu8; len];
                    r.read_bytes(&mut out);
                    assert_eq!(
                        out,
                        flat[start..start + len],
                        "{cuts:?}: {start}+{len} after {before}"
                    );
                    let end = (start + len) * 8;
                    assert_eq!(r.position(), end);
                    if end < 320 {
                        let n = (320 - end).min(13) as u32;
                        assert_eq!(
                            r.read(n),
                            bits(&flat, end, n),
                            "{cuts:?}: after {start}+{len}"
                        );
                    }
                }
            }
        }
        for start in 0..320 {
            for n in [0, 1, 7, 63, 64, 65, 128, 129, 200] {
                if start + n >= 320 {
                    continue;
                }
                let mut r = s.reader(start);
                r.skip(n);
                assert_eq!(r.position(), start + n);
                let m = (320 - start - n).min(17) as u32;
                assert_eq!(
                    r.read(m),
                    bits(&flat, start + n, m),
                    "{cuts:?}: {start} skip {n}"
                );
            }
        }
    }
}

#[test]
fn a_copied_reader_goes_on_by_itself() {
    let flat = stream(40);
    let p = pieces(&flat, &[3, 9, 10, 25]);
    let s = Scattered::new(&p[..]);
    let mut r = s.reader(5);
    r.read(20);
    let mut copy = r;
    assert_eq!(copy.read(30), bits(&flat, 25, 30));
    assert_eq!(r.position(), 25);
    assert_eq!(r.read(30), bits(&flat, 25, 30));
    #[allow(clippy::clone_on_copy)] // Clone is part of the reader's API: it must agree
    let mut cloned = r.clone();
    assert_eq!(cloned.read(64), bits(&flat, 55, 64));
    assert_eq!(r.read(64), bits(&flat, 55, 64));
}

#[test]
fn no_pieces_or_only_empty_ones_are_an_empty_stream() {
    let none: [&[u8]; 0] = [];
    let s = Scattered::new(&none[..]);
    assert_eq!((s.len(), s.bit_len(), s.is_empty()), (0, 0, true));
    let empties: [&[u8]; 3] = [&[], &[], &[]];
    let s = Scattered::new(&empties[..]);
    assert_eq!((s.len(), s.is_empty()), (0, true));
    assert_eq!(empties[..].total_len(), 0);
    let one: [&[u8]; 2] = [&[], &[0xA5]];
    let s = Scattered::new(&one[..]);
    assert_eq!((s.len(), s.is_empty()), (1, false));
    assert_eq!(s.read_bits(0, 8), 0xA5);
}

#[test]
fn a_chunk_is_up_to_eight_bytes_left_aligned() {
    let bytes = stream(12);
    for len in 0..=12 {
        let c = Chunk::of(&bytes[..len]);
        let n = len.min(8);
        let mut word = [0u8; 8];
        word[..n].copy_from_slice(&bytes[..n]);
        let expected = Chunk {
            word: u64::from_be_bytes(word),
            len: n,
            left: len - n,
        };
        assert_eq!(c, expected, "{len} bytes");
    }
    // Pieces give their chunks from any byte of any piece.
    let p = pieces(&bytes, &[0, 5, 5, 12]);
    for i in 0..p.count() {
        for skip in 0..=p[i].len() {
            assert_eq!(
                p[..].chunk(i, skip),
                Chunk::of(&p[i][skip..]),
                "piece {i} from {skip}"
            );
        }
    }
}

#[test]
fn copy_out_fills_from_any_place_and_says_where_it_ended() {
    let flat = stream(30);
    let p = pieces(&flat, &[0, 1, 4, 4, 12, 13, 21, 29]);
    let starts: Vec<usize> = (0..p.len())
        .map(|i| p[..i].iter().map(|x| x.len()).sum())
        .collect();
    for i in 0..p.len() {
        for skip in 0..=p[i].len() {
            let byte = starts[i] + skip;
            for len in 0..=30 - byte {
                let mut out = vec![0xEEu8; len];
                let end = p[..].copy_out(Place { index: i, skip }, &mut out);
                assert_eq!(out, flat[byte..byte + len], "from {i}/{skip}, {len} bytes");
                let at = starts.get(end.index).copied().unwrap_or(30) + end.skip;
                assert_eq!(
                    at,
                    byte + len,
                    "from {i}/{skip}, {len} bytes: ended at {end:?}"
                );
            }
        }
    }
    // Moving on: within a piece, and past its last byte to the next piece's first.
    let mut place = Place { index: 2, skip: 1 };
    place.step(2, false);
    assert_eq!(place, Place { index: 2, skip: 3 });
    place.step(1, true);
    assert_eq!(place, Place { index: 3, skip: 0 });
}

/// Classic CAN frames as DroneCAN sends them: the first of several starts with the transfer
/// CRC, each ends with its tail byte.
fn frames_of(payload: &[u8], room: usize) -> Vec<Vec<u8>> {
    let multi = payload.len() > room;
    let mut bytes = if multi { vec![0xC1, 0xC2] } else { vec![] };
    bytes.extend_from_slice(payload);
    let chunks: Vec<&[u8]> = if bytes.is_empty() {
        vec![&[]]
    } else {
        bytes.chunks(room).collect()
    };
    let last = chunks.len() - 1;
    chunks
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let tail = 3
                | if i == 0 { 0x80 } else { 0 }
                | if i == last { 0x40 } else { 0 }
                | if i % 2 == 1 { 0x20 } else { 0 };
            [c, &[tail][..]].concat()
        })
        .collect()
}

#[test]
fn frame_payloads_are_the_payload_without_tail_bytes_and_crc() {
    for room in [7, 63, 3] {
        for len in 0..=90 {
            let payload = stream(len);
            let frames = frames_of(&payload, room);
            let refs: Vec<&[u8]> = frames.iter().map(Vec::as_slice).collect();
            let p = FramePayloads::new(&refs);
            assert_eq!(p.count(), frames.len());
            let joined: Vec<u8> = (0..p.count()).flat_map(|i| p.piece(i).to_vec()).collect();
            assert_eq!(joined, payload, "{len} bytes in frames of {room}");
            assert_eq!(p.total_len(), len);
            let s = Scattered::new(&p);
            assert_eq!(s.len(), len);
            for i in 0..p.count() {
                for skip in 0..=p.piece(i).len() {
                    assert_eq!(
                        p.chunk(i, skip),
                        Chunk::of(&p.piece(i)[skip..]),
                        "{len}/{room}: frame {i} from {skip}"
                    );
                }
            }
            for offset in 0..len * 8 {
                let n = (len * 8 - offset).min(64) as u32;
                assert_eq!(
                    s.read_bits(offset, n),
                    bits(&payload, offset, n),
                    "{len}/{room}: {offset}+{n}"
                );
            }
            for start in 0..=len {
                let mut r = s.reader(start * 8);
                let mut out = vec![0u8; len - start];
                r.read_bytes(&mut out);
                assert_eq!(out, payload[start..], "{len}/{room}: bytes from {start}");
            }
        }
    }
}

#[test]
fn malformed_frames_give_what_is_there() {
    // A first frame of several too short for the CRC, an empty frame (not even a tail byte):
    // the receiver refuses such transfers, but the pieces never read out of bounds.
    let frames: [&[u8]; 4] = [&[0xC1, 0x80], &[], &[1, 2, 0x20], &[3, 0x40]];
    let p = FramePayloads::new(&frames);
    assert_eq!(p.piece(0), &[] as &[u8]);
    assert_eq!(p.piece(1), &[] as &[u8]);
    assert_eq!(p.piece(2), &[1, 2]);
    assert_eq!(p.piece(3), &[3]);
    assert_eq!(p.total_len(), 3);
    let s = Scattered::new(&p);
    assert_eq!(s.read_bits(0, 24), 0x01_02_03);
    let first_only: [&[u8]; 2] = [&[0xC1, 0xC2, 9, 0x80], &[0x60]];
    let p = FramePayloads::new(&first_only);
    assert_eq!(
        (p.piece(0), p.piece(1), p.total_len()),
        (&[9u8][..], &[] as &[u8], 1)
    );
}

#[test]
fn copy_out_past_the_end_fills_what_there_is_and_returns_the_end() {
    // "Where the pieces end first, the rest of `out` is unspecified": the bytes there are come
    // first, and the place returned is past the last piece.
    let bytes = [1u8, 2, 3, 4, 5];
    let p: [&[u8]; 2] = [&bytes[..3], &bytes[3..]];
    let mut out = [0u8; 8];
    let end = p[..].copy_out(Place { index: 0, skip: 1 }, &mut out);
    assert_eq!(out[..4], [2, 3, 4, 5]);
    assert_eq!(end, Place { index: 2, skip: 0 });
    let frames: [&[u8]; 3] = [
        &[0xC1, 0xC2, 1, 2, 3, 4, 5, 0x80],
        &[6, 7, 8, 9, 10, 11, 12, 0x20],
        &[13, 0x40],
    ];
    let p = FramePayloads::new(&frames);
    let mut out = [0u8; 20];
    let end = p.copy_out(Place { index: 0, skip: 3 }, &mut out);
    assert_eq!(out[..10], [4, 5, 6, 7, 8, 9, 10, 11, 12, 13]);
    assert_eq!(end, Place { index: 3, skip: 0 });
}

#[test]
fn every_read_after_every_other_gives_the_joined_bytes() {
    // A longer stream: a read can follow another from anywhere, near it or far ahead or behind.
    let flat = stream(100);
    let cuts: [&[usize]; 3] = [
        &[7, 14, 21, 28, 35, 42, 49, 56, 63, 70, 77, 84, 91],
        &[1, 50, 51, 99],
        &[],
    ];
    for cuts in cuts {
        let p = pieces(&flat, cuts);
        let s = Scattered::new(&p[..]);
        for a in 0..100 {
            for b in 0..100 {
                let (n, m) = (1 + (a * 7 + b) % 64, 1 + (a + b * 5) % 64);
                let (n, m) = (n.min(800 - a * 8) as u32, m.min(800 - b * 8 - 3) as u32);
                assert_eq!(
                    s.read_bits(a * 8, n),
                    bits(&flat, a * 8, n),
                    "{cuts:?}: {a}"
                );
                let at = b * 8 + 3;
                assert_eq!(
                    s.read_bits(at, m),
                    bits(&flat, at, m),
                    "{cuts:?}: {a} then {b}"
                );
            }
        }
    }
}
