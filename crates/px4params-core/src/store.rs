//! The instance parameter store: every parameter's instances in memory reserved up front.
//!
//! A parameter is a type (its root node) with `instances` numbered slots (`INA238#0` ..
//! `INA238#3`), or a single shared slot that always exists. Each slot keeps its current value
//! and its default, encoded with the DroneCAN rules without tail array optimization (so that a
//! stored value delimits itself), plus its state: present, used, unsaved.
//!
//! [`plan`] lays the parameters out and says how much memory they need; [`Store::new`] takes
//! that memory from the caller (slices in firmware, arrays, or `Vec`s on a host) and never
//! allocates. Every operation is all-or-nothing: it checks everything before it writes, and
//! whole-value writes are staged in a scratch area before they are committed.
//!
//! Bytes per parameter: its type's default, then for each instance its value and its default,
//! each `slot_bytes` long (the type's largest encoding). One scratch area of the largest
//! `slot_bytes` follows all parameters.
//!
//! Optional leaf tables ([`Store::with_tables`]) serve drivers, which read leaves far more
//! often than anything writes them: where each instance's first leaves are is worked out
//! whenever its value or default changes, so that [`Store::read`] is a lookup and a bit read.

// Errors are returned by value: the core never allocates, so they cannot be boxed.
#![allow(clippy::result_large_err)]

use core::convert::Infallible;
use core::fmt;

use crate::bits::{to_stream, write_bits};
use crate::codec::{self, EncodeOptions, LeafKind, Source};
use crate::error::{Error, ErrorKind, Path, Step};
use crate::layout::{Kind, Layout, NodeId, Role};
use crate::leaf::{self, Leaf, Position, Target};
use crate::plan::{Active, Plans};
use crate::scalar::{self, Scalar, ScalarError};
use crate::table::{LeafSlot, LeafTable, UNRESOLVED};

/// The most leaves resolved per instance value or default ([`table_slots`]): later leaves are
/// found through the table on each read.
const RESOLVED_MAX: usize = 32;

/// Stored values never use tail array optimization: each one delimits itself.
const STORED: EncodeOptions = EncodeOptions {
    tao: false,
    saturate: false,
    keep_versions: false,
};

/// One parameter's place in the store.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct ParamDef {
    /// The parameter's type.
    pub root: NodeId,
    /// Number of instance slots (1 for a shared parameter).
    pub instances: u16,
    /// A single value that always exists and has no instance number.
    pub shared: bool,
    /// First slot (the type default's), set by [`plan`].
    pub first_slot: u32,
    /// First byte of the parameter's memory, set by [`plan`].
    pub first_byte: u32,
    /// Bytes per stored value: the type's largest encoding, set by [`plan`].
    pub slot_bytes: u32,
}

impl ParamDef {
    /// An instanced parameter with `max_instances` slots.
    pub const fn instanced(root: NodeId, max_instances: u16) -> Self {
        Self {
            root,
            instances: max_instances,
            shared: false,
            first_slot: 0,
            first_byte: 0,
            slot_bytes: 0,
        }
    }

    /// A shared parameter: one value, always present.
    pub const fn shared(root: NodeId) -> Self {
        Self {
            root,
            instances: 1,
            shared: true,
            first_slot: 0,
            first_byte: 0,
            slot_bytes: 0,
        }
    }

    fn bytes(&self) -> usize {
        (1 + 2 * self.instances as usize) * self.slot_bytes as usize
    }
}

/// Memory a store needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capacity {
    /// Number of [`Slot`]s.
    pub slots: usize,
    /// Number of bytes for values and defaults, scratch area included.
    pub bytes: usize,
}

/// Lays out `defs` one after the other and returns the memory they need.
pub fn plan(layout: &Layout<'_>, defs: &mut [ParamDef]) -> Result<Capacity> {
    let mut totals = Totals::default();
    for (index, def) in defs.iter_mut().enumerate() {
        *def = totals.place(layout, index, def)?;
    }
    Ok(totals.capacity())
}

/// Running totals while parameters are laid out one after the other.
#[derive(Default)]
struct Totals {
    slots: usize,
    bytes: usize,
    scratch: usize,
}

impl Totals {
    /// Where `def` (parameter `index`) goes next; adds it to the totals.
    fn place(&mut self, layout: &Layout<'_>, index: usize, def: &ParamDef) -> Result<ParamDef> {
        let param = index as u32;
        let node = layout
            .nodes
            .get(def.root as usize)
            .ok_or(StoreError::NoSuchParam { param })?;
        let slot_bytes = node.max_bits.div_ceil(8) as usize;
        if slot_bytes > u16::MAX as usize
            || def.instances == 0
            || (def.shared && def.instances != 1)
        {
            return Err(StoreError::Unsupported { param });
        }
        let placed = ParamDef {
            first_slot: self.slots as u32,
            first_byte: self.bytes as u32,
            slot_bytes: slot_bytes as u32,
            ..*def
        };
        self.slots += 1 + def.instances as usize;
        self.bytes += placed.bytes();
        if self.bytes > u32::MAX as usize {
            return Err(StoreError::Unsupported { param });
        }
        self.scratch = self.scratch.max(slot_bytes);
        Ok(placed)
    }

    fn capacity(&self) -> Capacity {
        Capacity {
            slots: self.slots,
            bytes: self.bytes + self.scratch,
        }
    }
}

const PRESENT: u8 = 1;
const USED: u8 = 2;
const UNSAVED: u8 = 4;
/// Named by a record of the file being applied ([`crate::file::apply`]'s check): a second
/// record of the slot is refused. Cleared when the check ends.
const FILED: u8 = 8;

/// The state of one instance (or of a parameter's type default).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[repr(C)]
pub struct Slot {
    value_len: u16,
    default_len: u16,
    flags: u8,
}

impl Slot {
    /// The instance exists.
    pub fn present(&self) -> bool {
        self.flags & PRESENT != 0
    }
    /// A driver has read it.
    pub fn used(&self) -> bool {
        self.flags & USED != 0
    }
    /// Changed (or removed) since the last save.
    pub fn unsaved(&self) -> bool {
        self.flags & UNSAVED != 0
    }
}

/// Which of an instance's two values an operation works on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    /// The current value.
    Value,
    /// The default value (`param set-default`).
    Default,
}

/// A store operation's error. `E` is the value source's error for whole-value writes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum StoreError<E = Infallible> {
    /// No parameter with this index.
    NoSuchParam {
        /// The index asked for.
        param: u32,
    },
    /// A parameter the store cannot hold (a value over 65535 bytes, or no slot).
    Unsupported {
        /// Its index.
        param: u32,
    },
    /// A parameter definition not laid out as [`plan`] lays it out.
    NotPlanned {
        /// Its index.
        param: u32,
    },
    /// An instance number at or above `max_instances`.
    InstanceOutOfRange {
        /// The number asked for.
        instance: u32,
        /// The parameter's `max_instances`.
        max_instances: u16,
    },
    /// The instance does not exist.
    NotPresent {
        /// Its number.
        instance: u16,
    },
    /// The instance exists already.
    AlreadyPresent {
        /// Its number.
        instance: u16,
    },
    /// Every instance slot is taken.
    Full {
        /// The parameter's `max_instances`.
        max_instances: u16,
    },
    /// A shared parameter has no instances to add or remove.
    Shared,
    /// `p_version` fields are written by the store, never by the user.
    VersionLeaf {
        /// The leaf's path.
        path: Path,
    },
    /// The memory given does not match the parameters' [`plan`].
    Memory {
        /// What the plan needs.
        needed: Capacity,
    },
    /// The pages or their index cannot hold the values ([`crate::pages`]).
    PagesFull {
        /// Bytes the values need.
        needed: usize,
        /// Number of values.
        values: usize,
    },
    /// Pages of different sizes, or of size 0 ([`crate::pages`]).
    UnequalPages,
    /// The value or leaf was refused by the codec.
    Codec(Error<E>),
}

impl<E> From<Error<E>> for StoreError<E> {
    fn from(e: Error<E>) -> Self {
        Self::Codec(e)
    }
}

impl StoreError {
    /// The same error for a caller whose value source has error type `E`.
    pub fn widen<E>(self) -> StoreError<E> {
        match self {
            Self::NoSuchParam { param } => StoreError::NoSuchParam { param },
            Self::Unsupported { param } => StoreError::Unsupported { param },
            Self::NotPlanned { param } => StoreError::NotPlanned { param },
            Self::InstanceOutOfRange {
                instance,
                max_instances,
            } => StoreError::InstanceOutOfRange {
                instance,
                max_instances,
            },
            Self::NotPresent { instance } => StoreError::NotPresent { instance },
            Self::AlreadyPresent { instance } => StoreError::AlreadyPresent { instance },
            Self::Full { max_instances } => StoreError::Full { max_instances },
            Self::Shared => StoreError::Shared,
            Self::VersionLeaf { path } => StoreError::VersionLeaf { path },
            Self::Memory { needed } => StoreError::Memory { needed },
            Self::PagesFull { needed, values } => StoreError::PagesFull { needed, values },
            Self::UnequalPages => StoreError::UnequalPages,
            Self::Codec(e) => StoreError::Codec(Error {
                kind: e.kind.map_value(|never| match never {}),
                bit_offset: e.bit_offset,
                path: e.path,
            }),
        }
    }
}

impl<E: fmt::Display> StoreError<E> {
    /// Formats the error as one line (without the instance's name, which the caller knows),
    /// with field names from `layout`; a parameter by its number (`parameter #3`).
    pub fn display<'a>(&'a self, layout: &'a Layout<'a>) -> impl fmt::Display + 'a {
        StoreErrorDisplay::<E, &str> {
            error: self,
            layout,
            names: &[],
        }
    }

    /// [`StoreError::display`] for a caller that knows parameters by name: parameter `i` is
    /// called `names[i]` (`parameter INA238`), by its number where `names` lacks it.
    pub fn display_named<'a, N: AsRef<str>>(
        &'a self,
        layout: &'a Layout<'a>,
        names: &'a [N],
    ) -> impl fmt::Display + 'a {
        StoreErrorDisplay {
            error: self,
            layout,
            names,
        }
    }
}

struct StoreErrorDisplay<'a, E, N> {
    error: &'a StoreError<E>,
    layout: &'a Layout<'a>,
    /// The parameters' names, by number (none: parameters by number).
    names: &'a [N],
}

/// A parameter in an error: by its name where there is one, else by its number.
struct Param<'a> {
    param: u32,
    name: Option<&'a str>,
}

impl fmt::Display for Param<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name {
            Some(name) => f.write_str(name),
            None => write!(f, "#{}", self.param),
        }
    }
}

impl<E: fmt::Display, N: AsRef<str>> fmt::Display for StoreErrorDisplay<'_, E, N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let param = |param: &u32| Param {
            param: *param,
            name: self.names.get(*param as usize).map(AsRef::as_ref),
        };
        match self.error {
            StoreError::NoSuchParam { param: p } => write!(f, "no parameter {}", param(p)),
            StoreError::NotPlanned { param: p } => write!(
                f,
                "parameter {} is not laid out as plan() lays it out",
                param(p)
            ),
            StoreError::Unsupported { param: p } => write!(
                f,
                "parameter {} cannot be stored (no slot, or a value over 65535 bytes)",
                param(p)
            ),
            StoreError::InstanceOutOfRange {
                instance,
                max_instances,
            } => write!(
                f,
                "instance {instance} is out of range (max_instances is {max_instances}: \
                 instances 0..{})",
                max_instances.saturating_sub(1)
            ),
            StoreError::NotPresent { .. } => {
                f.write_str("instance does not exist (add it first: param add)")
            }
            StoreError::AlreadyPresent { .. } => f.write_str("instance exists already"),
            StoreError::Full { max_instances } => write!(
                f,
                "all {max_instances} instances are in use (max_instances is {max_instances})"
            ),
            StoreError::Shared => {
                f.write_str("a shared parameter has no instances to add or remove")
            }
            StoreError::VersionLeaf { path } => write!(
                f,
                "{} is set automatically to the type's version and cannot be written",
                path.display(self.layout)
            ),
            StoreError::Memory { needed } => write!(
                f,
                "store memory does not match its plan ({} slots and {} bytes needed)",
                needed.slots, needed.bytes
            ),
            StoreError::UnequalPages => f.write_str("pages must all have one size, greater than 0"),
            StoreError::PagesFull { needed, values } => write!(
                f,
                "the pages or their index are too small ({values} values of {needed} bytes)"
            ),
            StoreError::Codec(e) => e.display(self.layout).fmt(f),
        }
    }
}

/// The store, over caller-provided memory: definitions `D`, slots `S` and bytes `B` (slices,
/// arrays or vectors), and optionally leaf tables `T` ([`Store::with_tables`]) that make
/// reading a leaf by number a table lookup. The layout is passed to each operation that needs
/// it.
#[derive(Clone, Debug)]
pub struct Store<D, S, B, T = [LeafSlot; 0]> {
    defs: D,
    slots: S,
    bytes: B,
    tables: T,
    scratch: usize,
}

/// Number of [`LeafSlot`]s that [`Store::with_tables`] needs for `defs` (laid out by [`plan`])
/// to give every parameter's type a complete leaf table ([`crate::table`]) and every instance
/// its resolved leaves: one per parameter, each distinct type's table, and for each instance's
/// value and default one per leaf its table may answer for (up to 32: where the instance's
/// first leaves are, worked out whenever its value changes, so that a read goes straight to
/// the bits).
pub fn table_slots(layout: &Layout<'_>, defs: &[ParamDef]) -> usize {
    let mut total = defs.len();
    for (i, def) in defs.iter().enumerate() {
        if (def.root as usize) >= layout.nodes.len() {
            continue;
        }
        let (slots, entries) = LeafTable::needed(layout, def.root);
        if !defs[..i].iter().any(|d| d.root == def.root) {
            total += slots;
        }
        total += resolved_per_value(entries) * 2 * def.instances as usize;
    }
    total
}

/// Leaves resolved per value of a type whose table has `entries` leaf entries.
fn resolved_per_value(entries: usize) -> usize {
    entries.min(RESOLVED_MAX)
}

type Result<T, E = Infallible> = core::result::Result<T, StoreError<E>>;

impl<D, S, B> Store<D, S, B>
where
    D: AsRef<[ParamDef]>,
    S: AsRef<[Slot]> + AsMut<[Slot]>,
    B: AsRef<[u8]> + AsMut<[u8]>,
{
    /// A store over `defs` (laid out by [`plan`]) with every instance absent, shared
    /// parameters present, and each type's default the zero value ([`leaf::encode_default`]).
    pub fn new(layout: &Layout<'_>, defs: D, slots: S, bytes: B) -> Result<Self> {
        Store::with_tables(layout, defs, slots, bytes, [])
    }
}

impl<D, S, B, T> Store<D, S, B, T>
where
    D: AsRef<[ParamDef]>,
    S: AsRef<[Slot]> + AsMut<[Slot]>,
    B: AsRef<[u8]> + AsMut<[u8]>,
    T: AsRef<[LeafSlot]> + AsMut<[LeafSlot]>,
{
    /// [`Store::new`], with the parameters' leaf tables built in `tables`: then reading or
    /// writing leaf `[k]` is a table lookup ([`crate::table`]) for the leaves a type's shape
    /// fixes, and reading one of an instance's first leaves a lookup of where it was found
    /// when the value last changed. [`table_slots`] says how many slots cover every type and
    /// instance completely; with fewer, the tables cover what fits, instances are resolved
    /// while room remains, and the rest is walked as without them (same results).
    pub fn with_tables(
        layout: &Layout<'_>,
        defs: D,
        slots: S,
        bytes: B,
        mut tables: T,
    ) -> Result<Self> {
        let (needed, scratch) = check_plan(layout, defs.as_ref())?;
        if slots.as_ref().len() < needed.slots || bytes.as_ref().len() < needed.bytes {
            return Err(StoreError::Memory { needed });
        }
        build_tables(layout, defs.as_ref(), tables.as_mut());
        let mut store = Self {
            defs,
            slots,
            bytes,
            tables,
            scratch: needed.bytes - scratch,
        };
        store.slots.as_mut().fill(Slot::default());
        for param in 0..store.defs.as_ref().len() {
            let def = store.defs.as_ref()[param];
            let region = store.bytes_mut(def.first_byte as usize, def.slot_bytes as usize);
            let len = leaf::encode_default(layout, def.root, region, false)?;
            store.with_slot(def.first_slot as usize, |s| s.default_len = len as u16);
            if def.shared {
                store.fill_instance(param as u32, &def, 0);
                store.with_slot(def.first_slot as usize + 1, |s| s.flags = PRESENT);
            }
        }
        Ok(store)
    }

    /// The parameters.
    pub fn defs(&self) -> &[ParamDef] {
        self.defs.as_ref()
    }

    /// Parameter `param`'s definition.
    pub fn def(&self, param: u32) -> Result<ParamDef> {
        self.def_of(param).copied()
    }

    /// [`Store::def`] by reference: the store's operations copy it out of the result (a
    /// definition inside a result is moved in pieces).
    fn def_of(&self, param: u32) -> Result<&ParamDef> {
        self.defs
            .as_ref()
            .get(param as usize)
            .ok_or(StoreError::NoSuchParam { param })
    }

    /// Sets parameter `param`'s type default (the value new instances start from), e.g. from
    /// the type's `@default` metadata. `data` is checked like [`Store::set_encoded`]. A shared
    /// parameter's default changes with it, and so does its value unless it was changed.
    pub fn set_type_default(&mut self, layout: &Layout<'_>, param: u32, data: &[u8]) -> Result<()> {
        let def = *self.def_of(param)?;
        check_encoded(layout, def.root, data)?;
        self.write_bytes(def.first_byte as usize, data);
        self.with_slot(def.first_slot as usize, |s| {
            s.default_len = data.len() as u16
        });
        if def.shared {
            self.stage(data);
            self.commit(param, &def, 0, Which::Default, data.len());
        }
        Ok(())
    }

    /// The type default of parameter `param`.
    pub fn type_default(&self, param: u32) -> Result<&[u8]> {
        let def = *self.def_of(param)?;
        let len = self.slot_at(def.first_slot as usize).default_len as usize;
        Ok(self.bytes_at(def.first_byte as usize, len))
    }

    /// The state of an instance.
    pub fn slot(&self, param: u32, instance: u16) -> Result<Slot> {
        let def = *self.def_of(param)?;
        let index = slot_index(&def, instance)?;
        Ok(self.slot_at(index))
    }

    /// The numbers of the instances that exist, in order.
    pub fn instances(&self, param: u32) -> Result<impl Iterator<Item = u16> + '_> {
        let def = *self.def_of(param)?;
        let present = self.instance_slots(&def).iter().enumerate();
        Ok(present.filter(|(_, s)| s.present()).map(|(i, _)| i as u16))
    }

    /// Adds instance `instance`, or the lowest free one when `None`; returns its number. It
    /// starts with the type default as value and default.
    pub fn add(&mut self, param: u32, instance: Option<u16>) -> Result<u16> {
        let def = *self.def_of(param)?;
        if def.shared {
            return Err(StoreError::Shared);
        }
        let instance = match instance {
            Some(i) => {
                if self.slot_at(slot_index(&def, i)?).present() {
                    return Err(StoreError::AlreadyPresent { instance: i });
                }
                i
            }
            None => self.instances_free(&def).ok_or(StoreError::Full {
                max_instances: def.instances,
            })?,
        };
        self.fill_instance(param, &def, instance);
        let index = def.first_slot as usize + 1 + instance as usize;
        self.with_slot(index, |s| s.flags = PRESENT | UNSAVED);
        Ok(instance)
    }

    /// Removes an instance; the others keep their numbers.
    pub fn remove(&mut self, param: u32, instance: u16) -> Result<()> {
        let def = *self.def_of(param)?;
        if def.shared {
            return Err(StoreError::Shared);
        }
        let index = self.present_slot(&def, instance)?;
        self.with_slot(index, |s| {
            *s = Slot {
                flags: UNSAVED,
                ..Slot::default()
            }
        });
        Ok(())
    }

    /// The encoded value or default of an instance.
    pub fn get(&self, param: u32, instance: u16, which: Which) -> Result<&[u8]> {
        let def = *self.def_of(param)?;
        let index = self.present_slot(&def, instance)?;
        Ok(self.region(&def, index, which))
    }

    /// Whether an instance's value differs from its default.
    pub fn changed(&self, param: u32, instance: u16) -> Result<bool> {
        Ok(
            self.get(param, instance, Which::Value)?
                != self.get(param, instance, Which::Default)?,
        )
    }

    /// Reads a leaf of an instance's value or default.
    pub fn get_leaf(
        &self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        target: Target<'_>,
    ) -> Result<(Leaf, Scalar)> {
        let def = *self.def_of(param)?;
        let index = self.present_slot(&def, instance)?;
        let found = match self.table(param) {
            Some(table) => {
                // The value and what follows it in memory: bits are read 64 at a time.
                let (start, len) = self.span(&def, index, which);
                let data = &self.bytes.as_ref()[start..];
                if let Target::Index(k) = target {
                    let resolved = self.resolved(param, &def, index, which, k);
                    if let Some(found) = resolved.and_then(|r| table.get_resolved(r, data, k)) {
                        return Ok(found);
                    }
                }
                table.get_leaf_prefix(layout, data, len, target)
            }
            None => {
                let data = self.region(&def, index, which);
                leaf::get_leaf(layout, def.root, data, target, false)
            }
        };
        found.map_err(StoreError::Codec)
    }

    /// Reads leaf `[k]` of an instance's value or default: the fast path for drivers (no field
    /// path is kept; errors are worked out by [`Store::get_leaf`]).
    pub fn read(
        &self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        k: usize,
    ) -> Result<Scalar> {
        if !Active::TABLES {
            // Without plans, read by one walk (leaf tables are a host's speed-up), in line:
            // the caller's handling of errors and the walk's are one code.
            return self.read_walked(layout, param, instance, which, k);
        }
        let def = *self.def_of(param)?;
        let index = self.present_slot(&def, instance)?;
        // The value and what follows it in memory: bits are read 64 at a time.
        let (start, len) = self.span(&def, index, which);
        let data = &self.bytes.as_ref()[start..];
        let known = match self.resolved(param, &def, index, which, k) {
            // Resolution is the table's final answer: a leaf it did not find is walked.
            Some(resolved) => LeafTable::read_resolved(resolved, data),
            None => self
                .table(param)
                .and_then(|table| table.read_known(data, len, k)),
        };
        match known {
            Some(value) => Ok(value),
            None => self.read_untabled(layout, param, instance, which, k),
        }
    }

    /// [`Store::read`] of a leaf its table does not answer for: walked, out of line so that
    /// the table's path stays small.
    #[inline(never)]
    fn read_untabled(
        &self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        k: usize,
    ) -> Result<Scalar> {
        self.read_walked(layout, param, instance, which, k)
    }

    /// Reads leaf `[k]` by walking the value: every read of a store without tables (the C
    /// ABI's), and those a table does not answer for ([`Store::read_untabled`]).
    #[inline(always)]
    fn read_walked(
        &self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        k: usize,
    ) -> Result<Scalar> {
        let def = *self.def_of(param)?;
        let index = self.present_slot(&def, instance)?;
        let data = self.region(&def, index, which);
        // Without plans the leaf is found and read in one walk; hosts seek first (faster).
        let sought = match Active::SEEK {
            false => None,
            true => leaf::seek(layout, def.root, data, k),
        };
        match sought {
            Some(p) => Ok(p.read(data)),
            // Matched, not `?`: the error is moved once (firmware's code is smaller).
            None => match leaf::get_leaf_at(layout, def.root, data, k, false) {
                Ok((_, value)) => Ok(value),
                Err(e) => Err(StoreError::Codec(e)),
            },
        }
    }

    /// Writes a leaf of an instance's value or default. A primitive leaf is written in place;
    /// a union tag or array length re-encodes the value (see [`leaf::set_leaf`]). Writing a
    /// default also writes the value when the value was equal to the old default, as PX4's
    /// `param set-default` does. A value the leaf would keep as a NaN or an infinity is refused
    /// ([`ScalarError::NotFinite`]).
    #[allow(clippy::too_many_arguments)] // one call names one leaf of one instance: all needed
    pub fn set_leaf(
        &mut self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        target: Target<'_>,
        value: Scalar,
        saturate: bool,
    ) -> Result<()> {
        let k = match target {
            Target::Index(k) => k,
            Target::Path(_) => {
                let def = *self.def_of(param)?;
                let index = self.present_slot(&def, instance)?;
                let data = self.region(&def, index, which);
                leaf::locate(layout, def.root, data, target, false)?.index
            }
        };
        self.set_leaf_at(layout, param, instance, which, k, value, saturate)
    }

    /// [`Store::set_leaf`] of leaf `[k]`.
    #[allow(clippy::too_many_arguments)] // one call names one leaf of one instance: all needed
    pub fn set_leaf_at(
        &mut self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        k: usize,
        value: Scalar,
        saturate: bool,
    ) -> Result<()> {
        let def = *self.def_of(param)?;
        let index = self.present_slot(&def, instance)?;
        if !Active::TABLES {
            let at = (instance, index);
            return self.set_leaf_copied(layout, param, &def, at, which, k, value, saturate);
        }
        let data = self.region(&def, index, which);
        // Seek (through the leaf table) first; the leaf's path is found only for an error.
        let fast = self
            .seek(layout, &def, param, data, k)
            .filter(|p| matches!(p.kind, LeafKind::Scalar(_)) && !p.version);
        // Where the leaf is, and for a primitive leaf, its kind and new bits.
        let (bit_offset, scalar) = match fast {
            Some(Position {
                bit_offset,
                kind: LeafKind::Scalar(kind),
                ..
            }) => match stored_raw(kind, value, saturate) {
                Ok(raw) => (bit_offset, Some((kind, raw))),
                // Find the field path for the error.
                Err(e) => {
                    let found = leaf::locate_at(layout, def.root, data, k, false)?;
                    return Err(StoreError::Codec(Error {
                        kind: ErrorKind::Scalar(e),
                        bit_offset,
                        path: found.path,
                    }));
                }
            },
            _ => {
                let found = leaf::locate_at(layout, def.root, data, k, false)?;
                if is_version(layout, &found.path) {
                    return Err(StoreError::VersionLeaf { path: found.path });
                }
                let scalar = match found.kind {
                    LeafKind::Scalar(kind) => {
                        let raw = stored_raw(kind, value, saturate).map_err(|e| Error {
                            kind: ErrorKind::Scalar(e),
                            bit_offset: found.bit_offset,
                            path: found.path,
                        })?;
                        Some((kind, raw))
                    }
                    _ => None,
                };
                (found.bit_offset, scalar)
            }
        };
        if let Some((kind, raw)) = scalar {
            let follows = which == Which::Default && self.values_equal(&def, index);
            let bits = codec::scalar_bits(kind);
            let stream = to_stream(raw, bits);
            let mut targets = [Some(which), None];
            if follows {
                targets[1] = Some(Which::Value);
            }
            for w in targets.into_iter().flatten() {
                let (start, _) = self.span(&def, index, w);
                let bytes = self.bytes.as_mut();
                write_bits(&mut bytes[start..], bit_offset, stream, bits);
            }
            self.slots.as_mut()[index].flags |= UNSAVED;
            return Ok(());
        }
        let (scratch, end) = (self.scratch, self.bytes.as_ref().len());
        let (head, tail) = self.bytes.as_mut().split_at_mut(scratch);
        let (start, len) = span_of(&def, self.slots.as_ref()[index], index, which);
        let options = EncodeOptions { saturate, ..STORED };
        // A tag or a length: the value is written anew.
        let new_len = crate::walk::transcode(
            layout,
            def.root,
            &head[start..start + len],
            k,
            value,
            &mut tail[..end - scratch],
            options,
        )?;
        self.commit(param, &def, instance, which, new_len);
        Ok(())
    }

    /// [`Store::set_leaf_at`] as firmware builds do it, in little code: the leaf is found in
    /// one walk, and the value with it written goes through the scratch area (a primitive leaf
    /// copied and written over, a tag or length transcoded). The instance is `(instance,
    /// index)`: its number and its slot, which the caller found present.
    #[allow(clippy::too_many_arguments)] // one call names one leaf of one instance: all needed
    fn set_leaf_copied(
        &mut self,
        layout: &Layout<'_>,
        param: u32,
        def: &ParamDef,
        (instance, index): (u16, usize),
        which: Which,
        k: usize,
        value: Scalar,
        saturate: bool,
    ) -> Result<()> {
        let (start, len) = self.span(def, index, which);
        // The value before the scratch area, the scratch area (to its end) after it; nothing
        // (never: the memory was checked against the plan) is read and written as empty.
        let (head, out) = self
            .bytes
            .as_mut()
            .split_at_mut_checked(self.scratch)
            .unwrap_or_default();
        let data = head.get(start..start + len).unwrap_or_default();
        // Found as a read finds it: the walk's own result, used where it lies.
        let found = &leaf::get_leaf_at(layout, def.root, data, k, false);
        let found = match found {
            Ok((found, _)) => found,
            Err(e) => return Err(StoreError::Codec(*e)),
        };
        if is_version(layout, &found.path) {
            return Err(StoreError::VersionLeaf { path: found.path });
        }
        if let LeafKind::Scalar(kind) = found.kind {
            if let Err(e) = stored_raw(kind, value, saturate) {
                let (bit_offset, path) = (found.bit_offset, found.path);
                let kind = ErrorKind::Scalar(e);
                return Err(StoreError::Codec(Error {
                    kind,
                    bit_offset,
                    path,
                }));
            }
        }
        let options = EncodeOptions { saturate, ..STORED };
        let new_len = leaf::set_located(layout, def.root, data, found, value, out, options)?;
        self.commit(param, def, instance, which, new_len);
        Ok(())
    }

    /// Writes a whole value or default from `source` (which may leave out `p_version` fields:
    /// they are filled in; given, they must equal the type's version). A NaN or an infinity is
    /// refused, as [`Store::set_encoded`] refuses it.
    pub fn set_from<Src: Source>(
        &mut self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        source: &mut Src,
        saturate: bool,
    ) -> Result<(), Src::Error> {
        let def = *self.def_of(param).map_err(StoreError::widen)?;
        self.present_slot(&def, instance)
            .map_err(StoreError::widen)?;
        let options = EncodeOptions { saturate, ..STORED };
        let out = self.bytes_mut(self.scratch, def.slot_bytes as usize);
        let len = codec::encode(layout, def.root, source, out, options)?;
        // What the source gave passes the check a stored value passes (finite floats).
        let encoded = self.bytes.as_ref().get(self.scratch..self.scratch + len);
        check_encoded(layout, def.root, encoded.unwrap_or_default()).map_err(StoreError::widen)?;
        self.commit(param, &def, instance, which, len);
        Ok(())
    }

    /// Writes a whole encoded value or default (without tail array optimization), after
    /// checking that it decodes completely, that its `p_version` fields hold the version and
    /// that its floats are finite (a store keeps no NaN or infinity).
    pub fn set_encoded(
        &mut self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        data: &[u8],
    ) -> Result<()> {
        let def = *self.def_of(param)?;
        self.present_slot(&def, instance)?;
        check_encoded(layout, def.root, data)?;
        self.stage(data);
        self.commit(param, &def, instance, which, data.len());
        Ok(())
    }

    /// Back to the state [`Store::new`] and the type defaults give: every instance absent,
    /// shared parameters at their type defaults, all marked unsaved.
    pub fn clear(&mut self) {
        for param in 0..self.defs.as_ref().len() {
            let def = self.defs.as_ref()[param];
            let first = def.first_slot as usize + 1;
            if def.shared {
                self.fill_instance(param as u32, &def, 0);
                self.with_slot(first, |s| s.flags = PRESENT | UNSAVED);
            } else {
                for instance in first..first + def.instances as usize {
                    self.with_slot(instance, |s| {
                        *s = Slot {
                            flags: UNSAVED,
                            ..Slot::default()
                        }
                    });
                }
            }
        }
    }

    /// Writes `data`, a stored value of `old` (an older version of the parameter's type), as a
    /// value of the current version ([`crate::translate`]): fields carried over by name, the
    /// new ones from the instance's default (for a value) or the type's default (for a
    /// default). With `check_only` it translates without writing anything.
    #[allow(clippy::too_many_arguments)]
    pub fn set_translated(
        &mut self,
        layout: &Layout<'_>,
        param: u32,
        instance: u16,
        which: Which,
        old: NodeId,
        data: &[u8],
        check_only: bool,
    ) -> Result<(), crate::translate::TranslateError> {
        let def = *self.def_of(param).map_err(StoreError::widen)?;
        let index = slot_index(&def, instance).map_err(StoreError::widen)?;
        // The old value whole, as its own type decodes it: the translation reads only the
        // fields it carries over, and would take a cut or overlong value without a word.
        check_encoded(layout, old, data).map_err(StoreError::widen)?;
        let present = self.slot_at(index).present();
        if !check_only {
            self.present_slot(&def, instance)
                .map_err(StoreError::widen)?;
        }
        let (from, len) = if which == Which::Value && present {
            self.span(&def, index, Which::Default)
        } else {
            let len = self.slot_at(def.first_slot as usize).default_len;
            (def.first_byte as usize, len as usize)
        };
        // Out of range (never: see `Store::slot_at`), the base and the output are empty.
        let (head, tail) = self
            .bytes
            .as_mut()
            .split_at_mut_checked(self.scratch)
            .unwrap_or_default();
        let base = head.get(from..from + len).unwrap_or_default();
        let out = tail.get_mut(..def.slot_bytes as usize).unwrap_or_default();
        let written = crate::translate::translate_value(layout, old, data, def.root, base, out)?;
        if !check_only {
            self.commit(param, &def, instance, which, written);
        }
        Ok(())
    }

    /// Marks the slot of `param`'s `instance` as named by the file being applied; whether it
    /// was already (a second record of it).
    pub(crate) fn mark_filed(&mut self, param: u32, instance: u16) -> Result<bool> {
        let def = *self.def_of(param)?;
        let index = slot_index(&def, instance)?;
        let before = self.slot_at(index).flags & FILED != 0;
        self.with_slot(index, |s| s.flags |= FILED);
        Ok(before)
    }

    /// Forgets every [`Store::mark_filed`] mark.
    pub(crate) fn clear_filed(&mut self) {
        for slot in self.slots.as_mut() {
            slot.flags &= !FILED;
        }
    }

    /// Checks `data` as [`Store::set_encoded`] would, without writing it.
    pub fn check_value(&self, layout: &Layout<'_>, param: u32, data: &[u8]) -> Result<()> {
        check_encoded(layout, self.def(param)?.root, data)
    }

    /// Sets an instance's value back to its default.
    pub fn reset(&mut self, param: u32, instance: u16) -> Result<()> {
        let def = *self.def_of(param)?;
        let index = self.present_slot(&def, instance)?;
        let (from, len) = self.span(&def, index, Which::Default);
        self.put(param, &def, index, Which::Value, from, len);
        self.with_slot(index, |slot| slot.flags |= UNSAVED);
        Ok(())
    }

    /// Marks an instance as read by a driver (PX4's "used").
    pub fn mark_used(&mut self, param: u32, instance: u16) -> Result<()> {
        let def = *self.def_of(param)?;
        let index = self.present_slot(&def, instance)?;
        self.with_slot(index, |s| s.flags |= USED);
        Ok(())
    }

    /// Marks everything as saved.
    pub fn mark_saved(&mut self) {
        for slot in self.slots.as_mut() {
            slot.flags &= !UNSAVED;
        }
    }

    /// Parameter `param`'s leaf table, if it has one.
    #[inline]
    fn table(&self, param: u32) -> Option<LeafTable<'_>> {
        let tables = self.tables.as_ref();
        let index = tables.get(param as usize)?;
        let start = index.a as usize;
        if start == 0 {
            return None;
        }
        Some(LeafTable::built(
            tables.get(start..start + index.b as usize)?,
        ))
    }

    /// Where leaf `[k]` of an instance's value or default was resolved (see
    /// [`Store::resolve`]), if it was.
    #[inline(always)]
    fn resolved(
        &self,
        param: u32,
        def: &ParamDef,
        index: usize,
        which: Which,
        k: usize,
    ) -> Option<LeafSlot> {
        let (first, n) = self.resolved_area(param, def, index, which)?;
        if k >= n {
            return None;
        }
        self.tables.as_ref().get(first + k).copied()
    }

    /// Where an instance's resolved leaves are in the tables' storage, and how many there
    /// are (`None`: not resolved).
    #[inline(always)]
    fn resolved_area(
        &self,
        param: u32,
        def: &ParamDef,
        index: usize,
        which: Which,
    ) -> Option<(usize, usize)> {
        let packed = self.tables.as_ref().get(param as usize)?.c;
        let (start, n) = ((packed >> 8) as usize, (packed & 0xFF) as usize);
        let instance = index - def.first_slot as usize - 1;
        let value = match which {
            Which::Value => 2 * instance,
            Which::Default => 2 * instance + 1,
        };
        (start != 0).then_some((start + value * n, n))
    }

    /// Works out where the leaves of an instance's value or default are, after it changed:
    /// the leaves its table answers for, as many as were given room.
    fn resolve(&mut self, param: u32, def: &ParamDef, index: usize, which: Which) {
        let Some((first, n)) = self.resolved_area(param, def, index, which) else {
            return;
        };
        let mut found = [UNRESOLVED; RESOLVED_MAX];
        let found = &mut found[..n];
        if let Some(table) = self.table(param) {
            let (start, len) = self.span(def, index, which);
            table.resolve(&self.bytes.as_ref()[start..], len, found);
        }
        if let Some(area) = self.tables.as_mut().get_mut(first..first + n) {
            area.copy_from_slice(found);
        }
    }

    /// [`leaf::seek`] in a value of parameter `param`, through its table if it has one.
    #[inline]
    fn seek(
        &self,
        layout: &Layout<'_>,
        def: &ParamDef,
        param: u32,
        data: &[u8],
        k: usize,
    ) -> Option<Position> {
        match self.table(param) {
            Some(table) => table.seek(layout, data, k),
            None => leaf::seek(layout, def.root, data, k),
        }
    }

    fn instances_free(&self, def: &ParamDef) -> Option<u16> {
        let slots = self.instance_slots(def);
        slots.iter().position(|s| !s.present()).map(|i| i as u16)
    }

    // The memory was checked against the plan when the store was made, so every slot and byte
    // range the store works out is in range. The accessors below still check (safe code), and
    // one out of range (never) reads as an absent slot or no bytes and is not written, where
    // indexing would panic: firmware links no panic from the store.

    /// Slot `index` (out of range: an absent slot).
    fn slot_at(&self, index: usize) -> Slot {
        self.slots.as_ref().get(index).copied().unwrap_or_default()
    }

    /// Changes slot `index` (out of range: nothing).
    fn with_slot(&mut self, index: usize, change: impl FnOnce(&mut Slot)) {
        if let Some(slot) = self.slots.as_mut().get_mut(index) {
            change(slot);
        }
    }

    /// The slots of a parameter's instances (out of range: none).
    fn instance_slots(&self, def: &ParamDef) -> &[Slot] {
        let first = def.first_slot as usize + 1;
        let slots = self.slots.as_ref();
        slots
            .get(first..first + def.instances as usize)
            .unwrap_or_default()
    }

    /// `len` bytes at `start` (out of range: none).
    fn bytes_at(&self, start: usize, len: usize) -> &[u8] {
        self.bytes
            .as_ref()
            .get(start..start + len)
            .unwrap_or_default()
    }

    /// `len` bytes at `start`, to write (out of range: none).
    fn bytes_mut(&mut self, start: usize, len: usize) -> &mut [u8] {
        self.bytes
            .as_mut()
            .get_mut(start..start + len)
            .unwrap_or_default()
    }

    /// Writes `data` at `start` (out of range: nothing; a copy into [`Store::bytes_mut`]'s
    /// empty slice would panic on the lengths).
    fn write_bytes(&mut self, start: usize, data: &[u8]) {
        if let Some(to) = self.bytes.as_mut().get_mut(start..start + data.len()) {
            to.copy_from_slice(data);
        }
    }

    // In line: its error is then made where the caller's result is (or dropped with it),
    // not returned through memory and copied (its call cost firmware more than its code).
    #[inline(always)]
    fn present_slot(&self, def: &ParamDef, instance: u16) -> Result<usize> {
        let index = slot_index(def, instance)?;
        if !self.slot_at(index).present() {
            return Err(StoreError::NotPresent { instance });
        }
        Ok(index)
    }

    fn span(&self, def: &ParamDef, index: usize, which: Which) -> (usize, usize) {
        span_of(def, self.slot_at(index), index, which)
    }

    fn region(&self, def: &ParamDef, index: usize, which: Which) -> &[u8] {
        let (start, len) = self.span(def, index, which);
        self.bytes_at(start, len)
    }

    fn values_equal(&self, def: &ParamDef, index: usize) -> bool {
        let (value, default) = (
            self.region(def, index, Which::Value),
            self.region(def, index, Which::Default),
        );
        // Byte by byte: a slice comparison would bring `memcmp` into firmware.
        value.len() == default.len() && value.iter().zip(default).all(|(a, b)| a == b)
    }

    /// Copies the type default into an instance's value and default.
    fn fill_instance(&mut self, param: u32, def: &ParamDef, instance: u16) {
        let len = self.slot_at(def.first_slot as usize).default_len as usize;
        let index = def.first_slot as usize + 1 + instance as usize;
        let from = def.first_byte as usize;
        self.put(param, def, index, Which::Value, from, len);
        self.put(param, def, index, Which::Default, from, len);
    }

    /// Copies the `len` bytes at `from` into an instance's value or default (slot `index`).
    fn put(
        &mut self,
        param: u32,
        def: &ParamDef,
        index: usize,
        which: Which,
        from: usize,
        len: usize,
    ) {
        let (to, _) = self.span(def, index, which);
        copy_apart(self.bytes.as_mut(), from, len, to);
        self.with_slot(index, |slot| match which {
            Which::Value => slot.value_len = len as u16,
            Which::Default => slot.default_len = len as u16,
        });
        self.resolve(param, def, index, which);
    }

    fn stage(&mut self, data: &[u8]) {
        self.write_bytes(self.scratch, data);
    }

    /// Moves the staged `len` bytes into an instance's value or default (and into its value
    /// too when a default is written and the value was equal to the old default).
    fn commit(&mut self, param: u32, def: &ParamDef, instance: u16, which: Which, len: usize) {
        let index = def.first_slot as usize + 1 + instance as usize;
        let follows = which == Which::Default && self.values_equal(def, index);
        self.put(param, def, index, which, self.scratch, len);
        if follows {
            self.put(param, def, index, Which::Value, self.scratch, len);
        }
        self.with_slot(index, |s| s.flags |= UNSAVED);
    }
}

/// Builds the leaf tables of `defs` in `tables`: first one slot per parameter that says where
/// its type's table is and where its instances' resolved leaves are (`{start, len, resolved}`,
/// start 0 for none; `resolved` is the start shifted left by 8 bits, or-ed with the leaves per
/// value, 0 for none), then the tables, one per type, then the parameters' resolved leaves,
/// each instance's value and then its default (filled in as instances get values).
fn build_tables(layout: &Layout<'_>, defs: &[ParamDef], tables: &mut [LeafSlot]) {
    if tables.len() < defs.len() {
        tables.fill(LeafSlot::default());
        return;
    }
    let (index, rest) = tables.split_at_mut(defs.len());
    let mut used = 0;
    for (i, def) in defs.iter().enumerate() {
        index[i] = match defs[..i].iter().position(|d| d.root == def.root) {
            Some(same) => index[same],
            None => match LeafTable::build(layout, def.root, &mut rest[used..]) {
                Ok(table) => {
                    let slot = LeafSlot {
                        a: (defs.len() + used) as u32,
                        b: table.len() as u32,
                        c: 0,
                    };
                    used += table.len();
                    slot
                }
                Err(_) => LeafSlot::default(),
            },
        };
    }
    for (i, def) in defs.iter().enumerate() {
        let (start, len) = (index[i].a as usize, index[i].b as usize);
        if start == 0 {
            continue;
        }
        let table = LeafTable::built(&rest[start - defs.len()..][..len]);
        let n = resolved_per_value(table.entries());
        let area = n * 2 * def.instances as usize;
        let first = defs.len() + used;
        if n == 0 || area > rest.len() - used || first >= 1 << 24 {
            continue;
        }
        rest[used..used + area].fill(UNRESOLVED);
        index[i].c = (first as u32) << 8 | n as u32;
        used += area;
    }
}

fn span_of(def: &ParamDef, slot: Slot, index: usize, which: Which) -> (usize, usize) {
    let instance = index - def.first_slot as usize - 1;
    let value = def.first_byte as usize + (1 + 2 * instance) * def.slot_bytes as usize;
    match which {
        Which::Value => (value, slot.value_len as usize),
        Which::Default => (value + def.slot_bytes as usize, slot.default_len as usize),
    }
}

fn slot_index(def: &ParamDef, instance: u16) -> Result<usize> {
    if instance >= def.instances {
        return Err(StoreError::InstanceOutOfRange {
            instance: instance.into(),
            max_instances: def.instances,
        });
    }
    Ok(def.first_slot as usize + 1 + instance as usize)
}

/// Checks that `defs` are laid out as [`plan`] lays them out; returns the memory they need and
/// the size of the scratch area at its end.
fn check_plan(layout: &Layout<'_>, defs: &[ParamDef]) -> Result<(Capacity, usize)> {
    let mut totals = Totals::default();
    for (index, def) in defs.iter().enumerate() {
        if totals.place(layout, index, def)? != *def {
            return Err(StoreError::NotPlanned {
                param: index as u32,
            });
        }
    }
    Ok((totals.capacity(), totals.scratch))
}

/// Copies `len` bytes at `from` to `to`, two regions that never overlap (the slots of one
/// parameter and its scratch): a plain copy, which firmware has anyway, where `copy_within`
/// would bring `memmove` (1.5 KB on Cortex-M7).
fn copy_apart(bytes: &mut [u8], from: usize, len: usize, to: usize) {
    if from == to {
        return;
    }
    // One split at the higher region and one bounds check per region, whichever way the copy
    // goes (half the code of a split per direction).
    let (low, high) = (from.min(to), from.max(to));
    let Some((head, tail)) = bytes.split_at_mut_checked(high) else {
        return;
    };
    // Out of range (never: the memory was checked against the plan): nothing is copied.
    let (Some(low), Some(high)) = (head.get_mut(low..low + len), tail.get_mut(..len)) else {
        return;
    };
    // One copy, whichever way it goes.
    let (source, target): (&[u8], &mut [u8]) = match from < to {
        true => (low, high),
        false => (high, low),
    };
    target.copy_from_slice(source);
}

fn is_version(layout: &Layout<'_>, path: &Path) -> bool {
    match path.last() {
        Some(Step::Field(f)) => matches!(
            layout.fields.get(f as usize).map(|f| f.role),
            Some(Role::Version(_))
        ),
        _ => false,
    }
}

/// The raw bits of `value` in a leaf of `kind`, as [`codec::scalar_raw`] casts it, refused
/// where they would be a NaN or an infinity: a store keeps finite numbers only (a NaN shunt
/// is a battery monitor that reads nothing).
fn stored_raw(kind: Kind, value: Scalar, saturate: bool) -> core::result::Result<u64, ScalarError> {
    let raw = codec::scalar_raw(kind, value, saturate)?;
    match kind {
        Kind::Float { bits, .. } if !scalar::raw_is_finite(raw, bits.into()) => {
            Err(ScalarError::NotFinite { value })
        }
        _ => Ok(raw),
    }
}

/// Checks that `data` is exactly one stored value of `root` whose `p_version` fields hold the
/// version and whose floats are finite. In line, so that the codec's error becomes the store's
/// where it is returned.
#[inline(always)]
fn check_encoded(layout: &Layout<'_>, root: NodeId, data: &[u8]) -> Result<()> {
    codec::check_stored(layout, root, data).map_err(StoreError::Codec)
}
