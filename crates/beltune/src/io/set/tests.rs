use super::*;
use crate::io::clean_stale_temporaries;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("beltune-set-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    v.sort();
    v
}

#[test]
fn a_set_is_replaced_as_a_whole_with_its_manifest() {
    let dir = temp("whole");
    let out = dir.join("out");
    write_folder_atomic(&out, &[("a", b"1"), ("b", b"1")], &[]).unwrap();
    write_folder_atomic(&out, &[("a", b"2"), ("c", b"2")], &[]).unwrap();
    assert_eq!(names(&out), [MANIFEST_FILE, "a", "c"]);
    assert_eq!(std::fs::read(out.join("a")).unwrap(), b"2");
    assert_eq!(
        read_manifest(&out).unwrap(),
        ["a", "c"].iter().map(OsString::from).collect()
    );
    // nothing but `out` beside it: the old set and the temporary are gone
    assert_eq!(names(&dir), ["out"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn replacing_a_set_keeps_everything_beltune_did_not_write() {
    let dir = temp("keep");
    let out = dir.join("proj");
    write_folder_atomic(
        &out,
        &[("commissioning.json", b"{}"), ("old.csv", b"x")],
        &[],
    )
    .unwrap();
    // what a user (or the tuning page) put beside the result
    std::fs::create_dir_all(out.join("src")).unwrap();
    std::fs::write(out.join("src/main.c"), "int main;").unwrap();
    std::fs::create_dir_all(out.join(".git")).unwrap();
    std::fs::write(out.join(".git/HEAD"), "ref").unwrap();
    std::fs::create_dir_all(out.join("tuned-20261203T101010Z")).unwrap();
    std::fs::write(out.join("tuned-20261203T101010Z/controller.toml"), "k = 1").unwrap();
    std::fs::write(out.join("notes.txt"), "belt re-tensioned").unwrap();
    std::os::unix::fs::symlink("notes.txt", out.join("link")).unwrap();
    write_folder_atomic(&out, &[("commissioning.json", b"{\"n\":2}")], &[]).unwrap();
    assert_eq!(
        names(&out),
        [
            MANIFEST_FILE,
            ".git",
            "commissioning.json",
            "link",
            "notes.txt",
            "src",
            "tuned-20261203T101010Z"
        ]
    );
    assert_eq!(
        std::fs::read_to_string(out.join("src/main.c")).unwrap(),
        "int main;"
    );
    assert_eq!(
        std::fs::read_to_string(out.join(".git/HEAD")).unwrap(),
        "ref"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("link")).unwrap(),
        "belt re-tensioned"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("tuned-20261203T101010Z/controller.toml")).unwrap(),
        "k = 1"
    );
    assert_eq!(
        std::fs::read(out.join("commissioning.json")).unwrap(),
        b"{\"n\":2}"
    );
    assert_eq!(names(&dir), ["proj"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_folder_without_manifest_has_only_the_known_names_replaced() {
    let dir = temp("legacy");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    for f in ["commissioning.json", "report.html", "mine.txt"] {
        std::fs::write(out.join(f), "old").unwrap();
    }
    // a user's folder under one of beltune's names is not beltune's
    std::fs::create_dir_all(out.join("frf.csv")).unwrap();
    let legacy = ["commissioning.json", "report.html", "frf.csv"];
    write_folder_atomic(&out, &[("commissioning.json", b"new")], &legacy).unwrap();
    assert_eq!(
        names(&out),
        [MANIFEST_FILE, "commissioning.json", "frf.csv", "mine.txt"]
    );
    assert!(out.join("frf.csv").is_dir());
    assert_eq!(
        std::fs::read_to_string(out.join("mine.txt")).unwrap(),
        "old"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_users_file_under_a_new_files_name_is_refused_and_nothing_changes() {
    let dir = temp("clash");
    let out = dir.join("out");
    write_folder_atomic(&out, &[("a", b"1")], &[]).unwrap();
    std::fs::write(out.join("b"), "the user's b").unwrap();
    let e = write_folder_atomic(&out, &[("a", b"2"), ("b", b"2")], &[]).unwrap_err();
    assert!(e.to_string().contains("not beltune's"), "{e}");
    assert_eq!(
        std::fs::read_to_string(out.join("b")).unwrap(),
        "the user's b"
    );
    assert_eq!(std::fs::read(out.join("a")).unwrap(), b"1");
    assert_eq!(names(&dir), ["out"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_killed_replacement_gets_the_users_entries_back() {
    let dir = temp("killed");
    let out = dir.join("out");
    write_folder_atomic(&out, &[("a", b"1")], &[]).unwrap();
    // as a writer killed between carrying the user's entries aside and the
    // exchange leaves it (pid 0 is never a user process)
    let tmp = dir.join(".out.tmp-0-1-2");
    std::fs::create_dir_all(tmp.join("tuned-x")).unwrap();
    std::fs::write(tmp.join("tuned-x/controller.toml"), "k = 1").unwrap();
    std::fs::write(tmp.join("notes.txt"), "mine").unwrap();
    std::fs::write(tmp.join("a"), "2").unwrap();
    std::fs::write(tmp.join(CARRIED_FILE), b"notes.txt\0tuned-x\0").unwrap();
    // a clash: the folder got a notes.txt of its own meanwhile
    std::fs::write(out.join("notes.txt"), "newer").unwrap();
    assert!(
        clean_stale_temporaries(&dir).is_empty(),
        "kept while it holds the user's entry"
    );
    assert!(out.join("tuned-x/controller.toml").exists());
    assert_eq!(
        std::fs::read_to_string(tmp.join("notes.txt")).unwrap(),
        "mine"
    );
    std::fs::rename(out.join("notes.txt"), dir.join("elsewhere.txt")).unwrap();
    assert_eq!(clean_stale_temporaries(&dir), vec![tmp.clone()]);
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    assert_eq!(std::fs::read(out.join("a")).unwrap(), b"1");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn concurrent_replacements_of_one_folder_keep_the_users_entries() {
    let dir = temp("concurrent");
    let out = dir.join("out");
    write_folder_atomic(&out, &[("a", b"0"), ("b", b"0")], &[]).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let writers: Vec<_> = (0..6)
        .map(|w| {
            let out = out.clone();
            std::thread::spawn(move || {
                for k in 0..20 {
                    let v = format!("{w}-{k}");
                    write_folder_atomic(&out, &[("a", v.as_bytes()), ("b", v.as_bytes())], &[])
                        .unwrap();
                }
            })
        })
        .collect();
    for w in writers {
        w.join().unwrap();
    }
    assert_eq!(names(&out), [MANIFEST_FILE, "a", "b", "notes.txt"]);
    // one whole set
    assert_eq!(
        std::fs::read(out.join("a")).unwrap(),
        std::fs::read(out.join("b")).unwrap()
    );
    assert_eq!(names(&dir), ["out"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Run by [`random_kills_never_lose_the_users_entries`] in a child process:
/// replace the set in `BELTUNE_SET_CHILD` until killed.
#[test]
#[ignore = "a child process of random_kills_never_lose_the_users_entries"]
fn replacement_loop_child() {
    let Some(out) = std::env::var_os("BELTUNE_SET_CHILD") else {
        return;
    };
    let out = PathBuf::from(out);
    for k in 0u64.. {
        let v = k.to_string();
        write_folder_atomic(&out, &[("a", v.as_bytes()), ("b", v.as_bytes())], &[]).unwrap();
    }
}

#[test]
fn random_kills_never_lose_the_users_entries() {
    use rand::{Rng, SeedableRng};
    let dir = temp("kills");
    let out = dir.join("out");
    write_folder_atomic(&out, &[("a", b"0"), ("b", b"0")], &[]).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::create_dir_all(out.join("tuned-x")).unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let exe = std::env::current_exe().unwrap();
    for _ in 0..25 {
        let mut child = std::process::Command::new(&exe)
            .args([
                "--exact",
                "io::set::tests::replacement_loop_child",
                "--ignored",
            ])
            .args(["--nocapture", "--test-threads", "1"])
            .env("BELTUNE_SET_CHILD", &out)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_micros(
            rng.random_range(2_000..60_000),
        ));
        child.kill().unwrap();
        child.wait().unwrap();
        // the next writer cleans up first
        write_folder_atomic(&out, &[("a", b"n"), ("b", b"n")], &[]).unwrap();
        assert_eq!(
            names(&out),
            [MANIFEST_FILE, "a", "b", "notes.txt", "tuned-x"],
            "after a kill"
        );
        assert_eq!(
            std::fs::read_to_string(out.join("notes.txt")).unwrap(),
            "mine"
        );
        assert_eq!(names(&dir), ["out"], "a temporary left behind");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
