//! Integration tests of the drop-cutter (one binary keeps link time down).

mod analytic;
mod brute;
mod ocl;
mod support;
mod threads;
