//! cam-verify: see `docs/architecture.md`.
mod chains;
pub mod column;
pub mod depth;
pub mod deviation;
pub mod envelope;
pub mod exact;
pub mod heatmap;
pub mod imprint;
pub mod locate;
pub mod material;
pub mod measure;
pub mod model;
pub mod pipeline;
pub mod ply;
mod polycdt;
pub mod proximity;
mod radix;
pub mod rapids;
pub mod refine;
pub mod remesh;
pub mod report;
pub mod sweep;
#[cfg(test)]
mod testkit;
pub mod testpaths;
pub mod zmap;

pub use pipeline::{
    Stage, StageProgress, Timings, Verification, VerifyConfig, VerifyError, verify,
    verify_with_progress,
};
