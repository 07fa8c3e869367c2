//! The store file (`docs/store-format.md`): what differs from the defaults, one CRC-checked
//! record per instance, behind a table naming the structured parameters the records use.
//!
//! One implementation for the host and for firmware, over caller-provided buffers:
//! - [`check`] verifies a whole file (header, trailer CRC-32, the table and its fingerprint,
//!   every record's structure and CRC-16) before anything is read out of it;
//! - [`Writer`] writes a file record by record, [`write_store`] a [`Store`]'s content;
//! - [`apply`] puts a checked file into a store, all of it or (when any record is refused)
//!   nothing.
//!
//! The host keeps what needs a file system or a schema: atomic replace, backups, locking,
//! and translating values stored by an older minor version of their type.

use core::fmt;

use crate::bits::read_bits;
use crate::crc::{crc16, crc32};
use crate::layout::{Kind, Layout, NodeId, Role};
use crate::store::{ParamDef, Slot, Store, StoreError, Which};
use crate::translate::TranslateError;

/// The first four bytes of every store file.
pub const MAGIC: [u8; 4] = *b"PX4P";
/// The format version [`Writer`] writes: classic records carry their type
/// ([`CLASSIC_FLOAT`]).
pub const FORMAT_VERSION: u8 = 3;
/// Format 2: classic records without their type (read as the reading store's type).
pub const FORMAT_2: u8 = 2;
/// Format 1: no parameter table (records index the writer's whole parameter list).
pub const FORMAT_1: u8 = 1;
/// Record kind: a structured parameter's instance.
pub const KIND_STRUCTURED: u8 = 1;
/// Record kind: a classic parameter.
pub const KIND_CLASSIC: u8 = 2;
/// Record kind: the parameter table.
pub const KIND_TABLE: u8 = 3;
/// Record flag: the record holds a default.
pub const HAS_DEFAULT: u8 = 0x10;
/// Record flag: the record holds a value.
pub const HAS_VALUE: u8 = 0x20;
/// Classic record flag (format 3): the four bytes are a float32; without it, an int32.
pub const CLASSIC_FLOAT: u8 = 0x40;
/// Magic, version, flags and the table's fingerprint.
pub const HEADER_LEN: usize = 10;
/// The CRC-32 of everything before it.
pub const TRAILER_LEN: usize = 4;
/// A classic parameter's name is 1 to 16 characters (PX4's limit).
pub const CLASSIC_NAME_MAX: usize = 16;

const CRC16_SEED: u16 = 0xFFFF;

/// Why a file was refused, at [`FileError::offset`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum FileErrorKind<'a> {
    /// No `PX4P` header.
    NotAStoreFile,
    /// A format version this reader does not know.
    Version(u8),
    /// Shorter than a header and a trailer.
    NoTrailer,
    /// The trailer's CRC-32 does not match.
    Corrupted,
    /// Header flags other than 0.
    HeaderFlags(u8),
    /// The table's lines do not hash to the header's fingerprint.
    Fingerprint,
    /// A record's (or the table's) CRC-16 does not match.
    RecordCrc,
    /// A record runs past the end of the file.
    PastEnd,
    /// A number longer than five bytes.
    LongNumber,
    /// A file (format 2 or later) whose first record is not the table.
    TableFirst,
    /// A table entry with a byte above 127.
    TableNotAscii,
    /// A table entry that is not `NAME=TYPE.MAJOR`.
    TableEntry(&'a [u8]),
    /// A record's first byte with unknown flags (the whole byte).
    RecordFlags(u8),
    /// An instance number above 65535.
    Instance(u64),
    /// A second parameter table.
    SecondTable,
    /// An unknown record kind.
    RecordKind(u8),
    /// A classic record's name that is no PX4 parameter name (1 to [`CLASSIC_NAME_MAX`]
    /// upper-case letters, digits and `_`, a letter first).
    ClassicName(&'a [u8]),
    /// A parameter the table names twice (its `NAME`): records of both lines would be one
    /// parameter's.
    TableTwice(&'a [u8]),
}

/// A file refused by [`check`]: what and where (byte offset in the file).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FileError<'a> {
    /// What is wrong.
    pub kind: FileErrorKind<'a>,
    /// Byte offset of the problem (the start of the record it is in).
    pub offset: usize,
}

impl fmt::Display for FileError<'_> {
    /// One line, without the offset (the caller adds the file's name and the offset).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use FileErrorKind as K;
        let malformed =
            |f: &mut fmt::Formatter<'_>, what: &str| write!(f, "record is malformed: {what}");
        match self.kind {
            K::NotAStoreFile => f.write_str("not a px4params store file (no PX4P header)"),
            K::Version(v) => write!(
                f,
                "store file format version {v} (this px4params reads {FORMAT_1} to {FORMAT_VERSION})"
            ),
            K::NoTrailer => f.write_str("file is truncated (no trailer)"),
            K::Corrupted => f.write_str(
                "file is corrupted or truncated (CRC-32 mismatch); nothing was applied",
            ),
            K::HeaderFlags(flags) => write!(f, "unknown header flags 0x{flags:02x}"),
            K::Fingerprint => {
                f.write_str("the parameter table does not match the header's fingerprint")
            }
            K::RecordCrc => f.write_str("record is corrupted (CRC-16 mismatch)"),
            K::PastEnd => malformed(f, "it runs past the end of the file"),
            K::LongNumber => malformed(f, "a number is too long"),
            K::TableFirst => malformed(f, "a file of format 2 or later starts with its parameter table"),
            K::TableNotAscii => malformed(f, "a parameter table entry is not ASCII"),
            K::TableEntry(line) => {
                f.write_str("record is malformed: parameter table entry ")?;
                write_quoted(f, line)?;
                f.write_str(" is not NAME=TYPE.MAJOR")
            }
            K::RecordFlags(head) => write!(f, "record is malformed: unknown flags 0x{head:02x}"),
            K::Instance(n) => write!(f, "record is malformed: instance {n} is out of range"),
            K::SecondTable => malformed(f, "a second parameter table"),
            K::RecordKind(kind) => write!(f, "record is malformed: unknown record kind {kind}"),
            K::TableTwice(name) => {
                f.write_str("record is malformed: the parameter table names ")?;
                write_quoted(f, name)?;
                f.write_str(" twice")
            }
            K::ClassicName(name) => {
                f.write_str("record is malformed: classic parameter name ")?;
                write_quoted(f, name)?;
                write!(
                    f,
                    " is not 1 to {CLASSIC_NAME_MAX} upper-case letters, digits and '_', a \
                     letter first"
                )
            }
        }
    }
}

/// Whether `name` is a PX4 parameter name: 1 to [`CLASSIC_NAME_MAX`] upper-case letters,
/// digits and `_`, a letter first (what the classic parameters' list accepts).
fn is_classic_name(name: &[u8]) -> bool {
    match name.split_first() {
        Some((first, rest)) => {
            name.len() <= CLASSIC_NAME_MAX
                && first.is_ascii_uppercase()
                && rest
                    .iter()
                    .all(|&b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_')
        }
        None => false,
    }
}

/// ASCII text quoted as Python's `repr` quotes it (the message names the entry as it is).
fn write_quoted(f: &mut fmt::Formatter<'_>, text: &[u8]) -> fmt::Result {
    let quote = if text.contains(&b'\'') && !text.contains(&b'"') {
        '"'
    } else {
        '\''
    };
    write!(f, "{quote}")?;
    for &b in text {
        match b {
            b'\\' => f.write_str("\\\\")?,
            b'\t' => f.write_str("\\t")?,
            b'\n' => f.write_str("\\n")?,
            b'\r' => f.write_str("\\r")?,
            _ if b as char == quote => write!(f, "\\{quote}")?,
            0x20..=0x7E => write!(f, "{}", b as char)?,
            _ => write!(f, "\\x{b:02x}")?,
        }
    }
    write!(f, "{quote}")
}

/// What a classic parameter's four bytes are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClassicType {
    /// A little-endian int32 (PX4's `INT32`).
    Int32,
    /// A little-endian float32 (PX4's `FLOAT`).
    Float32,
}

/// A record's key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key<'a> {
    /// A structured parameter: its index in the file's table (format 2 and later), or in the
    /// writer's list of structured parameters (format 1).
    Structured(u64),
    /// A classic parameter: its name (a PX4 parameter name, checked), and its type (`None` in
    /// a format 1 or 2 file, which did not say).
    Classic(&'a [u8], Option<ClassicType>),
}

/// One checked record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Record<'a> {
    /// Byte offset of the record in the file.
    pub offset: usize,
    /// Whose record it is.
    pub key: Key<'a>,
    /// The instance number (0 for shared and classic parameters).
    pub instance: u16,
    /// The instance's default, when it differs from the type's.
    pub default: Option<&'a [u8]>,
    /// The value, when it differs from the default.
    pub value: Option<&'a [u8]>,
    /// The record's bytes without its CRC.
    pub raw: &'a [u8],
}

/// A file [`check`] verified completely.
#[derive(Clone, Copy, Debug)]
pub struct Checked<'a> {
    data: &'a [u8],
    /// Its format version (1 to [`FORMAT_VERSION`]).
    pub version: u8,
    /// The header's fingerprint: the CRC-32 of the table's lines joined with `\n`.
    pub fingerprint: u32,
    table: Option<usize>,
    records: usize,
    end: usize,
}

impl<'a> Checked<'a> {
    /// The parameter table's `NAME=TYPE.MAJOR` lines (none in a format 1 file).
    pub fn table(&self) -> TableLines<'a> {
        let mut reader = Reader::new(self.data, self.table.unwrap_or(0), self.end);
        let count = match self.table {
            Some(_) => reader.take(1).and_then(|_| reader.varint()).unwrap_or(0),
            None => 0,
        };
        TableLines { reader, count }
    }

    /// Whether the file has a parameter table (format 2 and later).
    pub fn has_table(&self) -> bool {
        self.table.is_some()
    }

    /// The records, in file order.
    pub fn records(&self) -> Records<'a> {
        Records {
            data: self.data,
            version: self.version,
            pos: self.records,
            end: self.end,
        }
    }
}

/// The lines of a checked file's parameter table.
#[derive(Clone, Debug)]
pub struct TableLines<'a> {
    reader: Reader<'a>,
    count: u64,
}

impl<'a> Iterator for TableLines<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        if self.count == 0 {
            return None;
        }
        self.count -= 1;
        let len = self.reader.varint().ok()?;
        let line = self.reader.take(len).ok()?;
        core::str::from_utf8(line).ok()
    }
}

/// The records of a checked file.
#[derive(Clone, Debug)]
pub struct Records<'a> {
    data: &'a [u8],
    version: u8,
    pos: usize,
    end: usize,
}

impl<'a> Iterator for Records<'a> {
    type Item = Record<'a>;

    fn next(&mut self) -> Option<Record<'a>> {
        if self.pos >= self.end {
            return None;
        }
        let (record, next) = read_record(self.data, self.version, self.pos, self.end).ok()?;
        self.pos = next;
        Some(record)
    }
}

/// Checks all of `data` and returns it as a [`Checked`] file.
pub fn check(data: &[u8]) -> Result<Checked<'_>, FileError<'_>> {
    let fail = |kind, offset| Err(FileError { kind, offset });
    if data.len() < HEADER_LEN || data[..4] != MAGIC {
        return fail(FileErrorKind::NotAStoreFile, 0);
    }
    let version = data[4];
    if !(FORMAT_1..=FORMAT_VERSION).contains(&version) {
        return fail(FileErrorKind::Version(version), 4);
    }
    if data.len() < HEADER_LEN + TRAILER_LEN {
        return fail(FileErrorKind::NoTrailer, data.len());
    }
    let end = data.len() - TRAILER_LEN;
    if crc32(0, &data[..end]) != u32::from_le_bytes(le4(&data[end..])) {
        return fail(FileErrorKind::Corrupted, end);
    }
    if data[5] != 0 {
        return fail(FileErrorKind::HeaderFlags(data[5]), 5);
    }
    let fingerprint = u32::from_le_bytes(le4(&data[6..]));
    let mut pos = HEADER_LEN;
    let mut table = None;
    if version >= FORMAT_2 {
        let mut reader = Reader::new(data, pos, end);
        let lines_crc = reader.table()?;
        check_crc16(data, pos, reader.pos)?;
        if lines_crc != fingerprint {
            return fail(FileErrorKind::Fingerprint, pos);
        }
        table = Some(pos);
        pos = reader.pos + 2;
    }
    let records = pos;
    while pos < end {
        let (_, next) = read_record(data, version, pos, end)?;
        pos = next;
    }
    let checked = Checked {
        data,
        version,
        fingerprint,
        table,
        records,
        end,
    };
    // A name twice: which line's records would hold? (Quadratic, without memory: a table
    // has a line per structured parameter, tens.)
    fn name(line: &str) -> &[u8] {
        line.split('=').next().unwrap_or(line).as_bytes()
    }
    for (i, line) in checked.table().enumerate() {
        if checked
            .table()
            .take(i)
            .any(|earlier| name(earlier) == name(line))
        {
            return fail(FileErrorKind::TableTwice(name(line)), table.unwrap_or(0));
        }
    }
    Ok(checked)
}

fn le4(bytes: &[u8]) -> [u8; 4] {
    let mut out = [0; 4];
    out.copy_from_slice(&bytes[..4]);
    out
}

/// The record at `pos` of a file of format `version`, with its CRC checked, and where the
/// next one starts.
fn read_record(
    data: &[u8],
    version: u8,
    pos: usize,
    end: usize,
) -> Result<(Record<'_>, usize), FileError<'_>> {
    let mut reader = Reader::new(data, pos, end);
    let record = reader.record(version)?;
    check_crc16(data, pos, reader.pos)?;
    Ok((record, reader.pos + 2))
}

fn check_crc16(data: &[u8], start: usize, end: usize) -> Result<(), FileError<'_>> {
    // The reader made sure two bytes follow.
    let stored = u16::from_le_bytes([data[end], data[end + 1]]);
    if crc16(CRC16_SEED, &data[start..end]) != stored {
        return Err(FileError {
            kind: FileErrorKind::RecordCrc,
            offset: start,
        });
    }
    Ok(())
}

/// Reads one record (or the table) starting at `start`, never past `end`.
#[derive(Clone, Debug)]
struct Reader<'a> {
    data: &'a [u8],
    start: usize,
    pos: usize,
    end: usize,
}

impl<'a> Reader<'a> {
    fn new(data: &'a [u8], pos: usize, end: usize) -> Self {
        Self {
            data,
            start: pos,
            pos,
            end,
        }
    }

    fn fail<T>(&self, kind: FileErrorKind<'a>) -> Result<T, FileError<'a>> {
        Err(FileError {
            kind,
            offset: self.start,
        })
    }

    fn take(&mut self, n: u64) -> Result<&'a [u8], FileError<'a>> {
        if n > (self.end - self.pos) as u64 {
            return self.fail(FileErrorKind::PastEnd);
        }
        let chunk = &self.data[self.pos..self.pos + n as usize];
        self.pos += n as usize;
        Ok(chunk)
    }

    fn byte(&mut self) -> Result<u8, FileError<'a>> {
        Ok(self.take(1)?[0])
    }

    /// LEB128, at most five bytes.
    fn varint(&mut self) -> Result<u64, FileError<'a>> {
        let mut value = 0u64;
        let mut shift = 0;
        loop {
            let byte = self.byte()?;
            value |= u64::from(byte & 0x7F) << shift;
            if byte & 0x80 == 0 {
                return Ok(value);
            }
            shift += 7;
            if shift > 28 {
                return self.fail(FileErrorKind::LongNumber);
            }
        }
    }

    fn two_more(&self) -> Result<(), FileError<'a>> {
        if self.pos + 2 > self.end {
            return self.fail(FileErrorKind::PastEnd);
        }
        Ok(())
    }

    /// The parameter table; returns the CRC-32 of its lines joined with `\n`.
    fn table(&mut self) -> Result<u32, FileError<'a>> {
        if self.byte()? != KIND_TABLE {
            return self.fail(FileErrorKind::TableFirst);
        }
        let mut lines_crc = 0;
        for i in 0..self.varint()? {
            let len = self.varint()?;
            let line = self.take(len)?;
            if !line.is_ascii() {
                return self.fail(FileErrorKind::TableNotAscii);
            }
            match line.iter().position(|&b| b == b'=') {
                Some(eq) if eq > 0 && eq + 1 < line.len() => {}
                _ => return self.fail(FileErrorKind::TableEntry(line)),
            }
            if i > 0 {
                lines_crc = crc32(lines_crc, b"\n");
            }
            lines_crc = crc32(lines_crc, line);
        }
        self.two_more()?;
        Ok(lines_crc)
    }

    fn record(&mut self, version: u8) -> Result<Record<'a>, FileError<'a>> {
        let head = self.byte()?;
        let (kind, flags) = (head & 0x0F, head & 0xF0);
        let typed = kind == KIND_CLASSIC && version >= FORMAT_VERSION;
        let known = HAS_DEFAULT | HAS_VALUE | if typed { CLASSIC_FLOAT } else { 0 };
        if flags & !known != 0 {
            return self.fail(FileErrorKind::RecordFlags(head));
        }
        let (key, instance, fixed) = match kind {
            KIND_CLASSIC => {
                let len = self.byte()?;
                let name = self.take(len.into())?;
                if !is_classic_name(name) {
                    return self.fail(FileErrorKind::ClassicName(name));
                }
                let ty = match flags & CLASSIC_FLOAT {
                    _ if !typed => None,
                    0 => Some(ClassicType::Int32),
                    _ => Some(ClassicType::Float32),
                };
                (Key::Classic(name, ty), 0, Some(4))
            }
            KIND_STRUCTURED => {
                let index = self.varint()?;
                let instance = self.varint()?;
                if instance > u64::from(u16::MAX) {
                    return self.fail(FileErrorKind::Instance(instance));
                }
                (Key::Structured(index), instance as u16, None)
            }
            KIND_TABLE => return self.fail(FileErrorKind::SecondTable),
            _ => return self.fail(FileErrorKind::RecordKind(kind)),
        };
        let mut payload = |flag: u8| -> Result<Option<&'a [u8]>, FileError<'a>> {
            if flags & flag == 0 {
                return Ok(None);
            }
            let len = match fixed {
                Some(n) => n,
                None => self.varint()?,
            };
            self.take(len).map(Some)
        };
        let default = payload(HAS_DEFAULT)?;
        let value = payload(HAS_VALUE)?;
        self.two_more()?;
        Ok(Record {
            offset: self.start,
            key,
            instance,
            default,
            value,
            raw: &self.data[self.start..self.pos],
        })
    }
}

// -- writing ------------------------------------------------------------------------------------

/// Why a file could not be written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum WriteError {
    /// The buffer is too small; the file needs at least this many bytes.
    BufferFull {
        /// Bytes needed so far (a lower bound of the whole).
        needed: usize,
    },
    /// A classic parameter's name is empty or longer than [`CLASSIC_NAME_MAX`].
    ClassicName,
}

impl fmt::Display for WriteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WriteError::BufferFull { needed } => {
                write!(
                    f,
                    "the store file needs more than the buffer's {needed} bytes"
                )
            }
            WriteError::ClassicName => write!(
                f,
                "a classic parameter's name must be 1 to {CLASSIC_NAME_MAX} characters"
            ),
        }
    }
}

/// Writes a store file into a caller's buffer: [`Writer::new`] writes the header and the
/// table, then records, then [`Writer::finish`] the trailer.
#[derive(Debug)]
pub struct Writer<'b> {
    buf: &'b mut [u8],
    len: usize,
}

impl<'b> Writer<'b> {
    /// Starts a file whose table holds `table`'s `NAME=TYPE.MAJOR` lines (records refer to
    /// them by position).
    pub fn new<'l, T>(buf: &'b mut [u8], table: T) -> Result<Self, WriteError>
    where
        T: IntoIterator<Item = &'l str>,
        T::IntoIter: Clone,
    {
        let lines = table.into_iter();
        let mut fingerprint = 0;
        let mut count = 0u64;
        for (i, line) in lines.clone().enumerate() {
            if i > 0 {
                fingerprint = crc32(fingerprint, b"\n");
            }
            fingerprint = crc32(fingerprint, line.as_bytes());
            count += 1;
        }
        let mut w = Self { buf, len: 0 };
        w.put(&MAGIC)?;
        w.put(&[FORMAT_VERSION, 0])?;
        w.put(&fingerprint.to_le_bytes())?;
        let start = w.len;
        w.put(&[KIND_TABLE])?;
        w.varint(count)?;
        for line in lines {
            w.varint(line.len() as u64)?;
            w.put(line.as_bytes())?;
        }
        w.crc16_from(start)?;
        Ok(w)
    }

    /// A structured parameter's record: `index` in the table, `instance` (0 when shared), the
    /// default if it differs from the type's, the value if it differs from the default.
    pub fn structured(
        &mut self,
        index: u32,
        instance: u16,
        default: Option<&[u8]>,
        value: Option<&[u8]>,
    ) -> Result<(), WriteError> {
        let start = self.len;
        self.put(&[KIND_STRUCTURED | flags(default, value)])?;
        self.varint(index.into())?;
        self.varint(instance.into())?;
        for payload in [default, value].into_iter().flatten() {
            self.varint(payload.len() as u64)?;
            self.put(payload)?;
        }
        self.crc16_from(start)
    }

    /// A classic parameter's record: its type, and values of four bytes each.
    pub fn classic(
        &mut self,
        name: &[u8],
        ty: ClassicType,
        default: Option<&[u8]>,
        value: Option<&[u8]>,
    ) -> Result<(), WriteError> {
        if name.is_empty() || name.len() > CLASSIC_NAME_MAX {
            return Err(WriteError::ClassicName);
        }
        let float = match ty {
            ClassicType::Int32 => 0,
            ClassicType::Float32 => CLASSIC_FLOAT,
        };
        let start = self.len;
        self.put(&[
            KIND_CLASSIC | float | flags(default, value),
            name.len() as u8,
        ])?;
        self.put(name)?;
        for payload in [default, value].into_iter().flatten() {
            self.put(payload)?;
        }
        self.crc16_from(start)
    }

    /// A record read from another file ([`Record::raw`]), written back as it was.
    pub fn raw(&mut self, record: &[u8]) -> Result<(), WriteError> {
        let start = self.len;
        self.put(record)?;
        self.crc16_from(start)
    }

    /// Writes the trailer; returns the file's length.
    pub fn finish(mut self) -> Result<usize, WriteError> {
        let crc = crc32(0, &self.buf[..self.len]);
        self.put(&crc.to_le_bytes())?;
        Ok(self.len)
    }

    fn put(&mut self, bytes: &[u8]) -> Result<(), WriteError> {
        let end = self.len + bytes.len();
        let Some(to) = self.buf.get_mut(self.len..end) else {
            return Err(WriteError::BufferFull { needed: end });
        };
        to.copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }

    fn varint(&mut self, mut n: u64) -> Result<(), WriteError> {
        loop {
            let byte = (n & 0x7F) as u8;
            n >>= 7;
            if n == 0 {
                return self.put(&[byte]);
            }
            self.put(&[byte | 0x80])?;
        }
    }

    fn crc16_from(&mut self, start: usize) -> Result<(), WriteError> {
        let crc = crc16(CRC16_SEED, &self.buf[start..self.len]);
        self.put(&crc.to_le_bytes())
    }
}

fn flags(default: Option<&[u8]>, value: Option<&[u8]>) -> u8 {
    (if default.is_some() { HAS_DEFAULT } else { 0 })
        | (if value.is_some() { HAS_VALUE } else { 0 })
}

// -- a store's file -----------------------------------------------------------------------------

/// How a store's parameter is named in its file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileName<'n> {
    /// A structured parameter: its table line, `NAME=TYPE.MAJOR` (`INA238=px.Ina238.1`).
    Structured(&'n str),
    /// A classic parameter: its name (`BAT1_CAPACITY`) and type; its values are 4 bytes.
    Classic(&'n str, ClassicType),
}

/// The names a store's parameters have in its file, by parameter index: a slice of
/// [`FileName`]s on a host, generated tables in firmware.
pub trait FileNames {
    /// Parameter `param`'s name (`None` past the last parameter).
    fn name(&self, param: u32) -> Option<FileName<'_>>;

    /// The root of minor version `minor` of parameter `param`'s type, when the layout has that
    /// older version: values it stored are translated on [`apply`].
    fn older(&self, _param: u32, _minor: u32) -> Option<NodeId> {
        None
    }
}

impl FileNames for [FileName<'_>] {
    fn name(&self, param: u32) -> Option<FileName<'_>> {
        self.get(param as usize).copied()
    }
}

/// Writes `store`'s content: for each parameter in `order` (indices into the store and into
/// `names`), a record per instance (a shared or classic parameter only when it differs from
/// its defaults); then `foreign`, records kept from a file that this store could not place.
/// Returns the file's length in `buf`.
pub fn write_store<'f, D, S, B, T>(
    store: &Store<D, S, B, T>,
    names: &(impl FileNames + ?Sized),
    order: &[u32],
    foreign: impl IntoIterator<Item = &'f [u8]>,
    buf: &mut [u8],
) -> Result<usize, SaveError>
where
    D: AsRef<[ParamDef]>,
    S: AsRef<[Slot]> + AsMut<[Slot]>,
    B: AsRef<[u8]> + AsMut<[u8]>,
    T: AsRef<[crate::table::LeafSlot]> + AsMut<[crate::table::LeafSlot]>,
{
    for &param in order {
        names.name(param).ok_or(SaveError::NoName { param })?;
        store.def(param).map_err(|_| SaveError::NoName { param })?;
    }
    // The table: the structured parameters that have records, in `order`.
    let has_records = |param: u32| match names.name(param) {
        None | Some(FileName::Classic(..)) => false,
        Some(FileName::Structured(_)) => {
            let shared = store.def(param).map(|d| d.shared).unwrap_or(false);
            let mut instances = store.instances(param).into_iter().flatten();
            match shared {
                false => instances.next().is_some(),
                true => instances.any(|i| differs(store, param, i) != (None, None)),
            }
        }
    };
    let table = order
        .iter()
        .filter(|&&p| has_records(p))
        .map(|&p| match names.name(p) {
            Some(FileName::Structured(line) | FileName::Classic(line, _)) => line,
            None => "",
        });
    let mut w = Writer::new(buf, table)?;
    let mut index = 0;
    for &param in order {
        let shared = store.def(param).map(|d| d.shared).unwrap_or(false);
        let instances = store.instances(param).into_iter().flatten();
        match names.name(param) {
            None => {}
            Some(FileName::Classic(name, ty)) => {
                for instance in instances {
                    let (default, value) = differs(store, param, instance);
                    if default.is_some() || value.is_some() {
                        w.classic(name.as_bytes(), ty, default, value)?;
                    }
                }
            }
            Some(FileName::Structured(_)) => {
                if !has_records(param) {
                    continue;
                }
                for instance in instances {
                    let (default, value) = differs(store, param, instance);
                    if shared && default.is_none() && value.is_none() {
                        continue;
                    }
                    w.structured(index, instance, default, value)?;
                }
                index += 1;
            }
        }
    }
    for record in foreign {
        w.raw(record)?;
    }
    Ok(w.finish()?)
}

/// An instance's default if it differs from its type's, and its value if it differs from its
/// default.
fn differs<D, S, B, T>(
    store: &Store<D, S, B, T>,
    param: u32,
    instance: u16,
) -> (Option<&[u8]>, Option<&[u8]>)
where
    D: AsRef<[ParamDef]>,
    S: AsRef<[Slot]> + AsMut<[Slot]>,
    B: AsRef<[u8]> + AsMut<[u8]>,
    T: AsRef<[crate::table::LeafSlot]> + AsMut<[crate::table::LeafSlot]>,
{
    let (Ok(value), Ok(default), Ok(type_default)) = (
        store.get(param, instance, Which::Value),
        store.get(param, instance, Which::Default),
        store.type_default(param),
    ) else {
        return (None, None);
    };
    (
        (default != type_default).then_some(default),
        (value != default).then_some(value),
    )
}

/// Why a store could not be saved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SaveError {
    /// The file does not fit the buffer, or a name cannot be written.
    Write(WriteError),
    /// `order` names a parameter the store or `names` does not have.
    NoName {
        /// Its index.
        param: u32,
    },
}

impl From<WriteError> for SaveError {
    fn from(e: WriteError) -> Self {
        SaveError::Write(e)
    }
}

impl fmt::Display for SaveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SaveError::Write(e) => e.fmt(f),
            SaveError::NoName { param } => write!(f, "no parameter #{param} to save"),
        }
    }
}

// -- applying -----------------------------------------------------------------------------------

/// Why a checked file could not be applied to a store (nothing of it was).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ApplyError {
    /// A format 1 file: only the host reads those (it knows the older parameter lists).
    Format1,
    /// A record of a structured parameter the store does not have under that table line
    /// (another type, another major version, or no such parameter).
    UnknownParameter {
        /// The record's offset in the file.
        offset: usize,
    },
    /// A second record of one parameter instance (or classic parameter): which would hold?
    Twice {
        /// The second record's offset in the file.
        offset: usize,
    },
    /// The store refused a record: an instance out of range, a value that does not decode,
    /// or one stored by another minor version of its type that the layout does not have (or
    /// that does not translate).
    Refused {
        /// The record's offset in the file.
        offset: usize,
        /// What the store said.
        error: StoreError<TranslateError>,
    },
}

impl ApplyError {
    /// The offset of the record it is about (0 for [`ApplyError::Format1`]).
    pub fn offset(&self) -> usize {
        match *self {
            ApplyError::Format1 => 0,
            ApplyError::UnknownParameter { offset }
            | ApplyError::Twice { offset }
            | ApplyError::Refused { offset, .. } => offset,
        }
    }
}

/// What [`apply`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Applied {
    /// Records applied.
    pub records: usize,
    /// Classic records of parameters the store does not have (left out).
    pub foreign: usize,
}

/// Applies a checked file to `store`: every record is checked against the store first; then,
/// with `clear`, the store is cleared ([`Store::clear`]: a load rather than a merge), all
/// records are written, and the store is marked saved. On an error nothing was written.
pub fn apply<D, S, B, T>(
    store: &mut Store<D, S, B, T>,
    layout: &Layout<'_>,
    names: &(impl FileNames + ?Sized),
    file: &Checked<'_>,
    clear: bool,
) -> Result<Applied, ApplyError>
where
    D: AsRef<[ParamDef]>,
    S: AsRef<[Slot]> + AsMut<[Slot]>,
    B: AsRef<[u8]> + AsMut<[u8]>,
    T: AsRef<[crate::table::LeafSlot]> + AsMut<[crate::table::LeafSlot]>,
{
    if !file.has_table() {
        return Err(ApplyError::Format1);
    }
    let mut applied = Applied::default();
    for pass in [Pass::Check, Pass::Write] {
        applied = Applied::default();
        if pass == Pass::Write && clear {
            store.clear();
        }
        for record in file.records() {
            let Some(param) = place(names, file, &record) else {
                match record.key {
                    Key::Classic(..) => applied.foreign += 1,
                    Key::Structured(_) => {
                        return Err(ApplyError::UnknownParameter {
                            offset: record.offset,
                        })
                    }
                }
                continue;
            };
            let refused = |error| ApplyError::Refused {
                offset: record.offset,
                error,
            };
            if let Err(error) = put(store, layout, names, param, &record, pass) {
                store.clear_filed();
                return Err(refused(error));
            }
            // Each record marks its slot (one the check found): a second one finds the mark.
            if pass == Pass::Check && store.mark_filed(param, record.instance) != Ok(false) {
                store.clear_filed();
                return Err(ApplyError::Twice {
                    offset: record.offset,
                });
            }
            applied.records += 1;
        }
        store.clear_filed();
    }
    store.mark_saved();
    Ok(applied)
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Pass {
    Check,
    Write,
}

/// The store's parameter a record is for. A classic record of another type than the
/// store's parameter of its name is for none: its bytes would be read as the other type.
fn place(
    names: &(impl FileNames + ?Sized),
    file: &Checked<'_>,
    record: &Record<'_>,
) -> Option<u32> {
    let table = match record.key {
        Key::Classic(..) => None,
        Key::Structured(index) => Some(file.table().nth(usize::try_from(index).ok()?)?),
    };
    (0..)
        .map_while(|p| Some((p, names.name(p)?)))
        .find(|(_, n)| match (*n, record.key) {
            (FileName::Structured(line), _) => Some(line) == table,
            (FileName::Classic(name, ty), Key::Classic(stored, stored_ty)) => {
                name.as_bytes() == stored && stored_ty.map_or(true, |s| s == ty)
            }
            (FileName::Classic(..), Key::Structured(_)) => false,
        })
        .map(|(p, _)| p)
}

fn put<D, S, B, T>(
    store: &mut Store<D, S, B, T>,
    layout: &Layout<'_>,
    names: &(impl FileNames + ?Sized),
    param: u32,
    record: &Record<'_>,
    pass: Pass,
) -> Result<(), StoreError<TranslateError>>
where
    D: AsRef<[ParamDef]>,
    S: AsRef<[Slot]> + AsMut<[Slot]>,
    B: AsRef<[u8]> + AsMut<[u8]>,
    T: AsRef<[crate::table::LeafSlot]> + AsMut<[crate::table::LeafSlot]>,
{
    let def = store.def(param).map_err(StoreError::widen)?;
    let instance = record.instance;
    let check = pass == Pass::Check;
    if check {
        if def.shared && instance != 0 {
            return Err(StoreError::NotPresent { instance });
        }
        if instance >= def.instances {
            return Err(StoreError::InstanceOutOfRange {
                instance: instance.into(),
                max_instances: def.instances,
            });
        }
    } else if !def.shared
        && !store
            .slot(param, instance)
            .map_err(StoreError::widen)?
            .present()
    {
        store
            .add(param, Some(instance))
            .map_err(StoreError::widen)?;
    }
    for (payload, which) in [
        (record.default, Which::Default),
        (record.value, Which::Value),
    ] {
        let Some(payload) = payload else { continue };
        // A value stored by an older minor version is translated, when the layout has it.
        let older = match stored_minor(layout, def.root, payload) {
            Some((stored, current)) if stored != current => names.older(param, stored),
            _ => None,
        };
        match (older, check) {
            (Some(old), _) => {
                store.set_translated(layout, param, instance, which, old, payload, check)?
            }
            (None, true) => store
                .check_value(layout, param, payload)
                .map_err(StoreError::widen)?,
            (None, false) => store
                .set_encoded(layout, param, instance, which, payload)
                .map_err(StoreError::widen)?,
        }
    }
    Ok(())
}

/// The minor version a stored value of `root` was written by (its leading `p_version`
/// field), and the current one; `None` for a type without `p_version`.
pub fn stored_minor(layout: &Layout<'_>, root: NodeId, payload: &[u8]) -> Option<(u32, u32)> {
    let first = layout.members(root).first()?;
    let Role::Version(current) = first.role else {
        return None;
    };
    match layout.node(first.node).kind {
        Kind::Uint { bits, .. } if bits <= 8 && !payload.is_empty() => {
            Some((read_bits(payload, 0, bits.into()) as u32, current))
        }
        _ => None,
    }
}
