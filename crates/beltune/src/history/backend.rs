//! The two back ends behind one interface: an embedded SQLite file
//! (`rusqlite`, compiled in) and a PostgreSQL server (`postgres`, the sync
//! client). Statements are written once, with `$1, $2, ...` placeholders in
//! order (SQLite reads them as parameters numbered by first appearance);
//! only the migrations' identity column and their lock differ by dialect
//! ([`Dialect`]).
//!
//! Concurrency: SQLite runs in WAL mode, every write transaction starts
//! with `BEGIN IMMEDIATE` (it takes the write lock at once, so two writers
//! queue instead of deadlocking on a lock upgrade) and waits up to
//! [`BUSY_TIMEOUT`] for it; PostgreSQL serializes the migrations with a
//! transaction-scoped advisory lock. A writer killed inside a transaction
//! leaves nothing of it: SQLite rolls the WAL back on the next open,
//! PostgreSQL aborts the transaction when the connection drops.

use crate::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How long an SQLite writer waits for the write lock.
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(60);

/// A parameter or a column value: typed, so that a NULL has a type on
/// PostgreSQL too.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// An integer (`BIGINT`).
    Int(Option<i64>),
    /// A float (`DOUBLE PRECISION`); NaN and infinities are stored as NULL.
    Real(Option<f64>),
    /// Text (`TEXT`).
    Text(Option<String>),
}

impl Value {
    /// A float, NULL where it is not finite.
    pub fn real(x: f64) -> Value {
        Value::Real(x.is_finite().then_some(x))
    }

    /// Text.
    pub fn text(s: impl Into<String>) -> Value {
        Value::Text(Some(s.into()))
    }

    /// The float (NaN for NULL or another type).
    pub fn as_f64(&self) -> f64 {
        match self {
            Value::Real(Some(x)) => *x,
            Value::Int(Some(i)) => *i as f64,
            _ => f64::NAN,
        }
    }

    /// The integer, if one.
    pub fn as_i64(&self) -> Option<i64> {
        match self {
            Value::Int(i) => *i,
            _ => None,
        }
    }

    /// The text, if any.
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Value::Text(Some(s)) => Some(s),
            _ => None,
        }
    }
}

/// The column types of a query's result, to read PostgreSQL's typed rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// `BIGINT`.
    Int,
    /// `DOUBLE PRECISION`.
    Real,
    /// `TEXT`.
    Text,
}

/// Which SQL dialect a back end speaks (only the migrations differ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dialect {
    /// SQLite 3.
    Sqlite,
    /// PostgreSQL.
    Postgres,
}

impl Dialect {
    /// A migration's DDL with `{id}` replaced by the dialect's
    /// auto-numbered primary key.
    pub fn ddl(self, sql: &str) -> String {
        sql.replace(
            "{id}",
            match self {
                Dialect::Sqlite => "INTEGER PRIMARY KEY AUTOINCREMENT",
                Dialect::Postgres => "BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY",
            },
        )
    }
}

/// Where the history is kept.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// An SQLite file.
    Sqlite(PathBuf),
    /// A PostgreSQL server (`postgres://` or `postgresql://` URL).
    Postgres(String),
}

impl Location {
    /// `postgres://...` or `postgresql://...` is a server, anything else a file.
    pub fn parse(s: &str) -> Location {
        if s.starts_with("postgres://") || s.starts_with("postgresql://") {
            Location::Postgres(s.to_string())
        } else {
            Location::Sqlite(PathBuf::from(s))
        }
    }

    /// For messages: the file, or the server URL without its password.
    pub fn display(&self) -> String {
        match self {
            Location::Sqlite(p) => p.display().to_string(),
            Location::Postgres(url) => match url.split_once('@') {
                Some((cred, rest)) => match cred.split_once("://") {
                    Some((scheme, user)) => {
                        let user = user.split(':').next().unwrap_or("");
                        format!("{scheme}://{user}@{rest}")
                    }
                    None => url.clone(),
                },
                None => url.clone(),
            },
        }
    }
}

/// An open connection.
pub enum Conn {
    /// SQLite.
    Sqlite(rusqlite::Connection),
    /// PostgreSQL.
    Postgres(Box<postgres::Client>),
}

fn db_err(loc: &str, e: impl std::fmt::Display) -> Error {
    Error::Database {
        location: loc.to_string(),
        reason: e.to_string(),
    }
}

impl Conn {
    /// Open `loc` (an SQLite file is created, its folder must exist).
    pub fn open(loc: &Location) -> Result<Conn> {
        let name = loc.display();
        match loc {
            Location::Sqlite(path) => open_sqlite(path).map_err(|e| db_err(&name, e)),
            Location::Postgres(url) => {
                let config: postgres::Config = url.parse().map_err(|e| db_err(&name, e))?;
                let client = config
                    .connect(postgres::NoTls)
                    .map_err(|e| db_err(&name, e))?;
                Ok(Conn::Postgres(Box::new(client)))
            }
        }
    }

    /// The dialect.
    pub fn dialect(&self) -> Dialect {
        match self {
            Conn::Sqlite(_) => Dialect::Sqlite,
            Conn::Postgres(_) => Dialect::Postgres,
        }
    }

    /// Run statements without parameters (DDL, transaction control).
    pub fn batch(&mut self, sql: &str) -> std::result::Result<(), String> {
        match self {
            Conn::Sqlite(c) => c.execute_batch(sql).map_err(|e| e.to_string()),
            Conn::Postgres(c) => c.batch_execute(sql).map_err(|e| e.to_string()),
        }
    }

    /// Start a write transaction (SQLite: with the write lock at once).
    pub fn begin_write(&mut self) -> std::result::Result<(), String> {
        match self {
            Conn::Sqlite(_) => self.batch("BEGIN IMMEDIATE"),
            Conn::Postgres(_) => self.batch("BEGIN"),
        }
    }

    /// Run one statement with `params`; returns the rows changed.
    pub fn execute(&mut self, sql: &str, params: &[Value]) -> std::result::Result<u64, String> {
        match self {
            Conn::Sqlite(c) => c
                .execute(
                    sql,
                    rusqlite::params_from_iter(params.iter().map(SqliteValue)),
                )
                .map(|n| n as u64)
                .map_err(|e| e.to_string()),
            Conn::Postgres(c) => {
                let boxed = pg_params(params);
                let refs: Vec<&(dyn postgres::types::ToSql + Sync)> =
                    boxed.iter().map(|b| b.as_ref()).collect();
                c.execute(sql, &refs).map_err(|e| e.to_string())
            }
        }
    }

    /// Run one query with `params`, its columns of the types `columns`.
    pub fn query(
        &mut self,
        sql: &str,
        params: &[Value],
        columns: &[Column],
    ) -> std::result::Result<Vec<Vec<Value>>, String> {
        match self {
            Conn::Sqlite(c) => {
                let mut stmt = c.prepare(sql).map_err(|e| e.to_string())?;
                let rows = stmt
                    .query_map(
                        rusqlite::params_from_iter(params.iter().map(SqliteValue)),
                        |row| {
                            columns
                                .iter()
                                .enumerate()
                                .map(|(i, col)| {
                                    Ok(match col {
                                        Column::Int => Value::Int(row.get(i)?),
                                        Column::Real => Value::Real(row.get(i)?),
                                        Column::Text => Value::Text(row.get(i)?),
                                    })
                                })
                                .collect::<rusqlite::Result<Vec<Value>>>()
                        },
                    )
                    .map_err(|e| e.to_string())?;
                rows.collect::<rusqlite::Result<Vec<_>>>()
                    .map_err(|e| e.to_string())
            }
            Conn::Postgres(c) => {
                let boxed = pg_params(params);
                let refs: Vec<&(dyn postgres::types::ToSql + Sync)> =
                    boxed.iter().map(|b| b.as_ref()).collect();
                let rows = c.query(sql, &refs).map_err(|e| e.to_string())?;
                rows.iter()
                    .map(|row| {
                        columns
                            .iter()
                            .enumerate()
                            .map(|(i, col)| {
                                Ok(match col {
                                    Column::Int => Value::Int(row.try_get(i)?),
                                    Column::Real => Value::Real(row.try_get(i)?),
                                    Column::Text => Value::Text(row.try_get(i)?),
                                })
                            })
                            .collect::<std::result::Result<Vec<Value>, postgres::Error>>()
                    })
                    .collect::<std::result::Result<Vec<_>, _>>()
                    .map_err(|e| e.to_string())
            }
        }
    }
}

/// Open an SQLite file, trying again for up to [`BUSY_TIMEOUT`] while it
/// is busy: switching a new file to WAL and the first open of its log take
/// locks that SQLite's busy handler does not wait for, so writer processes
/// racing to open a new database got "database is locked" at once.
fn open_sqlite(path: &Path) -> rusqlite::Result<Conn> {
    let started = std::time::Instant::now();
    let mut pause = Duration::from_millis(5);
    loop {
        match open_sqlite_once(path) {
            Err(rusqlite::Error::SqliteFailure(e, _))
                if matches!(
                    e.code,
                    rusqlite::ErrorCode::DatabaseBusy | rusqlite::ErrorCode::DatabaseLocked
                ) && started.elapsed() < BUSY_TIMEOUT =>
            {
                std::thread::sleep(pause);
                pause = (pause * 2).min(Duration::from_millis(200));
            }
            other => return other,
        }
    }
}

fn open_sqlite_once(path: &Path) -> rusqlite::Result<Conn> {
    let c = rusqlite::Connection::open(path)?;
    c.busy_timeout(BUSY_TIMEOUT)?;
    // WAL: readers do not block the writer, and a killed writer's
    // transaction is rolled back from the log on the next open
    c.pragma_update(None, "journal_mode", "WAL")?;
    c.pragma_update(None, "synchronous", "FULL")?;
    c.pragma_update(None, "foreign_keys", "ON")?;
    Ok(Conn::Sqlite(c))
}

struct SqliteValue<'a>(&'a Value);

impl rusqlite::ToSql for SqliteValue<'_> {
    fn to_sql(&self) -> rusqlite::Result<rusqlite::types::ToSqlOutput<'_>> {
        use rusqlite::types::{ToSqlOutput, Value as V};
        Ok(ToSqlOutput::Owned(match self.0 {
            Value::Int(Some(i)) => V::Integer(*i),
            Value::Real(Some(x)) => V::Real(*x),
            Value::Text(Some(s)) => V::Text(s.clone()),
            Value::Int(None) | Value::Real(None) | Value::Text(None) => V::Null,
        }))
    }
}

fn pg_params(params: &[Value]) -> Vec<Box<dyn postgres::types::ToSql + Sync>> {
    params
        .iter()
        .map(|v| -> Box<dyn postgres::types::ToSql + Sync> {
            match v {
                Value::Int(i) => Box::new(*i),
                Value::Real(x) => Box::new(*x),
                Value::Text(s) => Box::new(s.clone()),
            }
        })
        .collect()
}
