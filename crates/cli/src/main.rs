//! The `cam` binary.
fn main() {}
