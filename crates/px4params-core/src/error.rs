//! Codec errors: what went wrong, at which bit, along which field path. No allocation.

use core::fmt;

use crate::layout::Layout;
use crate::scalar::{Scalar, ScalarError};

/// Deepest field path an error remembers; deeper positions are cut (shown as `...`).
pub const MAX_PATH_DEPTH: usize = 12;

/// One step of a field path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// A struct field or union variant: its index in [`Layout::fields`].
    Field(u32),
    /// An array element.
    Index(u32),
}

// The flag marks fields, not indices: an unused step then holds the flag alone, so a new
// path is not all zero bytes and is made by a few stores, not a `memset` call (firmware
// then links no `memset`; see docs/firmware.md#size).
const FIELD_FLAG: u32 = 1 << 31;

/// A step in the 32 bits a [`Path`] keeps it in.
pub(crate) fn pack_step(step: Step) -> u32 {
    match step {
        Step::Field(f) => (f & !FIELD_FLAG) | FIELD_FLAG,
        Step::Index(i) => i & !FIELD_FLAG,
    }
}

/// The position of a value inside a type, e.g. `bus.i2c.address` or `cells[3]`.
///
/// Steps are packed in 32 bits each (the top bit tells a field from an array index) so that
/// errors stay small enough to return by value.
// Equality compares the steps the path holds (up to `depth`), not what popped steps left behind.
#[derive(Clone, Copy)]
pub struct Path {
    steps: [u32; MAX_PATH_DEPTH],
    depth: u32,
}

impl PartialEq for Path {
    fn eq(&self, other: &Self) -> bool {
        // Step by step: a slice comparison would bring `memcmp` into firmware for 48 bytes.
        let held = (self.depth as usize).min(MAX_PATH_DEPTH);
        let same = self.steps.iter().zip(&other.steps).take(held);
        self.depth == other.depth && same.fold(true, |all, (a, b)| all & (a == b))
    }
}

impl Eq for Path {}

// The steps the path holds and its depth: what popped steps left behind, or a new path's
// unused steps, are not part of it.
impl fmt::Debug for Path {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Path")
            .field("steps", &DebugSteps(self))
            .field("depth", &self.depth)
            .finish()
    }
}

struct DebugSteps<'a>(&'a Path);

impl fmt::Debug for DebugSteps<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.0.steps()).finish()
    }
}

impl Default for Path {
    /// The empty path (the value itself).
    #[inline]
    fn default() -> Self {
        Self {
            steps: unused_steps(),
            depth: 0,
        }
    }
}

/// The steps of an empty path. (Out of line, so that they are written where the path lies, not
/// made aside and copied there: a `memcpy` call, which firmware then links.)
#[inline(never)]
fn unused_steps() -> [u32; MAX_PATH_DEPTH] {
    [FIELD_FLAG; MAX_PATH_DEPTH]
}

impl Path {
    /// A path `depth` steps deep holding `steps` (packed by [`pack_step`]; those beyond
    /// `depth` are not read).
    #[inline]
    pub(crate) fn from_packed(depth: u32, steps: [u32; MAX_PATH_DEPTH]) -> Self {
        Self { steps, depth }
    }

    /// Appends a step (remembered only within [`MAX_PATH_DEPTH`]).
    #[inline]
    pub fn push(&mut self, step: Step) {
        if (self.depth as usize) < MAX_PATH_DEPTH {
            self.steps[self.depth as usize] = pack_step(step);
        }
        self.depth += 1;
    }

    /// Removes the last step.
    #[inline]
    pub fn pop(&mut self) {
        self.depth = self.depth.saturating_sub(1);
    }

    /// The remembered steps.
    pub fn steps(&self) -> impl Iterator<Item = Step> + '_ {
        self.steps[..(self.depth as usize).min(MAX_PATH_DEPTH)]
            .iter()
            .map(|&s| {
                if s & FIELD_FLAG != 0 {
                    Step::Field(s & !FIELD_FLAG)
                } else {
                    Step::Index(s)
                }
            })
    }

    /// The last step, if remembered.
    pub fn last(&self) -> Option<Step> {
        if self.depth == 0 || self.depth as usize > MAX_PATH_DEPTH {
            return None;
        }
        self.steps().last()
    }

    /// Whether the path is empty (the value itself).
    pub fn is_empty(&self) -> bool {
        self.depth == 0
    }

    /// Formats the path with field names from `layout`.
    pub fn display<'a>(&'a self, layout: &'a Layout<'a>) -> impl fmt::Display + 'a {
        PathDisplay { path: self, layout }
    }
}

struct PathDisplay<'a> {
    path: &'a Path,
    layout: &'a Layout<'a>,
}

impl fmt::Display for PathDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, step) in self.path.steps().enumerate() {
            match step {
                Step::Field(field) => {
                    if i > 0 {
                        f.write_str(".")?;
                    }
                    let name = self
                        .layout
                        .fields
                        .get(field as usize)
                        .map_or("?", |fl| self.layout.name(fl));
                    f.write_str(name)?;
                }
                Step::Index(index) => write!(f, "[{index}]")?,
            }
        }
        if self.path.depth as usize > MAX_PATH_DEPTH {
            f.write_str("...")?;
        }
        Ok(())
    }
}

/// What went wrong. `E` is the error type of the value source or sink (the Python binding's
/// carries the offending Python type's name; pure Rust uses [`Infallible`](core::convert::Infallible)
/// or [`crate::value::LeafError`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ErrorKind<E> {
    /// The data ends before the value does.
    Truncated {
        /// Bits the value needs at least.
        needed_bits: usize,
        /// Bits there are.
        available_bits: usize,
    },
    /// Whole bytes remain after the value.
    TrailingBytes {
        /// Length of the value in bytes.
        used: usize,
        /// Length of the data in bytes.
        len: usize,
    },
    /// A union tag that selects no variant.
    BadUnionTag {
        /// The tag read.
        tag: u64,
        /// Number of variants.
        variants: u32,
    },
    /// An array longer than its maximum (read from data or given as input).
    ArrayTooLong {
        /// The length found.
        len: u64,
        /// The maximum.
        max: u32,
    },
    /// A static array given with the wrong number of elements.
    WrongArrayLength {
        /// The length given.
        len: u64,
        /// The declared length.
        expected: u32,
    },
    /// The output buffer is smaller than the encoded value.
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
    },
    /// A scalar that does not fit its field.
    Scalar(ScalarError),
    /// A required field is missing from the input.
    MissingField,
    /// `p_version` given with another value than the type's version.
    VersionMismatch {
        /// The value given.
        given: Scalar,
        /// The type's version.
        expected: u32,
    },
    /// No leaf with this index.
    NoSuchLeaf {
        /// The index asked for.
        index: usize,
        /// Number of leaves of the value.
        count: usize,
    },
    /// No field with this name, or a path that does not parse.
    NoSuchPath,
    /// The path names a union variant other than the selected one.
    VariantNotSelected,
    /// The path ends at a struct, union or array instead of a leaf.
    NotALeaf,
    /// The layout nests deeper than the codec follows, or the small walk (firmware's) comes to
    /// a node or field the layout lacks (a malformed layout; an empty array never comes to its
    /// element's node).
    TooDeep,
    /// The value source or sink failed.
    Value(E),
}

impl<E> ErrorKind<E> {
    /// The same error with the value source's or sink's error turned into another kind.
    pub fn map_value<F>(self, f: impl FnOnce(E) -> ErrorKind<F>) -> ErrorKind<F> {
        match self {
            Self::Truncated {
                needed_bits,
                available_bits,
            } => ErrorKind::Truncated {
                needed_bits,
                available_bits,
            },
            Self::TrailingBytes { used, len } => ErrorKind::TrailingBytes { used, len },
            Self::BadUnionTag { tag, variants } => ErrorKind::BadUnionTag { tag, variants },
            Self::ArrayTooLong { len, max } => ErrorKind::ArrayTooLong { len, max },
            Self::WrongArrayLength { len, expected } => {
                ErrorKind::WrongArrayLength { len, expected }
            }
            Self::BufferTooSmall { needed } => ErrorKind::BufferTooSmall { needed },
            Self::Scalar(s) => ErrorKind::Scalar(s),
            Self::MissingField => ErrorKind::MissingField,
            Self::VersionMismatch { given, expected } => {
                ErrorKind::VersionMismatch { given, expected }
            }
            Self::NoSuchLeaf { index, count } => ErrorKind::NoSuchLeaf { index, count },
            Self::NoSuchPath => ErrorKind::NoSuchPath,
            Self::VariantNotSelected => ErrorKind::VariantNotSelected,
            Self::NotALeaf => ErrorKind::NotALeaf,
            Self::TooDeep => ErrorKind::TooDeep,
            Self::Value(e) => f(e),
        }
    }
}

/// A codec error: what, where in the data, and where in the type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Error<E> {
    /// What went wrong.
    pub kind: ErrorKind<E>,
    /// Bit offset in the encoded data where it went wrong.
    pub bit_offset: usize,
    /// Field path where it went wrong.
    pub path: Path,
}

impl<E: fmt::Display> Error<E> {
    /// Formats the error as one line, with field names from `layout`.
    pub fn display<'a>(&'a self, layout: &'a Layout<'a>) -> impl fmt::Display + 'a {
        ErrorDisplay {
            error: self,
            layout,
        }
    }
}

struct ErrorDisplay<'a, E> {
    error: &'a Error<E>,
    layout: &'a Layout<'a>,
}

impl<E: fmt::Display> fmt::Display for ErrorDisplay<'_, E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.error.path.is_empty() {
            write!(f, "{}: ", self.error.path.display(self.layout))?;
        }
        self.error.kind.fmt(f)
    }
}

fn fmt_scalar(f: &mut fmt::Formatter<'_>, s: &Scalar) -> fmt::Result {
    match s {
        Scalar::Uint(v) => write!(f, "{v}"),
        Scalar::Int(v) => write!(f, "{v}"),
        // Beyond 16 digits or below 1e-5 with an exponent (`1e300`, not 301 digits).
        Scalar::Float(v) if *v != 0.0 && !(1e-5..1e16).contains(&v.abs()) => write!(f, "{v:e}"),
        Scalar::Float(v) => write!(f, "{v}"),
        Scalar::Bool(v) => write!(f, "{v}"),
    }
}

impl<E: fmt::Display> fmt::Display for ErrorKind<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Truncated {
                needed_bits,
                available_bits,
            } => write!(
                f,
                "data is truncated: needs at least {needed_bits} bits, has {available_bits}"
            ),
            Self::TrailingBytes { used, len } => write!(
                f,
                "data is too long: the value ends after {used} bytes, the data has {len}"
            ),
            Self::BadUnionTag { tag, variants } => write!(
                f,
                "union tag {tag} selects no variant (expected 0..{})",
                variants.saturating_sub(1)
            ),
            Self::ArrayTooLong { len, max } => {
                write!(f, "array has {len} elements, at most {max} allowed")
            }
            Self::WrongArrayLength { len, expected } => {
                write!(f, "array has {len} elements, expected exactly {expected}")
            }
            Self::BufferTooSmall { needed } => {
                write!(f, "output buffer too small: {needed} bytes needed")
            }
            Self::Scalar(ScalarError::OutOfRange { value, min, max }) => {
                f.write_str("value ")?;
                fmt_scalar(f, value)?;
                f.write_str(" is out of range (expected ")?;
                fmt_scalar(f, min)?;
                f.write_str(" to ")?;
                fmt_scalar(f, max)?;
                f.write_str(")")
            }
            Self::Scalar(ScalarError::WrongKind { expected }) => write!(f, "expected {expected}"),
            Self::Scalar(ScalarError::NotFinite { value }) => {
                f.write_str("value ")?;
                fmt_scalar(f, value)?;
                match value {
                    Scalar::Float(v) if !v.is_finite() => f.write_str(" is not a finite number")?,
                    _ => f.write_str(" becomes an infinity in this field")?,
                }
                f.write_str(" (a store keeps no NaN or infinity)")
            }
            Self::MissingField => f.write_str("missing field"),
            Self::VersionMismatch { given, expected } => {
                f.write_str("p_version is set automatically; got ")?;
                fmt_scalar(f, given)?;
                write!(f, ", the type's version is {expected}")
            }
            Self::NoSuchLeaf { index, count } => write!(
                f,
                "no leaf [{index}] (the value has {count} leaves: [0]..[{}])",
                count.saturating_sub(1)
            ),
            Self::NoSuchPath => f.write_str("no such field"),
            Self::VariantNotSelected => f.write_str("this union variant is not the selected one"),
            Self::NotALeaf => f.write_str("not a leaf (a struct, union or array)"),
            Self::TooDeep => f.write_str("type nests too deeply"),
            Self::Value(e) => e.fmt(f),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::format;
    use std::string::ToString;
    use std::vec::Vec;

    fn path(steps: &[Step]) -> Path {
        let mut path = Path::default();
        for &step in steps {
            path.push(step);
        }
        path
    }

    #[test]
    fn floats_in_messages_take_an_exponent_beyond_16_digits_or_below_1e_5() {
        let shown = |v: f64| {
            let e: ErrorKind<core::convert::Infallible> =
                ErrorKind::Scalar(ScalarError::NotFinite {
                    value: Scalar::Float(v),
                });
            e.to_string()
        };
        let cases = [
            (1e300, "1e300"),
            (-1.5e16, "-1.5e16"),
            (65505.0, "65505"),
            (0.00001, "0.00001"),
            (2.5e-6, "2.5e-6"),
            (0.0, "0"),
        ];
        for (v, text) in cases {
            assert!(
                shown(v).starts_with(&format!("value {text} ")),
                "{v}: {}",
                shown(v)
            );
        }
    }

    #[test]
    fn steps_come_back_as_pushed_at_the_edges_of_31_bits() {
        let edges = [0, 1, 0x7FFF_FFFE, 0x7FFF_FFFF];
        let steps: Vec<Step> = edges
            .iter()
            .flat_map(|&n| [Step::Field(n), Step::Index(n)])
            .collect();
        let held = path(&steps);
        assert_eq!(held.steps().collect::<Vec<_>>(), steps);
        // The top bit is the kind's: a 32-bit value keeps its low 31 bits, as before.
        let cut = path(&[Step::Field(0x8000_0005), Step::Index(0xFFFF_FFFF)]);
        let kept = [Step::Field(5), Step::Index(0x7FFF_FFFF)];
        assert_eq!(cut.steps().collect::<Vec<_>>(), kept);
    }

    #[test]
    fn a_new_path_is_empty_and_equal_to_a_packed_empty_one() {
        let new = Path::default();
        assert!(new.is_empty());
        assert_eq!(new.last(), None);
        assert_eq!(new.steps().count(), 0);
        assert_eq!(new, Path::from_packed(0, [0; MAX_PATH_DEPTH]));
        // A field and an index 0 differ, pushed or packed.
        let field = path(&[Step::Field(0)]);
        let index = path(&[Step::Index(0)]);
        assert_ne!(field, index);
        let mut packed = [0; MAX_PATH_DEPTH];
        packed[0] = pack_step(Step::Index(0));
        assert_eq!(Path::from_packed(1, packed), index);
        packed[0] = pack_step(Step::Field(0));
        assert_eq!(Path::from_packed(1, packed), field);
    }

    #[test]
    fn popped_steps_are_not_part_of_a_path() {
        let mut popped = path(&[Step::Field(3), Step::Index(9)]);
        popped.pop();
        assert_eq!(popped, path(&[Step::Field(3)]));
        assert_eq!(popped.last(), Some(Step::Field(3)));
        assert_eq!(
            format!("{popped:?}"),
            "Path { steps: [Field(3)], depth: 1 }"
        );
    }

    #[test]
    fn a_path_deeper_than_it_holds_keeps_its_depth_and_is_shown_cut() {
        let layout = Layout {
            nodes: &[],
            fields: &[crate::layout::Field {
                name_start: 0,
                name_len: 1,
                node: 0,
                role: crate::layout::Role::Data,
            }],
            names: "x",
            segments: &[],
            flat: &[],
            straight: &[],
        };
        let mut deep = Path::default();
        for _ in 0..MAX_PATH_DEPTH + 2 {
            deep.push(Step::Field(0));
        }
        assert_eq!(deep.last(), None);
        assert_eq!(deep.steps().count(), MAX_PATH_DEPTH);
        assert_eq!(
            deep.display(&layout).to_string(),
            "x.x.x.x.x.x.x.x.x.x.x.x..."
        );
        deep.pop();
        deep.pop();
        assert_eq!(deep.last(), Some(Step::Field(0)));
        deep.pop();
        deep.push(Step::Index(7));
        assert_eq!(
            deep.display(&layout).to_string(),
            "x.x.x.x.x.x.x.x.x.x.x[7]"
        );
    }
}
