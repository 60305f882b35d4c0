//! Integration tests of cam-plan on analytic CL surfaces (and meshes once available).

mod surfaces;

mod errors;
mod feed_forward;
mod links_ends;
#[cfg(feature = "mesh")]
mod mesh;
mod penetration;
mod side_step;

/// Runs `f` in a rayon pool of `n` threads (for checking that plans do not depend on it).
pub fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}
