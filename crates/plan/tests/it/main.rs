//! Integration tests of cam-plan on analytic CL surfaces (and meshes once available).

mod surfaces;

mod errors;
mod feed_forward;
mod links_ends;
#[cfg(feature = "mesh")]
mod mesh;
mod penetration;
mod side_step;
