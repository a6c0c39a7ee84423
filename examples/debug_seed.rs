//! Writes random scene `seed` as a scene file (for debugging a failing case).
fn main() {
    let seed: u64 = std::env::args().nth(1).unwrap().parse().unwrap();
    let out = std::env::args().nth(2).unwrap();
    let s =
        umbra::generate::random(seed, umbra::generate::RandomOptions { width: 64, height: 48, ..Default::default() })
            .unwrap();
    s.write(std::path::Path::new(&out)).unwrap();
}
