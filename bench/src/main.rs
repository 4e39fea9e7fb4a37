//! can-bench (being written).
fn main() {}
