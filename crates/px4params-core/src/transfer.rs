//! DroneCAN transfers over classic CAN and CAN FD: splitting a payload into frames, and
//! checking received frames so their payload can be decoded in place ([`crate::scatter`]).
//!
//! Each frame ends with a tail byte: start of transfer (`0x80`), end of transfer (`0x40`),
//! toggle (`0x20`, clear in the first frame, alternating) and the 5-bit transfer ID. A payload
//! longer than one frame is preceded by its CRC-16-CCITT-FALSE (little-endian), seeded with
//! [`crate::crc::transfer_crc_seed`].

use core::fmt;

use crate::crc::{crc16, crc16_pieces};
use crate::plan::{Active, Plans};
use crate::scatter::{copy_few, gather, FramePayloads, Pieces, RUN};

const START: u8 = 0x80;
const END: u8 = 0x40;
const TOGGLE: u8 = 0x20;

/// The tail byte of frame `index` of a transfer (`last`: the transfer's last frame): all 8
/// bits are fixed by the frame's place, the start bit on the first, the end bit on the last,
/// the toggle alternating from clear.
#[inline(always)]
const fn tail_byte(transfer_id: u8, index: usize, last: bool) -> u8 {
    let start = if index == 0 { START } else { 0 };
    let end = if last { END } else { 0 };
    let toggle = if index % 2 == 1 { TOGGLE } else { 0 };
    transfer_id | start | end | toggle
}

/// Largest frame: 8 bytes on classic CAN, 64 on CAN FD.
pub const fn frame_max(canfd: bool) -> usize {
    if canfd {
        64
    } else {
        8
    }
}

/// The CAN FD data lengths a frame can have (DLC granularity).
fn fd_length(len: usize) -> usize {
    match len {
        0..=8 => len,
        9..=12 => 12,
        13..=16 => 16,
        17..=20 => 20,
        21..=24 => 24,
        25..=32 => 32,
        33..=48 => 48,
        _ => 64,
    }
}

/// One frame's data, tail byte included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame {
    data: [u8; 64],
    len: u8,
}

impl Frame {
    /// The frame's bytes.
    pub fn as_bytes(&self) -> &[u8] {
        &self.data[..usize::from(self.len)]
    }
}

/// The frames of one transfer, produced one at a time (no allocation).
#[derive(Clone, Debug)]
pub struct Frames<'a> {
    payload: &'a [u8],
    /// Zero bytes appended for CAN FD length granularity.
    pad: usize,
    crc: Option<[u8; 2]>,
    /// Position in the stream `crc ++ payload ++ padding`.
    pos: usize,
    index: usize,
    transfer_id: u8,
    max: usize,
}

/// Splits `payload` into the frames of a transfer. `crc_seed` is the data type's
/// [`crate::crc::transfer_crc_seed`]; `transfer_id` is taken modulo 32.
pub fn frames(payload: &[u8], crc_seed: u16, transfer_id: u8, canfd: bool) -> Frames<'_> {
    let max = frame_max(canfd);
    let mut pad = 0;
    if canfd && payload.len() > 7 {
        // As libuavcan/pydronecan: pad so the last frame has a valid CAN FD length.
        let mut total = payload.len() + 1;
        if total > max {
            total += 2;
        }
        let rest = total % (max - 1);
        pad = fd_length(rest) - rest;
    }
    let crc = (payload.len() + pad > max - 1).then(|| {
        // The padding's zeros one at a time (no zeroed buffer: a CAN FD pad is a few bytes).
        let mut crc = crc16(crc_seed, payload);
        for _ in 0..pad {
            crc = crc16(crc, &[0]);
        }
        crc.to_le_bytes()
    });
    Frames {
        payload,
        pad,
        crc,
        pos: 0,
        index: 0,
        transfer_id: transfer_id & 0x1F,
        max,
    }
}

impl Frames<'_> {
    fn stream_len(&self) -> usize {
        self.crc.map_or(0, |c| c.len()) + self.payload.len() + self.pad
    }

    fn stream_byte(&self, i: usize) -> u8 {
        let head = self.crc.map_or(0, |c| c.len());
        match self.crc {
            Some(crc) if i < head => crc[i],
            _ => self.payload.get(i - head).copied().unwrap_or(0),
        }
    }
}

impl Iterator for Frames<'_> {
    type Item = Frame;

    fn next(&mut self) -> Option<Frame> {
        let total = self.stream_len();
        if self.pos >= total && (self.index > 0 || total > 0) {
            return None;
        }
        let take = (total - self.pos).min(self.max - 1);
        let last = self.pos + take >= total;
        let tail = tail_byte(self.transfer_id, self.index, last);
        // Every byte written once, zeros after the tail (not a zeroed array written over:
        // firmware then calls no `memset`).
        let pos = self.pos;
        self.pos += take;
        self.index += 1;
        Some(Frame {
            data: core::array::from_fn(|i| {
                if i < take {
                    self.stream_byte(pos + i)
                } else if i == take {
                    tail
                } else {
                    0
                }
            }),
            len: (take + 1) as u8,
        })
    }
}

/// Why received frames do not form a transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum TransferError {
    /// No frames at all.
    Empty,
    /// A frame without even a tail byte.
    EmptyFrame {
        /// Frame number.
        frame: usize,
    },
    /// A frame with another transfer ID than the first.
    TransferId {
        /// Frame number.
        frame: usize,
        /// Its transfer ID.
        got: u8,
        /// The first frame's.
        expected: u8,
    },
    /// The first frame lacks the start bit.
    NoStart,
    /// A later frame has the start bit: a repeated first frame or a new transfer.
    UnexpectedStart {
        /// Frame number.
        frame: usize,
    },
    /// The last frame lacks the end bit: frames are missing at the end.
    NoEnd,
    /// A frame before the last has the end bit.
    UnexpectedEnd {
        /// Frame number.
        frame: usize,
    },
    /// The toggle bit does not alternate: a frame is missing, repeated or out of order.
    Toggle {
        /// Frame number.
        frame: usize,
    },
    /// A multi-frame transfer too short to hold its CRC.
    TooShort,
    /// The payload does not fit the buffer given to [`receive_into`].
    TooLong {
        /// The payload's length in bytes.
        len: usize,
        /// The buffer's.
        room: usize,
    },
    /// The transfer CRC does not match the payload.
    Crc {
        /// The CRC in the first frame.
        got: u16,
        /// The CRC of the payload received.
        computed: u16,
    },
}

impl fmt::Display for TransferError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Empty => f.write_str("no frames"),
            Self::EmptyFrame { frame } => write!(f, "frame {frame} is empty (no tail byte)"),
            Self::TransferId {
                frame,
                got,
                expected,
            } => write!(
                f,
                "frame {frame} has transfer ID {got}, the transfer's is {expected}"
            ),
            Self::NoStart => f.write_str("the first frame has no start-of-transfer bit"),
            Self::UnexpectedStart { frame } => write!(
                f,
                "frame {frame} has the start-of-transfer bit (repeated or new transfer)"
            ),
            Self::NoEnd => f.write_str("the last frame has no end-of-transfer bit (frames missing)"),
            Self::UnexpectedEnd { frame } => {
                write!(f, "frame {frame} has the end-of-transfer bit before the last frame")
            }
            Self::Toggle { frame } => write!(
                f,
                "frame {frame} has the wrong toggle bit (a frame is missing, repeated or out of order)"
            ),
            Self::TooShort => f.write_str("multi-frame transfer too short to hold its CRC"),
            Self::TooLong { len, room } => write!(
                f,
                "the payload's {len} bytes do not fit the {room}-byte buffer"
            ),
            Self::Crc { got, computed } => write!(
                f,
                "transfer CRC mismatch: frames say {got:#06x}, payload gives {computed:#06x}"
            ),
        }
    }
}

/// A checked transfer: its ID and its payload pieces (decode them with
/// [`crate::scatter::Scattered`]).
#[derive(Clone, Copy, Debug)]
pub struct Received<'f, 'a> {
    /// The transfer ID.
    pub transfer_id: u8,
    /// The payload, in pieces.
    pub payload: FramePayloads<'f, 'a>,
}

/// Checks the frames of one transfer: tail bits, transfer ID, toggle, and the CRC of a
/// multi-frame transfer. The frames stay where they are; on hosts a payload of up to 64 bytes
/// is gathered into a run the result keeps (classic frames checked and gathered in one pass),
/// and the CRC and a decoder read it as flat bytes.
// Inline: the caller's frame holds the result (with its gathered run) without a copy.
#[inline]
pub fn receive<'f, 'a>(
    frames: &'f [&'a [u8]],
    crc_seed: u16,
) -> Result<Received<'f, 'a>, TransferError> {
    receive_with::<Active>(frames, crc_seed)
}

/// [`receive`] with the plans `P` (`tests/parity.rs` holds the sets to each other).
#[inline]
pub fn receive_with<'f, 'a, P: Plans>(
    frames: &'f [&'a [u8]],
    crc_seed: u16,
) -> Result<Received<'f, 'a>, TransferError> {
    let mut payload = FramePayloads::new(frames);
    if P::CLASSIC_FRAMES {
        if let Some((transfer_id, got, len)) = classic_gathered(frames, payload.run_mut()) {
            if crc16(crc_seed, payload.set_gathered(len)) == got {
                return Ok(Received {
                    transfer_id,
                    payload,
                });
            }
        }
    }
    let (transfer_id, len) = check_tails(frames)?;
    if let Some(got) = sent_crc(frames)? {
        let computed = if !P::GATHERED_CRC {
            // Firmware built for size: no gathering buffer; the steps go on across the
            // pieces.
            crc16_pieces(crc_seed, (0..payload.count()).map(|i| payload.piece(i)))
        } else if (..=RUN).contains(&len) {
            // Most transfers are a few frames: gathered into the run the payload keeps, so
            // that it is decoded from there as from flat bytes.
            crc16(crc_seed, payload.gather(len))
        } else {
            gathered_crc::<320>(crc_seed, frames, len)
        };
        check_crc(got, computed)?;
    }
    Ok(Received {
        transfer_id,
        payload,
    })
}

/// [`receive`] into a buffer, as firmware reassembles a transfer: checks the frames and
/// copies the payload to the start of `out` (bytes after it are left alone); returns the
/// transfer ID and the payload's length. The payload can then be decoded in one piece.
/// A payload that does not fit `out` leaves it alone; another fault (a bad tail byte, the
/// CRC) may leave bytes of the payload's place in `out` written.
pub fn receive_into(
    frames: &[&[u8]],
    crc_seed: u16,
    out: &mut [u8],
) -> Result<(u8, usize), TransferError> {
    receive_into_with::<Active>(frames, crc_seed, out)
}

/// [`receive_into`] with the plans `P`.
pub fn receive_into_with<P: Plans>(
    frames: &[&[u8]],
    crc_seed: u16,
    out: &mut [u8],
) -> Result<(u8, usize), TransferError> {
    if P::CLASSIC_FRAMES {
        if let Some((transfer_id, got, len)) = classic_gathered(frames, out) {
            if crc16(crc_seed, &out[..len]) == got {
                return Ok((transfer_id, len));
            }
        }
    }
    let (transfer_id, len) = check_tails(frames)?;
    let got = sent_crc(frames)?;
    let room = out.len();
    let out = out
        .get_mut(..len)
        .ok_or(TransferError::TooLong { len, room })?;
    gather(frames, out);
    if let Some(got) = got {
        check_crc(got, crc16(crc_seed, out))?;
    }
    Ok((transfer_id, len))
}

/// The plan for a multi-frame transfer of classic CAN frames, each full (8 bytes) but the
/// last, whose payload fits `out`: one pass over the frames checks each tail byte and moves
/// each middle frame whole, in one 8-byte store (its tail byte lands where the next frame's
/// payload goes). Returns the transfer ID, the CRC the first frame carries and the
/// payload's length; declines (`None`) on any other transfer and on any fault, which the
/// general path then finds and words. A bad tail byte found part way leaves bytes of `out`
/// written.
#[inline(always)]
fn classic_gathered(frames: &[&[u8]], out: &mut [u8]) -> Option<(u8, u16, usize)> {
    let (first, rest) = frames.split_first()?;
    let (last, middle) = rest.split_last()?;
    let first = <&[u8; 8]>::try_from(*first).ok()?;
    let (&last_tail, last_piece) = last.split_last()?;
    // A last frame with no payload would leave the one before's tail byte past the end.
    // Lengths first: a transfer whose payload does not fit `out` leaves it alone.
    if last_piece.is_empty() || middle.iter().any(|frame| frame.len() != 8) {
        return None;
    }
    let len = 5 + 7 * middle.len() + last_piece.len();
    let out = out.get_mut(..len)?;
    let transfer_id = first[7] & 0x1F;
    if first[7] != tail_byte(transfer_id, 0, false) {
        return None;
    }
    copy_few(&mut out[..5], &first[2..7]);
    let mut at = 5;
    for (i, frame) in (1..).zip(middle) {
        let frame = <&[u8; 8]>::try_from(*frame).ok()?;
        if frame[7] != tail_byte(transfer_id, i, false) {
            return None;
        }
        out.get_mut(at..at + 8)?.copy_from_slice(frame);
        at += 7;
    }
    if last_tail != tail_byte(transfer_id, frames.len() - 1, true) {
        return None;
    }
    copy_few(out.get_mut(at..)?, last_piece);
    Some((transfer_id, u16::from_le_bytes([first[0], first[1]]), len))
}

/// Checks every frame's tail byte; returns the transfer ID and the payload's length (bytes
/// other than tail bytes and a multi-frame transfer's CRC, which [`sent_crc`] checks is there).
fn check_tails(frames: &[&[u8]]) -> Result<(u8, usize), TransferError> {
    let (first, rest) = frames.split_first().ok_or(TransferError::Empty)?;
    let tail = *first.last().ok_or(TransferError::EmptyFrame { frame: 0 })?;
    let expected = tail & 0x1F;
    let last = rest.len();
    if tail != tail_byte(expected, 0, last == 0) {
        return Err(tail_error(0, tail, expected, last));
    }
    let mut bytes = first.len();
    for (i, frame) in (1..).zip(rest) {
        let tail = *frame.last().ok_or(TransferError::EmptyFrame { frame: i })?;
        bytes += frame.len();
        if tail != tail_byte(expected, i, i == last) {
            return Err(tail_error(i, tail, expected, last));
        }
    }
    let crc = if last > 0 { 2 } else { 0 };
    Ok((expected, (bytes - frames.len()).saturating_sub(crc)))
}

/// The CRC a multi-frame transfer starts with (`None` for a single frame, which has none).
fn sent_crc(frames: &[&[u8]]) -> Result<Option<u16>, TransferError> {
    match frames {
        [_] | [] => Ok(None),
        [first, ..] => match **first {
            [low, high, _, ..] => Ok(Some(u16::from_le_bytes([low, high]))),
            _ => Err(TransferError::TooShort),
        },
    }
}

fn check_crc(got: u16, computed: u16) -> Result<(), TransferError> {
    if got != computed {
        return Err(TransferError::Crc { got, computed });
    }
    Ok(())
}

/// What is wrong with frame `i`'s tail byte `tail`, which is not the one its place fixes.
#[cold]
fn tail_error(i: usize, tail: u8, expected: u8, last: usize) -> TransferError {
    if tail & 0x1F != expected {
        return TransferError::TransferId {
            frame: i,
            got: tail & 0x1F,
            expected,
        };
    }
    match (i, tail & START != 0) {
        (0, false) => return TransferError::NoStart,
        (i, true) if i > 0 => return TransferError::UnexpectedStart { frame: i },
        _ => {}
    }
    match (i == last, tail & END != 0) {
        (true, false) => TransferError::NoEnd,
        (false, true) => TransferError::UnexpectedEnd { frame: i },
        _ => TransferError::Toggle { frame: i },
    }
}

/// The CRC of a multi-frame transfer's payload of more than [`RUN`] bytes, gathered into one
/// run of `N` bytes (longer payloads take [`crc16_pieces`]) so that [`crc16`] takes eight
/// bytes a step across the frames' edges.
fn gathered_crc<const N: usize>(crc: u16, frames: &[&[u8]], len: usize) -> u16 {
    let mut run = [0u8; N];
    match run.get_mut(..len) {
        Some(run) => {
            gather(frames, run);
            crc16(crc, run)
        }
        None => {
            let payload = FramePayloads::new(frames);
            crc16_pieces(crc, (0..payload.count()).map(|i| payload.piece(i)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;
    use std::vec::Vec;

    fn split(payload: &[u8], canfd: bool) -> Vec<Vec<u8>> {
        frames(payload, 0x1234, 5, canfd)
            .map(|f| f.as_bytes().to_vec())
            .collect()
    }

    #[test]
    fn single_and_multi_frame() {
        assert_eq!(split(&[1, 2, 3], false), [[1, 2, 3, 0xC5]]);
        assert_eq!(split(&[], false), [[0xC5]]);
        let f = split(&[1, 2, 3, 4, 5, 6, 7, 8], false);
        assert_eq!(f.len(), 2);
        assert_eq!(f[0][7], 0x85);
        assert_eq!(f[1], [6, 7, 8, 0x65]);
        let crc = crc16(0x1234, &[1, 2, 3, 4, 5, 6, 7, 8]);
        assert_eq!(f[0][..2], crc.to_le_bytes());
    }

    /// A frame's bytes after its tail byte are zero, so that frames with the same bytes are
    /// equal (`Frame` compares all 64).
    #[test]
    fn a_frame_is_its_bytes_then_zeros() {
        for canfd in [false, true] {
            for len in [0usize, 1, 7, 8, 20, 62, 63, 64, 130] {
                let payload: Vec<u8> = (0..len).map(|i| (i as u8) | 0x80).collect();
                let mut sent = 0;
                for frame in frames(&payload, 0x1234, 9, canfd) {
                    let n = usize::from(frame.len);
                    assert_eq!(frame.as_bytes(), &frame.data[..n]);
                    assert!(frame.data[n..].iter().all(|&b| b == 0), "{len} {canfd}");
                    let again = Frame {
                        data: core::array::from_fn(|i| if i < n { frame.data[i] } else { 0 }),
                        len: frame.len,
                    };
                    assert_eq!(frame, again);
                    sent += n;
                }
                assert!(sent > len);
            }
        }
    }

    #[test]
    fn the_crc_covers_every_payload_byte_across_frame_edges() {
        for canfd in [false, true] {
            for len in 0..100usize {
                let payload: Vec<u8> = (0..len).map(|i| (i * 29 + 3) as u8).collect();
                let f = split(&payload, canfd);
                let refs: Vec<&[u8]> = f.iter().map(Vec::as_slice).collect();
                assert!(
                    receive(&refs, 0x1234).is_ok(),
                    "length {len}, CAN FD {canfd}"
                );
                if canfd || f.len() == 1 {
                    continue;
                }
                // One bit changed anywhere in the payload (after the CRC, before the tail).
                for (i, frame) in f.iter().enumerate() {
                    for j in (if i == 0 { 2 } else { 0 })..frame.len() - 1 {
                        let mut changed = f.clone();
                        changed[i][j] ^= 0x10;
                        let refs: Vec<&[u8]> = changed.iter().map(Vec::as_slice).collect();
                        assert!(
                            matches!(receive(&refs, 0x1234), Err(TransferError::Crc { .. })),
                            "length {len}, frame {i}, byte {j}"
                        );
                    }
                }
            }
        }
    }

    /// Frames of any sizes (not only CAN's) carrying `payload`, its CRC first.
    fn cut(payload: &[u8], sizes: &[usize]) -> Vec<Vec<u8>> {
        let mut bytes = crc16(0x1234, payload).to_le_bytes().to_vec();
        bytes.extend_from_slice(payload);
        let mut out = Vec::new();
        let mut rest = &bytes[..];
        for (i, &size) in sizes.iter().cycle().enumerate() {
            let (piece, more) = rest.split_at(size.min(rest.len()));
            rest = more;
            let mut tail = 5 | if i % 2 == 1 { TOGGLE } else { 0 };
            tail |= if i == 0 { START } else { 0 } | if rest.is_empty() { END } else { 0 };
            out.push([piece, &[tail]].concat());
            if rest.is_empty() {
                return out;
            }
        }
        unreachable!("the sizes are not all zero")
    }

    #[test]
    fn long_transfers_and_pieces_of_any_size_are_checked_whole() {
        for len in [300, 318, 319, 320, 321, 640, 700, 4000] {
            let payload: Vec<u8> = (0..len).map(|i| (i * 29 + 3) as u8).collect();
            for sizes in [
                &[7][..],
                &[63],
                &[3, 7, 1],
                &[500],
                &[7, 7, 400, 7, 2],
                &[2, 330],
            ] {
                let mut f = cut(&payload, sizes);
                let refs: Vec<&[u8]> = f.iter().map(Vec::as_slice).collect();
                assert!(receive(&refs, 0x1234).is_ok(), "{len} bytes in {sizes:?}");
                if f.len() == 1 {
                    continue; // a single frame carries no CRC
                }
                // The last payload byte changed.
                let last = f.len() - 1;
                let at = f[last].len() - 2;
                f[last][at] ^= 1;
                let refs: Vec<&[u8]> = f.iter().map(Vec::as_slice).collect();
                let crc = matches!(receive(&refs, 0x1234), Err(TransferError::Crc { .. }));
                assert!(crc, "{len} bytes in {sizes:?}");
            }
        }
    }

    /// `receive_into` agrees with `receive` (its payload joined), leaving the buffer's bytes
    /// after the payload alone; one byte short of room is refused.
    fn agrees_with_receive_into(refs: &[&[u8]]) {
        let mut out = [0xAAu8; 5000];
        let into = receive_into(refs, 0x1234, &mut out);
        let joined = receive(refs, 0x1234).map(|r| {
            let pieces = (0..r.payload.count()).map(|i| r.payload.piece(i));
            (
                r.transfer_id,
                pieces.flat_map(<[u8]>::to_vec).collect::<Vec<u8>>(),
            )
        });
        match (into, joined) {
            (Ok((id, len)), Ok((expected_id, payload))) => {
                assert_eq!((id, &out[..len]), (expected_id, &payload[..]));
                assert!(out[len..].iter().all(|&b| b == 0xAA));
                if len > 0 {
                    let short = receive_into(refs, 0x1234, &mut out[..len - 1]);
                    let too_long = TransferError::TooLong { len, room: len - 1 };
                    assert_eq!(short, Err(too_long));
                }
            }
            (into, joined) => assert_eq!(into.map(|_| ()), joined.map(|_| ())),
        }
    }

    #[test]
    fn receive_into_a_buffer_agrees_with_receive() {
        for canfd in [false, true] {
            for len in (0..100usize).chain([300, 321, 700]) {
                let payload: Vec<u8> = (0..len).map(|i| (i * 29 + 3) as u8).collect();
                let mut f = split(&payload, canfd);
                agrees_with_receive_into(&f.iter().map(Vec::as_slice).collect::<Vec<_>>());
                // Broken: a payload byte, a tail byte, a frame left out.
                let last = f.len() - 1;
                f[last][0] ^= 1;
                agrees_with_receive_into(&f.iter().map(Vec::as_slice).collect::<Vec<_>>());
                f[last][0] ^= 1;
                let tail = f[0].len() - 1;
                f[0][tail] ^= TOGGLE;
                agrees_with_receive_into(&f.iter().map(Vec::as_slice).collect::<Vec<_>>());
                f[0][tail] ^= TOGGLE;
                f.remove(last / 2);
                agrees_with_receive_into(&f.iter().map(Vec::as_slice).collect::<Vec<_>>());
            }
        }
        for sizes in [&[3, 7, 1][..], &[500], &[7, 7, 400, 7, 2], &[0, 9]] {
            let payload: Vec<u8> = (0..1000).map(|i| (i * 7 + 1) as u8).collect();
            let f = cut(&payload, sizes);
            agrees_with_receive_into(&f.iter().map(Vec::as_slice).collect::<Vec<_>>());
        }
        assert_eq!(
            receive_into(&[], 0x1234, &mut [0; 8]),
            Err(TransferError::Empty)
        );
        let short = receive_into(&[&[1, 2, 3, 0xC5]], 0x1234, &mut [0; 2]).unwrap_err();
        assert_eq!(
            short.to_string(),
            "the payload's 3 bytes do not fit the 2-byte buffer"
        );
    }

    #[test]
    fn receive_checks_everything() {
        let payload: Vec<u8> = (0..40).collect();
        let f = split(&payload, false);
        let refs: Vec<&[u8]> = f.iter().map(Vec::as_slice).collect();
        let r = receive(&refs, 0x1234).unwrap();
        assert_eq!(r.transfer_id, 5);
        let joined: Vec<u8> = (0..r.payload.count())
            .flat_map(|i| r.payload.piece(i).to_vec())
            .collect();
        assert_eq!(joined, payload);
        let mut swapped = refs.clone();
        swapped.swap(1, 2);
        assert_eq!(
            receive(&swapped, 0x1234).unwrap_err(),
            TransferError::Toggle { frame: 1 }
        );
        assert_eq!(
            receive(&refs[..3], 0x1234).unwrap_err(),
            TransferError::NoEnd
        );
        assert!(matches!(
            receive(&refs, 0x4321).unwrap_err(),
            TransferError::Crc { .. }
        ));
    }
}
