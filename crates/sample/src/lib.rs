//! cam-sample: see `docs/architecture.md`.
