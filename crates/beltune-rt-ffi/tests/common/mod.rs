//! Helpers shared by the tests that compile C programs.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The staticlib cargo built for this test run: the newest
/// `libbeltune_rt_ffi-*.a` beside the test executable.
pub fn staticlib() -> PathBuf {
    let deps = std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .to_path_buf();
    let mut found: Vec<(std::time::SystemTime, PathBuf)> = std::fs::read_dir(&deps)
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            let n = p.file_name()?.to_str()?.to_string();
            if !(n.starts_with("libbeltune_rt_ffi") && n.ends_with(".a")) {
                return None;
            }
            Some((p.metadata().ok()?.modified().ok()?, p))
        })
        .collect();
    found.sort();
    found.pop().expect("libbeltune_rt_ffi.a built by cargo").1
}

/// Compile the C program `source` with `cc` (C99, every warning an error)
/// against include/beltune_rt.h, the headers in `include_dir` and the
/// staticlib into `exe`; panics with the compiler's message if it fails.
pub fn compile_c(source: &Path, include_dir: &Path, exe: &Path) {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let o = Command::new("cc")
        .args([
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-O1",
            "-I",
        ])
        .arg(manifest.join("include"))
        .arg("-I")
        .arg(include_dir)
        .arg(source)
        .arg(staticlib())
        .args(["-lm", "-lpthread", "-ldl", "-o"])
        .arg(exe)
        .output()
        .expect("a C compiler `cc` is required for this test");
    assert!(
        o.status.success(),
        "cc failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
