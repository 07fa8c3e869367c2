//! Instruction counts of the codec's calls, for `benches/instructions.py` to run under
//! valgrind's callgrind: `instructions OP N` performs `OP` N times, so that the count of N
//! runs minus the count of 0 runs, divided by N, is the instructions of one call (stable where
//! time on this machine is not).
//!
//! OP: `battery/encode`, `battery/decode`, `ina238/encode`, `ina238/decode`.

#[path = "../crates/px4params-core/tests/common/mod.rs"]
mod common;

use px4params_core::codec::{decode, encode, DecodeOptions, EncodeOptions};
use px4params_core::compile::OwnedLayout;
use px4params_core::value::{LeafSink, LeafSource};
use px4params_core::Scalar;
use std::hint::black_box;

fn battery_leaves() -> Vec<Scalar> {
    let mut leaves: Vec<Scalar> = [300.5, 16.8, -12.25, 201.0, 55.5, 99.0, 0.0]
        .into_iter()
        .map(Scalar::Float)
        .collect();
    leaves.extend([3, 97, 80, 2, 1, 123_456].map(Scalar::Uint));
    let name = b"PX4 smart battery 6S";
    leaves.push(Scalar::Uint(name.len() as u64));
    leaves.extend(name.iter().map(|&b| Scalar::Uint(b.into())));
    leaves
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (op, n) = match args.as_slice() {
        [_, op, n] => (op.as_str(), n.parse::<usize>().expect("N: a count")),
        // `cargo bench` runs every bench target with `--bench`: nothing to do here.
        _ => return,
    };
    let (ty, what) = op.split_once('/').expect("OP: TYPE/encode or TYPE/decode");
    let mut owned = OwnedLayout::default();
    let (root, leaves) = match ty {
        "battery" => (common::battery_info(&mut owned), battery_leaves()),
        "ina238" => {
            let mut v: Vec<Scalar> = [0, 0, 0, 1, 0x45, 200].map(Scalar::Uint).to_vec();
            v.push(Scalar::Float(0.0003));
            (common::ina238(&mut owned), v)
        }
        _ => panic!("unknown type {ty}"),
    };
    let layout = owned.as_layout();
    let mut out = vec![0u8; layout.max_bytes(root)];
    let len = encode(
        &layout,
        root,
        &mut LeafSource::new(&leaves),
        &mut out,
        EncodeOptions::default(),
    )
    .unwrap();
    let bytes = out[..len].to_vec();
    let mut storage = [Scalar::Uint(0); 64];
    for _ in 0..n {
        match what {
            "encode" => {
                let mut src = LeafSource::new(black_box(&leaves));
                let r = encode(&layout, root, &mut src, &mut out, EncodeOptions::default());
                black_box(r.unwrap());
            }
            "decode" => {
                let mut sink = LeafSink::new(&mut storage);
                let r = decode(
                    &layout,
                    root,
                    black_box(&bytes[..]),
                    &mut sink,
                    DecodeOptions::default(),
                );
                black_box(r.unwrap());
            }
            _ => panic!("unknown operation {what}"),
        }
    }
}
