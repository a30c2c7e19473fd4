//! `beltune history`: the runs of the history database (every
//! commissioning and health run, `beltune::history`), as a list, as JSON,
//! or as a page with each quantity's trend and its limits; and the history
//! flags `commission` and `health` share (`--db`, `--axis`).

use crate::cmd::commission::preflight::bad;
use beltune::history::{HistoryDb, Location, NewRun};
use beltune::record::folder::OutputTarget;
use std::path::{Path, PathBuf};

/// The history database's file name when `--db` is not given.
pub const DEFAULT_DB_FILE: &str = "beltune-history.sqlite";

/// Where the history is, shared by `commission` and `health`.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct DbArgs {
    /// The history database: an SQLite FILE, or a PostgreSQL server
    /// (`postgres://USER@HOST/DB`). Default: `beltune-history.sqlite` beside
    /// the results (next to the `commissioning/` and `health/` folders, or
    /// next to the --out folder).
    #[arg(long, value_name = "FILE|URL")]
    pub db: Option<String>,
    /// The axis' name in the history (default: the plant's name).
    #[arg(long, value_name = "NAME")]
    pub axis: Option<String>,
}

impl DbArgs {
    /// The database of these flags for results going to `target`.
    pub fn location(&self, target: &OutputTarget) -> Location {
        match &self.db {
            Some(db) => Location::parse(db),
            None => Location::Sqlite(beside(target).join(DEFAULT_DB_FILE)),
        }
    }

    /// Check the database before the axis moves: a server is reached and
    /// migrated, an SQLite file that exists is opened and migrated, and a
    /// new one's folder exists (it is created with the first run, so that a
    /// refused command writes nothing).
    pub fn check(&self, target: &OutputTarget) -> anyhow::Result<Location> {
        if let Some(name) = &self.axis {
            check_axis_name(name)?;
        }
        let loc = self.location(target);
        match &loc {
            // the default file goes beside the results, whose folder the
            // result's writing creates
            Location::Sqlite(_) if self.db.is_none() => {}
            Location::Sqlite(path) if !path.exists() => {
                let dir = match path.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
                    _ => PathBuf::from("."),
                };
                if !dir.is_dir() {
                    return Err(bad(format!(
                        "--db {}: the folder {} does not exist",
                        path.display(),
                        dir.display()
                    )));
                }
            }
            _ => {
                HistoryDb::open(&loc)?;
            }
        }
        Ok(loc)
    }
}

/// An axis name: 1 to 200 printable characters.
fn check_axis_name(name: &str) -> anyhow::Result<()> {
    if name.is_empty() || name.len() > 200 || name.chars().any(char::is_control) {
        return Err(bad(format!(
            "--axis `{}`: a name of 1 to 200 printable characters",
            name.escape_debug()
        )));
    }
    Ok(())
}

/// The folder that holds the results of `target` (the history file goes there).
fn beside(target: &OutputTarget) -> PathBuf {
    let parent = |p: &Path| match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    match target {
        OutputTarget::History { root } => parent(root),
        OutputTarget::Exact { dir, .. } => parent(dir),
    }
}

/// Record `run` in `loc`; its number.
pub fn record(loc: &Location, run: &NewRun) -> anyhow::Result<i64> {
    if let Location::Sqlite(path) = loc {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
        }
    }
    let mut db = HistoryDb::open(loc)?;
    Ok(db.record(run)?)
}

/// Arguments of `beltune history`.
#[derive(clap::Args)]
pub struct Args {
    /// The history database: an SQLite FILE or a `postgres://` URL
    /// (default: `beltune-history.sqlite` here).
    #[arg(long, value_name = "FILE|URL")]
    pub db: Option<String>,
    /// Only this axis.
    #[arg(long, value_name = "NAME")]
    pub axis: Option<String>,
    /// Write a page with the runs and each quantity's trend and limits.
    #[arg(long, value_name = "FILE")]
    pub html: Option<PathBuf>,
    /// Print the runs (with their quantities) as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    let loc = match &args.db {
        Some(db) => Location::parse(db),
        None => Location::Sqlite(PathBuf::from(DEFAULT_DB_FILE)),
    };
    if let Location::Sqlite(path) = &loc {
        if !path.is_file() {
            return Err(bad(format!(
                "no history database {} (commission or check an axis first, or give --db)",
                path.display()
            )));
        }
    }
    let mut db = HistoryDb::open(&loc)?;
    let runs = db.runs(args.axis.as_deref())?;
    if let Some(html) = &args.html {
        let title = match &args.axis {
            Some(a) => format!("beltune history: {a}"),
            None => "beltune history: every axis".to_string(),
        };
        let report = beltune::report::health::history_report(&title, &runs);
        beltune::io::write_atomic(html, beltune::report::render_html(&report)?.as_bytes())?;
        if !args.json {
            eprintln!("wrote {}", html.display());
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&runs)?);
        return Ok(());
    }
    if runs.is_empty() {
        println!(
            "no runs{} in {}",
            args.axis
                .as_ref()
                .map(|a| format!(" of `{a}`"))
                .unwrap_or_default(),
            loc.display()
        );
        return Ok(());
    }
    for r in &runs {
        let far = r
            .run
            .quantities
            .iter()
            .find(|q| q.name == "stiffness_far")
            .map(|q| format!("c {:.1} kN/m", q.value / 1e3))
            .unwrap_or_default();
        println!(
            "{:>5}  {:<16} {:<13} {}  {:<5} {:>14}  {}",
            r.id,
            r.run.axis,
            r.run.kind.key(),
            r.run.created_utc,
            r.run.status,
            far,
            r.run.result_dir.as_deref().unwrap_or("")
        );
        for rec in &r.run.recommendations {
            println!("       - {rec}");
        }
    }
    Ok(())
}
