//! Where a value's bits go in the stream (DroneCAN's scalar layout: the value's bytes least
//! significant first, each byte's bits most significant first) is written in one module,
//! `src/bits.rs`; every other module asks it (issue 39). This reads the core's own sources and
//! names any line outside `bits.rs` that converts between bytes and stream words itself.
//!
//! The CRC, the store file and the transfer's CRC bytes have byte orders of their own formats
//! (little-endian words, not the scalar rule); none of them uses the operations below.

use std::fs;
use std::path::Path;

/// Operations that only code knowing the bit order needs: big-endian loads and stores of
/// stream words, the byte swap of the scalar rule, the top bits of a word taken as a value,
/// and a byte's bits counted from its top.
const STREAM_OPERATIONS: &[&str] = &[
    "from_be_bytes",
    "to_be_bytes",
    "swap_bytes",
    ">> (64 -",
    ">> (128 -",
    "0xFF <<",
    "0x80 >>",
    "fn to_stream",
    "fn from_stream",
];

/// Range checks of an n-bit field (`u64::MAX >> (64 - n)`) are the casting rules, not the
/// bit order.
const NOT_BIT_ORDER: &[&str] = &["MAX >> (64 -"];

/// The code of a source file: without its in-file test module and its comments.
fn code_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let end = text.find("#[cfg(test)]\nmod tests").unwrap_or(text.len());
    text[..end]
        .lines()
        .enumerate()
        .map(|(i, line)| (i + 1, line.split("//").next().unwrap_or("")))
}

#[test]
fn only_bits_rs_knows_the_bit_order() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut found = Vec::new();
    let mut files = 0;
    for entry in fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        if path.extension() != Some("rs".as_ref()) || path.ends_with("bits.rs") {
            continue;
        }
        files += 1;
        let text = fs::read_to_string(&path).unwrap();
        for (number, code) in code_lines(&text) {
            let hit = STREAM_OPERATIONS.iter().find(|op| code.contains(*op));
            if let Some(op) = hit.filter(|_| !NOT_BIT_ORDER.iter().any(|ok| code.contains(ok))) {
                let name = path.file_name().unwrap().to_string_lossy();
                found.push(format!("{name}:{number}: `{op}` in `{}`", code.trim()));
            }
        }
    }
    assert!(
        files > 15,
        "read only {files} source files in {}",
        src.display()
    );
    assert!(
        found.is_empty(),
        "bit-order code outside src/bits.rs (ask bits.rs instead):\n{}",
        found.join("\n")
    );
}

#[test]
fn the_check_sees_bit_order_code() {
    // The check above must be able to fail: the same scan over a line that does the rule's
    // work itself.
    let text = "fn f(w: u64, n: u32) -> u64 {\n    w >> (64 - n) // the first n bits\n}\n";
    let lines: Vec<_> = code_lines(text)
        .filter(|(_, code)| STREAM_OPERATIONS.iter().any(|op| code.contains(op)))
        .collect();
    assert_eq!(lines, [(2, "    w >> (64 - n) ")]);
    let masked = "let fits = v <= u64::MAX >> (64 - bits);";
    assert!(NOT_BIT_ORDER.iter().any(|ok| masked.contains(ok)));
}
