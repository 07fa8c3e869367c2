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
//! `battery/receive_decode` and `battery/receive_into_decode`: the frames checked and the
//! value decoded (from the pieces, or from the payload gathered into a buffer), to set beside
//! `battery/decode` (the flat decode).
//!
//! `instructions time ROUNDS ITERS OP` times OP instead, in ROUNDS rounds of ITERS calls,
//! and prints `rust_ns c_ns` (medians of the rounds, nanoseconds per call). With `PX4PARAMS_CBENCH` naming the C baseline built as a shared library
//! (`../shared/anchors/dronecan-c`, `c_setup`/`c_op`/`c_run`), each round runs the same
//! message through the C code right after ours, interleaved in one process, so that this
//! machine's drift falls on both alike (`c_ns` is `-` without it, or for an OP the baseline
//! has no counterpart of).

#[path = "../crates/px4params-core/tests/common/mod.rs"]
mod common;

use px4params_core::codec::{
    decode, decode_leaves, encode, encode_leaves, DecodeOptions, EncodeOptions,
};
use px4params_core::compile::OwnedLayout;
use px4params_core::crc::crc16;
use px4params_core::leaf::{get_leaf, Target};
use px4params_core::scatter::{FramePayloads, Scattered};
use px4params_core::store::{plan, table_slots, ParamDef, Slot, Store, Which};
use px4params_core::table::{LeafSlot, LeafTable};
use px4params_core::transfer::{frames, receive, receive_into};
use px4params_core::value::{LeafSink, LeafSource};
use px4params_core::Scalar;
use std::ffi::{c_char, c_int, c_long, c_void, CString};
use std::hint::black_box;
use std::time::Instant;

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

/// The C baseline's op for one of ours (`cbench.c`'s `op_names`).
fn c_op_name(op: &str) -> Option<&'static str> {
    Some(match op {
        "battery/encode" => "bat_enc",
        "battery/decode" => "bat_dec",
        "node_status/encode" => "ns_enc",
        "node_status/decode" => "ns_dec",
        "file_read_response/encode" => "rd0_enc",
        "file_read_response/decode" => "rd0_dec",
        _ => return None,
    })
}

/// The C baseline as a shared library, loaded at run time (glibc's `dlopen`).
struct CBench {
    run: extern "C" fn(c_int, c_long),
    op: extern "C" fn(*const c_char) -> c_int,
}

extern "C" {
    fn dlopen(filename: *const c_char, flags: c_int) -> *mut c_void;
    fn dlsym(handle: *mut c_void, symbol: *const c_char) -> *mut c_void;
}

impl CBench {
    fn load(path: &str) -> CBench {
        const RTLD_NOW: c_int = 2;
        let path = CString::new(path).unwrap();
        // SAFETY: a library built from cbench.c, whose exports have these signatures.
        unsafe {
            let handle = dlopen(path.as_ptr(), RTLD_NOW);
            assert!(!handle.is_null(), "PX4PARAMS_CBENCH: cannot load {path:?}");
            let symbol = |name: &str| {
                let name = CString::new(name).unwrap();
                let f = dlsym(handle, name.as_ptr());
                assert!(!f.is_null(), "PX4PARAMS_CBENCH: no {name:?}");
                f
            };
            let setup: extern "C" fn() = std::mem::transmute(symbol("c_setup"));
            setup();
            CBench {
                run: std::mem::transmute::<*mut c_void, extern "C" fn(c_int, c_long)>(symbol(
                    "c_run",
                )),
                op: std::mem::transmute::<*mut c_void, extern "C" fn(*const c_char) -> c_int>(
                    symbol("c_op"),
                ),
            }
        }
    }

    fn op(&self, name: &str) -> c_int {
        let name = CString::new(name).unwrap();
        let op = (self.op)(name.as_ptr());
        assert!(op >= 0, "cbench has no op {name:?}");
        op
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `time ROUNDS ITERS OP`: how to time the op instead of counting it.
struct Timing {
    rounds: usize,
    iters: usize,
    c: Option<(CBench, c_int)>,
}

static TIMING: std::sync::OnceLock<Timing> = std::sync::OnceLock::new();

/// Ours and C's nanoseconds per call (medians of the rounds), interleaved round by round.
fn timed(t: &Timing, op: &mut dyn FnMut()) {
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    for _ in 0..t.rounds {
        let start = Instant::now();
        for _ in 0..t.iters {
            op();
        }
        ours.push(start.elapsed().as_secs_f64() * 1e9 / t.iters as f64);
        if let Some((c, k)) = &t.c {
            let start = Instant::now();
            (c.run)(*k, t.iters as c_long);
            theirs.push(start.elapsed().as_secs_f64() * 1e9 / t.iters as f64);
        }
    }
    let c_ns = if theirs.is_empty() {
        "-".to_string()
    } else {
        format!("{:.1}", median(theirs))
    };
    println!("{:.1} {c_ns}", median(ours));
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (op, n) = match args.as_slice() {
        [_, time, rounds, iters, op] if time == "time" => {
            let c = std::env::var("PX4PARAMS_CBENCH").ok().and_then(|path| {
                let c = CBench::load(&path);
                let k = c.op(c_op_name(op)?);
                Some((c, k))
            });
            let timing = Timing {
                rounds: rounds.parse().expect("ROUNDS: a count"),
                iters: iters.parse().expect("ITERS: a count"),
                c,
            };
            TIMING.set(timing).ok();
            (op.as_str(), 0)
        }
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
        "receive_decode" => repeat(n, || {
            let r = receive(black_box(&frame_refs), SEED).unwrap();
            let data = Scattered::new(&r.payload);
            let mut sink = LeafSink::new(&mut storage);
            let r = decode(&layout, root, &data, &mut sink, DecodeOptions::default());
            black_box(r.unwrap());
        }),
        "receive_into_decode" => repeat(n, || {
            let (_, len) = receive_into(black_box(&frame_refs), SEED, &mut out).unwrap();
            let mut sink = LeafSink::new(&mut storage);
            let r = decode(
                &layout,
                root,
                &out[..len],
                &mut sink,
                DecodeOptions::default(),
            );
            black_box(r.unwrap());
        }),
        // Decoded from the frames' payloads where they lie, unchecked (criterion's
        // `BatteryInfo descatter/frames`): the reader over pieces.
        "frames_decode" => repeat(n, || {
            let payload = FramePayloads::new(black_box(&frame_refs));
            let data = Scattered::new(&payload);
            let mut sink = LeafSink::new(&mut storage);
            let r = decode(&layout, root, &data, &mut sink, DecodeOptions::default());
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

/// Runs `op` `n` times (each operation its own loop: no dispatch inside the count), or times
/// it (`time`).
fn repeat(n: usize, mut op: impl FnMut()) {
    if let Some(timing) = TIMING.get() {
        return timed(timing, &mut op);
    }
    for _ in 0..n {
        op();
    }
}
