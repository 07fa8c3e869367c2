//! Which speed-ups a build runs, chosen once and by type.
//!
//! Every operation with a speed-up has one dispatcher, generic over a [`Plans`] set: it asks
//! the plan first and otherwise runs the small walk ([`crate::walk`]), which answers for every
//! value. Hosts run [`HostPlans`]; firmware builds (feature `compact`) run [`NoPlans`], the
//! walk alone (a third of the code). The choice of [`Active`] below is the only place where
//! the feature is read, so that the host's tests can run both sets in one build (see
//! `tests/parity.rs`) and exercise the code that flies.

/// A set of plans: each constant says whether a plan runs.
pub trait Plans {
    /// Bits read and written through one 64-bit window where they fit one (else a byte at a
    /// time), and scattered bytes read through that window.
    const WINDOWED_BITS: bool;
    /// The codec over flat leaf lists: encoder and decoder with fixed-offset runs of leaves
    /// in one loop (else the walk encodes and decodes).
    const FLAT: bool;
    /// Leaf `[k]` found by the seek that steps over fixed-shape parts, with its field path
    /// or without (else the walk locates).
    const SEEK: bool;
    /// The store's leaf tables, and leaves written in place (else the walk reads and writes).
    const TABLES: bool;
    /// Translation between type versions by the path-keeping translator, and stored
    /// versions checked by the decoder (else the walk).
    const TRANSLATE: bool;
    /// A multi-frame transfer's CRC over its payload gathered in runs (else across pieces).
    const GATHERED_CRC: bool;
    /// A transfer of full classic CAN frames (all but the last 8 bytes) checked and gathered
    /// in one pass over its frames (else the tails are checked, then the payload gathered).
    const CLASSIC_FRAMES: bool;
    /// Bytes per step of the CRC-16 (8: tables of 4 KB; 0: half a byte, a 32-byte table).
    const CRC_SLICES: usize;
    /// Small fixed-shape types (a fixed run, perhaps ending in an array of primitives)
    /// encoded and decoded in one straight pass ([`crate::straight`]).
    const STRAIGHT: bool;
}

/// Every plan: what hosts run.
#[derive(Clone, Copy, Debug)]
pub struct HostPlans;

impl Plans for HostPlans {
    const WINDOWED_BITS: bool = true;
    const FLAT: bool = true;
    const SEEK: bool = true;
    const TABLES: bool = true;
    const TRANSLATE: bool = true;
    const GATHERED_CRC: bool = true;
    const CLASSIC_FRAMES: bool = true;
    const CRC_SLICES: usize = 8;
    const STRAIGHT: bool = true;
}

/// No plan: the walk alone, what firmware built for size runs.
#[derive(Clone, Copy, Debug)]
pub struct NoPlans;

impl Plans for NoPlans {
    const WINDOWED_BITS: bool = false;
    const FLAT: bool = false;
    const SEEK: bool = false;
    const TABLES: bool = false;
    const TRANSLATE: bool = false;
    const GATHERED_CRC: bool = false;
    const CLASSIC_FRAMES: bool = false;
    const CRC_SLICES: usize = 0;
    const STRAIGHT: bool = false;
}

/// The plans this build runs.
#[cfg(not(feature = "compact"))]
pub type Active = HostPlans;
/// The plans this build runs.
#[cfg(feature = "compact")]
pub type Active = NoPlans;
