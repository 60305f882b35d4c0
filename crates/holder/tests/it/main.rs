//! Integration tests of cam-holder (one binary, modules per topic).

mod avoid;
mod common;
mod curvature;
mod library;
mod pocket;
mod rib;
mod select;
mod swept;
