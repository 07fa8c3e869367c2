//! The core of px4params: DroneCAN (UAVCAN v0) bit-packed serialization driven by compiled
//! layouts, leaf access in encoded data, flat leaf values, descattering (decoding from
//! payloads in pieces), the fixed-capacity instance parameter store and its file format, data
//! type signatures and CAN transfers.
//!
//! `no_std` and allocation-free; the `alloc` feature adds [`compile::OwnedLayout`] to build
//! layouts at run time. Firmware can instead keep a [`layout::Layout`] in static tables.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

#[cfg(feature = "alloc")]
extern crate alloc;
#[cfg(test)]
extern crate std;

/// The core's version (its crate's, which is the workspace's): `px4params --version` prints it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

pub mod bits;
pub mod codec;
#[cfg(feature = "alloc")]
pub mod compile;
pub mod crc;
pub mod error;
pub mod file;
mod interp;
pub mod layout;
pub mod leaf;
pub mod pages;
pub mod plan;
#[cfg(feature = "alloc")]
pub mod program;
pub mod rules;
pub mod scalar;
pub mod scatter;
pub mod store;
pub mod straight;
pub mod table;
pub mod transfer;
pub mod translate;
pub mod value;
pub mod walk;

pub use codec::{decode, encode, DecodeOptions, EncodeOptions};
pub use error::{Error, ErrorKind, Path};
pub use layout::{Kind, Layout, NodeId};
pub use leaf::{get_leaf, locate, set_leaf, Target};
pub use scalar::{Cast, Scalar};
