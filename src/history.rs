//! The trainees' history: every scored attempt (trainee, scene, the model's hash, when, and
//! every score) in an SQLite database, so that a trainee's learning curve can be drawn across
//! sessions (`palpus history`).
//!
//! SQLite because several sessions may write at once (each insert is one transaction; a writer
//! waits for another up to [`BUSY_TIMEOUT`]) and a crash mid-write leaves the file consistent.
//! A file that is not a palpus history, or is damaged, is reported and never written to.

use std::path::{Path, PathBuf};
use std::time::Duration;

use rusqlite::{Connection, OpenFlags, params};
use serde::Serialize;

use crate::session::score::Score;

/// The schema's version (`PRAGMA user_version`); a file of a later one is refused.
const SCHEMA_VERSION: i64 = 1;

/// How long a writer waits for another session's write.
const BUSY_TIMEOUT: Duration = Duration::from_secs(30);

const SCHEMA: &str = "CREATE TABLE attempts (
    id INTEGER PRIMARY KEY,
    at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now')),
    trainee TEXT NOT NULL,
    scene TEXT NOT NULL,
    model_sha256 TEXT NOT NULL,
    device TEXT NOT NULL,
    passed INTEGER NOT NULL,
    verdict TEXT NOT NULL,
    target TEXT NOT NULL,
    layers_given TEXT NOT NULL,
    target_depth_m REAL,
    overshoot_m REAL,
    allowed_overshoot_m REAL NOT NULL,
    peak_force_n REAL NOT NULL,
    time_to_target_s REAL,
    withdrawals INTEGER NOT NULL,
    reinsertions INTEGER NOT NULL,
    smoothness_sparc REAL,
    deepest_m REAL NOT NULL
)";

/// The columns [`SCHEMA`] makes, in order: a table named `attempts` with others is not ours.
const COLUMNS: [&str; 19] = [
    "id",
    "at",
    "trainee",
    "scene",
    "model_sha256",
    "device",
    "passed",
    "verdict",
    "target",
    "layers_given",
    "target_depth_m",
    "overshoot_m",
    "allowed_overshoot_m",
    "peak_force_n",
    "time_to_target_s",
    "withdrawals",
    "reinsertions",
    "smoothness_sparc",
    "deepest_m",
];

/// Why the history could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum HistoryError {
    /// The folder for a new history could not be made.
    #[error("{}: {source}", path.display())]
    Folder {
        /// The folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not a palpus history, is damaged, or is of a later version: left as it is.
    #[error("{}: not a usable palpus history ({reason}); it was left as it is: move it away or give --history another file", path.display())]
    Unusable {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// SQLite refused an operation (a lock held past the timeout, a full disk, …).
    #[error("{}: {source}", path.display())]
    Sqlite {
        /// The file.
        path: PathBuf,
        /// What SQLite said.
        source: rusqlite::Error,
    },
    /// `palpus history` on a file that does not exist.
    #[error("{}: no history yet (a run of a scene with a [task.goal] writes one)", path.display())]
    Missing {
        /// The file.
        path: PathBuf,
    },
}

impl HistoryError {
    fn sqlite(path: &Path) -> impl Fn(rusqlite::Error) -> Self + Copy + '_ {
        move |source| Self::Sqlite {
            path: path.to_owned(),
            source,
        }
    }

    fn unusable(path: &Path) -> impl Fn(String) -> Self + Copy + '_ {
        move |reason| Self::Unusable {
            path: path.to_owned(),
            reason,
        }
    }
}

/// One stored attempt.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Attempt {
    /// Its number in the history (1, 2, … in the order stored).
    pub id: i64,
    /// When it was stored, UTC (ISO 8601).
    pub at: String,
    /// Who made it.
    pub trainee: String,
    /// The scene's name.
    pub scene: String,
    /// SHA-256 of the models it rendered.
    pub model_sha256: String,
    /// The device.
    pub device: String,
    /// The score.
    pub score: Score,
}

/// The history file: `$PALPUS_HISTORY`, else `history.sqlite` under the user's data
/// directory (`$XDG_DATA_HOME/palpus`, else `~/.local/share/palpus`).
pub fn default_path() -> PathBuf {
    if let Some(file) = std::env::var_os("PALPUS_HISTORY") {
        return PathBuf::from(file);
    }
    let dir = match (std::env::var_os("XDG_DATA_HOME"), std::env::var_os("HOME")) {
        (Some(d), _) if !d.is_empty() => PathBuf::from(d),
        (_, Some(home)) => PathBuf::from(home).join(".local").join("share"),
        _ => PathBuf::from("."),
    };
    dir.join("palpus").join("history.sqlite")
}

/// An open history.
#[derive(Debug)]
pub struct History {
    path: PathBuf,
    db: Connection,
}

impl History {
    /// Opens the history at `path` to add attempts, making it (and its folder) when missing.
    pub fn open_or_create(path: &Path) -> Result<Self, HistoryError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| HistoryError::Folder {
                path: dir.to_owned(),
                source,
            })?;
        }
        Self::open_with(
            path,
            OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_CREATE,
        )
    }

    /// Opens an existing history to read it.
    pub fn open(path: &Path) -> Result<Self, HistoryError> {
        if !path.exists() {
            return Err(HistoryError::Missing {
                path: path.to_owned(),
            });
        }
        Self::open_with(path, OpenFlags::SQLITE_OPEN_READ_ONLY)
    }

    fn open_with(path: &Path, flags: OpenFlags) -> Result<Self, HistoryError> {
        let sqlite = HistoryError::sqlite(path);
        let unusable = HistoryError::unusable(path);
        let db =
            Connection::open_with_flags(path, flags | OpenFlags::SQLITE_OPEN_NO_MUTEX).map_err(sqlite)?;
        db.busy_timeout(BUSY_TIMEOUT).map_err(sqlite)?;
        // A file that is not SQLite fails its first read: nothing has been written to it.
        let check: String = db
            .query_row("PRAGMA quick_check", [], |r| r.get(0))
            .map_err(|e| unusable(e.to_string()))?;
        if check != "ok" {
            return Err(unusable(format!("integrity check: {check}")));
        }
        // One statement, one snapshot: read apart, another session's creation could commit
        // between them and show its table without its version.
        let (version, tables): (i64, i64) = db
            .query_row(
                "SELECT (SELECT user_version FROM pragma_user_version), (SELECT count(*) FROM sqlite_master)",
                [],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .map_err(|e| unusable(e.to_string()))?;
        let history = Self {
            path: path.to_owned(),
            db,
        };
        match (version, tables) {
            (0, 0) if !flags.contains(OpenFlags::SQLITE_OPEN_READ_ONLY) => history.create()?,
            (SCHEMA_VERSION, _) => history.check_columns()?,
            (0, _) => return Err(unusable("an SQLite database of something else".into())),
            (v, _) => {
                return Err(unusable(format!(
                    "schema version {v}; this palpus reads {SCHEMA_VERSION}"
                )));
            }
        }
        Ok(history)
    }

    /// Makes the table in an empty database, in one transaction with its version, so that two
    /// sessions creating it at once leave one table.
    fn create(&self) -> Result<(), HistoryError> {
        let sqlite = HistoryError::sqlite(&self.path);
        self.db.execute_batch("BEGIN IMMEDIATE").map_err(sqlite)?;
        let made = (|| {
            let version: i64 = self.db.query_row("PRAGMA user_version", [], |r| r.get(0))?;
            if version == 0 {
                self.db.execute_batch(SCHEMA)?;
                self.db
                    .execute_batch(&format!("PRAGMA user_version = {SCHEMA_VERSION}"))?;
            }
            self.db.execute_batch("COMMIT")
        })();
        if made.is_err() {
            let _ = self.db.execute_batch("ROLLBACK");
        }
        made.map_err(sqlite)?;
        self.check_columns()
    }

    fn check_columns(&self) -> Result<(), HistoryError> {
        let unusable = HistoryError::unusable(&self.path);
        let mut statement = self
            .db
            .prepare("SELECT name FROM pragma_table_info('attempts')")
            .map_err(|e| unusable(e.to_string()))?;
        let columns: Vec<String> = statement
            .query_map([], |r| r.get(0))
            .and_then(Iterator::collect)
            .map_err(|e| unusable(e.to_string()))?;
        if columns != COLUMNS {
            return Err(unusable(format!(
                "its attempts table has the columns [{}]",
                columns.join(", ")
            )));
        }
        Ok(())
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Stores one attempt; returns its number.
    pub fn add(
        &self,
        trainee: &str,
        scene: &str,
        model_sha256: &str,
        device: &str,
        score: &Score,
    ) -> Result<i64, HistoryError> {
        self.db
            .execute(
                "INSERT INTO attempts (trainee, scene, model_sha256, device, passed, verdict, target,
                    layers_given, target_depth_m, overshoot_m, allowed_overshoot_m, peak_force_n,
                    time_to_target_s, withdrawals, reinsertions, smoothness_sparc, deepest_m)
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17)",
                params![
                    trainee,
                    scene,
                    model_sha256,
                    device,
                    score.passed,
                    score.verdict,
                    score.target,
                    score.layers_given.join(","),
                    score.target_depth_m,
                    score.overshoot_m,
                    score.allowed_overshoot_m,
                    score.peak_force_n,
                    score.time_to_target_s,
                    score.withdrawals,
                    score.reinsertions,
                    score.smoothness_sparc,
                    score.deepest_m,
                ],
            )
            .map_err(HistoryError::sqlite(&self.path))?;
        Ok(self.db.last_insert_rowid())
    }

    /// The attempts of `trainee` and `scene` (each when given), oldest first.
    pub fn attempts(&self, trainee: Option<&str>, scene: Option<&str>) -> Result<Vec<Attempt>, HistoryError> {
        let sqlite = HistoryError::sqlite(&self.path);
        let mut statement = self
            .db
            .prepare(
                "SELECT id, at, trainee, scene, model_sha256, device, passed, verdict, target,
                    layers_given, target_depth_m, overshoot_m, allowed_overshoot_m, peak_force_n,
                    time_to_target_s, withdrawals, reinsertions, smoothness_sparc, deepest_m
                 FROM attempts WHERE (?1 IS NULL OR trainee = ?1) AND (?2 IS NULL OR scene = ?2)
                 ORDER BY id",
            )
            .map_err(sqlite)?;
        let rows = statement
            .query_map(params![trainee, scene], |r| {
                let layers: String = r.get(9)?;
                Ok(Attempt {
                    id: r.get(0)?,
                    at: r.get(1)?,
                    trainee: r.get(2)?,
                    scene: r.get(3)?,
                    model_sha256: r.get(4)?,
                    device: r.get(5)?,
                    score: Score {
                        passed: r.get(6)?,
                        verdict: r.get(7)?,
                        target: r.get(8)?,
                        layers_given: layers
                            .split(',')
                            .filter(|l| !l.is_empty())
                            .map(str::to_owned)
                            .collect(),
                        target_depth_m: r.get(10)?,
                        overshoot_m: r.get(11)?,
                        allowed_overshoot_m: r.get(12)?,
                        peak_force_n: r.get(13)?,
                        time_to_target_s: r.get(14)?,
                        withdrawals: r.get(15)?,
                        reinsertions: r.get(16)?,
                        smoothness_sparc: r.get(17)?,
                        deepest_m: r.get(18)?,
                    },
                })
            })
            .map_err(sqlite)?;
        rows.collect::<Result<Vec<_>, _>>().map_err(sqlite)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn score(passed: bool, overshoot_mm: f64) -> Score {
        Score {
            passed,
            verdict: if passed {
                "stopped".into()
            } else {
                "went past".into()
            },
            target: "vessel_wall".into(),
            layers_given: vec!["capsule".into(), "vessel_wall".into()],
            target_depth_m: Some(0.0232),
            overshoot_m: Some(overshoot_mm * 1e-3),
            allowed_overshoot_m: 0.003,
            peak_force_n: 1.57,
            time_to_target_s: Some(2.58),
            withdrawals: 1,
            reinsertions: 1,
            smoothness_sparc: None,
            deepest_m: 0.0286,
        }
    }

    #[test]
    fn attempts_round_trip_and_filter() {
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("sub").join("history.sqlite");
        let h = History::open_or_create(&path).expect("new");
        assert_eq!(
            h.add("ana", "needle_liver", "ab", "sim", &score(false, 5.4))
                .expect("add"),
            1
        );
        assert_eq!(
            h.add("ben", "needle_liver", "ab", "sim", &score(true, 1.4))
                .expect("add"),
            2
        );
        assert_eq!(
            h.add("ana", "epidural", "cd", "sim", &score(true, 2.0))
                .expect("add"),
            3
        );
        drop(h);
        let h = History::open(&path).expect("existing");
        let all = h.attempts(None, None).expect("all");
        assert_eq!(all.len(), 3);
        assert_eq!(all[0].score, score(false, 5.4));
        assert!(all[0].at.ends_with('Z') && all[0].at.len() == 24, "{}", all[0].at);
        let ana: Vec<i64> = h
            .attempts(Some("ana"), None)
            .expect("ana")
            .iter()
            .map(|a| a.id)
            .collect();
        assert_eq!(ana, [1, 3]);
        assert_eq!(h.attempts(Some("ana"), Some("epidural")).expect("one").len(), 1);
        assert!(h.attempts(Some("carl"), None).expect("none").is_empty());
    }

    #[test]
    fn a_file_that_is_not_a_history_is_reported_and_left_as_it_is() {
        let dir = tempfile::tempdir().expect("dir");
        let text = dir.path().join("notes.sqlite");
        std::fs::write(&text, "a trainee's notes, not a database\n".repeat(200)).expect("write");
        let before = std::fs::read(&text).expect("read");
        for open in [History::open_or_create, History::open] {
            let err = open(&text).expect_err("not a database");
            assert!(matches!(err, HistoryError::Unusable { .. }), "{err}");
            assert!(err.to_string().contains("notes.sqlite"), "{err}");
        }
        assert_eq!(std::fs::read(&text).expect("read"), before);

        // Another application's database.
        let other = dir.path().join("other.sqlite");
        Connection::open(&other)
            .and_then(|c| c.execute_batch("CREATE TABLE t (x INTEGER); INSERT INTO t VALUES (1)"))
            .expect("other");
        let before = std::fs::read(&other).expect("read");
        let err = History::open_or_create(&other).expect_err("someone else's");
        assert!(err.to_string().contains("something else"), "{err}");
        assert_eq!(std::fs::read(&other).expect("read"), before);

        // A history with a damaged page: the integrity check finds it.
        let damaged = dir.path().join("damaged.sqlite");
        let h = History::open_or_create(&damaged).expect("new");
        for k in 0..200 {
            h.add(
                "ana",
                "needle_liver",
                &"x".repeat(200),
                "sim",
                &score(k % 2 == 0, 1.0),
            )
            .expect("add");
        }
        drop(h);
        let mut bytes = std::fs::read(&damaged).expect("read");
        assert!(bytes.len() > 8192);
        // The second page is the root of the table's b-tree: scribble over its header.
        for b in &mut bytes[4096..4096 + 800] {
            *b = 0xA5;
        }
        std::fs::write(&damaged, &bytes).expect("write");
        let err = History::open_or_create(&damaged).expect_err("damaged");
        assert!(matches!(err, HistoryError::Unusable { .. }), "{err}");
        assert_eq!(std::fs::read(&damaged).expect("read"), bytes);

        let err = History::open(&dir.path().join("none.sqlite")).expect_err("missing");
        assert!(matches!(err, HistoryError::Missing { .. }), "{err}");
    }

    #[test]
    fn concurrent_writers_lose_nothing() {
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("history.sqlite");
        let threads: Vec<_> = (0..4)
            .map(|t| {
                let path = path.clone();
                std::thread::spawn(move || {
                    for k in 0..25 {
                        let h = History::open_or_create(&path).expect("open");
                        h.add(
                            &format!("t{t}"),
                            "needle_liver",
                            "ab",
                            "sim",
                            &score(k % 3 == 0, 1.0),
                        )
                        .expect("add");
                    }
                })
            })
            .collect();
        for t in threads {
            t.join().expect("writer");
        }
        let all = History::open(&path)
            .expect("open")
            .attempts(None, None)
            .expect("all");
        assert_eq!(all.len(), 100);
        let ids: Vec<i64> = all.iter().map(|a| a.id).collect();
        assert_eq!(ids, (1..=100).collect::<Vec<_>>());
    }
}
