//! End-to-end tests of the `cam` binary (one integration binary).

mod cl;
mod support;
