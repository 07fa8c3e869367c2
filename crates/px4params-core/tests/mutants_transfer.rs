//! DroneCAN transfers (`px4params_core::transfer`) against the rules of the DroneCAN (UAVCAN
//! v0) specification, section "Transport layer", built here naively from the rules and
//! checked against frames pydronecan 1.0.27 (`dronecan.transport.Transfer.to_frames`) sent:
//! - every frame ends with its tail byte: start of transfer 0x80 (first frame only), end of
//!   transfer 0x40 (last frame only), toggle 0x20 (clear in the first frame, then alternating)
//!   and the transfer ID modulo 32 in the low five bits;
//! - a payload that does not fit one frame (7 bytes on classic CAN, 63 on CAN FD) is preceded
//!   by the transfer CRC: CRC-16-CCITT-FALSE over the payload, starting from the CRC of the
//!   data type signature's 8 bytes (little-endian), sent low byte first;
//! - on CAN FD a payload over 7 bytes is padded with zeros (covered by the CRC) so that its
//!   last frame has a length CAN FD can send (0..=8, 12, 16, 20, 24, 32, 48, 64).
//!
//! A receiver checks all of it and says which frame broke which rule (issue 40).

#[path = "support/store_file.rs"]
mod store_file;

use px4params_core::crc::transfer_crc_seed;
use px4params_core::scatter::Pieces;
use px4params_core::transfer::{frame_max, frames, receive, receive_into, TransferError};
use store_file::crc16_from;

/// uavcan.protocol.param.GetSet's data type signature (as pydronecan computes it from the DSDL).
const GETSET_SIGNATURE: u64 = 0xA7B6_22F9_39D1_A4D5;
/// Its transfer CRC seed: pydronecan's `base_crc` for the type.
const GETSET_SEED: u16 = 0xFB10;

const START: u8 = 0x80;
const END: u8 = 0x40;
const TOGGLE: u8 = 0x20;

/// The CAN FD data lengths (the DLC's steps).
const FD_LENGTHS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];

fn payload(n: usize) -> Vec<u8> {
    (0..n).map(|i| (i * 29 + 3) as u8).collect()
}

fn unhex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect()
}

/// The frames of a transfer, straight from the rules above.
fn by_the_rules(payload: &[u8], seed: u16, transfer_id: u8, canfd: bool) -> Vec<Vec<u8>> {
    let room = if canfd { 63 } else { 7 };
    let mut padded = payload.to_vec();
    if canfd && payload.len() > 7 {
        // The padding makes the last frame (payload, CRC if any, tail byte) a CAN FD length.
        let mut used = payload.len() + 1;
        if used > 64 {
            used += 2;
        }
        let last = used % 63;
        let sendable = FD_LENGTHS.iter().find(|&&l| l >= last).unwrap();
        padded.resize(payload.len() + sendable - last, 0);
    }
    let mut stream = Vec::new();
    if padded.len() > room {
        stream.extend_from_slice(&crc16_from(seed, &padded).to_le_bytes());
    }
    stream.extend_from_slice(&padded);
    let chunks: Vec<&[u8]> = if stream.is_empty() {
        vec![&[]]
    } else {
        stream.chunks(room).collect()
    };
    let last = chunks.len() - 1;
    chunks
        .iter()
        .enumerate()
        .map(|(i, chunk)| {
            let mut tail = transfer_id % 32;
            if i == 0 {
                tail |= START;
            }
            if i == last {
                tail |= END;
            }
            if i % 2 == 1 {
                tail |= TOGGLE;
            }
            [chunk, &[tail][..]].concat()
        })
        .collect()
}

fn sent(payload: &[u8], seed: u16, transfer_id: u8, canfd: bool) -> Vec<Vec<u8>> {
    frames(payload, seed, transfer_id, canfd)
        .map(|f| f.as_bytes().to_vec())
        .collect()
}

fn refs(frames: &[Vec<u8>]) -> Vec<&[u8]> {
    frames.iter().map(Vec::as_slice).collect()
}

/// The payload `receive` hands over, joined.
fn received(frames: &[&[u8]], seed: u16) -> Result<(u8, Vec<u8>), TransferError> {
    receive(frames, seed).map(|r| {
        let joined = (0..r.payload.count()).flat_map(|i| r.payload.piece(i).to_vec());
        (r.transfer_id, joined.collect())
    })
}

#[test]
fn the_seed_is_the_crc_of_the_signature_bytes() {
    assert_eq!(
        crc16_from(0xFFFF, &GETSET_SIGNATURE.to_le_bytes()),
        GETSET_SEED
    );
    assert_eq!(transfer_crc_seed(GETSET_SIGNATURE), GETSET_SEED);
}

#[test]
fn frames_are_those_pydronecan_sends() {
    // pydronecan 1.0.27, Transfer(transfer_id=..., canfd=...) with payload bytes
    // (i * 29 + 3) mod 256 and GetSet's data_type_crc, to_frames().
    let known: [(usize, u8, bool, &[&str]); 5] = [
        (0, 37, false, &["c5"]),
        (7, 37, false, &["03203d5a7794b1c5"]),
        (
            20,
            37,
            false,
            &[
                "43e803203d5a7785",
                "94b1ceeb08254225",
                "5f7c99b6d3f00d05",
                "2a65",
            ],
        ),
        (8, 3, true, &["03203d5a7794b1ce000000c3"]),
        (
            70,
            30,
            true,
            &[
                "933e03203d5a7794b1ceeb0825425f7c99b6d3f00d2a4764819ebbd8f5122f4c6986a3c0ddfa1734\
                 516e8ba8c5e2ff1c39567390adcae704213e5b7895b2cf9e",
                "ec092643607d9ab7d400007e",
            ],
        ),
    ];
    for (len, transfer_id, canfd, hex) in known {
        let expected: Vec<Vec<u8>> = hex.iter().map(|h| unhex(h)).collect();
        let got = sent(&payload(len), GETSET_SEED, transfer_id, canfd);
        assert_eq!(got, expected, "{len} bytes, CAN FD {canfd}");
        assert_eq!(
            by_the_rules(&payload(len), GETSET_SEED, transfer_id, canfd),
            expected
        );
    }
}

#[test]
fn every_length_is_framed_by_the_rules_and_received_whole() {
    for canfd in [false, true] {
        for len in 0..=300 {
            let data = payload(len);
            let transfer_id = (len * 7) as u8; // every ID, and numbers above 31
            let expected = by_the_rules(&data, GETSET_SEED, transfer_id, canfd);
            let got = sent(&data, GETSET_SEED, transfer_id, canfd);
            assert_eq!(got, expected, "{len} bytes, CAN FD {canfd}");
            let max = frame_max(canfd);
            for frame in &got {
                assert!(
                    frame.len() <= max,
                    "{len} bytes: a frame of {}",
                    frame.len()
                );
                // pydronecan 1.0.27 leaves a 63-byte last frame where the stream fills it
                // exactly (payloads of 62, 123, 186, ... bytes): not a CAN FD length, sent as
                // one of 64. The frames are pydronecan's (above); that case is let through.
                if canfd && frame.len() != 63 {
                    assert!(FD_LENGTHS.contains(&frame.len()), "{len}: {}", frame.len());
                }
            }
            // Received: the payload (and its padding, zeros), the ID modulo 32.
            let (id, whole) = received(&refs(&got), GETSET_SEED).unwrap();
            assert_eq!(id, transfer_id % 32);
            assert_eq!(whole[..len], data[..], "{len} bytes, CAN FD {canfd}");
            assert!(whole[len..].iter().all(|&b| b == 0));
            let mut out = vec![0xAA; whole.len() + 3];
            assert_eq!(
                receive_into(&refs(&got), GETSET_SEED, &mut out),
                Ok((transfer_id % 32, whole.len()))
            );
            assert_eq!(out[..whole.len()], whole[..]);
            assert_eq!(out[whole.len()..], [0xAA; 3]);
        }
    }
    assert_eq!((frame_max(false), frame_max(true)), (8, 64));
}

#[test]
fn the_iterator_ends_after_the_last_frame() {
    let mut it = frames(&[], GETSET_SEED, 1, false);
    assert_eq!(it.next().map(|f| f.as_bytes().to_vec()), Some(vec![0xC1]));
    assert_eq!(it.next(), None);
    assert_eq!(it.next(), None);
    let mut it = frames(&[1; 8], GETSET_SEED, 1, false);
    assert_eq!(it.by_ref().count(), 2);
    assert_eq!(it.next(), None);
}

/// Frames of any sizes (as a link may deliver, not only CAN's) carrying `data` with its CRC
/// first, tail bits by the rules.
fn cut(data: &[u8], seed: u16, sizes: &[usize]) -> Vec<Vec<u8>> {
    let mut stream = crc16_from(seed, data).to_le_bytes().to_vec();
    stream.extend_from_slice(data);
    let mut out: Vec<Vec<u8>> = Vec::new();
    let mut rest = &stream[..];
    for (i, &size) in sizes.iter().cycle().enumerate() {
        let (piece, more) = rest.split_at(size.min(rest.len()));
        rest = more;
        let mut tail = 9 | if i % 2 == 1 { TOGGLE } else { 0 };
        tail |= if i == 0 { START } else { 0 } | if rest.is_empty() { END } else { 0 };
        out.push([piece, &[tail]].concat());
        if rest.is_empty() {
            return out;
        }
    }
    unreachable!()
}

#[test]
fn the_crc_covers_every_byte_of_every_frame_of_any_size() {
    // Short payloads, those at the edges of the gathered runs (64 and 320 bytes) and longer.
    for len in [
        1, 5, 6, 7, 8, 13, 14, 15, 63, 64, 65, 100, 319, 320, 321, 700,
    ] {
        let data = payload(len);
        for sizes in [
            &[7][..],
            &[8],
            &[63],
            &[3, 7, 1],
            &[2, 1],
            &[7, 7, 7, 20],
            &[400],
        ] {
            let f = cut(&data, GETSET_SEED, sizes);
            if f.len() == 1 {
                continue; // one frame: no CRC
            }
            assert_eq!(received(&refs(&f), GETSET_SEED), Ok((9, data.clone())));
            let mut out = vec![0u8; len];
            assert_eq!(receive_into(&refs(&f), GETSET_SEED, &mut out), Ok((9, len)));
            assert_eq!(out, data);
            for i in 0..f.len() {
                for j in 0..f[i].len() - 1 {
                    let mut changed = f.clone();
                    changed[i][j] ^= 0x04;
                    let r = received(&refs(&changed), GETSET_SEED);
                    let sent_crc = u16::from_le_bytes([changed[0][0], changed[0][1]]);
                    let mut flipped = data.clone();
                    if i > 0 || j >= 2 {
                        // A payload byte: the CRC of what arrived is not the one sent.
                        let at = f[..i].iter().map(|f| f.len() - 1).sum::<usize>() + j - 2;
                        flipped[at] ^= 0x04;
                    }
                    let computed = crc16_from(GETSET_SEED, &flipped);
                    let crc = TransferError::Crc {
                        got: sent_crc,
                        computed,
                    };
                    assert_eq!(r, Err(crc), "{len} bytes in {sizes:?}: frame {i} byte {j}");
                    assert_eq!(
                        receive_into(&refs(&changed), GETSET_SEED, &mut out),
                        Err(crc),
                        "{len} bytes in {sizes:?}: frame {i} byte {j}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_crc_of_another_data_type_is_refused() {
    let f = sent(&payload(30), GETSET_SEED, 4, false);
    let other = transfer_crc_seed(0x1234_5678_9ABC_DEF0);
    let sent_crc = u16::from_le_bytes([f[0][0], f[0][1]]);
    let computed = crc16_from(other, &payload(30));
    let e = TransferError::Crc {
        got: sent_crc,
        computed,
    };
    assert_eq!(received(&refs(&f), other), Err(e));
    assert_eq!(
        e.to_string(),
        format!("transfer CRC mismatch: frames say {sent_crc:#06x}, payload gives {computed:#06x}")
    );
    // A single frame carries no CRC: any seed takes it.
    let single = sent(&payload(7), GETSET_SEED, 4, false);
    assert_eq!(received(&refs(&single), other), Ok((4, payload(7))));
}

/// Each rule a frame's tail byte can break, with the frame the receiver names.
#[test]
fn each_broken_tail_rule_is_named_with_its_frame() {
    let good = sent(&payload(30), GETSET_SEED, 12, false); // 5 frames
    assert_eq!(good.len(), 5);
    let check = |f: &[Vec<u8>], expected: TransferError, message: &str| {
        assert_eq!(received(&refs(f), GETSET_SEED), Err(expected), "{message}");
        let mut out = [0u8; 64];
        assert_eq!(receive_into(&refs(f), GETSET_SEED, &mut out), Err(expected));
        assert_eq!(expected.to_string(), message);
    };
    let with_tail = |i: usize, change: &dyn Fn(u8) -> u8| {
        let mut f = good.clone();
        let last = f[i].len() - 1;
        f[i][last] = change(f[i][last]);
        f
    };
    check(&[], TransferError::Empty, "no frames");
    let mut empty = good.clone();
    empty[2].clear();
    check(
        &empty,
        TransferError::EmptyFrame { frame: 2 },
        "frame 2 is empty (no tail byte)",
    );
    let mut empty_first = good.clone();
    empty_first[0].clear();
    check(
        &empty_first,
        TransferError::EmptyFrame { frame: 0 },
        "frame 0 is empty (no tail byte)",
    );
    check(
        &with_tail(3, &|t| (t & !0x1F) | 13),
        TransferError::TransferId {
            frame: 3,
            got: 13,
            expected: 12,
        },
        "frame 3 has transfer ID 13, the transfer's is 12",
    );
    // The first frame's ID is the transfer's: a later frame is named as wrong.
    check(
        &with_tail(0, &|t| (t & !0x1F) | 11),
        TransferError::TransferId {
            frame: 1,
            got: 12,
            expected: 11,
        },
        "frame 1 has transfer ID 12, the transfer's is 11",
    );
    check(
        &with_tail(0, &|t| t & !START),
        TransferError::NoStart,
        "the first frame has no start-of-transfer bit",
    );
    check(
        &with_tail(2, &|t| t | START),
        TransferError::UnexpectedStart { frame: 2 },
        "frame 2 has the start-of-transfer bit (repeated or new transfer)",
    );
    check(
        &good[..4],
        TransferError::NoEnd,
        "the last frame has no end-of-transfer bit (frames missing)",
    );
    check(
        &with_tail(1, &|t| t | END),
        TransferError::UnexpectedEnd { frame: 1 },
        "frame 1 has the end-of-transfer bit before the last frame",
    );
    check(
        &with_tail(0, &|t| t | END),
        TransferError::UnexpectedEnd { frame: 0 },
        "frame 0 has the end-of-transfer bit before the last frame",
    );
    for i in 0..5 {
        check(
            &with_tail(i, &|t| t ^ TOGGLE),
            TransferError::Toggle { frame: i },
            &format!(
                "frame {i} has the wrong toggle bit (a frame is missing, repeated or out of order)"
            ),
        );
    }
    // A repeated frame (CAN may deliver one twice): its toggle gives it away.
    let mut repeated = good.clone();
    repeated.insert(2, good[1].clone());
    check(
        &repeated,
        TransferError::Toggle { frame: 2 },
        "frame 2 has the wrong toggle bit (a frame is missing, repeated or out of order)",
    );
    // Two frames of a transfer: the first has the start bit, the last the end bit.
    let two = sent(&payload(10), GETSET_SEED, 0, false);
    let mut no_end = two.clone();
    let at = no_end[1].len() - 1;
    no_end[1][at] &= !END;
    check(
        &no_end,
        TransferError::NoEnd,
        "the last frame has no end-of-transfer bit (frames missing)",
    );
    // A single frame: start and end both, toggle clear.
    check(
        &[vec![1, 2, START | 3]],
        TransferError::NoEnd,
        "the last frame has no end-of-transfer bit (frames missing)",
    );
    check(
        &[vec![1, 2, END | 3]],
        TransferError::NoStart,
        "the first frame has no start-of-transfer bit",
    );
    check(
        &[vec![1, 2, START | END | TOGGLE | 3]],
        TransferError::Toggle { frame: 0 },
        "frame 0 has the wrong toggle bit (a frame is missing, repeated or out of order)",
    );
    assert_eq!(
        received(&[&[1, 2, START | END | 3]], GETSET_SEED),
        Ok((3, vec![1, 2]))
    );
}

#[test]
fn a_multi_frame_transfer_without_room_for_its_crc_is_refused() {
    for first in [
        &[START | 1][..],
        &[0x12, START | 1],
        &[0x12, 0x34, START | 1],
    ] {
        let f: [&[u8]; 2] = [first, &[TOGGLE | END | 1]];
        if first.len() == 3 {
            // The CRC and no payload: the CRC of nothing is the seed.
            let got = u16::from_le_bytes([0x12, 0x34]);
            let e = TransferError::Crc {
                got,
                computed: GETSET_SEED,
            };
            assert_eq!(received(&f, GETSET_SEED), Err(e));
            let crc = GETSET_SEED.to_le_bytes();
            let ok: [&[u8]; 2] = [&[crc[0], crc[1], START | 1], &[TOGGLE | END | 1]];
            assert_eq!(received(&ok, GETSET_SEED), Ok((1, vec![])));
            assert_eq!(receive_into(&ok, GETSET_SEED, &mut []), Ok((1, 0)));
            continue;
        }
        assert_eq!(received(&f, GETSET_SEED), Err(TransferError::TooShort));
        assert_eq!(
            receive_into(&f, GETSET_SEED, &mut [0; 8]),
            Err(TransferError::TooShort)
        );
        assert_eq!(
            TransferError::TooShort.to_string(),
            "multi-frame transfer too short to hold its CRC"
        );
    }
}

#[test]
fn receive_into_refuses_a_buffer_one_byte_short_and_leaves_it_alone() {
    for (len, canfd) in [(3, false), (7, false), (8, false), (40, false), (100, true)] {
        let f = sent(&payload(len), GETSET_SEED, 2, canfd);
        let (_, whole) = received(&refs(&f), GETSET_SEED).unwrap();
        let n = whole.len();
        let mut out = vec![0x5A; n - 1];
        assert_eq!(
            receive_into(&refs(&f), GETSET_SEED, &mut out),
            Err(TransferError::TooLong {
                len: n,
                room: n - 1
            })
        );
        assert!(out.iter().all(|&b| b == 0x5A));
        let mut exact = vec![0x5A; n];
        assert_eq!(receive_into(&refs(&f), GETSET_SEED, &mut exact), Ok((2, n)));
        assert_eq!(exact, whole);
    }
    assert_eq!(
        TransferError::TooLong { len: 9, room: 4 }.to_string(),
        "the payload's 9 bytes do not fit the 4-byte buffer"
    );
}
