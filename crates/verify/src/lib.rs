//! cam-verify: see `docs/architecture.md`.
