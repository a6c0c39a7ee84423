//! The README's library examples are code that builds: every line of its Rust blocks is in
//! `examples/readme.rs` (which `cargo test` compiles), in order, block by block.

#[test]
fn readme_rust_blocks_are_in_the_compiled_example() {
    let root = env!("CARGO_MANIFEST_DIR");
    let readme = std::fs::read_to_string(format!("{root}/README.md")).unwrap();
    let example = std::fs::read_to_string(format!("{root}/examples/readme.rs")).unwrap();
    let lines: Vec<&str> = example.lines().map(str::trim).collect();
    let mut blocks = 0;
    for block in readme.split("```rust\n").skip(1) {
        let block = block.split("```").next().unwrap_or_default();
        blocks += 1;
        let mut at = 0;
        for line in block.lines().map(str::trim).filter(|l| !l.is_empty()) {
            match lines[at..].iter().position(|l| *l == line) {
                Some(k) => at += k + 1,
                None => panic!("README line not in examples/readme.rs (in order): {line}"),
            }
        }
    }
    assert!(blocks >= 3, "the README has {blocks} Rust blocks");
}
