//! cam-gcode: see `docs/architecture.md`.
