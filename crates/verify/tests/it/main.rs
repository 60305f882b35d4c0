//! cam-verify integration tests: one binary, one module per topic.

mod deviation;
mod exact;
mod five_axis;
mod imprint;
mod measure;
mod pipeline;
mod rapids;
mod refine;
mod report;
mod sweep;
mod zmap;
