//! Integration tests of `cam-gcode`: one binary, one module per topic.

mod apt;
mod arcs;
mod golden;
mod post;
mod props;
mod read;
mod rs274;
mod support;
