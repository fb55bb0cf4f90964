//! Bakes the Poisson tile into the crate: `src/stamp/tile/generate.rs` runs here,
//! once, and its points, levels, orders and cell starts become static arrays.

// the modules are borrowed from the crate, which uses more of them
#![allow(dead_code)]

#[path = "src/stamp/tile/generate.rs"]
mod generate;
#[path = "src/rng.rs"]
mod rng;
#[path = "src/stamp/tile/shape.rs"]
mod shape;

use std::fmt::Write;

fn main() {
    for file in [
        "src/stamp/tile/generate.rs",
        "src/rng.rs",
        "src/stamp/tile/shape.rs",
    ] {
        println!("cargo::rerun-if-changed={file}");
    }
    let tile = generate::generate(generate::SEED);
    let mut src = String::new();
    // bit patterns, so no float goes through decimal text and back
    let points = tile.points.iter().fold(String::new(), |mut s, p| {
        let [x, y] = p.map(f32::to_bits);
        write!(s, "[f32::from_bits({x:#x}), f32::from_bits({y:#x})],").unwrap();
        s
    });
    let list = |v: &[u32]| v.iter().map(|x| format!("{x},")).collect::<String>();
    let levels: Vec<u32> = tile.levels.iter().map(|&l| l as u32).collect();
    let orders: Vec<u32> = tile.orders.iter().map(|&o| o as u32).collect();
    let n = tile.points.len();
    writeln!(src, "static POINTS: [[f32; 2]; {n}] = [{points}];").unwrap();
    writeln!(src, "static LEVELS: [u8; {n}] = [{}];", list(&levels)).unwrap();
    writeln!(src, "static ORDERS: [u8; {n}] = [{}];", list(&orders)).unwrap();
    let cells = tile.cell_start.len();
    let starts = list(&tile.cell_start);
    writeln!(src, "static CELL_START: [u32; {cells}] = [{starts}];").unwrap();
    let out = std::path::Path::new(&std::env::var("OUT_DIR").unwrap()).join("tile.rs");
    std::fs::write(out, src).unwrap();
}
