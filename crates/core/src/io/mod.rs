//! File input and output: part readers and atomic writes.

pub mod atomic;
pub mod obj;
pub mod stl;

pub use atomic::write_atomic;
