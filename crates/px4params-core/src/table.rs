//! Leaf tables: where each leaf `[k]` of a type is, worked out once, so that reading `[k]` is
//! a table lookup and a bit read instead of a walk through the layout.
//!
//! A table describes the leaves a value's shape fixes: all of them for a type without
//! unions or dynamic arrays; for a union, each variant's leaves and then the leaves after the
//! union, reached by reading the tag. It stops at a dynamic array (leaves from its length on are
//! found by walking the value, [`crate::leaf`]) and where the caller's storage runs out.
//!
//! The table is built into caller-provided [`LeafSlot`]s ([`LeafTable::build`];
//! [`LeafTable::slots_needed`] says how many cover everything). Results and errors are those
//! of [`leaf::locate`], [`leaf::get_leaf`] and [`leaf::seek`]: whatever the table does not
//! answer (paths, leaves beyond it, malformed data) goes to them.
//!
//! Layout of the slots: slot 0 is the table's header (its number of leaf entries, its type and
//! whether it was cut short) and doubles as a run that covers nothing (its terminator hands
//! over to the walk). Then come *runs*, each a header and its leaf entries at bit offsets from
//! the run's start, and the union *jump tables* that lead from a tag to a variant's run; at
//! the end, each leaf's field path (*path records*).

use crate::bits::BitRead;
use crate::codec::{LeafKind, MAX_DEPTH};
use crate::error::{pack_step, Path, Step, MAX_PATH_DEPTH};
use crate::layout::{Kind, Layout, NodeId, Role};
use crate::leaf::{self, read_uint, Leaf, LeafAccessError, Position, Target};
use crate::scalar::{self, Cast, Scalar};

/// One entry of a [`LeafTable`]'s storage (12 bytes; its content is private).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeafSlot {
    pub(crate) a: u32,
    pub(crate) b: u32,
    pub(crate) c: u32,
}

// A run's header is `{leaves, bits, end}`: its number of leaf entries (which follow it), its
// length in bits, and what follows it, `end`: a kind in the top two bits and a slot index.
/// No more leaves.
const END: u32 = 0;
/// The leaves continue in run `index`, starting where this run ends.
const GOTO: u32 = 1 << 30;
/// This run's last entry is a union's tag; the jump table at `index` gives each variant's run.
const UNION: u32 = 2 << 30;
/// Leaves beyond this run are found by walking the value.
const WALK: u32 = 3 << 30;
const KIND: u32 = 3 << 30;
const INDEX: u32 = !KIND;
// A leaf entry is `{offset, what, path}`: its bit offset from the run's start, what it is (its
// width in bits 0..8, its `CLASS` in bits 8..11, `TRUNCATED`, a tag's union node in bits 12..31
// and `VERSION` for a `p_version` field) and its path record. A path record is the path's
// depth and then its remembered steps (packed as in `Path`), 32 bits each, three to a slot,
// zeros after them to fill `RECORD_SLOTS` slots (so that a path is copied in one piece);
// records are numbered by where they start counted from the table's end (0: the empty path).
// A jump table entry is `{run, variants, tag bits}` (run 0: the walk).
const CLASS: u32 = 8;
const UINT: u32 = 0;
const INT: u32 = 1;
const FLOAT: u32 = 2;
const BOOL: u32 = 3;
const TAG: u32 = 4;
const TRUNCATED: u32 = 1 << 11;
const UNION_NODE: u32 = 12;
/// A leaf [`LeafTable::resolve`] did not find: its `what` has a class no entry has.
pub(crate) const UNRESOLVED: LeafSlot = LeafSlot {
    a: 0,
    b: u32::MAX,
    c: 0,
};
/// Unions with node numbers from here on are not put in tables.
const MAX_UNION_NODE: u32 = 1 << 19;
const VERSION: u32 = 1 << 31;
/// Slots of a path record: its depth and `MAX_PATH_DEPTH` steps, three words to a slot.
const RECORD_SLOTS: usize = (MAX_PATH_DEPTH + 1).div_ceil(3);
// `LeafTable::path` copies a record's 5 slots, 12 steps, word by word.
const _: () = assert!(RECORD_SLOTS == 5 && MAX_PATH_DEPTH == 12);
/// The most slots a table uses (types with more leaves are covered up to there).
const MAX_SLOTS: usize = 1 << 16;

/// The fewest slots a table is built in (it then covers nothing: every access walks).
// A module constant, not an associated one: cbindgen would put that in the C header.
pub const MIN_SLOTS: usize = 2;

/// The storage given to [`LeafTable::build`] holds fewer than [`MIN_SLOTS`] slots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TableTooSmall;

/// A type's leaf table, over slots built by [`LeafTable::build`].
#[derive(Clone, Copy, Debug)]
pub struct LeafTable<'s> {
    slots: &'s [LeafSlot],
}

impl<'s> LeafTable<'s> {
    /// Number of slots a table of `root` needs to cover every leaf the type's shape fixes
    /// (at most 65536: a type with more leaves is covered up to there).
    pub fn slots_needed(layout: &Layout<'_>, root: NodeId) -> usize {
        Self::needed(layout, root).0
    }

    /// [`LeafTable::slots_needed`], and the number of leaf entries of that complete table (at
    /// least the number of leaves it answers for, whatever the data).
    pub(crate) fn needed(layout: &Layout<'_>, root: NodeId) -> (usize, usize) {
        let mut builder = Builder::new(layout, &mut [], usize::MAX);
        builder.build(root);
        (builder.len + builder.high, builder.entries as usize)
    }

    /// Builds the table of `root` in `storage`, covering what fits (all of it with
    /// [`LeafTable::slots_needed`] slots).
    pub fn build(
        layout: &Layout<'_>,
        root: NodeId,
        storage: &'s mut [LeafSlot],
    ) -> Result<Self, TableTooSmall> {
        if storage.len() < MIN_SLOTS {
            return Err(TableTooSmall);
        }
        let cap = storage.len();
        let mut builder = Builder::new(layout, storage, cap);
        builder.build(root);
        let (len, high) = (builder.len, builder.high);
        // Path nodes were laid out from the storage's end: move them to follow the runs.
        storage.copy_within(cap - high..cap, len);
        Ok(Self {
            slots: &storage[..len + high],
        })
    }

    /// A table built earlier into these slots (as [`LeafTable::build`] left them).
    pub(crate) fn built(slots: &'s [LeafSlot]) -> Self {
        Self { slots }
    }

    /// The type the table describes.
    pub fn root(&self) -> NodeId {
        self.slots.first().map_or(0, |s| s.b)
    }

    /// Number of slots the table uses.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether the table uses no slots (never, for a built table).
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Whether the storage ran out before the table covered what the type's shape fixes.
    pub fn is_cut_short(&self) -> bool {
        self.slots.first().is_some_and(|s| s.c & INDEX != 0)
    }

    /// Number of leaf entries in the table: no leaf `[k]` with `k` from here on is answered
    /// by it.
    pub(crate) fn entries(&self) -> usize {
        self.slots.first().map_or(0, |s| s.a as usize)
    }

    /// Where leaves `[0]`, `[1]`, .. of the value in the first `len` bytes of `data` are, one
    /// to each slot of `out`, for [`LeafTable::read_resolved`]: resolved once for a value
    /// that is read many times (a store's instances).
    pub(crate) fn resolve(&self, data: &[u8], len: usize, out: &mut [LeafSlot]) {
        for (k, slot) in out.iter_mut().enumerate() {
            *slot = match self.find_within(data, len * 8, k) {
                Some((at, entry)) => LeafSlot {
                    a: at as u32,
                    b: entry.0,
                    c: entry.1,
                },
                None => UNRESOLVED,
            };
        }
    }

    /// The value of a leaf that [`LeafTable::resolve`] found in the value starting `data`
    /// (`None` when it did not: the table does not answer for the leaf).
    #[inline(always)]
    pub(crate) fn read_resolved(resolved: LeafSlot, data: &[u8]) -> Option<Scalar> {
        (resolved.b != UNRESOLVED.b)
            .then(|| Entry(resolved.b, resolved.c).read(data, resolved.a as usize))
    }

    /// [`LeafTable::read_resolved`] with the leaf's description, as [`LeafTable::get_leaf`]
    /// gives it, for leaf `[k]`.
    #[inline]
    pub(crate) fn get_resolved(
        &self,
        resolved: LeafSlot,
        data: &[u8],
        k: usize,
    ) -> Option<(Leaf, Scalar)> {
        let value = Self::read_resolved(resolved, data)?;
        let entry = Entry(resolved.b, resolved.c);
        let leaf = Leaf {
            index: k,
            bit_offset: resolved.a as usize,
            kind: entry.kind(),
            path: self.path(entry.1),
        };
        Some((leaf, value))
    }

    /// Finds leaf `target` in `data`, a value of the table's type: [`leaf::locate`], faster.
    pub fn locate<R: BitRead + ?Sized>(
        &self,
        layout: &Layout<'_>,
        data: &R,
        target: Target<'_>,
        tao: bool,
    ) -> Result<Leaf, LeafAccessError> {
        if let Target::Index(k) = target {
            if let Some((bit_offset, entry)) = self.find(data, k) {
                return Ok(Leaf {
                    index: k,
                    bit_offset,
                    kind: entry.kind(),
                    path: self.path(entry.1),
                });
            }
        }
        leaf::locate(layout, self.root(), data, target, tao)
    }

    /// Reads leaf `target` of `data`, a value of the table's type: [`leaf::get_leaf`], faster.
    pub fn get_leaf<R: BitRead + ?Sized>(
        &self,
        layout: &Layout<'_>,
        data: &R,
        target: Target<'_>,
        tao: bool,
    ) -> Result<(Leaf, Scalar), LeafAccessError> {
        if let Target::Index(k) = target {
            if let Some((bit_offset, entry)) = self.find(data, k) {
                let leaf = Leaf {
                    index: k,
                    bit_offset,
                    kind: entry.kind(),
                    path: self.path(entry.1),
                };
                return Ok((leaf, entry.read(data, bit_offset)));
            }
        }
        leaf::get_leaf(layout, self.root(), data, target, tao)
    }

    /// [`LeafTable::get_leaf`] for the store: the value is the first `len` bytes of `data`,
    /// which goes on (see [`LeafTable::read_known`]).
    #[inline]
    pub(crate) fn get_leaf_prefix(
        &self,
        layout: &Layout<'_>,
        data: &[u8],
        len: usize,
        target: Target<'_>,
    ) -> Result<(Leaf, Scalar), LeafAccessError> {
        if let Target::Index(k) = target {
            if let Some((bit_offset, entry)) = self.find_within(data, len * 8, k) {
                let leaf = Leaf {
                    index: k,
                    bit_offset,
                    kind: entry.kind(),
                    path: self.path(entry.1),
                };
                return Ok((leaf, entry.read(data, bit_offset)));
            }
        }
        let value = data.get(..len).unwrap_or(&[]);
        leaf::get_leaf(layout, self.root(), value, target, false)
    }

    /// Finds leaf `[k]` of `data`, a value of the table's type encoded without tail array
    /// optimization: [`leaf::seek`], faster.
    pub fn seek<R: BitRead + ?Sized>(
        &self,
        layout: &Layout<'_>,
        data: &R,
        k: usize,
    ) -> Option<Position> {
        match self.find(data, k) {
            Some((bit_offset, entry)) => Some(Position {
                bit_offset,
                kind: entry.kind(),
                version: entry.0 & VERSION != 0,
            }),
            None => leaf::seek(layout, self.root(), data, k),
        }
    }

    /// Reads leaf `[k]` of `data`, a value of the table's type encoded without tail array
    /// optimization, and says whether it is a `p_version` field: [`leaf::seek`] and
    /// [`Position::read`], faster. `None` when there is no such leaf or the data is
    /// malformed: [`LeafTable::get_leaf`] then says why.
    #[inline]
    pub fn read<R: BitRead + ?Sized>(
        &self,
        layout: &Layout<'_>,
        data: &R,
        k: usize,
    ) -> Option<(Scalar, bool)> {
        match self.find(data, k) {
            Some((at, entry)) => Some((entry.read(data, at), entry.0 & VERSION != 0)),
            None => leaf::seek(layout, self.root(), data, k).map(|p| (p.read(data), p.version)),
        }
    }

    /// [`LeafTable::read`] for the store, when the table alone answers (`None` leaves it to
    /// the walk): the value is the first `len` bytes of `data`, which goes on (so that bits
    /// are read a 64-bit window at a time even at the value's end).
    #[inline]
    pub(crate) fn read_known(&self, data: &[u8], len: usize, k: usize) -> Option<Scalar> {
        self.find_within(data, len * 8, k)
            .map(|(at, entry)| entry.read(data, at))
    }

    /// Whether the table alone answers for leaf `[k]` of `data` (without walking the value).
    pub fn covers<R: BitRead + ?Sized>(&self, data: &R, k: usize) -> bool {
        self.find(data, k).is_some()
    }

    /// Where leaf `[k]` is, if the table knows and the data holds it (every tag on the way
    /// valid, the leaf inside the data); `None` leaves the answer to the walk.
    #[inline(always)]
    fn find<R: BitRead + ?Sized>(&self, data: &R, k: usize) -> Option<(usize, Entry)> {
        self.find_within(data, data.bit_len(), k)
    }

    /// [`LeafTable::find`] in the first `limit` bits of `data` (the bits after them may be
    /// read, but only to be shifted out).
    #[inline(always)]
    fn find_within<R: BitRead + ?Sized>(
        &self,
        data: &R,
        limit: usize,
        k: usize,
    ) -> Option<(usize, Entry)> {
        let slots = self.slots;
        let (mut run, mut base, mut k) = (1usize, 0usize, k);
        loop {
            let header = slots.get(run)?;
            let n = header.a as usize;
            if k < n {
                let slot = slots.get(run + 1 + k)?;
                let entry = Entry(slot.b, slot.c);
                let at = base + slot.a as usize;
                if at + entry.bits() as usize > limit {
                    return None;
                }
                return Some((at, entry));
            }
            k -= n;
            let end = base + header.b as usize;
            let next = (header.c & INDEX) as usize;
            run = match header.c & KIND {
                GOTO => next,
                UNION => {
                    // The run ends with the tag.
                    let jumps = slots.get(next)?;
                    let (count, bits) = (jumps.b, jumps.c);
                    let t = if bits == 0 {
                        0
                    } else if end > limit {
                        return None;
                    } else {
                        read_uint(data, end - bits as usize, bits)
                    };
                    if t >= u64::from(count) {
                        return None;
                    }
                    slots.get(next + t as usize)?.a as usize
                }
                _ => return None,
            };
            // Runs only lead forward, so this ends.
            if run == 0 {
                return None;
            }
            base = end;
        }
    }

    /// The field path in path record `record`.
    #[inline]
    fn path(&self, record: u32) -> Path {
        let slots = self.slots;
        let start = slots.len().wrapping_sub(record as usize);
        match slots.get(start..start.wrapping_add(RECORD_SLOTS)) {
            Some(&[a, b, c, d, e]) if record != 0 => Path::from_packed(
                a.a,
                [a.b, a.c, b.a, b.b, b.c, c.a, c.b, c.c, d.a, d.b, d.c, e.a],
            ),
            _ => Path::default(),
        }
    }
}

/// A leaf entry's `what` and path record.
#[derive(Clone, Copy)]
struct Entry(u32, u32);

impl Entry {
    /// `what` of a primitive node's leaf or a union's tag (`None` for other nodes, and for
    /// unions whose node number does not fit).
    fn what(id: NodeId, kind: Kind, version: bool) -> Option<u32> {
        let (class, bits, cast) = match kind {
            Kind::Uint { bits, cast } => (UINT, bits, cast),
            Kind::Int { bits, cast } => (INT, bits, cast),
            Kind::Float { bits, cast } => (FLOAT, bits, cast),
            Kind::Bool => (BOOL, 1, Cast::Saturated),
            Kind::Union { tag_bits, .. } if id < MAX_UNION_NODE => {
                return Some(u32::from(tag_bits) | TAG << CLASS | id << UNION_NODE);
            }
            _ => return None,
        };
        let truncated = if cast == Cast::Truncated {
            TRUNCATED
        } else {
            0
        };
        let version = if version { VERSION } else { 0 };
        Some(u32::from(bits) | class << CLASS | truncated | version)
    }

    #[inline]
    fn bits(self) -> u32 {
        self.0 & 0xFF
    }

    #[inline]
    fn kind(self) -> LeafKind {
        let bits = self.bits() as u8;
        let cast = if self.0 & TRUNCATED != 0 {
            Cast::Truncated
        } else {
            Cast::Saturated
        };
        LeafKind::Scalar(match (self.0 >> CLASS) & 7 {
            UINT => Kind::Uint { bits, cast },
            INT => Kind::Int { bits, cast },
            FLOAT => Kind::Float { bits, cast },
            BOOL => Kind::Bool,
            _ => {
                return LeafKind::Tag {
                    bits,
                    union: (self.0 & !VERSION) >> UNION_NODE,
                }
            }
        })
    }

    /// The leaf's value at `at` (as the codec reads a primitive; a tag as a `Uint`).
    #[inline(always)]
    fn read<R: BitRead + ?Sized>(self, data: &R, at: usize) -> Scalar {
        let bits = self.bits();
        if bits == 0 {
            return Scalar::Uint(0);
        }
        let raw = read_uint(data, at, bits);
        match (self.0 >> CLASS) & 7 {
            INT => Scalar::Int(scalar::sign_extend(raw, bits)),
            FLOAT => Scalar::Float(scalar::float_from_raw(raw, bits)),
            BOOL => Scalar::Bool(raw != 0),
            _ => Scalar::Uint(raw),
        }
    }
}

/// Lays out a table (or, with no storage, counts its slots).
struct Builder<'l, 'a, 'o> {
    layout: &'l Layout<'a>,
    out: &'o mut [LeafSlot],
    cap: usize,
    /// Slots used from the start (runs, jump tables).
    len: usize,
    /// Slots used from the end (path records).
    high: usize,
    /// The field path of the value being laid out (steps beyond `MAX_PATH_DEPTH` are only
    /// counted).
    steps: [u32; MAX_PATH_DEPTH],
    depth: u32,
    /// The open run's header; 0 when no run is open (the rest of the value is walked).
    run: usize,
    /// Leaf entries of the open run.
    leaves: u32,
    /// Bits into the open run.
    pos: u64,
    /// The storage ran out.
    full: bool,
    /// Leaf entries laid out.
    entries: u32,
}

impl<'l, 'a, 'o> Builder<'l, 'a, 'o> {
    fn new(layout: &'l Layout<'a>, out: &'o mut [LeafSlot], cap: usize) -> Self {
        Self {
            layout,
            out,
            cap: cap.min(MAX_SLOTS),
            len: 0,
            high: 0,
            steps: [0; MAX_PATH_DEPTH],
            depth: 0,
            run: 0,
            leaves: 0,
            pos: 0,
            full: false,
            entries: 0,
        }
    }

    fn build(&mut self, root: NodeId) {
        self.len = 1;
        self.open();
        self.emit(root, 1, false);
        self.close(END);
        self.put(
            0,
            LeafSlot {
                a: self.entries,
                b: root,
                c: WALK | u32::from(self.full),
            },
        );
    }

    fn put(&mut self, i: usize, slot: LeafSlot) {
        if let Some(s) = self.out.get_mut(i) {
            *s = slot;
        }
    }

    fn get(&self, i: usize) -> LeafSlot {
        self.out.get(i).copied().unwrap_or_default()
    }

    /// `n` slots, or none when the storage is full (the table then ends everywhere).
    fn alloc(&mut self, n: usize) -> Option<usize> {
        if self.full || n > self.cap - self.len - self.high {
            self.close(WALK);
            self.full = true;
            return None;
        }
        self.len += n;
        Some(self.len - n)
    }

    /// Opens a run; 0 when there is no room.
    fn open(&mut self) -> usize {
        let run = self.alloc(1).unwrap_or(0);
        (self.run, self.leaves, self.pos) = (run, 0, 0);
        run
    }

    /// Closes the open run, if any, with terminator `end`.
    fn close(&mut self, end: u32) {
        if self.run != 0 {
            let header = LeafSlot {
                a: self.leaves,
                b: self.pos as u32,
                c: end,
            };
            self.put(self.run, header);
            self.run = 0;
        }
    }

    /// Adds `bits` to the open run; closes it when its offsets would not fit in 32 bits.
    fn advance(&mut self, bits: u64) {
        self.pos = self.pos.saturating_add(bits);
        if self.pos > u64::from(u32::MAX) {
            self.close(WALK);
        }
    }

    /// `n` slots at the end of the storage (the table's end once it is built), or none when
    /// the storage is full; returns where they start, counted from the end.
    fn alloc_end(&mut self, n: usize) -> Option<u32> {
        self.alloc(n)?;
        self.len -= n;
        self.high += n;
        Some(self.high as u32)
    }

    /// A leaf entry at the current position for `what` ([`Entry::what`]; `None` ends the
    /// run), with the current path.
    fn entry(&mut self, what: Option<u32>) {
        let Some(what) = what else {
            self.close(WALK);
            return;
        };
        if self.run == 0 {
            return;
        }
        let Some(i) = self.alloc(1) else {
            return;
        };
        let record = if self.depth == 0 {
            0
        } else {
            let held = (self.depth as usize).min(MAX_PATH_DEPTH);
            let mut words = [0u32; RECORD_SLOTS * 3];
            words[0] = self.depth;
            words[1..=held].copy_from_slice(&self.steps[..held]);
            let Some(record) = self.alloc_end(RECORD_SLOTS) else {
                return;
            };
            let start = self.cap - record as usize;
            for (j, w) in words.chunks(3).enumerate() {
                let slot = LeafSlot {
                    a: w[0],
                    b: w[1],
                    c: w[2],
                };
                self.put(start + j, slot);
            }
            record
        };
        let slot = LeafSlot {
            a: self.pos as u32,
            b: what,
            c: record,
        };
        self.put(i, slot);
        self.leaves += 1;
        self.entries += 1;
        self.advance(Entry(what, 0).bits().into());
    }

    fn push(&mut self, step: Step) {
        if let Some(s) = self.steps.get_mut(self.depth as usize) {
            *s = pack_step(step);
        }
        self.depth += 1;
    }

    fn pop(&mut self) {
        self.depth -= 1;
    }

    /// Adds the leaves of a value of node `id` at the current path, `depth` nodes deep (as
    /// the walk counts them), in a field whose role is `p_version` when `version`.
    fn emit(&mut self, id: NodeId, depth: usize, version: bool) {
        if self.run == 0 {
            return;
        }
        let layout = self.layout;
        let Some(node) = layout.nodes.get(id as usize).filter(|_| depth <= MAX_DEPTH) else {
            // The walk refuses what is too deep: leave it (and what follows) to it.
            self.close(WALK);
            return;
        };
        match node.kind {
            kind @ (Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool) => {
                self.entry(Entry::what(id, kind, version));
            }
            Kind::Void { bits } => self.advance(bits.into()),
            Kind::Struct { first, count } => {
                for i in first..first.saturating_add(count) {
                    let Some(field) = layout.fields.get(i as usize) else {
                        self.close(WALK);
                        return;
                    };
                    if let Some(Kind::Void { bits }) =
                        layout.nodes.get(field.node as usize).map(|n| n.kind)
                    {
                        self.advance(bits.into());
                        continue;
                    }
                    if self.run == 0 {
                        return;
                    }
                    let version = matches!(field.role, Role::Version(_));
                    self.push(Step::Field(i));
                    self.emit(field.node, depth + 1, version);
                    self.pop();
                }
            }
            Kind::Array { elem, len } => {
                for i in 0..len {
                    if self.run == 0 {
                        return;
                    }
                    self.push(Step::Index(i));
                    self.emit(elem, depth + 1, version);
                    self.pop();
                }
            }
            Kind::Union {
                first,
                count,
                tag_bits,
            } => self.union(id, node.kind, depth, first, count, tag_bits),
            // The length and the elements are the walk's.
            Kind::DynArray { .. } => self.close(WALK),
        }
    }

    fn union(&mut self, id: NodeId, kind: Kind, depth: usize, first: u32, count: u32, bits: u8) {
        self.entry(Entry::what(id, kind, false));
        let Some(jumps) = self.alloc(count as usize) else {
            return;
        };
        if self.run == 0 {
            return;
        }
        self.close(UNION | jumps as u32);
        // Runs that end a variant, chained through their terminators until the run after the
        // union exists.
        let mut pending = 0u32;
        for t in 0..count {
            let run = self.open();
            let jump = LeafSlot {
                a: run as u32,
                b: count,
                c: bits.into(),
            };
            self.put(jumps + t as usize, jump);
            if run == 0 {
                continue;
            }
            let variant = first + t;
            if let Some(field) = self.layout.fields.get(variant as usize).copied() {
                let version = matches!(field.role, Role::Version(_));
                self.push(Step::Field(variant));
                self.emit(field.node, depth + 1, version);
                self.pop();
            } else {
                self.close(WALK);
            }
            if self.run != 0 {
                let run = self.run;
                self.close(GOTO | pending);
                pending = run as u32;
            }
        }
        // The run after the union, where every variant goes on.
        let after = if pending != 0 { self.open() } else { 0 };
        while pending != 0 {
            let mut header = self.get(pending as usize);
            let next = header.c & INDEX;
            header.c = GOTO | after as u32;
            self.put(pending as usize, header);
            pending = next;
        }
    }
}
