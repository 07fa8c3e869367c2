//! The store file format (`px4params_core::file`) against docs/store-format.md: files built
//! byte by byte here (tests/support/store_file.rs), every refusal with its offset and message,
//! the writer's bytes, a store's file, and applying a file to a store.
//!
//! The parameters, in ID order: 0 `SENS=test.Sensor.1` (3 instances: uint4 p_version of minor
//! 1, uint7 address, bool enabled, int5 offset), 1 `BAT_N_CELLS` (classic, int32), 2
//! `TRIM=test.Sensor.1` (shared). Sensor's type default p_version 1, address 0x45, enabled,
//! offset -3 is `0001 1000101 1 11101` = `18 BE 80` (docs/codec.md: each byte filled from its
//! most significant bit); its minor version 0 is uint4 p_version, uint7 address, uint8 gain.

mod common;
#[path = "support/store_file.rs"]
mod store_file;

use common::VecStore;
use px4params_core::compile::OwnedLayout;
use px4params_core::file::ClassicType::{self, Float32, Int32};
use px4params_core::file::{
    self, apply, check, stored_minor, write_store, Applied, ApplyError, FileError, FileErrorKind,
    FileName, FileNames, Key, SaveError, WriteError, Writer,
};
use px4params_core::layout::{NodeId, Role};
use px4params_core::store::{ParamDef, StoreError, Which};
use px4params_core::Cast::Saturated;
use px4params_core::{Error, ErrorKind};
use store_file::{
    classic_record, crc32, float_record, store_file, structured_record, table_record, with_crc16,
};

const SENS: u32 = 0;
const BAT_N_CELLS: u32 = 1;
const TRIM: u32 = 2;
const SENS_DEFAULT: [u8; 3] = [0x18, 0xBE, 0x80];
/// Address 0x22: `0001 0100010 1 11101`.
const ADDRESS_22: [u8; 3] = [0x14, 0x5E, 0x80];
const SENS_LINE: &str = "SENS=test.Sensor.1";
const TRIM_LINE: &str = "TRIM=test.Sensor.1";
const NAMES: [FileName<'static>; 3] = [
    FileName::Structured(SENS_LINE),
    FileName::Classic("BAT_N_CELLS", ClassicType::Int32),
    FileName::Structured(TRIM_LINE),
];
/// File order: by name.
const ORDER: [u32; 3] = [BAT_N_CELLS, SENS, TRIM];

struct Fixture {
    layout: OwnedLayout,
    store: VecStore,
    sensor_1_0: NodeId,
}

fn fixture() -> Fixture {
    let mut l = OwnedLayout::default();
    let (sensor, sensor_1_0) = common::sensor_versions(&mut l);
    let i32_ = l.int(32, Saturated).unwrap();
    let defs = vec![
        ParamDef::instanced(sensor, 3),
        ParamDef::shared(i32_),
        ParamDef::shared(sensor),
    ];
    let view = l.as_layout();
    let mut store = common::vec_store(&view, defs);
    store.set_type_default(&view, SENS, &SENS_DEFAULT).unwrap();
    store
        .set_type_default(&view, BAT_N_CELLS, &4i32.to_le_bytes())
        .unwrap();
    store.set_type_default(&view, TRIM, &SENS_DEFAULT).unwrap();
    store.mark_saved();
    Fixture {
        layout: l,
        store,
        sensor_1_0,
    }
}

/// The file with its trailer computed again (after an edit inside it).
fn resealed(mut file: Vec<u8>) -> Vec<u8> {
    let end = file.len() - 4;
    let crc = crc32(&file[..end]);
    file[end..].copy_from_slice(&crc.to_le_bytes());
    file
}

fn refusal(data: &[u8]) -> (FileErrorKind<'_>, usize, String) {
    let e = check(data).unwrap_err();
    (e.kind, e.offset, e.to_string())
}

// -- check ----------------------------------------------------------------------------------

#[test]
fn the_catalogue_check_values_hold_for_the_tests_crcs() {
    store_file::assert_catalogue_check_values();
}

#[test]
fn a_file_is_checked_whole_and_read_out_record_by_record() {
    let sens0 = structured_record(0, 0, None, Some(&ADDRESS_22));
    let trim = structured_record(1, 0, Some(&ADDRESS_22), Some(&SENS_DEFAULT));
    let bat = classic_record("BAT_N_CELLS", 6);
    let data = store_file(2, &[SENS_LINE, TRIM_LINE], &[&bat, &sens0, &trim]);
    let checked = check(&data).unwrap();
    assert_eq!(checked.version, 2);
    assert!(checked.has_table());
    let joined = format!("{SENS_LINE}\n{TRIM_LINE}");
    assert_eq!(checked.fingerprint, crc32(joined.as_bytes()));
    assert_eq!(checked.table().collect::<Vec<_>>(), [SENS_LINE, TRIM_LINE]);
    let records: Vec<_> = checked.records().collect();
    assert_eq!(records.len(), 3);
    // The header is 10 bytes, the table 2 + 2 * 19 bytes and its CRC 2.
    let first = 10 + 2 + 2 * 19 + 2;
    let offsets: Vec<_> = records.iter().map(|r| r.offset).collect();
    assert_eq!(offsets, [first, first + 19, first + 19 + 9]);
    assert_eq!(records[0].key, Key::Classic(b"BAT_N_CELLS", None));
    assert_eq!(records[0].value, Some(&6i32.to_le_bytes()[..]));
    assert_eq!(records[0].default, None);
    assert_eq!(records[0].raw, &bat[..]);
    assert_eq!(records[1].key, Key::Structured(0));
    assert_eq!((records[1].instance, records[1].default), (0, None));
    assert_eq!(records[1].value, Some(&ADDRESS_22[..]));
    assert_eq!(records[2].key, Key::Structured(1));
    assert_eq!(records[2].default, Some(&ADDRESS_22[..]));
    assert_eq!(records[2].value, Some(&SENS_DEFAULT[..]));
    assert_eq!(records[2].raw, &trim[..]);
    // Format 1: no table, records straight after the header.
    let v1 = store_file(1, &[], &[&structured_record(4, 2, None, None)]);
    let checked = check(&v1).unwrap();
    assert_eq!((checked.version, checked.has_table()), (1, false));
    assert_eq!(checked.table().count(), 0);
    let record = checked.records().next().unwrap();
    assert_eq!(
        (record.offset, record.key, record.instance),
        (10, Key::Structured(4), 2)
    );
    // The smallest files: a format 1 header and trailer; a format 2 empty table.
    assert_eq!(
        check(&store_file(1, &[], &[])).unwrap().records().count(),
        0
    );
    let empty = store_file(2, &[], &[]);
    assert_eq!(empty.len(), 10 + 2 + 2 + 4);
    assert_eq!(check(&empty).unwrap().table().count(), 0);
}

#[test]
fn the_table_has_as_many_lines_as_it_says() {
    // A table whose CRC-16 starts with a 0 byte: read as one more line, that byte would be an
    // empty one. The lines stop at the table's count.
    let line = (0..)
        .map(|n| format!("SENS=test.Sensor{n}.1"))
        .find(|line| with_crc16(&table_record(&[line]))[2 + 1 + line.len()] == 0)
        .unwrap();
    let data = store_file(2, &[&line], &[&structured_record(0, 0, None, None)]);
    let checked = check(&data).unwrap();
    assert_eq!(checked.table().collect::<Vec<_>>(), [line.as_str()]);
    assert_eq!(checked.table().count(), 1);
}

#[test]
fn a_number_is_at_most_five_bytes() {
    // Index 0 written in five bytes (LEB128 allows the padding), instance 65535 in three.
    let long_index = [0x01, 0x80, 0x80, 0x80, 0x80, 0x00, 0xFF, 0xFF, 0x03];
    let data = store_file(2, &[SENS_LINE], &[&long_index]);
    let record = check(&data).unwrap().records().next().unwrap();
    assert_eq!((record.key, record.instance), (Key::Structured(0), 65535));
    let six = [0x01, 0x80, 0x80, 0x80, 0x80, 0x80, 0x00, 0x00];
    let data = store_file(2, &[SENS_LINE], &[&six]);
    let (kind, offset, text) = refusal(&data);
    assert_eq!((kind, offset), (FileErrorKind::LongNumber, 33));
    assert_eq!(text, "record is malformed: a number is too long");
    let too_big = [0x01, 0x00, 0x80, 0x80, 0x04];
    let data = store_file(2, &[SENS_LINE], &[&too_big]);
    let (kind, _, text) = refusal(&data);
    assert_eq!(kind, FileErrorKind::Instance(65536));
    assert_eq!(text, "record is malformed: instance 65536 is out of range");
}

#[test]
fn every_refusal_names_what_and_where() {
    let good = store_file(2, &[SENS_LINE], &[&structured_record(0, 1, None, None)]);
    let records_at = 10 + 3 + 18 + 2;
    // Header and trailer.
    let short = b"PX4P\x02\x00\x00\x00\x00";
    assert_eq!(
        refusal(short),
        (
            FileErrorKind::NotAStoreFile,
            0,
            "not a px4params store file (no PX4P header)".into()
        )
    );
    let mut magic = good.clone();
    magic[3] = b'Q';
    assert_eq!(refusal(&magic).0, FileErrorKind::NotAStoreFile);
    let mut v4 = good.clone();
    v4[4] = 4;
    assert_eq!(
        refusal(&v4),
        (
            FileErrorKind::Version(4),
            4,
            "store file format version 4 (this px4params reads 1 to 3)".into()
        )
    );
    let mut v0 = good.clone();
    v0[4] = 0;
    assert_eq!(refusal(&v0).0, FileErrorKind::Version(0));
    for len in [10, 13] {
        assert_eq!(
            refusal(&good[..len]),
            (
                FileErrorKind::NoTrailer,
                len,
                "file is truncated (no trailer)".into()
            )
        );
    }
    let end = good.len() - 4;
    for at in [5, 6, 12, end - 1, end, good.len() - 1] {
        let mut flipped = good.clone();
        flipped[at] ^= 0x40;
        assert_eq!(refusal(&flipped).0, FileErrorKind::Corrupted, "byte {at}");
    }
    assert_eq!(
        refusal(&good[..good.len() - 1]),
        (
            FileErrorKind::Corrupted,
            good.len() - 5,
            "file is corrupted or truncated (CRC-32 mismatch); nothing was applied".into()
        )
    );
    let mut flags = good.clone();
    flags[5] = 0x80;
    assert_eq!(
        refusal(&resealed(flags)),
        (
            FileErrorKind::HeaderFlags(0x80),
            5,
            "unknown header flags 0x80".into()
        )
    );
    // The table.
    let mut fingerprint = good.clone();
    fingerprint[6] ^= 1;
    assert_eq!(
        refusal(&resealed(fingerprint)),
        (
            FileErrorKind::Fingerprint,
            10,
            "the parameter table does not match the header's fingerprint".into()
        )
    );
    let mut table_crc = good.clone();
    table_crc[records_at - 1] ^= 1;
    assert_eq!(
        refusal(&resealed(table_crc)),
        (
            FileErrorKind::RecordCrc,
            10,
            "record is corrupted (CRC-16 mismatch)".into()
        )
    );
    let not_first = store_file(1, &[], &[&structured_record(0, 0, None, None)]);
    let mut not_first = not_first;
    not_first[4] = 2;
    assert_eq!(
        refusal(&resealed(not_first)),
        (
            FileErrorKind::TableFirst,
            10,
            "record is malformed: a file of format 2 or later starts with its parameter table"
                .into()
        )
    );
    let not_ascii = store_file(2, &["SENS=\u{e9}"], &[]);
    assert_eq!(
        refusal(&not_ascii),
        (
            FileErrorKind::TableNotAscii,
            10,
            "record is malformed: a parameter table entry is not ASCII".into()
        )
    );
    // A line needs a name, "=" and a type, and is quoted as Python quotes it.
    let entries: [(&str, &str); 7] = [
        ("SENS", "'SENS'"),
        ("=test.Sensor.1", "'=test.Sensor.1'"),
        ("SENS=", "'SENS='"),
        ("it's", "\"it's\""),
        ("'\"", "'\\'\"'"),
        ("a\\b\tc\nd\re", "'a\\\\b\\tc\\nd\\re'"),
        ("\x01\x7f", "'\\x01\\x7f'"),
    ];
    for (line, quoted) in entries {
        let data = store_file(2, &[SENS_LINE, line], &[]);
        let (kind, offset, text) = refusal(&data);
        assert_eq!(kind, FileErrorKind::TableEntry(line.as_bytes()));
        assert_eq!(offset, 10);
        assert_eq!(
            text,
            format!("record is malformed: parameter table entry {quoted} is not NAME=TYPE.MAJOR")
        );
    }
    // "S=T" is the shortest line there is.
    assert!(check(&store_file(2, &["S=T"], &[])).is_ok());
    // A table that runs past the end, or lacks its CRC.
    let mut past = vec![3, 1, 40];
    past.extend(b"SENS");
    assert_eq!(raw_file(&[&past]).0, FileErrorKind::PastEnd);
    assert_eq!(
        raw_file(&[&table_record(&[SENS_LINE])]).0,
        FileErrorKind::PastEnd
    );
    let mut no_crc = table_record(&[SENS_LINE]);
    no_crc.push(0);
    assert_eq!(raw_file(&[&no_crc]).0, FileErrorKind::PastEnd);
}

/// A file of these bytes after the header (fingerprint 0), sealed with a correct trailer;
/// its refusal.
fn raw_file(chunks: &[&[u8]]) -> (FileErrorKind<'static>, usize, String) {
    let mut data = b"PX4P\x02\x00".to_vec();
    data.extend(crc32(SENS_LINE.as_bytes()).to_le_bytes());
    for chunk in chunks {
        data.extend(*chunk);
    }
    data.extend(crc32(&data).to_le_bytes());
    let data: &'static [u8] = Vec::leak(data);
    refusal(data)
}

#[test]
fn a_bad_record_is_refused_at_its_offset() {
    let table = with_crc16(&table_record(&[SENS_LINE]));
    let at = 10 + table.len();
    let good = with_crc16(&structured_record(0, 0, None, None));
    let case = |record: &[u8]| {
        let mut chunks: Vec<&[u8]> = vec![&table, &good];
        chunks.push(record);
        let (kind, offset, text) = raw_file(&chunks);
        assert_eq!(offset, at + good.len(), "{kind:?}");
        (kind, text)
    };
    let mut bad_crc = with_crc16(&structured_record(0, 1, None, None));
    bad_crc[3] ^= 0xFF;
    assert_eq!(
        case(&bad_crc),
        (
            FileErrorKind::RecordCrc,
            "record is corrupted (CRC-16 mismatch)".into()
        )
    );
    assert_eq!(
        case(&with_crc16(&[0x41, 0, 0])),
        (
            FileErrorKind::RecordFlags(0x41),
            "record is malformed: unknown flags 0x41".into()
        )
    );
    assert_eq!(
        case(&with_crc16(&[0x81, 0, 0])).0,
        FileErrorKind::RecordFlags(0x81)
    );
    assert_eq!(
        case(&with_crc16(&table_record(&[SENS_LINE]))),
        (
            FileErrorKind::SecondTable,
            "record is malformed: a second parameter table".into()
        )
    );
    for kind in [0, 4, 15] {
        assert_eq!(
            case(&with_crc16(&[kind, 0, 0])),
            (
                FileErrorKind::RecordKind(kind),
                format!("record is malformed: unknown record kind {kind}")
            )
        );
    }
    // A value longer than what follows, and a record without its CRC.
    assert_eq!(
        case(&with_crc16(&[0x21, 0, 0, 9, 1, 2])),
        (
            FileErrorKind::PastEnd,
            "record is malformed: it runs past the end of the file".into()
        )
    );
    assert_eq!(case(&[0x01, 0, 0]).0, FileErrorKind::PastEnd);
    assert_eq!(case(&[0x01, 0, 0, 0]).0, FileErrorKind::PastEnd);
    // A classic record's values are four bytes, whatever follows: three and a CRC are not.
    assert_eq!(
        case(&with_crc16(&[0x22, 1, b'X', 1, 2, 3])).0,
        FileErrorKind::PastEnd
    );
    let two = [0x32, 1, b'X', 1, 2, 3, 4, 5, 6, 7, 8];
    let data = store_file(2, &[SENS_LINE], &[&two]);
    let record = check(&data).unwrap().records().next().unwrap();
    assert_eq!(record.key, Key::Classic(b"X", None));
    assert_eq!(record.default, Some(&[1u8, 2, 3, 4][..]));
    assert_eq!(record.value, Some(&[5u8, 6, 7, 8][..]));
}

#[test]
fn a_classic_record_named_as_no_px4_parameter_is_refused() {
    let table = with_crc16(&table_record(&[SENS_LINE]));
    // Kind 2 with a value, the name's length and bytes, the value (without the CRC-16).
    let record = |name: &[u8]| {
        let mut r = vec![0x22, name.len() as u8];
        r.extend(name);
        r.extend([5, 0, 0, 0]);
        r
    };
    // Upper-case letters, digits and '_', a letter first, 1 to 16: kept.
    for name in [&b"A"[..], b"SYS_AUTOSTART", b"Z9_", b"ABCDEFGHIJKLMNOP"] {
        let data = store_file(2, &[SENS_LINE], &[&record(name)]);
        let first = check(&data).unwrap().records().next().unwrap();
        assert_eq!(first.key, Key::Classic(name, None));
    }
    let refused = |name: &[u8]| {
        let (kind, offset, text) = raw_file(&[&table, &with_crc16(&record(name))]);
        assert_eq!(
            (kind, offset),
            (FileErrorKind::ClassicName(name), 10 + table.len())
        );
        text
    };
    assert_eq!(
        refused(b"X\x1b[31mRED\n"),
        "record is malformed: classic parameter name 'X\\x1b[31mRED\\n' is not 1 to 16 \
         upper-case letters, digits and '_', a letter first"
    );
    for name in [
        &b""[..],
        b"ABCDEFGHIJKLMNOPQ",
        b"sys",
        b"1A",
        b"_A",
        b"A-B",
        b"A B",
        b"A\xff",
    ] {
        refused(name);
    }
}

// -- the writer -----------------------------------------------------------------------------

#[test]
fn the_writer_writes_the_documented_bytes() {
    let mut buf = [0u8; 128];
    let mut w = Writer::new(&mut buf, [SENS_LINE, TRIM_LINE]).unwrap();
    w.classic(b"BAT_N_CELLS", Int32, None, Some(&6i32.to_le_bytes()))
        .unwrap();
    w.classic(
        b"BAT1_V_CHARGED",
        Float32,
        None,
        Some(&4.2f32.to_le_bytes()),
    )
    .unwrap();
    w.structured(0, 2, Some(&ADDRESS_22), None).unwrap();
    w.structured(1, 0, None, None).unwrap();
    w.raw(&[0x22, 1, b'X', 1, 0, 0, 0]).unwrap();
    let len = w.finish().unwrap();
    let expected = store_file(
        3,
        &[SENS_LINE, TRIM_LINE],
        &[
            &classic_record("BAT_N_CELLS", 6),
            &float_record("BAT1_V_CHARGED", 4.2),
            &structured_record(0, 2, Some(&ADDRESS_22), None),
            &structured_record(1, 0, None, None),
            &classic_record("X", 1),
        ],
    );
    assert_eq!(&buf[..len], &expected[..]);
    // Numbers of 128 and more take more bytes, seven bits each, low bits first.
    let mut buf = [0u8; 64];
    let mut w = Writer::new(&mut buf, [SENS_LINE]).unwrap();
    w.structured(300, 65535, None, None).unwrap();
    let len = w.finish().unwrap();
    let big = [0x01, 0xAC, 0x02, 0xFF, 0xFF, 0x03];
    assert_eq!(&buf[..len], &store_file(3, &[SENS_LINE], &[&big])[..]);
    // A classic record with a default and a value, both four bytes, no lengths.
    let mut buf = [0u8; 64];
    let mut w = Writer::new(&mut buf, [""; 0]).unwrap();
    w.classic(b"A", Float32, Some(&[1, 2, 3, 4]), Some(&[5, 6, 7, 8]))
        .unwrap();
    let len = w.finish().unwrap();
    let both = [0x72, 1, b'A', 1, 2, 3, 4, 5, 6, 7, 8];
    assert_eq!(&buf[..len], &store_file(3, &[], &[&both])[..]);
}

#[test]
fn the_writer_refuses_a_short_buffer_and_a_bad_classic_name() {
    let expected = store_file(3, &[SENS_LINE], &[&structured_record(0, 0, None, None)]);
    let write = |buf: &mut [u8]| -> Result<usize, WriteError> {
        let mut w = Writer::new(buf, [SENS_LINE])?;
        w.structured(0, 0, None, None)?;
        w.finish()
    };
    assert_eq!(write(&mut vec![0; expected.len()]), Ok(expected.len()));
    for cap in [0, 3, 9, 12, 31, 32, 33, 37, expected.len() - 1] {
        let e = write(&mut vec![0; cap]).unwrap_err();
        let WriteError::BufferFull { needed } = e else {
            panic!("{e:?}")
        };
        assert!(needed > cap && needed <= expected.len(), "{cap}: {needed}");
    }
    assert_eq!(
        write(&mut vec![0; expected.len() - 1]),
        Err(WriteError::BufferFull {
            needed: expected.len()
        })
    );
    assert_eq!(
        WriteError::BufferFull { needed: 40 }.to_string(),
        "the store file needs more than the buffer's 40 bytes"
    );
    let mut buf = [0u8; 64];
    let mut w = Writer::new(&mut buf, [""; 0]).unwrap();
    let four = Some(&[0u8; 4][..]);
    assert_eq!(
        w.classic(b"", Int32, None, four),
        Err(WriteError::ClassicName)
    );
    assert_eq!(
        w.classic(b"SEVENTEEN_LETTERS", Int32, None, four),
        Err(WriteError::ClassicName)
    );
    assert_eq!(w.classic(b"SIXTEEN_LETTERS_", Int32, None, four), Ok(()));
    assert_eq!(
        WriteError::ClassicName.to_string(),
        "a classic parameter's name must be 1 to 16 characters"
    );
}

// -- a store's file ---------------------------------------------------------------------------

#[test]
fn a_store_is_written_with_what_differs_from_its_defaults() {
    let mut f = fixture();
    let layout = f.layout.as_layout();
    let save = |store: &VecStore| -> Vec<u8> {
        let mut buf = [0u8; 256];
        let len = write_store(store, &NAMES[..], &ORDER, [], &mut buf).unwrap();
        buf[..len].to_vec()
    };
    assert_eq!(save(&f.store), store_file(3, &[], &[]));
    f.store.add(SENS, Some(2)).unwrap();
    f.store.add(SENS, Some(0)).unwrap();
    f.store
        .set_encoded(&layout, SENS, 0, Which::Value, &ADDRESS_22)
        .unwrap();
    f.store
        .set_encoded(&layout, BAT_N_CELLS, 0, Which::Value, &6i32.to_le_bytes())
        .unwrap();
    let expected = store_file(
        3,
        &[SENS_LINE],
        &[
            &classic_record("BAT_N_CELLS", 6),
            &structured_record(0, 0, None, Some(&ADDRESS_22)),
            &structured_record(0, 2, None, None),
        ],
    );
    assert_eq!(save(&f.store), expected);
    // A shared parameter with its own default: in the table, flag 0x10 (the value followed).
    f.store
        .set_encoded(&layout, TRIM, 0, Which::Default, &ADDRESS_22)
        .unwrap();
    // A classic default: flag 0x10, before the value.
    f.store
        .set_encoded(&layout, BAT_N_CELLS, 0, Which::Default, &5i32.to_le_bytes())
        .unwrap();
    let mut bat = vec![0x32, 11];
    bat.extend(b"BAT_N_CELLS");
    bat.extend(5i32.to_le_bytes());
    bat.extend(6i32.to_le_bytes());
    let expected = store_file(
        3,
        &[SENS_LINE, TRIM_LINE],
        &[
            &bat,
            &structured_record(0, 0, None, Some(&ADDRESS_22)),
            &structured_record(0, 2, None, None),
            &structured_record(1, 0, Some(&ADDRESS_22), None),
        ],
    );
    assert_eq!(save(&f.store), expected);
    // Records the store could not place are written back as they were, at the end.
    let kept = classic_record("OTHER", 9);
    let mut buf = [0u8; 256];
    let len = write_store(&f.store, &NAMES[..], &ORDER, [&kept[..]], &mut buf).unwrap();
    let with_kept = store_file(
        3,
        &[SENS_LINE, TRIM_LINE],
        &[
            &bat,
            &structured_record(0, 0, None, Some(&ADDRESS_22)),
            &structured_record(0, 2, None, None),
            &structured_record(1, 0, Some(&ADDRESS_22), None),
            &kept,
        ],
    );
    assert_eq!(&buf[..len], &with_kept[..]);
    // The order given is the file's: the table follows it.
    let mut buf = [0u8; 256];
    let len = write_store(&f.store, &NAMES[..], &[TRIM, SENS], [], &mut buf).unwrap();
    let checked = check(&buf[..len]).unwrap();
    assert_eq!(checked.table().collect::<Vec<_>>(), [TRIM_LINE, SENS_LINE]);
}

#[test]
fn a_store_without_names_or_room_is_not_written() {
    let mut f = fixture();
    f.store.add(SENS, None).unwrap();
    let mut buf = [0u8; 256];
    let e = write_store(&f.store, &NAMES[..2], &ORDER, [], &mut buf).unwrap_err();
    assert_eq!(e, SaveError::NoName { param: TRIM });
    assert_eq!(e.to_string(), "no parameter #2 to save");
    let e = write_store(&f.store, &NAMES[..], &[SENS, 3], [], &mut buf).unwrap_err();
    assert_eq!(e, SaveError::NoName { param: 3 });
    let more_names = [
        NAMES[0],
        NAMES[1],
        NAMES[2],
        FileName::Classic("EXTRA", Int32),
    ];
    let e = write_store(&f.store, &more_names[..], &[3], [], &mut buf).unwrap_err();
    assert_eq!(e, SaveError::NoName { param: 3 });
    let mut small = [0u8; 20];
    let e = write_store(&f.store, &NAMES[..], &ORDER, [], &mut small).unwrap_err();
    let SaveError::Write(WriteError::BufferFull { needed }) = e else {
        panic!("{e:?}")
    };
    assert!(needed > 20);
    assert_eq!(
        e.to_string(),
        format!("the store file needs more than the buffer's {needed} bytes")
    );
}

// -- applying a file ------------------------------------------------------------------------------

/// The names of [`NAMES`], and Sensor 1.0 as minor version 0 of SENS's type.
struct WithOlder(NodeId);

impl FileNames for WithOlder {
    fn name(&self, param: u32) -> Option<FileName<'_>> {
        NAMES.get(param as usize).copied()
    }

    fn older(&self, param: u32, minor: u32) -> Option<NodeId> {
        (param == SENS && minor == 0).then_some(self.0)
    }
}

fn applied(f: &mut Fixture, data: &[u8], clear: bool) -> Result<Applied, ApplyError> {
    let layout = f.layout.as_layout();
    let checked = check(data).unwrap();
    let names = WithOlder(f.sensor_1_0);
    apply(&mut f.store, &layout, &names, &checked, clear)
}

fn present(f: &Fixture, param: u32) -> Vec<u16> {
    f.store.instances(param).unwrap().collect()
}

#[test]
fn a_file_is_applied_as_a_load_or_a_merge() {
    let mut f = fixture();
    f.store.add(SENS, Some(1)).unwrap();
    let data = store_file(
        2,
        &[TRIM_LINE, SENS_LINE],
        &[
            &classic_record("BAT_N_CELLS", 6),
            &classic_record("NOT_HERE", 1),
            &structured_record(1, 0, None, Some(&ADDRESS_22)),
            &structured_record(0, 0, Some(&ADDRESS_22), None),
        ],
    );
    // A merge keeps SENS#1, and writes a record of an instance that is there into it.
    let again = store_file(
        2,
        &[SENS_LINE],
        &[&structured_record(0, 1, None, Some(&ADDRESS_22))],
    );
    assert_eq!(applied(&mut f, &again, false).unwrap().records, 1);
    assert_eq!(f.store.get(SENS, 1, Which::Value).unwrap(), ADDRESS_22);
    let merged = applied(&mut f, &data, false).unwrap();
    assert_eq!(
        merged,
        Applied {
            records: 3,
            foreign: 1
        }
    );
    assert_eq!(present(&f, SENS), [0, 1]);
    assert_eq!(f.store.get(SENS, 0, Which::Value).unwrap(), ADDRESS_22);
    assert_eq!(f.store.get(SENS, 0, Which::Default).unwrap(), SENS_DEFAULT);
    assert_eq!(f.store.get(TRIM, 0, Which::Default).unwrap(), ADDRESS_22);
    let bat = f.store.get(BAT_N_CELLS, 0, Which::Value).unwrap();
    assert_eq!(bat, 6i32.to_le_bytes());
    // Everything applied is saved: nothing is unsaved.
    for (param, instance) in [(SENS, 0), (SENS, 1), (TRIM, 0), (BAT_N_CELLS, 0)] {
        assert!(!f.store.slot(param, instance).unwrap().unsaved());
    }
    // A load starts from a cleared store.
    let mut f = fixture();
    f.store.add(SENS, Some(1)).unwrap();
    assert_eq!(applied(&mut f, &data, true).unwrap().records, 3);
    assert_eq!(present(&f, SENS), [0]);
    assert!(!f.store.slot(SENS, 1).unwrap().unsaved());
}

#[test]
fn a_classic_record_says_its_type_from_format_3_on() {
    fn records(data: &[u8]) -> Vec<Key<'_>> {
        check(data).unwrap().records().map(|r| r.key).collect()
    }
    let both = [classic_record("A", 1), float_record("B", 1.5)];
    let v3 = store_file(3, &[], &[&both[0], &both[1]]);
    assert_eq!(
        records(&v3),
        [
            Key::Classic(b"A", Some(Int32)),
            Key::Classic(b"B", Some(Float32))
        ]
    );
    // Format 2 did not say: the reader's type holds, and the flag is unknown there.
    let v2 = store_file(2, &[], &[&both[0]]);
    assert_eq!(records(&v2), [Key::Classic(b"A", None)]);
    let flagged = store_file(2, &[], &[&both[1]]);
    assert_eq!(
        refusal(&flagged),
        (
            FileErrorKind::RecordFlags(0x62),
            14,
            "record is malformed: unknown flags 0x62".into()
        )
    );
    // A structured record has no such flag in any format.
    let structured = store_file(3, &[SENS_LINE], &[&[0x41, 0, 0]]);
    assert_eq!(refusal(&structured).0, FileErrorKind::RecordFlags(0x41));
}

#[test]
fn a_classic_record_of_another_type_is_left_out_not_reread() {
    // BAT_N_CELLS is an int32 here: 6.0's float bits read as an int32 are 1086324736.
    let table = [SENS_LINE];
    for (record, taken) in [
        (float_record("BAT_N_CELLS", 6.0), false),
        (classic_record("BAT_N_CELLS", 6), true),
    ] {
        let mut f = fixture();
        let data = store_file(3, &table, &[&record]);
        let applied = applied(&mut f, &data, true).unwrap();
        assert_eq!(
            (applied.records, applied.foreign),
            (usize::from(taken), usize::from(!taken))
        );
        let bat = f.store.get(BAT_N_CELLS, 0, Which::Value).unwrap();
        assert_eq!(bat, if taken { 6i32 } else { 4 }.to_le_bytes());
    }
    // In format 2 the name alone places it: the store's type is the only one known.
    let mut f = fixture();
    let v2 = store_file(2, &table, &[&classic_record("BAT_N_CELLS", 6)]);
    assert_eq!(applied(&mut f, &v2, true).unwrap().records, 1);
}

#[test]
fn a_refused_record_leaves_the_store_as_it_was() {
    let table = [SENS_LINE, TRIM_LINE];
    let good = structured_record(0, 0, None, Some(&ADDRESS_22));
    let first = 10 + 2 + 2 * 19 + 2;
    let second = first + good.len() + 2;
    let cases: Vec<(Vec<u8>, ApplyError)> = vec![
        (
            store_file(
                2,
                &["GONE=test.Gone.1"],
                &[&structured_record(0, 0, None, None)],
            ),
            ApplyError::UnknownParameter { offset: 31 },
        ),
        (
            store_file(2, &table, &[&good, &structured_record(7, 0, None, None)]),
            ApplyError::UnknownParameter { offset: second },
        ),
        (
            store_file(2, &table, &[&good, &structured_record(0, 3, None, None)]),
            ApplyError::Refused {
                offset: second,
                error: StoreError::InstanceOutOfRange {
                    instance: 3,
                    max_instances: 3,
                },
            },
        ),
        (
            store_file(2, &table, &[&good, &structured_record(1, 1, None, None)]),
            ApplyError::Refused {
                offset: second,
                error: StoreError::NotPresent { instance: 1 },
            },
        ),
    ];
    for (data, expected) in cases {
        for clear in [false, true] {
            let mut f = fixture();
            f.store.add(SENS, Some(2)).unwrap();
            let e = applied(&mut f, &data, clear).unwrap_err();
            assert_eq!(e, expected);
            let offset = match expected {
                ApplyError::UnknownParameter { offset } | ApplyError::Refused { offset, .. } => {
                    offset
                }
                _ => unreachable!(),
            };
            assert!(offset == 31 || offset == second);
            assert_eq!(e.offset(), offset);
            assert_eq!(present(&f, SENS), [2], "{expected:?}");
            assert!(f.store.slot(SENS, 2).unwrap().unsaved(), "not marked saved");
        }
    }
    // A value that does not decode, after one that does.
    let mut f = fixture();
    let data = store_file(
        2,
        &table,
        &[&good, &structured_record(0, 1, None, Some(&[0x18]))],
    );
    let e = applied(&mut f, &data, true).unwrap_err();
    assert!(
        matches!(e, ApplyError::Refused { offset, error: StoreError::Codec(_) } if offset == second)
    );
    assert_eq!(present(&f, SENS), Vec::<u16>::new());
    // Format 1 is the host's to read.
    let v1 = store_file(1, &[], &[&structured_record(0, 0, None, None)]);
    assert_eq!(applied(&mut f, &v1, true), Err(ApplyError::Format1));
    assert_eq!(ApplyError::Format1.offset(), 0);
}

#[test]
fn a_value_of_an_older_minor_version_is_translated() {
    let mut f = fixture();
    // Sensor 1.0: p_version 0, address 0x22, gain 9 = 0000 0100010 00001001.
    let old = [0x04, 0x41, 0x20];
    let data = store_file(
        2,
        &[SENS_LINE],
        &[&structured_record(0, 1, None, Some(&old))],
    );
    assert_eq!(applied(&mut f, &data, true).unwrap().records, 1);
    // The address carried over; enabled and offset from the default; gain dropped.
    assert_eq!(f.store.get(SENS, 1, Which::Value).unwrap(), ADDRESS_22);
    // A minor version the names do not carry is refused.
    let newer = [0x24, 0x41, 0x20];
    let data = store_file(
        2,
        &[SENS_LINE],
        &[&structured_record(0, 2, None, Some(&newer))],
    );
    let e = applied(&mut f, &data, true).unwrap_err();
    let mismatch = |e: &ApplyError| {
        matches!(
            e,
            ApplyError::Refused {
                error: StoreError::Codec(Error {
                    kind: ErrorKind::VersionMismatch { expected: 1, .. },
                    ..
                }),
                ..
            }
        )
    };
    assert!(mismatch(&e), "{e:?}");
    assert_eq!(present(&f, SENS), [1]);
    // Names that carry no older version (the default of FileNames::older): Sensor 1.0's value
    // is refused as another version, not translated.
    let layout = f.layout.as_layout();
    let data = store_file(
        2,
        &[SENS_LINE],
        &[&structured_record(0, 2, None, Some(&old))],
    );
    let checked = check(&data).unwrap();
    let e = apply(&mut f.store, &layout, &NAMES[..], &checked, true).unwrap_err();
    assert!(mismatch(&e), "{e:?}");
    // A value of the current version is stored as it is, even where the names answer for
    // every minor version the schema keeps, the current one included.
    struct EveryMinor(NodeId);
    impl FileNames for EveryMinor {
        fn name(&self, param: u32) -> Option<FileName<'_>> {
            NAMES.get(param as usize).copied()
        }
        fn older(&self, _param: u32, _minor: u32) -> Option<NodeId> {
            Some(self.0)
        }
    }
    // Address 0x22, disabled, offset 5 (0001 0100010 0 00101): translated, the last two
    // would take the default's.
    const OWN_FIELDS: [u8; 3] = [0x14, 0x42, 0x80];
    let data = store_file(
        2,
        &[SENS_LINE],
        &[&structured_record(0, 0, None, Some(&OWN_FIELDS))],
    );
    let checked = check(&data).unwrap();
    let names = EveryMinor(f.sensor_1_0);
    let records = apply(&mut f.store, &layout, &names, &checked, true).map(|a| a.records);
    assert_eq!(records, Ok(1));
    assert_eq!(f.store.get(SENS, 0, Which::Value).unwrap(), OWN_FIELDS);
}

#[test]
fn a_second_record_of_one_instance_is_refused_and_nothing_applied() {
    // The firmware's load took the last of two records of INA238#1 (the host refused it): a
    // file is one configuration, not a choice between two.
    let table = [SENS_LINE, TRIM_LINE];
    let one = structured_record(0, 1, None, Some(&ADDRESS_22));
    let again = structured_record(0, 1, None, None);
    let first = 10 + 2 + 2 * 19 + 2;
    let second = first + one.len() + 2;
    let cases = [
        store_file(2, &table, &[&one, &again]),
        store_file(
            2,
            &table,
            &[
                &classic_record("BAT_N_CELLS", 6),
                &classic_record("BAT_N_CELLS", 7),
            ],
        ),
        // The shared parameter's one slot.
        store_file(
            2,
            &table,
            &[
                &structured_record(1, 0, None, None),
                &structured_record(1, 0, None, None),
            ],
        ),
    ];
    for (case, data) in cases.iter().enumerate() {
        for clear in [false, true] {
            let mut f = fixture();
            f.store.add(SENS, Some(2)).unwrap();
            let e = applied(&mut f, data, clear).unwrap_err();
            let ApplyError::Twice { offset } = e else {
                panic!("case {case}: {e:?}")
            };
            assert_eq!(e.offset(), offset);
            assert!(
                offset > first && (case > 0 || offset == second),
                "case {case}"
            );
            assert_eq!(present(&f, SENS), [2]);
            assert!(f.store.slot(SENS, 2).unwrap().unsaved(), "not marked saved");
            // The marks are gone: the good half alone applies, on the same store, twice.
            let good = store_file(2, &table, &[&one]);
            assert_eq!(applied(&mut f, &good, clear).unwrap().records, 1);
            assert_eq!(applied(&mut f, &good, clear).unwrap().records, 1);
            assert_eq!(f.store.get(SENS, 1, Which::Value).unwrap(), ADDRESS_22);
        }
    }
}

#[test]
fn a_table_that_names_a_parameter_twice_is_refused() {
    // Records of both lines were one parameter's: the last one won, in the host and the
    // firmware alike.
    for table in [[SENS_LINE, SENS_LINE], [SENS_LINE, "SENS=test.Other.2"]] {
        let data = store_file(
            2,
            &table,
            &[
                &structured_record(0, 0, None, Some(&ADDRESS_22)),
                &structured_record(1, 0, None, None),
            ],
        );
        assert_eq!(
            refusal(&data),
            (
                FileErrorKind::TableTwice(b"SENS"),
                10,
                "record is malformed: the parameter table names 'SENS' twice".into()
            )
        );
    }
    // One name per line, however alike: accepted.
    let data = store_file(2, &[SENS_LINE, TRIM_LINE, "SENSOR=test.Sensor.1"], &[]);
    assert!(check(&data).is_ok());
}

#[test]
fn a_value_of_an_older_version_is_checked_whole_before_it_is_translated() {
    // Sensor 1.0 is 3 bytes: the translation read only the fields it carries over, so a cut
    // value (2 bytes) or one with bytes after it (the host refuses both) was taken.
    let old = [0x04, 0x41, 0x20];
    let long = [0x04, 0x41, 0x20, 0xDE, 0xAD];
    for (bytes, cut) in [(&old[..2], true), (&long[..], false)] {
        let data = store_file(
            2,
            &[SENS_LINE],
            &[&structured_record(0, 1, None, Some(bytes))],
        );
        for clear in [false, true] {
            let mut f = fixture();
            f.store.add(SENS, Some(2)).unwrap();
            let e = applied(&mut f, &data, clear).unwrap_err();
            let ApplyError::Refused {
                error: StoreError::Codec(codec),
                ..
            } = e
            else {
                panic!("{e:?}")
            };
            let refused = match codec.kind {
                ErrorKind::Truncated { .. } => cut,
                ErrorKind::TrailingBytes { .. } => !cut,
                _ => false,
            };
            assert!(refused, "{codec:?}");
            assert_eq!(present(&f, SENS), [2]);
        }
    }
}

#[test]
fn the_stored_minor_version_is_the_leading_p_version() {
    let f = fixture();
    let layout = f.layout.as_layout();
    let sensor = f.store.def(SENS).unwrap().root;
    assert_eq!(stored_minor(&layout, sensor, &SENS_DEFAULT), Some((1, 1)));
    assert_eq!(stored_minor(&layout, sensor, &[0x04]), Some((0, 1)));
    assert_eq!(stored_minor(&layout, sensor, &[0xF0]), Some((15, 1)));
    assert_eq!(stored_minor(&layout, sensor, &[]), None);
    assert_eq!(stored_minor(&layout, f.sensor_1_0, &[0x14]), Some((1, 0)));
    // A type without p_version, or one that is not a struct.
    let int32 = f.store.def(BAT_N_CELLS).unwrap().root;
    assert_eq!(stored_minor(&layout, int32, &[1, 0, 0, 0]), None);
    let mut l = OwnedLayout::default();
    let u8_ = l.uint(8, Saturated).unwrap();
    let u16_ = l.uint(16, Saturated).unwrap();
    let plain = l.structure(&[("level", u8_, Role::Data)]).unwrap();
    let wide = l
        .structure(&[("p_version", u16_, Role::Version(3))])
        .unwrap();
    let eight = l
        .structure(&[("p_version", u8_, Role::Version(3))])
        .unwrap();
    let view = l.as_layout();
    assert_eq!(stored_minor(&view, plain, &[0x10]), None);
    assert_eq!(stored_minor(&view, wide, &[3, 0]), None);
    assert_eq!(stored_minor(&view, eight, &[0x83]), Some((0x83, 3)));
    // Unused here, but the format's constants are the documented ones.
    assert_eq!(
        (
            file::MAGIC,
            file::FORMAT_VERSION,
            file::FORMAT_2,
            file::FORMAT_1
        ),
        (*b"PX4P", 3, 2, 1)
    );
    assert_eq!(file::CLASSIC_FLOAT, 0x40);
    assert_eq!(
        (file::HEADER_LEN, file::TRAILER_LEN, file::CLASSIC_NAME_MAX),
        (10, 4, 16)
    );
    let e = FileError {
        kind: FileErrorKind::LongNumber,
        offset: 3,
    };
    assert_eq!(e.offset, 3);
}
