//! The history's one schema, as numbered migrations applied in order and
//! recorded in `schema_migrations` (docs/health.md#the-history-database).
//! A migration is never changed once released: a change of the schema is a
//! new migration at the end. `{id}` is the dialect's auto-numbered key
//! ([`super::backend::Dialect::ddl`]).

/// One step of the schema.
pub struct Migration {
    /// Its number, 1, 2, ... in order.
    pub version: i64,
    /// What it does.
    pub name: &'static str,
    /// Its statements (`;`-separated, both dialects).
    pub sql: &'static str,
}

/// Every migration, oldest first.
pub const MIGRATIONS: &[Migration] = &[
    Migration {
        version: 1,
        name: "axes, runs and their quantities",
        sql: "
CREATE TABLE axes (
    name TEXT PRIMARY KEY,
    created_utc TEXT NOT NULL
);
CREATE TABLE runs (
    id {id},
    axis TEXT NOT NULL REFERENCES axes (name),
    kind TEXT NOT NULL,
    created_utc TEXT NOT NULL,
    status TEXT NOT NULL,
    result_dir TEXT,
    baseline_dir TEXT,
    beltune_version TEXT NOT NULL,
    experiment_time_s DOUBLE PRECISION,
    record TEXT NOT NULL
);
CREATE INDEX runs_by_axis ON runs (axis, id);
CREATE TABLE quantities (
    run_id BIGINT NOT NULL REFERENCES runs (id),
    name TEXT NOT NULL,
    unit TEXT NOT NULL,
    value DOUBLE PRECISION,
    sigma DOUBLE PRECISION,
    baseline DOUBLE PRECISION,
    baseline_sigma DOUBLE PRECISION,
    change DOUBLE PRECISION,
    change_sigma DOUBLE PRECISION,
    limit_lower DOUBLE PRECISION,
    limit_upper DOUBLE PRECISION,
    limit_relative BIGINT,
    status TEXT,
    position_m DOUBLE PRECISION,
    PRIMARY KEY (run_id, name)
);
",
    },
    Migration {
        version: 2,
        name: "the recommendations of a run",
        sql: "ALTER TABLE runs ADD COLUMN recommendations TEXT;",
    },
];

/// The schema version this beltune writes.
pub fn current_version() -> i64 {
    MIGRATIONS.last().map_or(0, |m| m.version)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn migrations_are_numbered_in_order() {
        for (k, m) in MIGRATIONS.iter().enumerate() {
            assert_eq!(m.version, k as i64 + 1, "{}", m.name);
        }
    }
}
