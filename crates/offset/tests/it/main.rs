//! Integration tests of the drop-cutter (one binary keeps link time down).

mod analytic;
mod brute;
mod certify;
mod ocl;
mod support;
mod threads;
