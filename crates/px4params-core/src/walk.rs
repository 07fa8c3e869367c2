//! One small walk over a value, for firmware: it reads a value, writes one, or both at once,
//! and hands every leaf to a [`Visit`] that watches, supplies or replaces it.
//!
//! Every operation on values is one walk with its own visit: decoding into a flat leaf list
//! ([`decode`]), encoding from one ([`encode`]), finding leaf `[k]` ([`locate`]) or the leaf a
//! path names ([`locate_by`], for hosts and firmware alike: the union tags, array lengths and
//! tail arrays on the way are the loop's to read), rewriting a value with a new union tag or
//! array length ([`transcode`]), a type's default ([`encode_default`]), checking a stored
//! value's `p_version` fields and floats ([`check_stored`]) and translating a value of an older
//! type version ([`translate`]). Firmware builds (feature `compact`) do all of these through
//! this one interpreter of the DroneCAN rules, which is why it is here: one walk in the code
//! instead of one per operation.
//!
//! Hosts keep faster walks for most of them (the codec's encoder and decoder, leaf tables,
//! seeks), which tests hold to this one, and use this one where a write changes a value's
//! shape ([`transcode`], [`encode_default`]). Reads go through [`Input`], so the same code
//! reads contiguous bytes and scattered pieces alike.

use core::convert::Infallible;

use crate::bits::BitRead;
use crate::error::{Error, ErrorKind, Path, Step};
use crate::interp::{
    visit as run, visit_here, write_whole, write_whole_here, Bits, Halt, Job, LeafAt, PartAt,
    Reading, Steer, Visit, Walked,
};
use crate::layout::{Kind, Layout, NodeId};
use crate::rules::{
    DecodeOptions, Decoded, EncodeOptions, Leaf, LeafAccessError, LeafError, LeafKind, Position,
    TranslateError,
};
use crate::scalar::{self, Scalar, ScalarError};

/// The error of a walk whose visit refuses nothing.
fn plain(e: Error<LeafError>) -> LeafAccessError {
    Error {
        kind: e.kind.map_value(|_| ErrorKind::TooDeep),
        bit_offset: e.bit_offset,
        path: e.path,
    }
}

/// Collects the leaves read.
struct Collect<'s> {
    leaves: &'s mut [Scalar],
    len: usize,
}

impl Visit for Collect<'_> {
    fn leaf(&mut self, _: &LeafAt<'_>, old: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        // (Decoding reads every leaf it visits: `old` is there.)
        let (Some(slot), Some(old)) = (self.leaves.get_mut(self.len), old) else {
            return Err(Halt::Refused);
        };
        *slot = old;
        self.len += 1;
        Ok(None)
    }

    fn refusal(&self, fault: &mut Option<ErrorKind<LeafError>>) {
        *fault = Some(ErrorKind::Value(LeafError::Full));
    }
}

/// Supplies the leaves written, in order.
struct Supply<'s> {
    leaves: &'s [Scalar],
    next: usize,
}

impl Visit for Supply<'_> {
    fn leaf(&mut self, _: &LeafAt<'_>, _: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        let v = *self.leaves.get(self.next).ok_or(Halt::Refused)?;
        self.next += 1;
        Ok(Some(v))
    }

    fn refusal(&self, fault: &mut Option<ErrorKind<LeafError>>) {
        *fault = Some(ErrorKind::Value(LeafError::Exhausted));
    }
}

/// Decodes a value of type `root` from `data` into the flat leaf list `leaves` (what
/// [`crate::codec::decode`] with a [`crate::value::LeafSink`] gives).
pub fn decode<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    leaves: &mut [Scalar],
    options: DecodeOptions,
) -> Result<Decoded, Error<LeafError>> {
    let mut collect = Collect { leaves, len: 0 };
    let bits = Bits(data);
    let job = Job::reading(&bits, options.tao, Steer::No);
    let end = visit_here(layout, root, job, &mut collect)?.read;
    let (used, len) = (end.div_ceil(8), BitRead::bit_len(data) / 8);
    if !options.allow_trailing && len > used {
        return Err(Error {
            kind: ErrorKind::TrailingBytes { used, len },
            bit_offset: end,
            path: Path::default(),
        });
    }
    Ok(Decoded {
        bits: end,
        leaves: collect.len,
    })
}

/// Encodes the value of type `root` given as the flat leaf list `leaves` into `out`; returns
/// its length in bytes (what [`crate::codec::encode`] with a [`crate::value::LeafSource`]
/// gives).
pub fn encode(
    layout: &Layout<'_>,
    root: NodeId,
    leaves: &[Scalar],
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, Error<LeafError>> {
    let mut supply = Supply { leaves, next: 0 };
    write_whole_here(layout, root, None, out, options, &mut supply)
}

/// Finds a leaf: the one `aim` looks for.
struct Find<'w, A> {
    layout: &'w Layout<'w>,
    /// The data's length in bits.
    bit_len: usize,
    /// Where a leaf that lies beyond the data starts.
    beyond: usize,
    aim: A,
    found: Option<(Leaf, Scalar)>,
    /// The leaf found is a `p_version` field.
    version: bool,
}

impl<'w, A: Aim> Find<'w, A> {
    fn new<R: BitRead + ?Sized>(layout: &'w Layout<'w>, data: &R, aim: A) -> Self {
        Find {
            layout,
            bit_len: BitRead::bit_len(data),
            beyond: 0,
            aim,
            found: None,
            version: false,
        }
    }
}

/// Which leaf a [`Find`] looks for: leaf `[k]` ([`Index`]) or the one a path names
/// ([`Toward`]). Two types, so that firmware that finds leaves by number only links no paths.
trait Aim {
    /// Whether leaf `at` (whose value read is `old`) is the one.
    fn hit(&mut self, at: &LeafAt<'_>, old: Option<Scalar>) -> bool;
    /// Which parts the walk passes over, as they cannot hold the leaf.
    fn steer(&self) -> Steer;
    /// [`Visit::part`], for [`Steer::Visit`].
    fn part(&mut self, _: &Layout<'_>, _: &PartAt<'_>, _: &mut Reading<'_>) -> bool {
        false
    }
    /// Why the walk did not find it (it `walked` the whole value, or stopped short).
    fn missing(&mut self, walked: Walked) -> LeafAccessError;
}

/// Leaf `[k]`.
struct Index(usize);

impl Aim for Index {
    fn hit(&mut self, at: &LeafAt<'_>, _: Option<Scalar>) -> bool {
        at.index == self.0
    }

    fn steer(&self) -> Steer {
        Steer::Below(self.0)
    }

    fn missing(&mut self, walked: Walked) -> LeafAccessError {
        Error {
            kind: ErrorKind::NoSuchLeaf {
                index: self.0,
                count: walked.leaves,
            },
            bit_offset: walked.read,
            path: Path::default(),
        }
    }
}

/// Which leaf of a node a path names: the node itself, or its tag or length.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum LeafClass {
    Scalar,
    Tag,
    Len,
}

fn class(kind: LeafKind) -> LeafClass {
    match kind {
        LeafKind::Scalar(_) => LeafClass::Scalar,
        LeafKind::Tag { .. } => LeafClass::Tag,
        LeafKind::Len { .. } => LeafClass::Len,
    }
}

/// Where a part lies for a way ([`Toward::part`]).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Course {
    /// On the way: walked.
    On,
    /// Off it: passed over unread where it has a fixed shape.
    Off,
    /// The way ends (what the path names is not in the value): nothing more is read.
    Done,
}

/// What a path names inside a node on its way.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Next {
    /// A part of it, this step down.
    Step(Step),
    /// One of its own leaves: its value, its tag or its length.
    Leaf(LeafClass),
}

/// A path to a leaf, followed node by node as the walk comes to them.
pub(crate) trait Way {
    /// What the path names inside node `id`, the next node on it (the root first); `Err`:
    /// why it names nothing there.
    fn next(&mut self, layout: &Layout<'_>, id: NodeId) -> Result<Next, ErrorKind<Infallible>>;
}

/// A way followed through a value: which part of it the walk is in. The walk reads only the
/// parts before the leaf that decide where it is (the loop passes over the others), and it
/// ends at the leaf, or where the path names what the value does not hold.
struct Toward<'w> {
    layout: &'w Layout<'w>,
    way: &'w mut dyn Way,
    /// How many parts down the last part on the way is (0: the root).
    depth: usize,
    /// What the path names inside that part.
    next: Next,
    /// The part walked is that part (its own leaf, tag or length comes next).
    on: bool,
    /// What the path names is not in the value (a union variant not selected, an element
    /// beyond the array's length): said at the next part, after the loop's rules on the tag
    /// or length just read.
    missing: Option<LeafAccessError>,
}

impl Aim for Toward<'_> {
    fn steer(&self) -> Steer {
        Steer::Visit
    }

    fn part(&mut self, layout: &Layout<'_>, at: &PartAt<'_>, reading: &mut Reading<'_>) -> bool {
        match self.course(at, *reading.bits) {
            Course::On => false,
            // Fixed-shape parts off the way.
            Course::Off => reading.pass(layout, at.node),
            Course::Done => true,
        }
    }

    /// Whether leaf `at` (whose value read is `old`) is the one the path names. A union's
    /// tag or an array's length on the way says whether the value holds the rest of it.
    fn hit(&mut self, at: &LeafAt<'_>, old: Option<Scalar>) -> bool {
        if !self.on {
            return false;
        }
        let n = match old {
            Some(Scalar::Uint(n)) => n,
            _ => 0,
        };
        let (missing, bits) = match (self.next, at.kind) {
            (Next::Leaf(leaf), kind) => return class(kind) == leaf,
            (Next::Step(Step::Field(variant)), LeafKind::Tag { bits, union }) => {
                let first = match self.layout.node(union).kind {
                    Kind::Union { first, .. } => first,
                    _ => 0,
                };
                if variant.checked_sub(first).map(u64::from) == Some(n) {
                    return false;
                }
                let mut path = *at.path;
                path.push(Step::Field(variant));
                ((ErrorKind::VariantNotSelected, path), bits)
            }
            (Next::Step(Step::Index(i)), LeafKind::Len { bits, .. }) if u64::from(i) >= n => {
                ((ErrorKind::NoSuchPath, *at.path), bits)
            }
            _ => return false,
        };
        self.missing = Some(Error {
            kind: missing.0,
            bit_offset: at.bit_offset + usize::from(bits),
            path: missing.1,
        });
        false
    }

    fn missing(&mut self, walked: Walked) -> LeafAccessError {
        self.missing.take().unwrap_or(Error {
            kind: ErrorKind::NoSuchPath,
            bit_offset: walked.read,
            path: Path::default(),
        })
    }
}

impl Toward<'_> {
    /// Where part `at`, starting at bit `bit_offset`, lies.
    fn course(&mut self, at: &PartAt<'_>, bit_offset: usize) -> Course {
        if self.missing.is_some() {
            return Course::Done;
        }
        self.on = match (at.step, self.next) {
            // The root (padding, with no step either, is on no way).
            (None, _) => at.depth == 0,
            (Some(step), Next::Step(next)) => at.depth == self.depth + 1 && step == next,
            _ => false,
        };
        if !self.on {
            return Course::Off;
        }
        self.depth = at.depth;
        match self.way.next(self.layout, at.node) {
            Ok(next) => {
                self.next = next;
                Course::On
            }
            Err(kind) => {
                self.missing = Some(Error {
                    kind,
                    bit_offset,
                    path: *at.path,
                });
                Course::Done
            }
        }
    }
}

impl<A: Aim> Visit for Find<'_, A> {
    fn leaf(&mut self, at: &LeafAt<'_>, old: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        if !self.aim.hit(at, old) {
            return Ok(None);
        }
        if at.bit_offset > self.bit_len {
            // A tail array's length, after parts passed over unread that end beyond the data.
            self.beyond = at.bit_offset;
            return Err(Halt::Refused);
        }
        let leaf = Leaf {
            index: at.index,
            bit_offset: at.bit_offset,
            kind: at.kind,
            path: *at.path,
        };
        self.found = Some((leaf, old.unwrap_or(Scalar::Uint(0))));
        self.version = at.version.is_some();
        Err(Halt::Found)
    }

    fn refusal(&self, fault: &mut Option<ErrorKind<LeafError>>) {
        *fault = Some(ErrorKind::Truncated {
            needed_bits: self.beyond,
            available_bits: self.bit_len,
        });
    }

    fn part(&mut self, at: &PartAt<'_>, reading: &mut Reading<'_>) -> bool {
        self.aim.part(self.layout, at, reading)
    }
}

/// Walks `data` (a value of type `root`) until `find` finds its leaf.
fn find<R: BitRead + ?Sized, A: Aim>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    find: &mut Find<'_, A>,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    let bits = Bits(data);
    let job = Job::reading(&bits, tao, find.aim.steer());
    let walked = match run(layout, root, job, find) {
        Ok(walked) => walked,
        Err(e) => return Err(plain(e)),
    };
    match find.found {
        Some(found) => Ok(found),
        None => Err(find.aim.missing(walked)),
    }
}

/// Finds the leaf `way` names in `data`, a value of type `root`, and reads it (what
/// [`crate::leaf::get_leaf`] gives for [`crate::leaf::Target::Path`]).
pub(crate) fn locate_by<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    way: &mut dyn Way,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    let toward = Toward {
        layout,
        way,
        depth: 0,
        next: Next::Leaf(LeafClass::Scalar),
        on: false,
        missing: None,
    };
    find(
        layout,
        root,
        data,
        &mut Find::new(layout, data, toward),
        tao,
    )
}

/// Finds leaf `[k]` of `data`, a value of type `root`, and reads it (what
/// [`crate::leaf::get_leaf`] gives for [`crate::leaf::Target::Index`]).
pub fn locate<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    tao: bool,
) -> Result<(Leaf, Scalar), LeafAccessError> {
    find(
        layout,
        root,
        data,
        &mut Find::new(layout, data, Index(k)),
        tao,
    )
}

/// Where leaf `[k]` is (what [`crate::leaf::seek`] gives); `None` where [`locate`] fails.
pub fn seek<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
) -> Option<Position> {
    let mut found = Find::new(layout, data, Index(k));
    let (leaf, _) = find(layout, root, data, &mut found, false).ok()?;
    Some(Position {
        bit_offset: leaf.bit_offset,
        kind: leaf.kind,
        version: found.version && matches!(leaf.kind, LeafKind::Scalar(_)),
    })
}

/// Replaces leaf `[k]` and checks its new value.
struct Edit<'l> {
    layout: &'l Layout<'l>,
    k: usize,
    value: Scalar,
    /// The number of variants, or the array's maximum plus one, the value is not below.
    limit: u64,
}

impl Visit for Edit<'_> {
    fn leaf(&mut self, at: &LeafAt<'_>, _: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        if at.index != self.k {
            return Ok(None);
        }
        // A tag or length must select a variant or fit the array.
        let limit = match at.kind {
            LeafKind::Tag { union, .. } => match self.layout.node(union).kind {
                Kind::Union { count, .. } => u64::from(count),
                _ => 0,
            },
            LeafKind::Len { array, .. } => match self.layout.node(array).kind {
                Kind::DynArray { max, .. } => u64::from(max) + 1,
                _ => 0,
            },
            LeafKind::Scalar(_) => return Ok(Some(self.value)),
        };
        self.limit = limit;
        match self.value {
            Scalar::Uint(v) if v < limit => Ok(Some(self.value)),
            Scalar::Int(v) if v >= 0 && (v as u64) < limit => Ok(Some(self.value)),
            _ => Err(Halt::Refused),
        }
    }

    fn refusal(&self, fault: &mut Option<ErrorKind<LeafError>>) {
        *fault = Some(ErrorKind::Scalar(ScalarError::OutOfRange {
            value: self.value,
            min: Scalar::Uint(0),
            max: Scalar::Uint(self.limit.saturating_sub(1)),
        }));
    }
}

/// Re-encodes `data` (a value of `root`) into `out` with leaf `[k]` set to `value`: a new
/// union tag selects that variant with its default value, a new array length drops elements
/// at the end or appends default ones. Returns the new length in bytes.
pub fn transcode<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    k: usize,
    value: Scalar,
    out: &mut [u8],
    options: EncodeOptions,
) -> Result<usize, LeafAccessError> {
    let mut edit = Edit {
        layout,
        k,
        value,
        limit: 0,
    };
    write_whole(layout, root, Some(&Bits(data)), out, options, &mut edit).map_err(plain)
}

/// Writes the default value of `root` into `out`: zeros, `p_version` set to the type's
/// version, the first union variant, empty dynamic arrays. Returns the length in bytes.
pub fn encode_default(
    layout: &Layout<'_>,
    root: NodeId,
    out: &mut [u8],
    tao: bool,
) -> Result<usize, LeafAccessError> {
    struct Defaults;
    impl Visit for Defaults {
        fn leaf(&mut self, _: &LeafAt<'_>, _: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
            Ok(None)
        }
    }
    let options = EncodeOptions {
        tao,
        ..EncodeOptions::default()
    };
    write_whole(layout, root, None, out, options, &mut Defaults).map_err(plain)
}

/// Checks that `data` is exactly one value of `root` stored without tail array optimization
/// whose `p_version` fields hold the type's version and whose floats are finite.
pub fn check_stored(
    layout: &Layout<'_>,
    root: NodeId,
    data: &[u8],
) -> Result<(), Error<Infallible>> {
    /// The leaf refused: a version given and the one expected, or a float not finite (`None`).
    struct Stored(Scalar, Option<u32>);
    impl Visit for Stored {
        fn leaf(&mut self, at: &LeafAt<'_>, old: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
            *self = match (at.version, old) {
                (Some(expected), Some(given)) if !scalar::same_integer(given, expected) => {
                    Stored(given, Some(expected))
                }
                (_, Some(value @ Scalar::Float(v))) if !v.is_finite() => Stored(value, None),
                _ => return Ok(None),
            };
            Err(Halt::Refused)
        }

        fn refusal(&self, fault: &mut Option<ErrorKind<LeafError>>) {
            *fault = Some(match *self {
                Stored(given, Some(expected)) => ErrorKind::VersionMismatch { given, expected },
                Stored(value, None) => ErrorKind::Scalar(ScalarError::NotFinite { value }),
            });
        }
    }
    let bits = Bits(data);
    let job = Job::reading(&bits, false, Steer::No);
    let end = match run(layout, root, job, &mut Stored(Scalar::Uint(0), None)) {
        Ok(walked) => walked.read,
        Err(e) => return Err(plain(e)),
    };
    let (used, len) = (end.div_ceil(8), data.len());
    if len > used {
        return Err(Error {
            kind: ErrorKind::TrailingBytes { used, len },
            bit_offset: end,
            path: Path::default(),
        });
    }
    Ok(())
}

/// Reads the leaf at `path` (its node's own value, tag or length) of `data`, a value of
/// `root` stored without tail array optimization.
fn read_at<R: BitRead + ?Sized>(
    layout: &Layout<'_>,
    root: NodeId,
    data: &R,
    path: &Path,
    leaf: LeafClass,
) -> Result<Scalar, Halt> {
    let mut along = Along {
        path,
        depth: 0,
        leaf,
    };
    // Not there: the stored value holds less than the walk asks of it.
    match locate_by(layout, root, data, &mut along, false) {
        Ok((_, value)) => Ok(value),
        Err(_) => Err(Halt::Refused),
    }
}

/// The way of a field path: its steps, then leaf `leaf` of the node they lead to.
struct Along<'p> {
    path: &'p Path,
    depth: usize,
    leaf: LeafClass,
}

impl Way for Along<'_> {
    fn next(&mut self, _: &Layout<'_>, _: NodeId) -> Result<Next, ErrorKind<Infallible>> {
        let next = match self.path.steps().nth(self.depth) {
            Some(step) => Next::Step(step),
            None => Next::Leaf(self.leaf),
        };
        self.depth += 1;
        Ok(next)
    }
}

/// What a node holds, for telling a field that changed its kind of value.
fn shape(layout: &Layout<'_>, id: NodeId) -> u8 {
    match layout.node(id).kind {
        Kind::Uint { .. } | Kind::Int { .. } | Kind::Float { .. } | Kind::Bool => 0,
        Kind::Struct { .. } => 1,
        Kind::Union { .. } => 2,
        Kind::Array { .. } | Kind::DynArray { .. } => 3,
        Kind::Void { .. } => 4,
    }
}

/// Supplies the leaves of the new version of a value: each from the old value where it has
/// the same field (by name, holding the same kind of value), else from the base.
struct Carry<'a, R: ?Sized, B: ?Sized> {
    layout: &'a Layout<'a>,
    old_root: NodeId,
    old_data: &'a R,
    new_root: NodeId,
    base: &'a B,
    /// A static array the old value has with another length: that length, and the new one.
    wrong_len: Option<(u64, u32)>,
}

impl<R: BitRead + ?Sized, B: BitRead + ?Sized> Carry<'_, R, B> {
    /// The old value's node at `path` of the new type, with its path in the old value.
    fn old_at(&self, path: &Path) -> Result<(Option<NodeId>, Path), Halt> {
        let layout = self.layout;
        let (mut new, mut old) = (self.new_root, Some(self.old_root));
        let mut steps = Path::default();
        for step in path.steps() {
            let (next, carried) = match step {
                Step::Field(f) => {
                    let field = layout.fields[f as usize];
                    let name = layout.name(&field);
                    let member = match (layout.node(new).kind, old) {
                        // A union keeps the old value's variant only where the old value
                        // selects one of that name.
                        (Kind::Union { .. }, Some(o)) => {
                            let tag = read_at(
                                layout,
                                self.old_root,
                                self.old_data,
                                &steps,
                                LeafClass::Tag,
                            )?;
                            let selected = match (layout.node(o).kind, tag) {
                                (Kind::Union { first, .. }, Scalar::Uint(t)) => layout
                                    .members(o)
                                    .get(t as usize)
                                    .map(|v| (first + t as u32, v)),
                                _ => None,
                            };
                            selected
                                .filter(|(_, v)| layout.name(v) == name)
                                .map(|(i, _)| i)
                        }
                        (_, Some(o)) => layout.member_index(o, name),
                        (_, None) => None,
                    };
                    let carried = member
                        .map(|i| (i, layout.fields[i as usize].node))
                        .filter(|&(_, node)| shape(layout, node) == shape(layout, field.node));
                    if let Some((i, _)) = carried {
                        steps.push(Step::Field(i));
                    }
                    (field.node, carried.map(|(_, node)| node))
                }
                Step::Index(i) => {
                    let elem = |id: NodeId| match layout.node(id).kind {
                        Kind::Array { elem, .. } | Kind::DynArray { elem, .. } => Some(elem),
                        _ => None,
                    };
                    let carried = old.and_then(elem);
                    if carried.is_some() {
                        steps.push(Step::Index(i));
                    }
                    (elem(new).unwrap_or(new), carried)
                }
            };
            (new, old) = (next, carried);
        }
        Ok((old, steps))
    }

    /// The old value's length of the array at `path`, if it has an array there.
    fn old_len(&self, old: Option<NodeId>, steps: &Path) -> Result<Option<u64>, Halt> {
        Ok(match old.map(|o| self.layout.node(o).kind) {
            Some(Kind::Array { len, .. }) => Some(len.into()),
            Some(Kind::DynArray { .. }) => {
                let len = read_at(
                    self.layout,
                    self.old_root,
                    self.old_data,
                    steps,
                    LeafClass::Len,
                )?;
                match len {
                    Scalar::Uint(n) => Some(n),
                    _ => None,
                }
            }
            _ => None,
        })
    }
}

impl<R: BitRead + ?Sized, B: BitRead + ?Sized> Visit for Carry<'_, R, B> {
    fn leaf(&mut self, at: &LeafAt<'_>, _: Option<Scalar>) -> Result<Option<Scalar>, Halt> {
        if let Some(version) = at.version {
            return Ok(Some(Scalar::Uint(version.into())));
        }
        let layout = self.layout;
        let (old, steps) = self.old_at(at.path)?;
        let carried = match (at.kind, old) {
            (LeafKind::Scalar(_), Some(o)) if shape(layout, o) == 0 => Some(read_at(
                layout,
                self.old_root,
                self.old_data,
                &steps,
                LeafClass::Scalar,
            )?),
            (LeafKind::Tag { union, .. }, Some(o)) => {
                // The old variant, where the new type has one of that name and kind.
                let tag = read_at(layout, self.old_root, self.old_data, &steps, LeafClass::Tag)?;
                let variant = match tag {
                    Scalar::Uint(t) => layout.members(o).get(t as usize),
                    _ => None,
                };
                variant.and_then(|v| {
                    layout
                        .members(union)
                        .iter()
                        .position(|n| {
                            layout.name(n) == layout.name(v)
                                && shape(layout, n.node) == shape(layout, v.node)
                        })
                        .map(|i| Scalar::Uint(i as u64))
                })
            }
            (LeafKind::Len { .. }, old) => self.old_len(old, &steps)?.map(Scalar::Uint),
            _ => None,
        };
        match carried {
            Some(value) => Ok(Some(value)),
            None => read_at(layout, self.new_root, self.base, at.path, class(at.kind)).map(Some),
        }
    }

    fn fixed_len(&mut self, path: &Path, len: u32) -> Result<(), Halt> {
        let (old, steps) = self.old_at(path)?;
        match self.old_len(old, &steps)? {
            Some(n) if n != u64::from(len) => {
                self.wrong_len = Some((n, len));
                Err(Halt::Refused)
            }
            _ => Ok(()),
        }
    }

    fn refusal(&self, fault: &mut Option<ErrorKind<LeafError>>) {
        *fault = Some(match self.wrong_len {
            Some((len, expected)) => ErrorKind::WrongArrayLength { len, expected },
            // A leaf the old value or the base does not hold (TranslateError::Unreadable).
            None => ErrorKind::Value(LeafError::Exhausted),
        });
    }
}

/// Encodes into `out` the value of type `new` that `old_data` (a value of type `old`, stored
/// without tail array optimization) becomes, with what `new` added taken from `base` (a value
/// of `new`, same encoding): what [`crate::translate::translate`] writes, without its report.
/// Returns the length in bytes.
pub fn translate<R: BitRead + ?Sized, B: BitRead + ?Sized>(
    layout: &Layout<'_>,
    old: NodeId,
    old_data: &R,
    new: NodeId,
    base: &B,
    out: &mut [u8],
) -> Result<usize, Error<TranslateError>> {
    let mut carry = Carry {
        layout,
        old_root: old,
        old_data,
        new_root: new,
        base,
        wrong_len: None,
    };
    let options = EncodeOptions {
        tao: false,
        saturate: false,
        keep_versions: false,
    };
    let written = write_whole(layout, new, None, out, options, &mut carry);
    written.map_err(|e| Error {
        kind: e
            .kind
            .map_value(|_| ErrorKind::Value(TranslateError::Unreadable)),
        bit_offset: e.bit_offset,
        path: e.path,
    })
}
