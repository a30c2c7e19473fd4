//! The history database: every commissioning and health run of every axis,
//! with one schema ([`schema`], versioned migrations) in an embedded SQLite
//! file or on a PostgreSQL server, the same code on both ([`backend`]).
//!
//! | file | what |
//! | --- | --- |
//! | [`backend`] | the two back ends behind one interface, the dialects, concurrency |
//! | [`schema`] | the migrations |
//! | [`runs`] | what a commissioning or a health run stores |
//!
//! Each run is written in one transaction (its axis, the run and its
//! quantities): a reader sees a run whole or not at all, a writer killed
//! in the middle leaves nothing of it, and writers of several axes at once
//! queue on the database's own locks.

pub mod backend;
pub mod runs;
pub mod schema;

pub use backend::{Column, Location, Value};
pub use runs::{NewRun, QuantityRow, RunKind, RunRow};

use crate::{Error, Result};
use backend::{Conn, Dialect};

/// An open history (migrated to [`schema::current_version`]).
pub struct HistoryDb {
    conn: Conn,
    location: Location,
}

/// Advisory-lock key of the PostgreSQL migrations ("beltune" in ASCII).
const MIGRATION_LOCK_KEY: i64 = 0x0062_656c_7475_6e65;

impl HistoryDb {
    /// Open (an SQLite file is created) and migrate to the current schema.
    pub fn open(location: &Location) -> Result<HistoryDb> {
        let mut db = HistoryDb::open_unmigrated(location)?;
        db.migrate_to(schema::current_version())?;
        Ok(db)
    }

    /// Open without migrating (tests of the migrations).
    pub fn open_unmigrated(location: &Location) -> Result<HistoryDb> {
        Ok(HistoryDb {
            conn: Conn::open(location)?,
            location: location.clone(),
        })
    }

    /// Where it is.
    pub fn location(&self) -> &Location {
        &self.location
    }

    fn err(&self, reason: impl std::fmt::Display) -> Error {
        Error::Database {
            location: self.location.display(),
            reason: reason.to_string(),
        }
    }

    /// Apply the migrations up to `version`, in one transaction that holds
    /// the write lock (SQLite) or an advisory lock (PostgreSQL), so that
    /// processes opening a new database at once migrate it once. A database
    /// of a newer schema than this beltune knows is refused.
    pub fn migrate_to(&mut self, version: i64) -> Result<()> {
        let result = self.migrate_in_transaction(version);
        if result.is_err() {
            let _ = self.conn.batch("ROLLBACK");
        }
        result
    }

    fn migrate_in_transaction(&mut self, version: i64) -> Result<()> {
        self.conn.begin_write().map_err(|e| self.err(e))?;
        if self.conn.dialect() == Dialect::Postgres {
            self.conn
                .query(
                    "SELECT pg_advisory_xact_lock($1)::TEXT",
                    &[Value::Int(Some(MIGRATION_LOCK_KEY))],
                    &[Column::Text],
                )
                .map_err(|e| self.err(e))?;
        }
        self.conn
            .batch(
                "CREATE TABLE IF NOT EXISTS schema_migrations (
                    version BIGINT PRIMARY KEY,
                    name TEXT NOT NULL,
                    applied_utc TEXT NOT NULL
                )",
            )
            .map_err(|e| self.err(e))?;
        let have = self.version_in_transaction()?;
        let known = schema::current_version();
        if have > known {
            return Err(self.err(format!(
                "the schema is version {have}, this beltune knows {known}: written by a newer beltune"
            )));
        }
        let dialect = self.conn.dialect();
        for m in schema::MIGRATIONS
            .iter()
            .filter(|m| m.version > have && m.version <= version)
        {
            self.conn
                .batch(&dialect.ddl(m.sql))
                .map_err(|e| self.err(format!("migration {} ({}): {e}", m.version, m.name)))?;
            self.conn
                .execute(
                    "INSERT INTO schema_migrations (version, name, applied_utc) VALUES ($1, $2, $3)",
                    &[
                        Value::Int(Some(m.version)),
                        Value::text(m.name),
                        Value::text(now_utc()),
                    ],
                )
                .map_err(|e| self.err(e))?;
        }
        self.conn.batch("COMMIT").map_err(|e| self.err(e))?;
        Ok(())
    }

    fn version_in_transaction(&mut self) -> Result<i64> {
        let rows = self
            .conn
            .query(
                "SELECT MAX(version) FROM schema_migrations",
                &[],
                &[Column::Int],
            )
            .map_err(|e| self.err(e))?;
        Ok(rows.first().and_then(|r| r[0].as_i64()).unwrap_or_default())
    }

    /// The schema version of the database (0: empty).
    pub fn schema_version(&mut self) -> Result<i64> {
        self.version_in_transaction()
    }

    /// Run `f` in one write transaction: committed when it returns `Ok`,
    /// rolled back otherwise (and by the database if the process dies).
    pub fn write<T>(&mut self, f: impl FnOnce(&mut Writer<'_>) -> Result<T>) -> Result<T> {
        self.conn.begin_write().map_err(|e| self.err(e))?;
        let mut w = Writer { db: self };
        match f(&mut w) {
            Ok(v) => {
                w.db.conn.batch("COMMIT").map_err(|e| w.db.err(e))?;
                Ok(v)
            }
            Err(e) => {
                let _ = w.db.conn.batch("ROLLBACK");
                Err(e)
            }
        }
    }

    /// Record one run (its axis, the run, its quantities) in one
    /// transaction; returns its number.
    pub fn record(&mut self, run: &NewRun) -> Result<i64> {
        self.write(|w| w.insert_run(run))
    }

    /// The runs, oldest first, of `axis` or of every axis, with their quantities.
    pub fn runs(&mut self, axis: Option<&str>) -> Result<Vec<RunRow>> {
        runs::read_runs(self, axis)
    }

    /// The axes, by name.
    pub fn axes(&mut self) -> Result<Vec<String>> {
        let rows = self.query("SELECT name FROM axes ORDER BY name", &[], &[Column::Text])?;
        Ok(rows
            .into_iter()
            .filter_map(|r| r[0].as_str().map(str::to_string))
            .collect())
    }

    /// One query (the readers of [`runs`]).
    pub(crate) fn query(
        &mut self,
        sql: &str,
        params: &[Value],
        columns: &[Column],
    ) -> Result<Vec<Vec<Value>>> {
        self.conn
            .query(sql, params, columns)
            .map_err(|e| self.err(e))
    }
}

/// The statements of one write transaction ([`HistoryDb::write`]).
pub struct Writer<'a> {
    db: &'a mut HistoryDb,
}

impl Writer<'_> {
    /// One statement.
    pub fn execute(&mut self, sql: &str, params: &[Value]) -> Result<u64> {
        self.db
            .conn
            .execute(sql, params)
            .map_err(|e| self.db.err(e))
    }

    /// One query.
    pub fn query(
        &mut self,
        sql: &str,
        params: &[Value],
        columns: &[Column],
    ) -> Result<Vec<Vec<Value>>> {
        self.db.query(sql, params, columns)
    }

    /// The axis (created if new), the run and its quantities; the run's number.
    pub fn insert_run(&mut self, run: &NewRun) -> Result<i64> {
        runs::insert_run(self, run)
    }
}

/// Now as RFC 3339 UTC, to the second.
pub fn now_utc() -> String {
    humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string()
}
