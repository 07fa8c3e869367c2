//! Translating a stored value from one version of its type to another (both in one layout):
//! fields are carried over by name, fields the new version added take their values from a
//! base value (the instance's default), and fields it no longer has are dropped.
//!
//! The new value is encoded in one pass: a [`Source`] walks the new type and reads each leaf
//! it needs from the old data (by path, where the old type has a field of that name) or from
//! the base. A union keeps its variant when the new type has one of that name; an array is
//! carried whole. `p_version` fields take the new version. Each carried, new and dropped
//! field is reported by path, in the new type's order (dropped ones where their struct ends).

use crate::bits::BitRead;
use crate::codec::{self, EncodeOptions, Source};
use crate::error::Error;
use crate::layout::{Field, Kind, Layout, NodeId, Role};
use crate::leaf::{self, Target};
use crate::plan::{Active, Plans};
pub use crate::rules::{TranslateError, PATH_MAX};
use crate::scalar::Scalar;

/// What happened to a field, by its dotted path in the new type (dropped: in the old type).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change<'p> {
    /// Carried over from the old value (a leaf, or a whole array).
    Kept(&'p str),
    /// Added by the new type: taken from the base.
    New(&'p str),
    /// The old type's field (or union variant) the new one does not have, or has as another
    /// kind of value (a struct where there was a number).
    Dropped(&'p str),
}

#[derive(Clone, Copy)]
enum What {
    Kept,
    New,
    Dropped,
}

const DEPTH_MAX: usize = crate::codec::MAX_DEPTH * 2;

/// Encodes into `out` the value of type `new` that `old_data` (a value of type `old`, stored
/// without tail array optimization) becomes, with what `new` added taken from `base` (a value
/// of `new`, same encoding); reports each field's fate to `changes`. Returns the length.
pub fn translate<R: BitRead + ?Sized, B: BitRead + ?Sized>(
    layout: &Layout<'_>,
    old: NodeId,
    old_data: &R,
    new: NodeId,
    base: &B,
    out: &mut [u8],
    changes: &mut dyn FnMut(Change<'_>),
) -> core::result::Result<usize, Error<TranslateError>> {
    let mut source = Merge {
        layout,
        old_root: old,
        old_data,
        new_root: new,
        base,
        changes,
        path: PathBuf::default(),
        frames: [Frame::EMPTY; DEPTH_MAX],
        depth: 1,
    };
    source.frames[0] = Frame {
        old: Some(old),
        report: true,
        mark: 0,
    };
    let options = EncodeOptions {
        tao: false,
        saturate: false,
        keep_versions: false,
    };
    codec::encode(layout, new, &mut source, out, options)
}

/// [`translate`] without the report: what a store does with an older version's value, with
/// the build's [`crate::plan::Active`] plans (see [`translate_value_with`]).
pub fn translate_value<R: BitRead + ?Sized, B: BitRead + ?Sized>(
    layout: &Layout<'_>,
    old: NodeId,
    old_data: &R,
    new: NodeId,
    base: &B,
    out: &mut [u8],
) -> core::result::Result<usize, Error<TranslateError>> {
    translate_value_with::<Active, R, B>(layout, old, old_data, new, base, out)
}

/// [`translate_value`] with the plans `P`: the path-keeping translator
/// ([`Plans::TRANSLATE`]) answers or declines, and [`crate::walk`] answers what it declines
/// (the same bytes; every error worded by the walk).
pub fn translate_value_with<P: Plans, R: BitRead + ?Sized, B: BitRead + ?Sized>(
    layout: &Layout<'_>,
    old: NodeId,
    old_data: &R,
    new: NodeId,
    base: &B,
    out: &mut [u8],
) -> core::result::Result<usize, Error<TranslateError>> {
    if P::TRANSLATE {
        // The plan answers or declines: any fault is worded by the walk.
        if let Ok(n) = translate(layout, old, old_data, new, base, out, &mut |_| {}) {
            return Ok(n);
        }
    }
    crate::walk::translate(layout, old, old_data, new, base, out)
}

/// A dotted path being built, in a fixed buffer.
#[derive(Clone, Copy)]
struct PathBuf {
    bytes: [u8; PATH_MAX],
    len: usize,
}

impl Default for PathBuf {
    fn default() -> Self {
        Self {
            bytes: [0; PATH_MAX],
            len: 0,
        }
    }
}

impl PathBuf {
    fn as_str(&self) -> &str {
        // Only field names (ASCII identifiers), dots, brackets and digits are ever pushed.
        core::str::from_utf8(&self.bytes[..self.len]).unwrap_or("")
    }
}

impl PathBuf {
    // By hand rather than with `core::fmt`, which would cost firmware kilobytes of code.
    fn push(&mut self, s: &str) -> Result<()> {
        let end = self.len + s.len();
        let to = self
            .bytes
            .get_mut(self.len..end)
            .ok_or(TranslateError::PathTooLong)?;
        to.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }

    fn push_index(&mut self, index: usize) -> Result<()> {
        let mut digits = [0u8; 20];
        let mut at = digits.len();
        let mut n = index;
        loop {
            at -= 1;
            digits[at] = b'0' + (n % 10) as u8;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        self.push("[")?;
        self.push(core::str::from_utf8(&digits[at..]).unwrap_or("0"))?;
        self.push("]")
    }
}

/// Where the walk over the new type stands: the old type's node at the same path (None where
/// the old value has nothing there), whether to report what is found, and the path's length
/// to go back to.
#[derive(Clone, Copy)]
struct Frame {
    old: Option<NodeId>,
    report: bool,
    mark: usize,
}

impl Frame {
    const EMPTY: Frame = Frame {
        old: None,
        report: false,
        mark: 0,
    };
}

struct Merge<'l, 'a, 'c, R: ?Sized, B: ?Sized> {
    layout: &'l Layout<'a>,
    old_root: NodeId,
    old_data: &'l R,
    new_root: NodeId,
    base: &'l B,
    changes: &'c mut dyn FnMut(Change<'_>),
    path: PathBuf,
    frames: [Frame; DEPTH_MAX],
    depth: usize,
}

type Result<T> = core::result::Result<T, TranslateError>;

impl<R: BitRead + ?Sized, B: BitRead + ?Sized> Merge<'_, '_, '_, R, B> {
    fn top(&self) -> Frame {
        self.frames[self.depth - 1]
    }

    /// Goes down to `name` (a field or variant; `""` stays at the path) or, with `index`, to
    /// an element.
    fn enter(
        &mut self,
        old: Option<NodeId>,
        report: bool,
        name: &str,
        index: Option<usize>,
    ) -> Result<()> {
        if self.depth >= DEPTH_MAX {
            return Err(TranslateError::PathTooLong);
        }
        let mark = self.path.len;
        match index {
            Some(i) => self.path.push_index(i)?,
            None if name.is_empty() => {}
            None => {
                if self.path.len > 0 {
                    self.path.push(".")?;
                }
                self.path.push(name)?;
            }
        }
        self.frames[self.depth] = Frame { old, report, mark };
        self.depth += 1;
        Ok(())
    }

    fn leave(&mut self) {
        if self.depth > 1 {
            self.depth -= 1;
            self.path.len = self.frames[self.depth].mark;
        }
    }

    fn report(&mut self, what: What) {
        let path = self.path.as_str();
        (self.changes)(match what {
            What::Kept => Change::Kept(path),
            What::New => Change::New(path),
            What::Dropped => Change::Dropped(path),
        });
    }

    /// The old value's leaf at the current path with `suffix` (`._tag`, `._len`).
    fn old_leaf(&self, suffix: &str) -> Result<Scalar> {
        read(
            self.layout,
            self.old_root,
            self.old_data,
            &self.path,
            suffix,
        )
    }

    fn base_leaf(&self, suffix: &str) -> Result<Scalar> {
        read(self.layout, self.new_root, self.base, &self.path, suffix)
    }

    /// The old node's member called `name`, if the old node is a struct or union.
    fn old_member(&self, name: &str) -> Option<&Field> {
        let old = self.top().old?;
        let index = self.layout.member_index(old, name)?;
        self.layout.fields.get(index as usize)
    }
}

fn read<D: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &D,
    path: &PathBuf,
    suffix: &str,
) -> Result<Scalar> {
    let mut full = *path;
    full.push(suffix)?;
    let target = Target::Path(full.as_str().trim_start_matches('.'));
    leaf::get_leaf(layout, root, data, target, false)
        .map(|(_, v)| v)
        .map_err(|_| TranslateError::Unreadable)
}

/// What a node holds, for telling a field that changed its kind of value.
#[derive(PartialEq, Eq)]
enum Shape {
    Scalar,
    Struct,
    Union,
    Array,
    Void,
}

fn shape(kind: Kind) -> Shape {
    match kind {
        Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool => Shape::Scalar,
        Kind::Struct { .. } => Shape::Struct,
        Kind::Union { .. } => Shape::Union,
        Kind::Array { .. } | Kind::DynArray { .. } => Shape::Array,
        Kind::Void { .. } => Shape::Void,
    }
}

impl<R: BitRead + ?Sized, B: BitRead + ?Sized> Source for Merge<'_, '_, '_, R, B> {
    type Error = TranslateError;

    fn scalar(&mut self, _kind: Kind) -> Result<Scalar> {
        let frame = self.top();
        let carried = matches!(
            frame.old.map(|o| shape(self.layout.node(o).kind)),
            Some(Shape::Scalar)
        );
        if carried {
            if frame.report {
                self.report(What::Kept);
            }
            self.old_leaf("")
        } else {
            self.base_leaf("")
        }
    }

    fn begin_struct(&mut self) -> Result<()> {
        Ok(())
    }

    fn field(&mut self, index: u32, name: &str) -> Result<bool> {
        let layout = self.layout;
        let field = layout.fields[index as usize];
        if let Role::Version(_) = field.role {
            return Ok(false); // the encoder writes the new version
        }
        let frame = self.top();
        let new_shape = shape(layout.node(field.node).kind);
        let (old, report) = match (frame.old, self.old_member(name).copied()) {
            (Some(_), Some(f)) if shape(layout.node(f.node).kind) == new_shape => {
                (Some(f.node), frame.report)
            }
            (Some(_), Some(_)) => (None, false), // another kind of value: dropped below
            (Some(_), None) => (None, false),    // new in this version
            (None, _) => (None, false),
        };
        let changed_kind = frame.old.is_some() && old.is_none() && self.old_member(name).is_some();
        let added = frame.old.is_some() && self.old_member(name).is_none();
        self.enter(old, report, name, None)?;
        if frame.report && changed_kind {
            self.report(What::Dropped);
        }
        if frame.report && added {
            self.report(What::New);
        }
        Ok(true)
    }

    fn end_field(&mut self) {
        self.leave();
    }

    fn end_struct(&mut self, layout: &Layout<'_>, fields: &[Field], _: usize) -> Result<()> {
        // The old struct's fields the new one does not have.
        let frame = self.top();
        let Some(old) = frame.old.filter(|_| frame.report) else {
            return Ok(());
        };
        for f in layout.members(old) {
            let name = layout.name(f);
            if f.role != Role::Data || fields.iter().any(|n| layout.name(n) == name) {
                continue;
            }
            self.enter(None, false, name, None)?;
            self.report(What::Dropped);
            self.leave();
        }
        Ok(())
    }

    fn begin_union(&mut self, layout: &Layout<'_>, variants: &[Field]) -> Result<u32> {
        let frame = self.top();
        if let Some(old) = frame.old {
            let tag = self.old_leaf("._tag")?;
            let old_variant = match tag {
                Scalar::Uint(t) => layout.members(old).get(t as usize),
                _ => None,
            };
            if let Some(v) = old_variant {
                let name = layout.name(v);
                let same = |n: &Field| {
                    layout.name(n) == name
                        && shape(layout.node(n.node).kind) == shape(layout.node(v.node).kind)
                };
                if let Some(i) = variants.iter().position(same) {
                    self.enter(Some(v.node), frame.report, name, None)?;
                    return Ok(i as u32);
                }
                // The new type has no such variant (or holds another kind of value in it):
                // dropped, and the base's variant instead.
                self.enter(None, false, name, None)?;
                if frame.report {
                    self.report(What::Dropped);
                }
                self.leave();
            }
        }
        let tag = match self.base_leaf("._tag")? {
            Scalar::Uint(t) => t as u32,
            _ => 0,
        };
        let name = variants.get(tag as usize).map_or("", |v| layout.name(v));
        self.enter(None, false, name, None)?;
        Ok(tag)
    }

    fn end_union(&mut self) {
        self.leave();
    }

    fn begin_array(&mut self, fixed: Option<u32>) -> Result<usize> {
        let frame = self.top();
        let old_len = match frame.old.map(|o| self.layout.node(o).kind) {
            Some(Kind::Array { len, .. }) => Some(len as usize),
            Some(Kind::DynArray { .. }) => match self.old_leaf("._len")? {
                Scalar::Uint(n) => Some(n as usize),
                _ => None,
            },
            _ => None,
        };
        if old_len.is_some() && frame.report {
            self.report(What::Kept); // the whole array
        }
        let len = match (old_len, fixed) {
            (Some(n), _) => n,
            (None, Some(n)) => n as usize,
            (None, None) => match self.base_leaf("._len")? {
                Scalar::Uint(n) => n as usize,
                _ => 0,
            },
        };
        // Elements are read at `PATH[i]`, from the old array if it had one.
        let elem = match frame.old.map(|o| self.layout.node(o).kind) {
            Some(Kind::Array { elem, .. } | Kind::DynArray { elem, .. }) => Some(elem),
            _ => None,
        };
        self.enter(elem, false, "", None)?;
        Ok(len)
    }

    fn element(&mut self, index: usize) -> Result<()> {
        let frame = self.top();
        self.enter(frame.old, false, "", Some(index))
    }

    fn end_element(&mut self) {
        self.leave();
    }

    fn end_array(&mut self) {
        self.leave();
    }
}
