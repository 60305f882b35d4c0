//! Integration tests of `cam-sample` (one binary: link time on 2 cores).

mod analytic;
mod errors;
mod fixtures;
mod props;
mod util;
mod vertex_plane;
