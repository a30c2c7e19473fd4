//! No text from a `controller.toml` reaches the exported firmware source as
//! code: whatever its provenance holds (line breaks, `*/`, quotes, NUL,
//! backslashes, trigraphs, non-UTF-8 paths read lossily), the export's only
//! free text is its header of `//` comments, each one line that cannot end or
//! continue, and everything after the header is the same as for a plain
//! provenance. Compiled with `cc` (C) and `rustc` (Rust) for the cases the
//! hostile-input probe used, checked structurally for arbitrary strings.

use beltune::record::controller::ControllerFile;
use beltune::record::export::{c_header, comment_text, rust_module};
use beltune::record::provenance::Provenance;
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn manifest() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn fixture() -> ControllerFile {
    ControllerFile::load(&manifest().join("tests/data/controller.toml")).unwrap()
}

/// The fixture with `provenance`, through its TOML text and back (what a
/// user's edited `controller.toml` gives the export).
fn with_provenance(provenance: Provenance) -> ControllerFile {
    let file = ControllerFile {
        provenance,
        ..fixture()
    };
    let text = file.to_toml().unwrap();
    let back = ControllerFile::parse(&text, "edited controller.toml").unwrap();
    assert_eq!(
        back.provenance, file.provenance,
        "the TOML keeps the strings"
    );
    back
}

/// The export split into its leading comment lines and the rest.
fn split_header(text: &str) -> (Vec<&str>, String) {
    let lines: Vec<&str> = text.lines().collect();
    let n = lines.iter().take_while(|l| l.starts_with("//")).count();
    (lines[..n].to_vec(), lines[n..].join("\n"))
}

/// The header lines are one-line comments of printable ASCII that neither
/// end in a backslash (a C continuation) nor hold a trigraph, and the rest of
/// the export is that of a plain provenance.
fn assert_only_comments_differ(exported: &str, plain: &str) {
    let (header, body) = split_header(exported);
    let (plain_header, plain_body) = split_header(plain);
    assert_eq!(header.len(), plain_header.len(), "{exported}");
    assert_eq!(body, plain_body, "the code after the header changed");
    for l in header {
        assert!(l.bytes().all(|b| (0x20..0x7f).contains(&b)), "{l:?}");
        assert!(!l.ends_with('\\') && !l.contains("??"), "{l:?}");
    }
}

fn plain() -> Provenance {
    Provenance::now(vec!["beltune".into(), "commission".into()], Some(1))
}

/// The strings of the hostile-input probe: a directory name that holds C
/// preprocessor lines, a Rust item, a closed block comment, a trigraph
/// continuation, NUL and a non-UTF-8 path read lossily.
fn hostile() -> Provenance {
    let lossy = String::from_utf8_lossy(b"/tmp/\xff\xfe/out").into_owned();
    Provenance {
        beltune_version: "0.1.0\n#error injected".into(),
        created_utc: "2026-12-03T10:00:00Z\npub const INJECTED: f64 = 1e4; //".into(),
        command_line: vec![
            "beltune".into(),
            "commission".into(),
            "--out".into(),
            "nl\n#define BELTUNE_CONTROLLER_H\n#error X".into(),
            "*/ int x; /*".into(),
            "tail\\".into(),
            "??/".into(),
            "nul\0byte".into(),
            "'quoted' \"double\"".into(),
            lossy,
        ],
        seed: Some(7),
    }
}

#[test]
fn a_comment_is_one_safe_line_for_any_text() {
    assert_eq!(
        comment_text("plain text: a/b (c) = 1"),
        "plain text: a/b (c) = 1"
    );
    assert_eq!(comment_text("a\nb"), "a%0Ab");
    assert_eq!(comment_text("x\\"), "x%5C");
    assert_eq!(comment_text("??/"), "%3F%3F/");
    assert_eq!(comment_text("100%"), "100%25");
    assert_eq!(comment_text("\u{fffd}"), "%EF%BF%BD");
    assert_eq!(comment_text("nul\0"), "nul%00");
}

/// A `beltune_rt` rlib beside the test executable (cargo built it for this test).
fn rlib(name: &str) -> PathBuf {
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
            if !(n.starts_with(&format!("lib{name}-")) && n.ends_with(".rlib")) {
                return None;
            }
            Some((p.metadata().ok()?.modified().ok()?, p))
        })
        .collect();
    found.sort();
    found.pop().expect("the rlib cargo built").1
}

#[test]
fn the_hostile_probe_exports_compile_to_the_plain_controller() {
    let file = with_provenance(hostile());
    let plain_file = with_provenance(plain());
    let (c, rust) = (c_header(&file), rust_module(&file));
    assert_only_comments_differ(&c, &c_header(&plain_file));
    assert_only_comments_differ(&rust, &rust_module(&plain_file));
    for needle in [
        "#error",
        "#define BELTUNE_CONTROLLER_H\n#",
        "pub const INJECTED",
    ] {
        assert!(!c.contains(&format!("\n{needle}")), "{needle} in\n{c}");
        assert!(
            !rust.contains(&format!("\n{needle}")),
            "{needle} in\n{rust}"
        );
    }
    let dir = std::env::temp_dir().join(format!("beltune-inject-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // C: the header alone, with every warning an error
    std::fs::write(dir.join("controller.h"), &c).unwrap();
    std::fs::write(dir.join("use.c"), "#include \"controller.h\"\nint main(void) { return BELTUNE_CASCADE.ts_s > 0.0 ? 0 : 1; }\n").unwrap();
    let o = Command::new("cc")
        .args([
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-trigraphs",
            "-fsyntax-only",
            "-I",
        ])
        .arg(manifest().join("include"))
        .arg("-I")
        .arg(&dir)
        .arg(dir.join("use.c"))
        .output()
        .expect("a C compiler `cc` is required for this test");
    assert!(
        o.status.success(),
        "cc:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // Rust: the module against the beltune_rt this test was built with
    std::fs::write(dir.join("controller.rs"), &rust).unwrap();
    let deps = std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .to_path_buf();
    let rustc = Path::new(env!("CARGO")).with_file_name("rustc");
    let o = Command::new(rustc)
        .args([
            "--edition",
            "2021",
            "--crate-type",
            "lib",
            "--emit",
            "metadata",
            "-L",
        ])
        .arg(format!("dependency={}", deps.display()))
        .arg("--extern")
        .arg(format!("beltune_rt={}", rlib("beltune_rt").display()))
        .arg("-o")
        .arg(dir.join("libcontroller.rmeta"))
        .arg(dir.join("controller.rs"))
        .output()
        .expect("rustc beside cargo");
    assert!(
        o.status.success(),
        "rustc:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

fn any_text() -> impl Strategy<Value = String> {
    prop_oneof![
        ".*",
        "[\\x00-\\x7f]{0,40}",
        prop::collection::vec(
            prop_oneof![
                Just("\n".to_string()),
                Just("\r".to_string()),
                Just("*/".to_string()),
                Just("/*".to_string()),
                Just("\\".to_string()),
                Just("??/".to_string()),
                Just("\0".to_string()),
                Just("\"".to_string()),
                Just("#define X 1".to_string()),
                "[a-z ]{0,5}",
            ],
            0..8
        )
        .prop_map(|v| v.concat()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Arbitrary provenance strings change nothing but the comment header.
    #[test]
    fn any_provenance_changes_only_the_comment_header(
        version in any_text(),
        created in any_text(),
        args in prop::collection::vec(any_text(), 0..5),
    ) {
        let p = Provenance { beltune_version: version, created_utc: created, command_line: args, seed: None };
        let file = with_provenance(p);
        let plain_file = with_provenance(plain());
        assert_only_comments_differ(&c_header(&file), &c_header(&plain_file));
        assert_only_comments_differ(&rust_module(&file), &rust_module(&plain_file));
    }
}
