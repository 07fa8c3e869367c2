//! Instruction counts of the codec's calls, for `benches/instructions.py` to run under
//! valgrind's callgrind: `instructions OP N` performs `OP` N times, so that the count of N
//! runs minus the count of 0 runs, divided by N, is the instructions of one call (stable where
//! time on this machine is not).
//!
//! OP: `battery/encode`, `battery/decode`, `ina238/encode`, `ina238/decode`; leaf `[4]` of
//! INA238 (`bus.i2c.address`): `ina238/get_leaf4` (on encoded bytes), `store/get_leaf4` and
//! `store/read4` (in the store, built with its leaf tables), `ina238/table_get_leaf4` and
//! `ina238/table_read4` (the value alone) on encoded bytes, through the type's leaf table.
//! `battery/receive`: checking the CAN frames of a BatteryInfo transfer (tail bytes and the
//! transfer CRC), `battery/receive_into` the same copying the payload into a buffer;
//! `battery/transfer_crc`: the CRC alone, over the payload in one piece.
//! `node_status/encode|decode` and `file_read_response/encode|decode` (an empty read) are
//! issue 18's small messages, whose fixed cost per call matters most.

#[path = "../crates/px4params-core/tests/common/mod.rs"]
mod common;

use px4params_core::codec::{
    decode, decode_leaves, encode, encode_leaves, DecodeOptions, EncodeOptions,
};
use px4params_core::compile::OwnedLayout;
use px4params_core::crc::crc16;
use px4params_core::leaf::{get_leaf, Target};
use px4params_core::store::{plan, table_slots, ParamDef, Slot, Store, Which};
use px4params_core::table::{LeafSlot, LeafTable};
use px4params_core::transfer::{frames, receive, receive_into};
use px4params_core::value::{LeafSink, LeafSource};
use px4params_core::Scalar;
use std::hint::black_box;

/// The transfer CRC's seed (a data type signature's CRC, as for any type).
const SEED: u16 = 0xBEEF;

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
    if ty == "store" {
        return store_ops(what, n);
    }
    let mut owned = OwnedLayout::default();
    let (root, leaves) = match ty {
        "battery" => (common::battery_info(&mut owned), battery_leaves()),
        "node_status" => (
            common::node_status(&mut owned),
            [12345, 0, 0, 0, 7].map(Scalar::Uint).to_vec(),
        ),
        // An empty read: the error value and the data's length.
        "file_read_response" => (
            common::file_read_response(&mut owned),
            vec![Scalar::Int(0), Scalar::Uint(0)],
        ),
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
    let mut slots = vec![LeafSlot::default(); LeafTable::slots_needed(&layout, root)];
    let table = LeafTable::build(&layout, root, &mut slots).unwrap();
    let frame_data: Vec<Vec<u8>> = frames(&bytes, SEED, 3, false)
        .map(|f| f.as_bytes().to_vec())
        .collect();
    let frame_refs: Vec<&[u8]> = frame_data.iter().map(Vec::as_slice).collect();
    match what {
        "encode" => repeat(n, || {
            let mut src = LeafSource::new(black_box(&leaves));
            let r = encode(&layout, root, &mut src, &mut out, EncodeOptions::default());
            black_box(r.unwrap());
        }),
        "decode" => repeat(n, || {
            let mut sink = LeafSink::new(&mut storage);
            let data = black_box(&bytes[..]);
            let r = decode(&layout, root, data, &mut sink, DecodeOptions::default());
            black_box(r.unwrap());
        }),
        // A flat leaf list, as firmware holds a value: through the walk in compact builds.
        "encode_leaves" => repeat(n, || {
            let leaves = black_box(&leaves[..]);
            let r = encode_leaves(&layout, root, leaves, &mut out, EncodeOptions::default());
            black_box(r.unwrap());
        }),
        "decode_leaves" => repeat(n, || {
            let data = black_box(&bytes[..]);
            let r = decode_leaves(&layout, root, data, &mut storage, DecodeOptions::default());
            black_box(r.unwrap());
        }),
        "get_leaf4" => repeat(n, || {
            let r = get_leaf(
                &layout,
                root,
                black_box(&bytes[..]),
                Target::Index(black_box(4)),
                false,
            );
            black_box(r.unwrap());
        }),
        "table_get_leaf4" => repeat(n, || {
            let data = black_box(&bytes[..]);
            let r = table.get_leaf(&layout, data, Target::Index(black_box(4)), false);
            black_box(r.unwrap());
        }),
        "table_read4" => repeat(n, || {
            let data = black_box(&bytes[..]);
            let r = table.read(&layout, data, black_box(4));
            black_box(r.unwrap());
        }),
        "receive" => repeat(n, || {
            let r = receive(black_box(&frame_refs), SEED);
            black_box(r.unwrap().transfer_id);
        }),
        "receive_into" => repeat(n, || {
            let r = receive_into(black_box(&frame_refs), SEED, &mut out);
            black_box(r.unwrap());
        }),
        "transfer_crc" => repeat(n, || {
            black_box(crc16(SEED, black_box(&bytes[..])));
        }),
        _ => panic!("unknown operation {what}"),
    }
}

/// Leaf `[4]` of an INA238 instance in a store (as `benches/store.rs` sets it up).
fn store_ops(what: &str, n: usize) {
    let mut owned = OwnedLayout::default();
    let ina = common::ina238(&mut owned);
    let layout = owned.as_layout();
    let mut defs = vec![ParamDef::instanced(ina, 4)];
    let capacity = plan(&layout, &mut defs).unwrap();
    let slots = vec![Slot::default(); capacity.slots];
    let tables = vec![LeafSlot::default(); table_slots(&layout, &defs)];
    let bytes = vec![0u8; capacity.bytes];
    let mut store = Store::with_tables(&layout, defs, slots, bytes, tables).unwrap();
    let mut talk: Vec<Scalar> = [0, 0, 0, 1, 0x45, 200].map(Scalar::Uint).to_vec();
    talk.push(Scalar::Float(0.0003));
    store.add(0, Some(2)).unwrap();
    let mut src = px4params_core::value::LeafSource::new(&talk);
    store
        .set_from(&layout, 0, 2, Which::Value, &mut src, false)
        .unwrap();
    match what {
        "get_leaf4" => repeat(n, || {
            let r = store.get_leaf(
                &layout,
                0,
                black_box(2),
                Which::Value,
                Target::Index(black_box(4)),
            );
            black_box(r.unwrap());
        }),
        "read4" => repeat(n, || {
            let r = store.read(&layout, 0, black_box(2), Which::Value, black_box(4));
            black_box(r.unwrap());
        }),
        _ => panic!("unknown operation {what}"),
    }
}

/// Runs `op` `n` times (each operation its own loop: no dispatch inside the count).
fn repeat(n: usize, mut op: impl FnMut()) {
    for _ in 0..n {
        op();
    }
}
