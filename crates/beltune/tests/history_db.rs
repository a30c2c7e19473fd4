//! The history database on both back ends, the same code: an SQLite file and
//! a real PostgreSQL server that this test starts and stops (Debian's
//! `postgresql`; skipped with a message where its binaries are missing).
//! On each: the migrations (a first-schema database keeps its runs when
//! migrated, a newer one is refused), parallel writers of several axes in
//! separate processes that open a new database at once (nothing lost, the
//! schema migrated once), and a writer killed (SIGKILL) in the middle of
//! its transaction (the database stays consistent, the half-written run is
//! absent, the next writer goes on).
//!
//! The writers are this test binary run again with `child_writer` and
//! environment variables ([`spawn_writer`]).

use beltune::health::Quantity;
use beltune::history::{HistoryDb, Location, NewRun, QuantityRow, RunKind};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const CHILD_ENV: &str = "BELTUNE_HISTORY_TEST_CHILD";
/// Runs each parallel writer records.
const RUNS_PER_WRITER: usize = 12;
/// Parallel writers, one axis each.
const WRITERS: usize = 4;

/// A run with every quantity (values from its number, so that a reader can
/// tell a run is whole).
fn sample_run(axis: &str, k: usize) -> NewRun {
    NewRun {
        axis: axis.to_string(),
        kind: if k % 3 == 0 {
            RunKind::Commissioning
        } else {
            RunKind::Health
        },
        created_utc: beltune::history::now_utc(),
        status: "ok".into(),
        result_dir: Some(format!("health/{axis}-{k}")),
        baseline_dir: None,
        beltune_version: "test".into(),
        experiment_time_s: 4.2,
        record_json: format!("{{\"run\": {k}}}"),
        recommendations: vec![format!("look at run {k}")],
        quantities: Quantity::ALL
            .iter()
            .map(|&q| QuantityRow::value(q, k as f64, 0.01, f64::NAN))
            .collect(),
    }
}

/// Every run of `db` is whole: all its quantities, each with the run's value.
fn assert_whole(db: &mut HistoryDb) -> usize {
    let runs = db.runs(None).unwrap();
    for r in &runs {
        assert_eq!(
            r.run.quantities.len(),
            Quantity::ALL.len(),
            "run {} of {} is not whole",
            r.id,
            r.run.axis
        );
        let k = r.run.quantities[0].value;
        assert!(r.run.quantities.iter().all(|q| q.value == k));
    }
    runs.len()
}

/// Run this binary's `child_writer` with `mode` on `location`.
fn spawn_writer(mode: &str, location: &str, axis: &str, marker: Option<&Path>) -> Child {
    let mut cmd = Command::new(std::env::current_exe().unwrap());
    cmd.args(["--exact", "child_writer", "--ignored", "--nocapture"])
        .env(CHILD_ENV, mode)
        .env("BELTUNE_HISTORY_TEST_DB", location)
        .env("BELTUNE_HISTORY_TEST_AXIS", axis)
        .stdout(Stdio::null())
        .stderr(Stdio::inherit());
    if let Some(m) = marker {
        cmd.env("BELTUNE_HISTORY_TEST_MARKER", m);
    }
    cmd.spawn().unwrap()
}

/// The writer process: `parallel` records [`RUNS_PER_WRITER`] runs;
/// `killed` starts a run, says so in the marker file and waits inside its
/// transaction to be killed. Does nothing when not started by a test.
#[test]
#[ignore = "run by the history tests as a separate writer process"]
fn child_writer() {
    let Ok(mode) = std::env::var(CHILD_ENV) else {
        return;
    };
    let location = Location::parse(&std::env::var("BELTUNE_HISTORY_TEST_DB").unwrap());
    let axis = std::env::var("BELTUNE_HISTORY_TEST_AXIS").unwrap();
    let mut db = HistoryDb::open(&location).unwrap();
    match mode.as_str() {
        "parallel" => {
            for k in 0..RUNS_PER_WRITER {
                db.record(&sample_run(&axis, k)).unwrap();
            }
        }
        "killed" => {
            let marker = PathBuf::from(std::env::var("BELTUNE_HISTORY_TEST_MARKER").unwrap());
            let _ = db.write(|w| {
                let run = sample_run(&axis, 99);
                // half a run: the run row and one quantity
                let id = w.insert_run(&NewRun {
                    quantities: run.quantities[..1].to_vec(),
                    ..run
                })?;
                std::fs::write(&marker, id.to_string()).unwrap();
                std::thread::sleep(Duration::from_secs(120));
                Ok(())
            });
            panic!("the killed writer was not killed");
        }
        other => panic!("unknown mode {other}"),
    }
}

/// Everything on one back end (`location` of an empty database).
fn exercise(location: &str, scratch: &Path) {
    let loc = Location::parse(location);
    // parallel writers of several axes, each opening the new database at
    // once (they race to migrate it)
    let children: Vec<Child> = (0..WRITERS)
        .map(|i| spawn_writer("parallel", location, &format!("axis-{i}"), None))
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success(), "a parallel writer failed");
    }
    let mut db = HistoryDb::open(&loc).unwrap();
    assert_eq!(db.schema_version().unwrap(), 2);
    assert_eq!(assert_whole(&mut db), WRITERS * RUNS_PER_WRITER);
    assert_eq!(db.axes().unwrap().len(), WRITERS);
    for i in 0..WRITERS {
        let runs = db.runs(Some(&format!("axis-{i}"))).unwrap();
        assert_eq!(runs.len(), RUNS_PER_WRITER);
        // in the order each writer wrote them
        let values: Vec<f64> = runs.iter().map(|r| r.run.quantities[0].value).collect();
        assert!(values.windows(2).all(|w| w[0] < w[1]), "{values:?}");
        assert_eq!(
            runs[1].run.recommendations,
            vec!["look at run 1".to_string()]
        );
    }
    // a writer killed inside its transaction
    let marker = scratch.join("killed-marker");
    let mut child = spawn_writer("killed", location, "axis-killed", Some(&marker));
    let t0 = Instant::now();
    while !marker.exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the killed writer never started its run"
        );
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the killed writer ended by itself: {status}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    // the next writer goes on (the killed one's lock is gone) and the
    // half-written run is not there
    let mut db = HistoryDb::open(&loc).unwrap();
    let id = db.record(&sample_run("axis-after", 7)).unwrap();
    assert_eq!(assert_whole(&mut db), WRITERS * RUNS_PER_WRITER + 1);
    assert!(db.runs(Some("axis-killed")).unwrap().is_empty());
    assert!(!db.axes().unwrap().contains(&"axis-killed".to_string()));
    assert_eq!(db.runs(Some("axis-after")).unwrap()[0].id, id);
    if let Location::Sqlite(path) = &loc {
        let c = rusqlite_check(path);
        assert_eq!(c, "ok");
    }
}

/// SQLite's own `PRAGMA integrity_check` of the file.
fn rusqlite_check(path: &Path) -> String {
    let rows = beltune::history::backend::Conn::open(&Location::Sqlite(path.to_path_buf()))
        .ok()
        .and_then(|mut c| {
            c.query(
                "PRAGMA integrity_check",
                &[],
                &[beltune::history::Column::Text],
            )
            .ok()
        })
        .unwrap_or_default();
    rows.first()
        .and_then(|r| r[0].as_str().map(str::to_string))
        .unwrap_or_default()
}

/// The migrations on `location` (an empty database): a first-schema
/// database keeps its run when migrated; one of a newer schema is refused.
fn migrations(location: &str) {
    let loc = Location::parse(location);
    let mut db = HistoryDb::open_unmigrated(&loc).unwrap();
    db.migrate_to(1).unwrap();
    assert_eq!(db.schema_version().unwrap(), 1);
    // a version-1 run (no recommendations column yet)
    db.write(|w| {
        w.execute(
            "INSERT INTO axes (name, created_utc) VALUES ($1, $2)",
            &[
                beltune::history::Value::text("old"),
                beltune::history::Value::text("2026-01-01T00:00:00Z"),
            ],
        )?;
        w.execute(
            "INSERT INTO runs (axis, kind, created_utc, status, beltune_version, record) VALUES ($1, $2, $3, $4, $5, $6)",
            &["old", "commissioning", "2026-01-01T00:00:00Z", "pass", "0.0.1", "{}"]
                .map(beltune::history::Value::text),
        )?;
        Ok(())
    })
    .unwrap();
    drop(db);
    let mut db = HistoryDb::open(&loc).unwrap();
    assert_eq!(db.schema_version().unwrap(), 2);
    let runs = db.runs(Some("old")).unwrap();
    assert_eq!(runs.len(), 1);
    assert!(runs[0].run.recommendations.is_empty());
    // a newer schema than this beltune knows
    db.write(|w| {
        w.execute(
            "INSERT INTO schema_migrations (version, name, applied_utc) VALUES ($1, $2, $3)",
            &[
                beltune::history::Value::Int(Some(99)),
                beltune::history::Value::text("from the future"),
                beltune::history::Value::text("2030-01-01T00:00:00Z"),
            ],
        )
        .map(|_| ())
    })
    .unwrap();
    let err = HistoryDb::open(&loc)
        .err()
        .expect("a newer schema is refused");
    assert!(err.to_string().contains("newer beltune"), "{err}");
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("beltune-history-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn sqlite_history_keeps_every_run_of_parallel_writers_and_survives_a_killed_writer() {
    let dir = scratch("sqlite");
    let file = dir.join("history.sqlite");
    exercise(file.to_str().unwrap(), &dir);
    let old = dir.join("old.sqlite");
    migrations(old.to_str().unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn postgres_history_keeps_every_run_of_parallel_writers_and_survives_a_killed_writer() {
    let Some(server) = pg::Server::start("pg") else {
        return;
    };
    exercise(&server.url("postgres"), &server.dir);
    server.create_database("old");
    migrations(&server.url("old"));
}

/// A private PostgreSQL server on a unix socket in a scratch folder, run as
/// the `postgres` user where the test runs as root (the server refuses
/// root), stopped and removed on drop.
mod pg {
    use std::path::{Path, PathBuf};
    use std::process::{Command, Stdio};

    pub struct Server {
        pub dir: PathBuf,
        bin: PathBuf,
        port: u16,
        as_user: Option<String>,
    }

    /// The newest `/usr/lib/postgresql/N/bin` with `initdb`, or `pg_config --bindir`.
    fn binaries() -> Option<PathBuf> {
        let mut found: Vec<(u32, PathBuf)> = std::fs::read_dir("/usr/lib/postgresql")
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| {
                let v: u32 = e.file_name().to_str()?.parse().ok()?;
                let bin = e.path().join("bin");
                bin.join("initdb").exists().then_some((v, bin))
            })
            .collect();
        found.sort();
        if let Some((_, bin)) = found.pop() {
            return Some(bin);
        }
        let out = Command::new("pg_config").arg("--bindir").output().ok()?;
        let bin = PathBuf::from(String::from_utf8(out.stdout).ok()?.trim());
        bin.join("initdb").exists().then_some(bin)
    }

    impl Server {
        fn run(&self, tool: &str, args: &[&str]) -> bool {
            let exe = self.bin.join(tool);
            let mut cmd = match &self.as_user {
                Some(user) => {
                    let mut c = Command::new("runuser");
                    c.args(["-u", user, "--"]).arg(&exe);
                    c
                }
                None => Command::new(&exe),
            };
            cmd.args(args)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        }

        /// Start one, or `None` (with a message) where PostgreSQL is not installed.
        pub fn start(name: &str) -> Option<Server> {
            let Some(bin) = binaries() else {
                eprintln!(
                    "skipped: no PostgreSQL server binaries (initdb) on this machine; install Debian's `postgresql` (.ci/run does)"
                );
                return None;
            };
            let dir = super::scratch(name);
            let root = unsafe { libc::geteuid() } == 0;
            let as_user = root.then(|| "postgres".to_string());
            if root {
                let user = std::ffi::CString::new("postgres").unwrap();
                let pw = unsafe { libc::getpwnam(user.as_ptr()) };
                assert!(
                    !pw.is_null(),
                    "running as root needs the `postgres` user (Debian's postgresql package creates it)"
                );
                let (uid, gid) = unsafe { ((*pw).pw_uid, (*pw).pw_gid) };
                std::os::unix::fs::chown(&dir, Some(uid), Some(gid)).unwrap();
            }
            let port = 40000 + (std::process::id() % 20000) as u16;
            let server = Server {
                dir,
                bin,
                port,
                as_user,
            };
            let data = server.dir.join("data");
            let (data_s, dir_s) = (
                data.to_str().unwrap().to_string(),
                server.dir.to_str().unwrap().to_string(),
            );
            assert!(
                server.run(
                    "initdb",
                    &[
                        "-D",
                        &data_s,
                        "-A",
                        "trust",
                        "-U",
                        "postgres",
                        "--no-sync",
                        "-E",
                        "UTF8",
                        "--locale=C"
                    ]
                ),
                "initdb failed"
            );
            let opts = format!("-k {dir_s} -h '' -p {port} -F");
            let log = format!("{dir_s}/server.log");
            assert!(
                server.run(
                    "pg_ctl",
                    &["-D", &data_s, "-l", &log, "-w", "-o", &opts, "start"]
                ),
                "pg_ctl start failed: see {log}"
            );
            Some(server)
        }

        /// The URL of database `db` on the socket.
        pub fn url(&self, db: &str) -> String {
            let host: String = self
                .dir
                .to_str()
                .unwrap()
                .chars()
                .map(|c| {
                    if c == '/' {
                        "%2F".to_string()
                    } else {
                        c.to_string()
                    }
                })
                .collect();
            format!("postgresql://postgres@{host}:{}/{db}", self.port)
        }

        /// A new empty database.
        pub fn create_database(&self, db: &str) {
            let mut c = postgres_client(&self.url("postgres"));
            c.batch_execute(&format!("CREATE DATABASE {db}")).unwrap();
        }

        fn data(&self) -> PathBuf {
            self.dir.join("data")
        }

        #[allow(dead_code)]
        pub fn path(&self) -> &Path {
            &self.dir
        }
    }

    fn postgres_client(url: &str) -> postgres::Client {
        url.parse::<postgres::Config>()
            .unwrap()
            .connect(postgres::NoTls)
            .unwrap()
    }

    impl Drop for Server {
        fn drop(&mut self) {
            let data = self.data();
            self.run(
                "pg_ctl",
                &[
                    "-D",
                    data.to_str().unwrap(),
                    "-m",
                    "immediate",
                    "-w",
                    "stop",
                ],
            );
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}
