//! A deterministic mutation soak of every parser of user files: captures, imported logs, model
//! files, scenes and recognizer files.
//!
//! Each parser must, on any bytes, return (never panic, never hang, never grow without bound)
//! and fail with a message that names the file it was given. Valid inputs are built here, then
//! mutated by the project's seeded generator (`capture::rng`): byte flips, inserts and deletes,
//! lines duplicated, dropped, swapped or cut, numbers replaced by extremes (0, -0, ±1e308,
//! 1e-308, NaN, inf, 2³²−1, -1, long digit strings), BOM, CRLF and NUL, and fields removed or
//! swapped (structurally for JSON, by `key = value` lines for TOML, by cells for CSV). A
//! mutant is a pure function of its target and index, so a failure names a seed that
//! reproduces it, and the mutant is also written to a file.
//!
//! `PALPUS_FUZZ_INPUTS` sets the mutants per target (default [`DEFAULT_INPUTS`], the short pass
//! run with every `cargo test`). The long soak:
//!
//! ```text
//! PALPUS_FUZZ_INPUTS=1000000 cargo test --release --locked --test it fuzz_parsers:: -- --nocapture --test-threads 1
//! ```
//!
//! A failing mutant is written under the temp dir (`palpus-fuzz/TARGET-SEED.bin`);
//! `PALPUS_FUZZ_REPLAY=` that file parses it alone again and prints what happened.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.
#![allow(clippy::print_stdout)] // The per-target summary is this test's report.

use std::cell::Cell;
use std::fmt::Write as _;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, Once};
use std::time::{Duration, Instant};

use capture::rng::{SplitMix64, derive_seed};
use capture::{Capture, CaptureKind, Metadata};
use capture::{ColumnMap, ImportSpec, import_csv};
use identify::{IdentifyOptions, ModelFile, ModelKind};
use palpus::scene::Scene;
use recognize::{FeatureSet, LabelledCapture, Method, RecognizerFile, TrainSettings};
use serde_json::Value;

/// Mutants per target in an ordinary `cargo test` (all five stay well under 20 s in a debug
/// build on two cores).
const DEFAULT_INPUTS: usize = 3000;

/// Base of every mutant's seed; the target's tag and the mutant's index are mixed in.
const SOAK_SEED: u64 = 0x5eed_f022_0000_0001;

/// One input taking longer than this is a hang: the watchdog writes it out and aborts.
const HANG_LIMIT: Duration = Duration::from_secs(60);

/// Resident memory the whole test process may reach, kB (1 GiB): the seeds are a few kB and
/// the largest accepted output (an import at its row cap) is far below it, so an input that
/// crosses it made a parser allocate from a number in the file.
const MAX_RSS_KB: u64 = 1 << 20;

fn manifest_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn inputs_per_target() -> usize {
    match std::env::var("PALPUS_FUZZ_INPUTS") {
        Ok(v) => v
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("PALPUS_FUZZ_INPUTS=`{v}` is not a count")),
        Err(_) => DEFAULT_INPUTS,
    }
}

// --- Panics and hangs -------------------------------------------------------------------

/// The last panic's message, location and stack, kept by the hook for the failure report
/// (the default hook would print it once per panic, with no seed).
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

thread_local! {
    /// Whether this thread is inside a parser: its panics are kept for the report; the
    /// test's own (a failed assertion) go to the default hook.
    static IN_PARSER: Cell<bool> = const { Cell::new(false) };
}

fn install_panic_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let default = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if IN_PARSER.with(Cell::get) {
                let report = format!("{info}\nstack:\n{}", std::backtrace::Backtrace::force_capture());
                *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(report);
            } else {
                default(info);
            }
        }));
    });
}

/// Runs `f` as a parse: a panic in it is caught, and its report kept.
fn guarded<T>(f: impl FnOnce() -> T) -> std::thread::Result<T> {
    IN_PARSER.with(|p| p.set(true));
    let outcome = panic::catch_unwind(AssertUnwindSafe(f));
    IN_PARSER.with(|p| p.set(false));
    outcome
}

/// Where failing mutants are written.
fn crash_dir() -> PathBuf {
    let dir = std::env::temp_dir().join("palpus-fuzz");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn save_mutant(target: &str, seed: u64, bytes: &[u8]) -> PathBuf {
    let path = crash_dir().join(format!("{target}-{seed:016x}.bin"));
    std::fs::write(&path, bytes).unwrap();
    path
}

/// The input being parsed, for the watchdog.
struct Current {
    seed: u64,
    bytes: Vec<u8>,
    started: Instant,
}

/// Aborts the process, after writing the input out, if one input runs past [`HANG_LIMIT`] or
/// the process past [`MAX_RSS_KB`]: an endless loop cannot be unwound, a test that never ends
/// reports nothing, and one killed for memory names no input.
struct Watchdog {
    current: Arc<Mutex<Current>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Watchdog {
    fn start(target: &'static str) -> Self {
        let current = Arc::new(Mutex::new(Current {
            seed: 0,
            bytes: Vec::new(),
            started: Instant::now(),
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (c, s) = (Arc::clone(&current), Arc::clone(&stop));
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(200));
                let cur = c.lock().unwrap_or_else(|e| e.into_inner());
                let rss = rss_kb().unwrap_or(0);
                let why = if cur.started.elapsed() > HANG_LIMIT {
                    format!("still running after {HANG_LIMIT:?}")
                } else if rss > 4 * MAX_RSS_KB {
                    // Freed memory may stay resident, so this names the input running when
                    // the process grew too large, which may not be the one that grew it; the
                    // check after each input names that one, unless the process dies first.
                    format!("runs with {rss} kB resident, or follows the input that grew it")
                } else {
                    continue;
                };
                let file = save_mutant(target, cur.seed, &cur.bytes);
                eprintln!(
                    "{target}: mutant seed {:#018x} {why}; input written to {}",
                    cur.seed,
                    file.display()
                );
                std::process::abort();
            }
        });
        Self {
            current,
            stop,
            thread: Some(thread),
        }
    }

    fn begin(&self, seed: u64, bytes: &[u8]) {
        let mut cur = self.current.lock().unwrap_or_else(|e| e.into_inner());
        cur.seed = seed;
        cur.bytes.clear();
        cur.bytes.extend_from_slice(bytes);
        cur.started = Instant::now();
    }

    fn end(&self) {
        // Time spent making the next mutant is not the parser's.
        self.current.lock().unwrap_or_else(|e| e.into_inner()).started = Instant::now();
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// VmHWM (peak resident memory) of this process, kB (Linux; `None` elsewhere).
fn peak_rss_kb() -> Option<u64> {
    proc_status_kb("VmHWM:")
}

/// VmRSS (resident memory now) of this process, kB (Linux; `None` elsewhere).
fn rss_kb() -> Option<u64> {
    proc_status_kb("VmRSS:")
}

fn proc_status_kb(field: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(field))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

// --- Mutation ---------------------------------------------------------------------------

#[derive(Debug, Clone, Copy, PartialEq)]
enum Syntax {
    Csv,
    Json,
    Toml,
}

/// Largest mutant the growing edits (line duplication, runs) make, bytes: large inputs are
/// tested, while the memory a parse takes stays the parser's, not the input's.
const MAX_MUTANT_BYTES: usize = 1 << 20;

/// Replacements for a number: extremes of f64 and of the integer types, spellings of
/// non-finite values, and things that only look like numbers.
const EXTREMES: &[&str] = &[
    "0",
    "-0",
    "0.0",
    "-0.0",
    "1e308",
    "-1e308",
    "1e-308",
    "-1e-308",
    "5e-324",
    "1.7976931348623157e308",
    "1e309",
    "-1e309",
    "NaN",
    "nan",
    "-NaN",
    "inf",
    "-inf",
    "+inf",
    "Infinity",
    "-Infinity",
    "4294967295",
    "4294967296",
    "-1",
    "-2147483649",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775809",
    "1e",
    "e5",
    ".",
    "-",
    "0x10",
    "1_000",
    "1,5",
    "",
];

/// Bytes worth inserting: the separators and brackets of the three syntaxes, line ends, BOM,
/// NUL and invalid UTF-8.
const INSERTS: &[&[u8]] = &[
    b",",
    b";",
    b"\t",
    b"\n",
    b"\r\n",
    b"\r",
    b"\"",
    b"'",
    b"{",
    b"}",
    b"[",
    b"]",
    b"[[",
    b"=",
    b"#",
    b":",
    b" ",
    b"\0",
    b"\\",
    b"\xEF\xBB\xBF",
    b"\xFF",
    b"\xC3",
    b"\xE2\x80\xA8",
    b"-",
    b"e",
    b".",
    b"# palpus-capture format=1",
    b"=\"\"",
    b"\"\\u0000\"",
];

struct Mutator<'a> {
    rng: SplitMix64,
    syntax: Syntax,
    seeds: &'a [Seed],
}

/// A valid input and, for JSON, its tree and the paths of its nodes.
struct Seed {
    bytes: Vec<u8>,
    json: Option<(Value, Vec<String>)>,
}

impl Seed {
    fn new(bytes: Vec<u8>, syntax: Syntax) -> Self {
        let json = (syntax == Syntax::Json).then(|| {
            let value: Value = serde_json::from_slice(&bytes).unwrap();
            let mut pointers = Vec::new();
            collect_pointers(&value, &mut String::new(), &mut pointers);
            (value, pointers)
        });
        Self { bytes, json }
    }
}

/// JSON pointers of every node below the root.
fn collect_pointers(value: &Value, prefix: &mut String, out: &mut Vec<String>) {
    let len = prefix.len();
    match value {
        Value::Object(map) => {
            for (key, child) in map {
                prefix.push('/');
                prefix.push_str(&key.replace('~', "~0").replace('/', "~1"));
                out.push(prefix.clone());
                collect_pointers(child, prefix, out);
                prefix.truncate(len);
            }
        }
        Value::Array(items) => {
            for (i, child) in items.iter().enumerate() {
                let _ = write!(prefix, "/{i}");
                out.push(prefix.clone());
                collect_pointers(child, prefix, out);
                prefix.truncate(len);
            }
        }
        _ => {}
    }
}

fn parent_and_last(pointer: &str) -> (&str, String) {
    let cut = pointer.rfind('/').unwrap_or(0);
    let last = pointer[cut + 1..].replace("~1", "/").replace("~0", "~");
    (&pointer[..cut], last)
}

impl Mutator<'_> {
    fn below(&mut self, n: usize) -> usize {
        self.rng.below(n)
    }

    fn chance(&mut self, one_in: usize) -> bool {
        self.rng.below(one_in) == 0
    }

    /// A mutant and the index of the seed it started from.
    fn mutant(&mut self) -> (usize, Vec<u8>) {
        let of = self.below(self.seeds.len());
        let seed = &self.seeds[of];
        let mut bytes = match &seed.json {
            Some((value, pointers)) if self.chance(2) => self.mutate_json(value, pointers),
            _ => seed.bytes.clone(),
        };
        if self.chance(32) {
            // Splice: the head of this seed with the tail of another.
            let other = &self.seeds[self.below(self.seeds.len())].bytes;
            let cut = self.below(bytes.len() + 1);
            let from = self.below(other.len() + 1);
            bytes.truncate(cut);
            bytes.extend_from_slice(&other[from..]);
        }
        let ops = 1 + self.below(4);
        for _ in 0..ops {
            self.mutate_text(&mut bytes);
        }
        (of, bytes)
    }

    /// Structural JSON edits: remove a member or element, swap two values, put an extreme
    /// number or a value of another type in.
    fn mutate_json(&mut self, seed: &Value, pointers: &[String]) -> Vec<u8> {
        let mut value = seed.clone();
        let edits = 1 + self.below(3);
        for _ in 0..edits {
            if pointers.is_empty() {
                break;
            }
            let p = &pointers[self.below(pointers.len())];
            match self.below(4) {
                0 => {
                    let (parent, last) = parent_and_last(p);
                    match value.pointer_mut(parent) {
                        Some(Value::Object(map)) => {
                            map.remove(&last);
                        }
                        Some(Value::Array(items)) => {
                            if let Ok(i) = last.parse::<usize>()
                                && i < items.len()
                            {
                                items.remove(i);
                            }
                        }
                        _ => {}
                    }
                }
                1 => {
                    let q = &pointers[self.below(pointers.len())];
                    let nested = p.starts_with(q.as_str()) || q.starts_with(p.as_str());
                    if !nested
                        && let (Some(a), Some(b)) = (value.pointer(p).cloned(), value.pointer(q).cloned())
                    {
                        if let Some(slot) = value.pointer_mut(p) {
                            *slot = b;
                        }
                        if let Some(slot) = value.pointer_mut(q) {
                            *slot = a;
                        }
                    }
                }
                2 => {
                    let replacement = self.extreme_json();
                    if let Some(slot) = value.pointer_mut(p) {
                        *slot = replacement;
                    }
                }
                _ => {
                    let replacement = match self.below(8) {
                        0 => Value::Null,
                        1 => Value::Bool(true),
                        2 => Value::String(String::new()),
                        3 => Value::String("x".repeat(1 + self.below(300))),
                        4 => Value::Array(Vec::new()),
                        5 => Value::Object(serde_json::Map::new()),
                        6 => Value::Array(vec![Value::from(1e308); 1 + self.below(64)]),
                        _ => Value::from(-1),
                    };
                    if let Some(slot) = value.pointer_mut(p) {
                        *slot = replacement;
                    }
                }
            }
        }
        if self.chance(2) {
            serde_json::to_vec_pretty(&value).unwrap()
        } else {
            serde_json::to_vec(&value).unwrap()
        }
    }

    fn extreme_json(&mut self) -> Value {
        match self.below(10) {
            0 => Value::from(0),
            1 => Value::from(-0.0),
            2 => Value::from(1e308),
            3 => Value::from(-1e308),
            4 => Value::from(1e-308),
            5 => Value::from(u32::MAX),
            6 => Value::from(-1),
            7 => Value::from(u64::MAX),
            8 => Value::from(i64::MIN),
            _ => Value::from(5e-324),
        }
    }

    fn number_text(&mut self) -> String {
        if self.chance(6) {
            let digits = 1 + self.below(2000);
            let mut s = String::with_capacity(digits + 3);
            if self.chance(2) {
                s.push('-');
            }
            if self.chance(3) {
                s.push_str("0.");
            }
            s.extend((0..digits).map(|_| '9'));
            if self.chance(3) {
                s.push_str("e-400");
            }
            s
        } else {
            EXTREMES[self.below(EXTREMES.len())].to_owned()
        }
    }

    fn mutate_text(&mut self, b: &mut Vec<u8>) {
        match self.below(14) {
            0 => {
                if !b.is_empty() {
                    let i = self.below(b.len());
                    b[i] ^= 1 << self.below(8);
                }
            }
            1 => {
                if !b.is_empty() {
                    let i = self.below(b.len());
                    b[i] = self.rng.next_u64() as u8;
                }
            }
            2 => {
                let at = self.below(b.len() + 1);
                if self.chance(4) {
                    let byte = self.rng.next_u64() as u8;
                    b.insert(at, byte);
                } else {
                    let ins = INSERTS[self.below(INSERTS.len())];
                    b.splice(at..at, ins.iter().copied());
                }
            }
            3 => {
                if !b.is_empty() {
                    let at = self.below(b.len());
                    let len = (1 + self.below(16)).min(b.len() - at);
                    b.drain(at..at + len);
                }
            }
            4 => {
                let lines = split_lines(b);
                let i = self.below(lines.len());
                let line = lines[i].to_vec();
                let times = if self.chance(16) { 1 + self.below(2000) } else { 1 };
                // Bounded, or a one-line (compact JSON) file grows by 2000× per op.
                let times = times.min(MAX_MUTANT_BYTES.saturating_sub(b.len()) / line.len().max(1));
                let mut out = Vec::with_capacity(b.len() + line.len() * times);
                for (k, l) in lines.iter().enumerate() {
                    out.extend_from_slice(l);
                    if k == i {
                        for _ in 0..times {
                            out.extend_from_slice(&line);
                        }
                    }
                }
                *b = out;
            }
            5 => {
                let lines = split_lines(b);
                let i = self.below(lines.len());
                *b = lines
                    .iter()
                    .enumerate()
                    .filter(|&(k, _)| k != i)
                    .flat_map(|(_, l)| l.iter().copied())
                    .collect();
            }
            6 => {
                let at = self.below(b.len() + 1);
                b.truncate(at);
            }
            7 => self.replace_number(b),
            8 => match self.below(3) {
                0 => {
                    b.splice(0..0, *b"\xEF\xBB\xBF");
                }
                1 => {
                    let mut out = Vec::with_capacity(b.len() * 2);
                    for &c in b.iter() {
                        if c == b'\n' {
                            out.push(b'\r');
                        }
                        out.push(c);
                    }
                    *b = out;
                }
                _ => {
                    let at = self.below(b.len() + 1);
                    b.insert(at, 0);
                }
            },
            9 => {
                let mut lines: Vec<Vec<u8>> = split_lines(b).iter().map(|l| l.to_vec()).collect();
                let (i, j) = (self.below(lines.len()), self.below(lines.len()));
                lines.swap(i, j);
                *b = lines.concat();
            }
            10 => self.delete_field(b),
            11 => self.swap_fields(b),
            12 => {
                let at = self.below(b.len() + 1);
                let unit: &[u8] = match self.below(4) {
                    0 => b"9",
                    1 => b",",
                    2 => b"[",
                    _ => b"a",
                };
                let run = unit.repeat((1 + self.below(4096)).min(MAX_MUTANT_BYTES.saturating_sub(b.len())));
                b.splice(at..at, run);
            }
            _ => self.replace_number(b),
        }
    }

    /// Replaces one numeric token (a digit, or a sign or point before one, and what follows
    /// of digits, points, exponents and signs).
    fn replace_number(&mut self, b: &mut Vec<u8>) {
        let spans = number_spans(b);
        if spans.is_empty() {
            return;
        }
        let (start, end) = spans[self.below(spans.len())];
        let text = self.number_text();
        b.splice(start..end, text.into_bytes());
    }

    /// Removes one field: a CSV cell, a TOML `key = value` line, or (JSON, as text) a line.
    fn delete_field(&mut self, b: &mut Vec<u8>) {
        let mut lines: Vec<Vec<u8>> = split_lines(b).iter().map(|l| l.to_vec()).collect();
        let i = self.below(lines.len());
        match self.syntax {
            Syntax::Csv => {
                let (cells, sep) = split_cells(&lines[i]);
                if cells.len() > 1 {
                    let k = self.below(cells.len());
                    let kept: Vec<&[u8]> = cells
                        .iter()
                        .enumerate()
                        .filter(|&(j, _)| j != k)
                        .map(|(_, c)| *c)
                        .collect();
                    lines[i] = join_cells(&kept, sep, ends_line(&lines[i]));
                }
            }
            Syntax::Toml => {
                let keys: Vec<usize> = (0..lines.len())
                    .filter(|&k| assignment(&lines[k]).is_some())
                    .collect();
                if !keys.is_empty() {
                    lines.remove(keys[self.below(keys.len())]);
                }
            }
            Syntax::Json => {
                lines.remove(i);
            }
        }
        *b = lines.concat();
    }

    /// Swaps two fields: two cells of a CSV line, or the values of two TOML or JSON
    /// `key = value` / `"key": value` lines.
    fn swap_fields(&mut self, b: &mut Vec<u8>) {
        let mut lines: Vec<Vec<u8>> = split_lines(b).iter().map(|l| l.to_vec()).collect();
        match self.syntax {
            Syntax::Csv => {
                let i = self.below(lines.len());
                let (cells, sep) = split_cells(&lines[i]);
                if cells.len() > 1 {
                    let mut cells: Vec<&[u8]> = cells;
                    let (x, y) = (self.below(cells.len()), self.below(cells.len()));
                    cells.swap(x, y);
                    let joined = join_cells(&cells, sep, ends_line(&lines[i]));
                    lines[i] = joined;
                }
            }
            Syntax::Toml | Syntax::Json => {
                let keys: Vec<(usize, usize)> = (0..lines.len())
                    .filter_map(|k| assignment(&lines[k]).map(|at| (k, at)))
                    .collect();
                if keys.len() > 1 {
                    let (i, at_i) = keys[self.below(keys.len())];
                    let (j, at_j) = keys[self.below(keys.len())];
                    let value_i = lines[i][at_i..].to_vec();
                    let value_j = lines[j][at_j..].to_vec();
                    lines[i].truncate(at_i);
                    lines[i].extend_from_slice(&value_j);
                    lines[j].truncate(at_j);
                    lines[j].extend_from_slice(&value_i);
                }
            }
        }
        *b = lines.concat();
    }
}

/// Lines with their line ends; at least one (possibly empty).
fn split_lines(b: &[u8]) -> Vec<&[u8]> {
    let mut lines: Vec<&[u8]> = b.split_inclusive(|&c| c == b'\n').collect();
    if lines.is_empty() {
        lines.push(&[]);
    }
    lines
}

fn ends_line(line: &[u8]) -> bool {
    line.last() == Some(&b'\n')
}

/// A line's cells by its most frequent separator, without the line end.
fn split_cells(line: &[u8]) -> (Vec<&[u8]>, u8) {
    let body = line.strip_suffix(b"\n").unwrap_or(line);
    let sep = [b',', b';', b'\t', b' ']
        .into_iter()
        .max_by_key(|&s| body.iter().filter(|&&c| c == s).count())
        .unwrap_or(b',');
    (body.split(|&c| c == sep).collect(), sep)
}

fn join_cells(cells: &[&[u8]], sep: u8, newline: bool) -> Vec<u8> {
    let mut out = cells.join(&sep);
    if newline {
        out.push(b'\n');
    }
    out
}

/// Where the value starts on a `key = value` (TOML) or `"key": value` (JSON) line.
fn assignment(line: &[u8]) -> Option<usize> {
    let first = line.iter().position(|c| !c.is_ascii_whitespace())?;
    if matches!(line[first], b'#' | b'[' | b'{' | b'}' | b']') {
        return None;
    }
    let at = line.iter().position(|&c| c == b'=' || c == b':')?;
    Some(at + 1)
}

/// Byte ranges of the numeric tokens.
fn number_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            || (matches!(b[i], b'-' | b'+' | b'.') && b.get(i + 1).is_some_and(u8::is_ascii_digit));
        if starts && (i == 0 || !b[i - 1].is_ascii_alphanumeric() && b[i - 1] != b'_') {
            let start = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_digit() || matches!(b[i], b'.' | b'e' | b'E' | b'-' | b'+')) {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// `PALPUS_FUZZ_REPLAY=FILE`, when FILE is a mutant written for `target` (`TARGET-SEED.bin`):
/// that one input is parsed instead of the soak, and what it did is printed.
fn replay_file(target: &str) -> Option<PathBuf> {
    let file = PathBuf::from(std::env::var_os("PALPUS_FUZZ_REPLAY")?);
    let name = file.file_name()?.to_str()?;
    name.starts_with(&format!("{target}-")).then_some(file)
}

// --- The soak ---------------------------------------------------------------------------

/// What a parse call is given, besides the bytes: a seed (checked as is) or a mutant (of
/// which seed, and its own seed, from which a target may derive the options it parses with).
#[derive(Debug, Clone, Copy)]
enum Input {
    Seed(usize),
    Mutant { of: usize, seed: u64 },
}

#[derive(Debug, Default)]
struct Tally {
    inputs: usize,
    errors: usize,
    accepted: usize,
    slowest: Duration,
    slowest_seed: u64,
}

/// Parses `inputs_per_target()` mutants of `seeds` with `parse`, failing on the first panic or
/// the first error whose message is empty or does not name `file`.
fn soak(
    target: &'static str,
    tag: u64,
    syntax: Syntax,
    seeds: &[Vec<u8>],
    file: &Path,
    mut parse: impl FnMut(&[u8], Input) -> Result<(), String>,
) -> Tally {
    install_panic_hook();
    let seeds: Vec<Seed> = seeds.iter().map(|s| Seed::new(s.clone(), syntax)).collect();
    let file_name = file.display().to_string();
    let n = inputs_per_target();
    if let Some(replay) = replay_file(target) {
        let bytes = std::fs::read(&replay).unwrap();
        let outcome = guarded(|| parse(&bytes, Input::Mutant { of: 0, seed: 0 }));
        let report = LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()).take();
        println!(
            "replay {target} {}: {:?}; panic: {}; peak_rss_kb {:?}",
            replay.display(),
            outcome.as_ref().map(|r| r.as_ref().err()),
            report.as_deref().unwrap_or("none"),
            peak_rss_kb()
        );
        return Tally::default();
    }
    let watchdog = Watchdog::start(target);
    let mut tally = Tally::default();
    let started = Instant::now();

    // The seeds themselves first: each must be accepted, or the soak mutates nothing valid.
    for (k, seed) in seeds.iter().enumerate() {
        if let Err(message) = parse(&seed.bytes, Input::Seed(k)) {
            panic!("{target}: seed {k} is refused: {message}");
        }
    }

    for i in 0..n {
        let seed = derive_seed(SOAK_SEED, &[tag, i as u64]);
        let mut mutator = Mutator {
            rng: SplitMix64::new(seed),
            syntax,
            seeds: &seeds,
        };
        let (of, bytes) = mutator.mutant();
        watchdog.begin(seed, &bytes);
        let t0 = Instant::now();
        let outcome = guarded(|| parse(&bytes, Input::Mutant { of, seed }));
        let took = t0.elapsed();
        watchdog.end();
        tally.inputs += 1;
        // Peak memory is a high-water mark, so the first input past the limit is the one that
        // took it there (with one test thread; with several, one of those running).
        if let Some(kb) = peak_rss_kb()
            && kb > MAX_RSS_KB
        {
            let saved = save_mutant(target, seed, &bytes);
            panic!(
                "{target}: mutant {i} (seed {seed:#018x}, written to {}) took the peak resident \
                 memory to {kb} kB (limit {MAX_RSS_KB} kB)",
                saved.display()
            );
        }
        if took > tally.slowest {
            tally.slowest = took;
            tally.slowest_seed = seed;
        }
        match outcome {
            Ok(Ok(())) => tally.accepted += 1,
            Ok(Err(message)) => {
                tally.errors += 1;
                if message.trim().is_empty() || !message.contains(&file_name) {
                    let saved = save_mutant(target, seed, &bytes);
                    panic!(
                        "{target}: mutant {i} (seed {seed:#018x}, written to {}): the error does not \
                         name `{file_name}`: {message:?}",
                        saved.display()
                    );
                }
            }
            Err(_) => {
                let saved = save_mutant(target, seed, &bytes);
                let report = LAST_PANIC
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .take()
                    .unwrap_or_default();
                panic!(
                    "{target}: mutant {i} (seed {seed:#018x}, written to {}) panicked: {report}",
                    saved.display()
                );
            }
        }
    }
    drop(watchdog);

    let peak = peak_rss_kb();
    println!(
        "fuzz {target}: inputs {} errors {} accepted {} panics 0 peak_rss_kb {} wall {:.1}s \
         ({:.0}/s), slowest {:.1} ms (seed {:#018x})",
        tally.inputs,
        tally.errors,
        tally.accepted,
        peak.map_or_else(|| "n/a".to_owned(), |kb| kb.to_string()),
        started.elapsed().as_secs_f64(),
        tally.inputs as f64 / started.elapsed().as_secs_f64().max(1e-9),
        tally.slowest.as_secs_f64() * 1e3,
        tally.slowest_seed,
    );
    tally
}

fn message(e: impl std::fmt::Display) -> String {
    e.to_string()
}

// --- Seeds ------------------------------------------------------------------------------

fn li_bi(name: &str) -> PathBuf {
    manifest_dir().join("assets/captures/li_bi").join(name)
}

/// A rubbing capture with every optional column a recognizer reads, on a surface whose
/// roughness and friction depend on `class`.
fn rubbing_capture(class: usize, trial: u64, rows: usize, rate_hz: f64) -> Capture {
    let meta = Metadata::new(CaptureKind::Rubbing, "sim-fuzz", rate_hz)
        .with("surface", format!("surface_{class}"))
        .with("trial", trial)
        .with("seed", trial);
    let columns = [
        "time_s",
        "tangential_position_m",
        "tangential_velocity_mps",
        "normal_position_m",
        "normal_force_n",
        "friction_force_n",
    ];
    let mut rng = SplitMix64::new(derive_seed(17, &[class as u64, trial]));
    let mut data = vec![Vec::with_capacity(rows); columns.len()];
    let roughness = 1e-5 * (1.0 + class as f64);
    let mu = 0.3 + 0.2 * class as f64;
    for i in 0..rows {
        let t = i as f64 / rate_hz;
        let x = 0.02 * (0.5 * t).sin();
        let force = 1.0 + 0.2 * (0.3 * t).cos() + 0.01 * rng.next_f64();
        let row = [
            t,
            x,
            0.01 * (0.5 * t).cos(),
            roughness * (rng.next_f64() - 0.5) + 1e-4 * (x * 300.0).sin(),
            force,
            mu * force + 0.02 * (rng.next_f64() - 0.5),
        ];
        for (column, v) in data.iter_mut().zip(row) {
            column.push(v);
        }
    }
    Capture::new(meta, columns.iter().map(|&c| c.to_owned()).collect(), data).unwrap()
}

fn insertion_capture(rows: usize) -> Capture {
    let meta = Metadata::new(CaptureKind::Insertion, "sim-fuzz", 1000.0).with("tissue", "liver");
    let columns = ["time_s", "depth_m", "axial_force_n", "velocity_mps"];
    let mut data = vec![Vec::with_capacity(rows); columns.len()];
    for i in 0..rows {
        let t = i as f64 / 1000.0;
        let depth = 0.005 * t;
        for (column, v) in data
            .iter_mut()
            .zip([t, depth, 50.0 * depth + 0.1 * depth.sqrt(), 0.005])
        {
            column.push(v);
        }
    }
    Capture::new(meta, columns.iter().map(|&c| c.to_owned()).collect(), data).unwrap()
}

fn capture_bytes(capture: &Capture) -> Vec<u8> {
    capture.write_to(Vec::new()).unwrap()
}

/// The first `lines` lines of a file.
fn head(path: &Path, lines: usize) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    split_lines(&bytes)[..lines].concat()
}

// --- Targets ----------------------------------------------------------------------------

#[test]
fn capture_reader_survives_mutants() {
    let seeds = vec![
        std::fs::read(li_bi("hard_contact_train.csv")).unwrap(),
        head(&li_bi("soft_contact_test.csv"), 40),
        capture_bytes(&rubbing_capture(0, 1, 60, 1000.0)),
        capture_bytes(&insertion_capture(40)),
    ];
    let file = Path::new("captures/fuzz/mutant.csv");
    soak("capture", 1, Syntax::Csv, &seeds, file, |bytes, input| {
        // Seeds are of both kinds, so they are read with no expected kind; mutants also with
        // each kind, which the reader checks against line 1.
        let expected = match input {
            Input::Seed(_) => None,
            Input::Mutant { seed, .. } => {
                [None, Some(CaptureKind::Rubbing), Some(CaptureKind::Insertion)][(seed % 3) as usize]
            }
        };
        Capture::read_from(bytes, file, expected)
            .map(|_| ())
            .map_err(message)
    });
}

#[test]
fn import_survives_mutants() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("log.csv");
    let mut comma = String::from("# rig log, forces in N\nt_ms,x_mm,Fn,Ff,temp\n");
    let mut semicolon = String::from("\"t\";\"x\";\"Fn\";\"Ff\"\n");
    let mut tab = String::from("x_um\tFn\tFf\n");
    let mut rng = SplitMix64::new(3);
    for i in 0..80 {
        let t = i as f64;
        let _ = writeln!(
            comma,
            "{t},{},{},{},21.5",
            (t * 0.05).sin(),
            0.3 + 0.01 * (t * 0.2).cos(),
            0.1 + 0.001 * t
        );
        // Jittered timestamps: interpolation (and, at a lower target rate, the low-pass).
        let jitter = 0.2 * (rng.next_f64() - 0.5);
        let _ = writeln!(semicolon, "{};{};{};{}", t + jitter, t * 1e-4, 0.3, 0.12);
        let _ = writeln!(tab, "{}\t{}\t{}", t * 10.0, 0.2 + 1e-3 * t, 0.05);
    }
    let seeds = vec![comma.into_bytes(), semicolon.into_bytes(), tab.into_bytes()];

    let kind = CaptureKind::Rubbing;
    let spec = |map: &str, rate: Option<f64>, input_rate: Option<f64>| {
        let mut s = ImportSpec::new(kind, ColumnMap::parse(map).unwrap());
        s.rate_hz = rate;
        s.input_rate_hz = input_rate;
        s.metadata.push(("surface".into(), "felt".into()));
        s
    };
    let specs = [
        spec(
            "time_s=t_ms[ms],tangential_position_m=x_mm[mm],normal_force_n=Fn,friction_force_n=Ff",
            None,
            None,
        ),
        spec(
            "time_s=t_ms[ms],tangential_position_m=x_mm[mm],normal_force_n=Fn,friction_force_n=Ff",
            Some(250.0),
            None,
        ),
        spec(
            "time_s=t[ms],tangential_position_m=x,normal_force_n=Fn,friction_force_n=Ff*-1",
            Some(1000.0),
            None,
        ),
        spec(
            "time_s=t[ms],tangential_position_m=x,normal_force_n=Fn",
            Some(3000.0),
            None,
        ),
        spec(
            "tangential_position_m=x_um[um],normal_force_n=Fn,friction_force_n=Ff",
            Some(100.0),
            Some(1000.0),
        ),
    ];
    // Each seed has the specs that fit its columns. A mutant is mostly imported with one of
    // its seed's, sometimes with any (which mostly refuses it on the map).
    let fits: [&[usize]; 3] = [&[0, 1], &[2, 3], &[4]];
    let tally = soak("import", 2, Syntax::Csv, &seeds, &file, |bytes, input| {
        std::fs::write(&file, bytes).map_err(message)?;
        let pick = match input {
            Input::Seed(k) => fits[k][0],
            Input::Mutant { seed, .. } if seed % 8 == 0 => (seed >> 3) as usize % specs.len(),
            Input::Mutant { of, seed } => fits[of][(seed >> 3) as usize % fits[of].len()],
        };
        import_csv(&file, &specs[pick]).map(|_| ()).map_err(message)
    });
    assert!(
        tally.inputs == 0 || tally.accepted > 0,
        "no mutant was imported: the soak only tested refusals"
    );
}

#[test]
fn model_files_survive_mutants() {
    let identified = |train: &str, kind: CaptureKind, model: ModelKind| {
        let capture = Capture::read_file(li_bi(train), kind).unwrap();
        let mut options = IdentifyOptions::new(model);
        options.max_samples = 60;
        options.max_fit_samples = 120;
        identify::identify(&capture, None, &options).unwrap().model
    };
    let models = [
        identified(
            "hard_contact_train.csv",
            CaptureKind::Rubbing,
            ModelKind::HardFriction,
        ),
        identified(
            "soft_contact_train.csv",
            CaptureKind::Rubbing,
            ModelKind::SoftFriction,
        ),
        identified(
            "needle_train.csv",
            CaptureKind::Insertion,
            ModelKind::NeedlePuncture,
        ),
    ];
    let seeds: Vec<Vec<u8>> = models
        .iter()
        .map(|m| serde_json::to_vec_pretty(m).unwrap())
        .collect();
    let file = Path::new("models/fuzz/mutant.json");
    soak("model", 3, Syntax::Json, &seeds, file, |bytes, _| {
        ModelFile::from_slice(bytes, file).map(|_| ()).map_err(message)
    });
}

#[test]
fn scenes_survive_mutants() {
    let mut seeds = Vec::new();
    for entry in std::fs::read_dir(manifest_dir().join("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            seeds.push((path.clone(), std::fs::read(&path).unwrap()));
        }
    }
    seeds.sort();
    assert!(!seeds.is_empty(), "no scenes/*.toml");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.toml");
    let seeds: Vec<Vec<u8>> = seeds.into_iter().map(|(_, b)| b).collect();
    soak(
        "scene",
        4,
        Syntax::Toml,
        &seeds,
        &file,
        |bytes, _| match std::str::from_utf8(bytes) {
            Ok(text) => Scene::parse(text, &file).map(|_| ()).map_err(message),
            // Not UTF-8: through the file, as `palpus run` reads it.
            Err(_) => {
                std::fs::write(&file, bytes).map_err(message)?;
                Scene::load(&file).map(|_| ()).map_err(message)
            }
        },
    );
}

#[test]
fn recognizer_files_survive_mutants() {
    // A k-NN over Nakano's rubbing windows, trained on two small surfaces, and the committed
    // SOM: two of the body variants, with their windowing, scaling and class lists.
    let rate_hz = 100.0;
    let mut captures = Vec::new();
    for class in 0..2 {
        for trial in 0..2 {
            let capture = rubbing_capture(class, trial, 500, rate_hz);
            let path = PathBuf::from(format!("surface_{class}_{trial}.csv"));
            let sha = capture::sha256_hex(&capture_bytes(&capture));
            captures.push(LabelledCapture::new(capture, &path, sha).unwrap());
        }
    }
    let mut settings = TrainSettings::new(Method::Knn);
    settings.features = FeatureSet::Nakano;
    let knn = recognize::train(&captures, &settings).unwrap();
    let seeds = vec![
        serde_json::to_vec_pretty(&knn).unwrap(),
        std::fs::read(manifest_dir().join("assets/models/nakano_som.json")).unwrap(),
    ];
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("recognizer.json");
    soak(
        "recognizer",
        5,
        Syntax::Json,
        &seeds,
        &file,
        |bytes, _| match std::str::from_utf8(bytes) {
            Ok(text) => RecognizerFile::from_json(text, &file)
                .map(|_| ())
                .map_err(message),
            // Not UTF-8: through the file, as `palpus recognize` reads it.
            Err(_) => {
                std::fs::write(&file, bytes).map_err(message)?;
                RecognizerFile::load(&file).map(|_| ()).map_err(message)
            }
        },
    );
}
