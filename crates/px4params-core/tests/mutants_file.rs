//! The store file's reader names the first fault it meets, byte by byte in the order
//! docs/store-format.md lays a record out (issue 40), also where that fault sits in the last
//! bytes before the trailer: a record's first byte is its kind and flags, so an unknown kind
//! is refused as such even when nothing follows it; a table line is checked once read, so a
//! line that is not `NAME=TYPE.MAJOR` is named even when the table's CRC is missing after it.
//! The files are built by hand (tests/support/store_file.rs: CRCs computed bit by bit).

#[path = "support/store_file.rs"]
mod store_file;

use px4params_core::file::{check, FileErrorKind};
use store_file::{crc32, table_record, with_crc16};

const SENS_LINE: &str = "SENS=test.Sensor.1";

/// Header (format 2, flags 0, the fingerprint of `SENS_LINE`), `body`, the CRC-32 trailer.
fn sealed(body: &[u8]) -> Vec<u8> {
    let mut data = b"PX4P\x02\x00".to_vec();
    data.extend(crc32(SENS_LINE.as_bytes()).to_le_bytes());
    data.extend(body);
    data.extend(crc32(&data).to_le_bytes());
    data
}

fn refusal(data: &[u8]) -> (FileErrorKind<'_>, usize, String) {
    let e = check(data).unwrap_err();
    (e.kind, e.offset, e.to_string())
}

#[test]
fn an_unknown_record_kind_in_the_last_byte_is_named() {
    let table = with_crc16(&table_record(&[SENS_LINE]));
    let at = 10 + table.len();
    for kind in [0u8, 4, 5, 15] {
        let mut body = table.clone();
        body.push(kind);
        assert_eq!(
            refusal(&sealed(&body)),
            (
                FileErrorKind::RecordKind(kind),
                at,
                format!("record is malformed: unknown record kind {kind}")
            ),
        );
    }
    // Unknown flags, likewise: 0x41 is kind 1 with flag 0x40, which no format has.
    let mut body = table.clone();
    body.push(0x41);
    assert_eq!(
        refusal(&sealed(&body)),
        (
            FileErrorKind::RecordFlags(0x41),
            at,
            "record is malformed: unknown flags 0x41".into()
        ),
    );
    // A known kind with nothing after it runs past the end.
    let mut body = table.clone();
    body.push(0x01);
    assert_eq!(refusal(&sealed(&body)).0, FileErrorKind::PastEnd);
}

#[test]
fn a_bad_table_line_that_ends_the_file_is_named() {
    // The table 3, 1 line, 4 bytes "SENS" (no `=`), and no CRC after it: the line is read to
    // the last byte before the trailer and refused for what it is.
    let mut body = table_record(&["SENS"]);
    assert_eq!(body, [3, 1, 4, b'S', b'E', b'N', b'S']);
    assert_eq!(
        refusal(&sealed(&body)),
        (
            FileErrorKind::TableEntry(b"SENS"),
            10,
            "record is malformed: parameter table entry 'SENS' is not NAME=TYPE.MAJOR".into()
        ),
    );
    // A good line there: only then is the missing CRC the fault.
    body = table_record(&[SENS_LINE]);
    assert_eq!(refusal(&sealed(&body)).0, FileErrorKind::PastEnd);
    // One byte of CRC is not two.
    body.push(0);
    assert_eq!(refusal(&sealed(&body)).0, FileErrorKind::PastEnd);
}
