//! End-to-end tests of the `cam` binary (one integration binary).

mod cl;
mod plan;
mod plan_checks;
mod plan_rs274;
mod support;
mod verify;
mod verify_zmap;
