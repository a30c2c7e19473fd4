//! The documentation stays true: every relative link of the README and of
//! `docs/` resolves (the file, and the heading an anchor names), the README
//! stays a front door (at most 15 KB), and the README's sample output is what
//! `beltune commission` prints today.

use std::path::{Path, PathBuf};

/// The repository root.
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every Markdown page of the documentation.
fn pages() -> Vec<PathBuf> {
    let r = root();
    let mut v = vec![
        r.join("README.md"),
        r.join("data/README.md"),
        r.join("crates/beltune-rt/README.md"),
    ];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(r.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    v.extend(docs);
    v
}

/// The targets of the inline links and images of `text` (`[x](t)`, `![x](t)`),
/// outside code blocks and code spans.
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_block = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
            continue;
        }
        if in_block {
            continue;
        }
        // drop code spans
        let mut plain = String::new();
        let mut in_span = false;
        for c in line.chars() {
            if c == '`' {
                in_span = !in_span;
            } else if !in_span {
                plain.push(c);
            }
        }
        let mut rest = plain.as_str();
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            let Some(end) = after.find(')') else { break };
            out.push(after[..end].trim().to_string());
            rest = &after[end..];
        }
    }
    out
}

/// GitHub's anchor of a heading: lower case, spaces to `-`, punctuation but
/// `-` and `_` dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                Some(c)
            } else if c == ' ' {
                Some('-')
            } else {
                None
            }
        })
        .collect()
}

/// The anchors of the headings of a Markdown file.
fn anchors(text: &str) -> Vec<String> {
    let mut in_block = false;
    text.lines()
        .filter(|l| {
            if l.trim_start().starts_with("```") {
                in_block = !in_block;
            }
            !in_block && l.starts_with('#')
        })
        .map(|l| slug(l.trim_start_matches('#')))
        .collect()
}

#[test]
fn every_relative_link_of_the_docs_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in links(&text) {
            if target.starts_with("http://")
                || target.starts_with("https://")
                || target.starts_with("mailto:")
            {
                continue;
            }
            checked += 1;
            let (file, anchor) = match target.split_once('#') {
                Some((f, a)) => (f, Some(a)),
                None => (target.as_str(), None),
            };
            let path = if file.is_empty() {
                page.clone()
            } else {
                page.parent().unwrap().join(file)
            };
            if !path.exists() {
                broken.push(format!("{}: {target} (no such file)", page.display()));
                continue;
            }
            if let Some(a) = anchor {
                let text = std::fs::read_to_string(&path).unwrap_or_default();
                if !anchors(&text).iter().any(|h| h == a) {
                    broken.push(format!("{}: {target} (no such heading)", page.display()));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
    assert!(
        checked > 30,
        "only {checked} links found: the link reader is broken"
    );
}

#[test]
fn the_link_checker_finds_links_and_headings() {
    let text = "# Exit statuses\nsee [a](docs/a.md#exit-statuses) and ![b](b.png); `[c](no)`\n```\n[d](no)\n```\n";
    assert_eq!(links(text), ["docs/a.md#exit-statuses", "b.png"]);
    assert_eq!(anchors(text), ["exit-statuses"]);
    assert_eq!(slug("The summary as JSON"), "the-summary-as-json");
    assert_eq!(slug("`beltune serve`"), "beltune-serve");
    assert_eq!(
        slug("Into the drive: controller.toml, Rust and C"),
        "into-the-drive-controllertoml-rust-and-c"
    );
}

/// The README is a front door: what, set-up, two commands, a sample, where to read on.
const README_MAX_BYTES: u64 = 15 * 1024;

#[test]
fn the_readme_is_a_front_door() {
    let readme = root().join("README.md");
    let size = std::fs::metadata(&readme).unwrap().len();
    assert!(size <= README_MAX_BYTES, "README.md has {size} bytes");
    let text = std::fs::read_to_string(&readme).unwrap();
    for must in [
        "cargo run --release -p beltune-cli -- commission",
        "cargo test --workspace --no-fail-fast",
    ] {
        assert!(text.contains(must), "the README lacks `{must}`");
    }
    let ci = std::fs::read_to_string(root().join(".ci/run")).unwrap();
    assert!(
        ci.lines().any(|l| l
            .trim_end()
            .ends_with("cargo test --workspace --no-fail-fast")),
        ".ci/run does not run the README's test command"
    );
}

/// A line of the sample with what varies from run to run masked: the
/// computation and wall time, and where the files went.
fn normalized(line: &str) -> String {
    let line = line.trim_end();
    if let Some(at) = line.find("computation ") {
        return format!("{}computation X s, wall time X s", &line[..at]);
    }
    if let Some((head, path)) = line.split_once("wrote: ") {
        let name = Path::new(path.trim())
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        return format!("{head}wrote: {name}");
    }
    line.to_string()
}

/// The README's sample output is the output of the main command today (the
/// simulation is deterministic: seed 1, fixed numbers; only the times the
/// host took and the folder differ).
#[test]
fn the_readme_shows_what_the_main_command_prints() {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let start = text
        .find("```text\n")
        .expect("the README has a ```text sample block");
    let body = &text[start + 8..];
    let sample: Vec<String> = body[..body.find("```").unwrap()]
        .lines()
        .map(normalized)
        .collect();
    let dir = std::env::temp_dir().join(format!("beltune-readme-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // as the README runs it: no --out, into ./commissioning/
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_beltune"))
        .arg("commission")
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed: Vec<String> = String::from_utf8_lossy(&out.stderr)
        .lines()
        .chain(String::from_utf8_lossy(&out.stdout).lines())
        .map(normalized)
        .collect();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(
        sample.join("\n"),
        printed.join("\n"),
        "the README's sample differs from `beltune commission` (update the README with its output)"
    );
}
