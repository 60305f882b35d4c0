//! cam-holder: see `docs/architecture.md`.
