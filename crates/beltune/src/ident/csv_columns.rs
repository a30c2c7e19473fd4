//! Recorded data from CSV files (header row, columns chosen by name), with
//! the validation the identification needs. Every problem is an
//! [`Error::Csv`] naming the file, the column and the row (the line number in
//! the file, the header being line 1).

use crate::{Error, Result};
use std::path::Path;

/// Columns read from a CSV file, in the order requested.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvColumns {
    /// The file, for messages.
    pub path: String,
    /// Requested column names.
    pub names: Vec<String>,
    /// Values, `data[c][r]` for column `c`, data row `r`.
    pub data: Vec<Vec<f64>>,
}

impl CsvColumns {
    /// The values of a requested column.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|c| self.data[c].as_slice())
    }

    /// Number of data rows.
    pub fn rows(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }

    fn err(&self, message: String) -> Error {
        Error::Csv {
            path: self.path.clone(),
            message,
        }
    }
}

/// File line number of data row `r` (header is line 1).
pub fn line_of_row(r: usize) -> usize {
    r + 2
}

/// Open a file for reading; a name ending in `.gz` is decompressed on the fly
/// (the bench recording ships as `data/twomass-bench/multisine-a.csv.gz`).
pub fn open_maybe_gzip(path: &Path) -> std::io::Result<Box<dyn std::io::Read>> {
    let file = std::io::BufReader::new(std::fs::File::open(path)?);
    let limit = crate::io::MAX_CSV_BYTES;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
    {
        Ok(Box::new(crate::io::CappedReader::new(
            flate2::read::MultiGzDecoder::new(file),
            limit,
        )))
    } else {
        Ok(Box::new(crate::io::CappedReader::new(file, limit)))
    }
}

/// Most data rows read from one CSV file (100 s at 10 kHz is 10^6).
pub const MAX_CSV_ROWS: usize = 10_000_000;

/// A CSV reader of `path` (a regular file of at most
/// [`crate::io::MAX_CSV_BYTES`], plain or gzip) and its header row.
fn open_csv(path: &Path) -> Result<(csv::Reader<Box<dyn std::io::Read>>, csv::StringRecord)> {
    let shown = path.display().to_string();
    let csv_err = |message: String| Error::Csv {
        path: shown.clone(),
        message,
    };
    crate::io::check_readable_file(path, crate::io::MAX_CSV_BYTES).map_err(|e| match e {
        Error::Parse { message, .. } => csv_err(message),
        Error::Io { source, .. } => csv_err(format!("cannot open: {source}")),
        other => other,
    })?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(open_maybe_gzip(path).map_err(|e| csv_err(format!("cannot open: {e}")))?);
    let headers = reader
        .headers()
        .map_err(|e| csv_err(format!("cannot read the header row: {e}")))?
        .clone();
    Ok((reader, headers))
}

/// The column names of a CSV file's header row (plain or gzip), without
/// reading its data: what a command checks before it starts any work.
pub fn read_csv_header(path: &Path) -> Result<Vec<String>> {
    Ok(open_csv(path)?.1.iter().map(str::to_string).collect())
}

/// Error naming the first of `names` that the header `header` lacks (with the
/// columns it has), as [`read_csv_columns`] would say it after reading the data.
pub fn require_columns(path: &Path, header: &[String], names: &[&str]) -> Result<()> {
    match names.iter().find(|n| !header.iter().any(|h| h == *n)) {
        None => Ok(()),
        Some(n) => Err(Error::Csv {
            path: path.display().to_string(),
            message: format!("missing column `{n}` (columns: {})", header.join(", ")),
        }),
    }
}

/// Read the named columns of a CSV file with a header row (plain or gzip,
/// see [`open_maybe_gzip`]). Errors name the
/// missing column (and list the available ones), or the row and column of a
/// cell that is empty, not a number, or not finite.
pub fn read_csv_columns(path: &Path, names: &[&str]) -> Result<CsvColumns> {
    let shown = path.display().to_string();
    let csv_err = |message: String| Error::Csv {
        path: shown.clone(),
        message,
    };
    let (mut reader, headers) = open_csv(path)?;
    let mut index = Vec::with_capacity(names.len());
    for (k, name) in names.iter().enumerate() {
        if names[..k].contains(name) {
            return Err(csv_err(format!(
                "column `{name}` is asked for twice (two different signals cannot share one column)"
            )));
        }
        let found: Vec<usize> = headers
            .iter()
            .enumerate()
            .filter(|(_, h)| h == name)
            .map(|(i, _)| i)
            .collect();
        if found.len() > 1 {
            return Err(csv_err(format!(
                "the header names column `{name}` {} times (columns {}); rename them",
                found.len(),
                found
                    .iter()
                    .map(|i| (i + 1).to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        match found.first().copied() {
            Some(i) => index.push(i),
            None => {
                return Err(csv_err(format!(
                    "missing column `{name}` (columns: {})",
                    headers.iter().collect::<Vec<_>>().join(", ")
                )))
            }
        }
    }
    let mut data = vec![Vec::new(); names.len()];
    for (r, rec) in reader.records().enumerate() {
        let line = line_of_row(r);
        if r >= MAX_CSV_ROWS {
            return Err(csv_err(format!(
                "more than {MAX_CSV_ROWS} data rows (the limit of one record)"
            )));
        }
        let rec = rec.map_err(|e| csv_err(format!("row {line}: {e}")))?;
        for (c, &i) in index.iter().enumerate() {
            let cell = rec.get(i).unwrap_or("");
            let v: f64 = cell.parse().map_err(|_| {
                csv_err(format!(
                    "row {line}, column `{}`: `{cell}` is not a number",
                    names[c]
                ))
            })?;
            if !v.is_finite() {
                return Err(csv_err(format!(
                    "row {line}, column `{}`: value `{cell}` is not finite",
                    names[c]
                )));
            }
            data[c].push(v);
        }
    }
    Ok(CsvColumns {
        path: shown,
        names: names.iter().map(|s| s.to_string()).collect(),
        data,
    })
}

/// The sampling of a time column.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Sampling {
    /// Mean sample period, s (time unit of the file).
    pub ts_s: f64,
    /// Largest relative deviation of one step from the mean, `max |dt - T_s| / T_s`.
    pub max_jitter: f64,
}

/// Check that the time column `name` of `cols` is strictly increasing and
/// has at least `min_rows` rows; return the mean sample period and jitter.
pub fn check_time(cols: &CsvColumns, name: &str, min_rows: usize) -> Result<Sampling> {
    let t = cols
        .column(name)
        .ok_or_else(|| cols.err(format!("missing column `{name}`")))?;
    if t.len() < min_rows.max(2) {
        return Err(cols.err(format!(
            "too few samples: {} data rows, need at least {}",
            t.len(),
            min_rows.max(2)
        )));
    }
    if let Some(r) = (1..t.len()).find(|&r| t[r] <= t[r - 1]) {
        return Err(cols.err(format!(
            "row {}, column `{name}`: time is not increasing ({} after {})",
            line_of_row(r),
            t[r],
            t[r - 1]
        )));
    }
    let ts = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    let max_jitter = t
        .windows(2)
        .map(|w| ((w[1] - w[0]) - ts).abs() / ts)
        .fold(0.0, f64::max);
    Ok(Sampling {
        ts_s: ts,
        max_jitter,
    })
}

/// Like [`check_time`], and additionally require uniform sampling (every step
/// within `tolerance` of the mean, relative), naming the first bad row.
pub fn check_uniform_time(
    cols: &CsvColumns,
    name: &str,
    min_rows: usize,
    tolerance: f64,
) -> Result<Sampling> {
    let s = check_time(cols, name, min_rows)?;
    if s.max_jitter > tolerance {
        let t = cols.column(name).expect("checked");
        let r = (1..t.len())
            .find(|&r| ((t[r] - t[r - 1]) - s.ts_s).abs() / s.ts_s > tolerance)
            .unwrap_or(1);
        return Err(cols.err(format!(
            "row {}, column `{name}`: non-uniform sampling (step {} vs mean {})",
            line_of_row(r),
            t[r] - t[r - 1],
            s.ts_s
        )));
    }
    Ok(s)
}

/// Error if `x` (column `name`) is constant: nothing is excited.
pub fn check_not_constant(cols: &CsvColumns, name: &str) -> Result<()> {
    let x = cols
        .column(name)
        .ok_or_else(|| cols.err(format!("missing column `{name}`")))?;
    if x.is_empty() {
        return Err(cols.err("no data rows (only the header)".to_string()));
    }
    if x.iter().all(|&v| v == x[0]) {
        return Err(cols.err(format!(
            "column `{name}` is constant ({}) in rows {}..{}: no excitation",
            x.first().copied().unwrap_or(0.0),
            line_of_row(0),
            line_of_row(x.len().saturating_sub(1))
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("beltune-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn msg(r: Result<impl std::fmt::Debug>) -> String {
        r.unwrap_err().to_string()
    }

    #[test]
    fn reads_columns_by_name_and_reports_bad_cells() {
        let p = tmp("ok.csv", "t,u,y\n0,1,2\n0.1,3,4\n0.2,5,6\n");
        let c = read_csv_columns(&p, &["y", "t"]).unwrap();
        assert_eq!(c.column("y").unwrap(), &[2.0, 4.0, 6.0]);
        assert_eq!(c.rows(), 3);
        let s = check_uniform_time(&c, "t", 3, 1e-6).unwrap();
        assert!((s.ts_s - 0.1).abs() < 1e-12);

        let m = msg(read_csv_columns(&p, &["t", "z"]));
        assert!(
            m.contains("missing column `z`") && m.contains("t, u, y"),
            "{m}"
        );
        let p = tmp("bad.csv", "t,u\n0,1\n0.1,abc\n");
        let m = msg(read_csv_columns(&p, &["t", "u"]));
        assert!(
            m.contains("row 3") && m.contains("`u`") && m.contains("abc"),
            "{m}"
        );
        let p = tmp("nan.csv", "t,u\n0,1\n0.1,NaN\n");
        let m = msg(read_csv_columns(&p, &["t", "u"]));
        assert!(m.contains("row 3") && m.contains("not finite"), "{m}");
        let p = tmp("time.csv", "t,u\n0,1\n0.1,2\n0.1,3\n");
        let c = read_csv_columns(&p, &["t", "u"]).unwrap();
        let m = msg(check_time(&c, "t", 2));
        assert!(m.contains("row 4") && m.contains("not increasing"), "{m}");
        let m = msg(check_time(&c, "t", 10));
        assert!(m.contains("too few samples"), "{m}");
        let p = tmp("const.csv", "t,u\n0,1\n0.1,1\n0.2,1\n");
        let c = read_csv_columns(&p, &["t", "u"]).unwrap();
        let m = msg(check_not_constant(&c, "u"));
        assert!(
            m.contains("`u` is constant") && m.contains("no excitation"),
            "{m}"
        );
    }
}
