//! Running the binary and building small inputs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn cam(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cam"))
        .args(args)
        .output()
        .expect("run cam")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Workspace root (two levels above this crate).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A unit square at z = 1 as two triangles, OBJ text.
pub const SQUARE_OBJ: &str = "v 0 0 1\nv 10 0 1\nv 10 10 1\nv 0 10 1\nf 1 2 3\nf 1 3 4\n";
