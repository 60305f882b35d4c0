//! cam-plan: see `docs/architecture.md`.
