//! Leaf access in the instance store (target: get and set of one leaf within 50 ns), with the
//! same access on a bare encoded buffer as the baseline measured in the same run: walked
//! (`leaf::get_leaf`) and through the type's leaf table (`LeafTable::get_leaf`). The store is
//! built with its leaf tables (`Store::with_tables`).

#[path = "../crates/px4params-core/tests/common/mod.rs"]
mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use px4params_core::compile::OwnedLayout;
use px4params_core::leaf::{get_leaf, Target};
use px4params_core::store::{plan, table_slots, ParamDef, Slot, Store, Which};
use px4params_core::table::{LeafSlot, LeafTable};
use px4params_core::value::LeafSource;
use px4params_core::Scalar;
use std::hint::black_box;

fn store_leaf_access(c: &mut Criterion) {
    let mut owned = OwnedLayout::default();
    let ina = common::ina238(&mut owned);
    let battery = common::battery_info(&mut owned);
    let layout = owned.as_layout();
    let mut defs = vec![ParamDef::instanced(ina, 4), ParamDef::shared(battery)];
    let capacity = plan(&layout, &mut defs).unwrap();
    // With its leaf tables (`Store::with_tables`): `[k]` is a table lookup.
    let tables = vec![LeafSlot::default(); table_slots(&layout, &defs)];
    let mut store = Store::with_tables(
        &layout,
        defs,
        vec![Slot::default(); capacity.slots],
        vec![0u8; capacity.bytes],
        tables,
    )
    .unwrap();
    let talk = [
        Scalar::Uint(0),
        Scalar::Uint(0),
        Scalar::Uint(0),
        Scalar::Uint(1),
        Scalar::Uint(0x45),
        Scalar::Uint(200),
        Scalar::Float(0.0003),
    ];
    for i in 0..4 {
        store.add(0, Some(i)).unwrap();
        store
            .set_from(
                &layout,
                0,
                i,
                Which::Value,
                &mut LeafSource::new(&talk),
                false,
            )
            .unwrap();
    }
    let bare = store.get(0, 2, Which::Value).unwrap().to_vec();

    c.bench_function("store/Ina238/get_leaf [4]", |b| {
        b.iter(|| {
            store
                .get_leaf(
                    &layout,
                    0,
                    black_box(2),
                    Which::Value,
                    Target::Index(black_box(4)),
                )
                .unwrap()
                .1
        })
    });
    c.bench_function("store/Ina238/read [4]", |b| {
        b.iter(|| {
            store
                .read(&layout, 0, black_box(2), Which::Value, black_box(4))
                .unwrap()
        })
    });
    c.bench_function("store/Ina238/read [6] float16", |b| {
        b.iter(|| {
            store
                .read(&layout, 0, black_box(2), Which::Value, black_box(6))
                .unwrap()
        })
    });
    c.bench_function("store/Ina238/get_leaf bus.i2c.address", |b| {
        b.iter(|| {
            let target = Target::Path(black_box("bus.i2c.address"));
            store
                .get_leaf(&layout, 0, black_box(2), Which::Value, target)
                .unwrap()
                .1
        })
    });
    c.bench_function("buffer/Ina238/get_leaf [4] (baseline)", |b| {
        b.iter(|| {
            get_leaf(
                &layout,
                ina,
                black_box(&bare[..]),
                Target::Index(black_box(4)),
                false,
            )
            .unwrap()
            .1
        })
    });
    let mut storage = vec![LeafSlot::default(); LeafTable::slots_needed(&layout, ina)];
    let table = LeafTable::build(&layout, ina, &mut storage).unwrap();
    c.bench_function("buffer/Ina238/get_leaf [4] (table)", |b| {
        b.iter(|| {
            table
                .get_leaf(
                    &layout,
                    black_box(&bare[..]),
                    Target::Index(black_box(4)),
                    false,
                )
                .unwrap()
                .1
        })
    });
    c.bench_function("buffer/Ina238/read [4] (table)", |b| {
        b.iter(|| {
            table
                .read(&layout, black_box(&bare[..]), black_box(4))
                .unwrap()
        })
    });
    let mut n = 0u64;
    c.bench_function("store/Ina238/set_leaf [5]", |b| {
        b.iter(|| {
            n = (n + 1) & 511;
            store
                .set_leaf(
                    &layout,
                    0,
                    black_box(2),
                    Which::Value,
                    Target::Index(5),
                    Scalar::Uint(n),
                    false,
                )
                .unwrap()
        })
    });
    c.bench_function("store/Ina238/set_leaf [6] float16", |b| {
        b.iter(|| {
            let v = Scalar::Float(black_box(0.0005));
            store
                .set_leaf(
                    &layout,
                    0,
                    black_box(2),
                    Which::Value,
                    Target::Index(6),
                    v,
                    false,
                )
                .unwrap()
        })
    });
}

criterion_group!(benches, store_leaf_access);
criterion_main!(benches);
