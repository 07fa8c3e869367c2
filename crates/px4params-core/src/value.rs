//! A value as its flat list of leaves (see [`crate::leaf`] for the numbering), held in
//! caller-provided storage: the representation firmware and the Rust store work with.

use crate::layout::{Field, Kind, Layout};
pub use crate::rules::LeafError;
use crate::rules::{ArrayLen, At, Sink, Source};
use crate::scalar::Scalar;

/// Reads a value from a leaf list, for [`crate::codec::encode`].
#[derive(Debug)]
pub struct LeafSource<'a> {
    leaves: &'a [Scalar],
    next: usize,
}

impl<'a> LeafSource<'a> {
    /// A source over `leaves`.
    pub fn new(leaves: &'a [Scalar]) -> Self {
        Self { leaves, next: 0 }
    }

    /// Leaves consumed so far.
    pub fn consumed(&self) -> usize {
        self.next
    }

    #[inline]
    fn take(&mut self) -> Result<Scalar, LeafError> {
        let v = *self.leaves.get(self.next).ok_or(LeafError::Exhausted)?;
        self.next += 1;
        Ok(v)
    }

    fn count(&mut self) -> Result<u64, LeafError> {
        match self.take()? {
            Scalar::Uint(v) => Ok(v),
            Scalar::Int(v) if v >= 0 => Ok(v as u64),
            _ => Err(LeafError::NotACount),
        }
    }
}

impl Source for LeafSource<'_> {
    type Error = LeafError;
    const FLAT: bool = true;

    #[inline]
    fn leaf_run(&mut self, n: usize) -> Option<Result<&[Scalar], LeafError>> {
        let run = self.leaves.get(self.next..self.next + n);
        if run.is_some() {
            self.next += n;
        }
        Some(run.ok_or(LeafError::Exhausted))
    }

    #[inline]
    fn pending_leaves(&self) -> Option<&[Scalar]> {
        self.leaves.get(self.next..)
    }

    #[inline]
    fn scalar(&mut self, _kind: Kind) -> Result<Scalar, LeafError> {
        self.take()
    }
    fn begin_struct(&mut self) -> Result<(), LeafError> {
        Ok(())
    }
    fn field(&mut self, _index: u32, _name: &str) -> Result<bool, LeafError> {
        Ok(true)
    }
    fn end_field(&mut self) {}
    fn end_struct(&mut self, _: &Layout<'_>, _: &[Field], _used: usize) -> Result<(), LeafError> {
        Ok(())
    }
    fn begin_union(&mut self, _layout: &Layout<'_>, _variants: &[Field]) -> Result<u32, LeafError> {
        Ok(u32::try_from(self.count()?).unwrap_or(u32::MAX))
    }
    fn end_union(&mut self) {}
    fn begin_array(&mut self, fixed: Option<u32>) -> Result<usize, LeafError> {
        match fixed {
            Some(len) => Ok(len as usize),
            None => Ok(usize::try_from(self.count()?).unwrap_or(usize::MAX)),
        }
    }
    fn element(&mut self, _index: usize) -> Result<(), LeafError> {
        Ok(())
    }
    fn end_element(&mut self) {}
    fn end_array(&mut self) {}
}

/// Collects a decoded value's leaves into caller-provided storage.
#[derive(Debug)]
pub struct LeafSink<'a> {
    leaves: &'a mut [Scalar],
    len: usize,
    depth: usize,
    // A tail-optimized array is always the last thing in a value, so one pending slot suffices.
    tail_slot: Option<(usize, usize)>,
}

impl<'a> LeafSink<'a> {
    /// A sink writing into `storage`.
    pub fn new(storage: &'a mut [Scalar]) -> Self {
        Self {
            leaves: storage,
            len: 0,
            depth: 0,
            tail_slot: None,
        }
    }

    /// The leaves collected.
    pub fn leaves(&self) -> &[Scalar] {
        &self.leaves[..self.len]
    }

    #[inline]
    fn push(&mut self, v: Scalar) -> Result<(), LeafError> {
        *self.leaves.get_mut(self.len).ok_or(LeafError::Full)? = v;
        self.len += 1;
        Ok(())
    }
}

impl Sink for LeafSink<'_> {
    type Error = LeafError;
    const FLAT: bool = true;

    #[inline]
    fn leaf_slots(&mut self, n: usize) -> Option<Result<&mut [Scalar], LeafError>> {
        let start = self.len;
        match self.leaves.get_mut(start..start + n) {
            Some(slots) => {
                self.len += n;
                Some(Ok(slots))
            }
            None => Some(Err(LeafError::Full)),
        }
    }

    #[inline]
    fn scalar(&mut self, value: Scalar, _at: At<'_>) -> Result<(), LeafError> {
        self.push(value)
    }
    fn begin_struct(&mut self, _fields: usize) -> Result<(), LeafError> {
        Ok(())
    }
    fn field(&mut self, _index: u32, _name: &str) -> Result<(), LeafError> {
        Ok(())
    }
    fn end_struct(&mut self) -> Result<(), LeafError> {
        Ok(())
    }
    fn begin_union(&mut self, tag: u32, _: u32, _: &str, _: At<'_>) -> Result<(), LeafError> {
        self.push(Scalar::Uint(tag.into()))
    }
    fn end_union(&mut self) -> Result<(), LeafError> {
        Ok(())
    }
    fn begin_array(&mut self, len: ArrayLen, _at: At<'_>) -> Result<(), LeafError> {
        self.depth += 1;
        match len {
            ArrayLen::Fixed(_) => Ok(()),
            ArrayLen::Prefixed(n) => self.push(Scalar::Uint(n as u64)),
            ArrayLen::Tail => {
                self.tail_slot = Some((self.len, self.depth));
                self.push(Scalar::Uint(0))
            }
        }
    }
    fn end_array(&mut self, len: usize) -> Result<(), LeafError> {
        if let Some((slot, depth)) = self.tail_slot {
            if depth == self.depth {
                self.leaves[slot] = Scalar::Uint(len as u64);
                self.tail_slot = None;
            }
        }
        self.depth -= 1;
        Ok(())
    }
}
