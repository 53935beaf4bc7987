//! The recorder: samples from the haptic thread to a capture file, without the haptic thread
//! ever waiting.
//!
//! The haptic thread pushes [`HapticSample`]s into a bounded SPSC ring (`rtrb`); when the ring
//! is full the sample is dropped and counted ([`crate::rt::RateStats::dropped_samples`]) rather
//! than blocking a tick. A recorder thread drains the ring, turns each sample into a capture
//! row through a mapping chosen by the caller, writes it with the strict [`CaptureWriter`], and
//! flushes to the file at least every [`RecorderConfig::flush_interval`] (≤ 100 ms).
//!
//! Crash safety: after a flush every row written so far is in the file as whole lines. A
//! process killed between flushes may leave the rows written since the last flush partly in
//! the file — the writer's buffer can spill to the file on its own when it fills — so the
//! last line of a killed recording may be cut. [`read_recording`] reads such a file: every
//! whole row, and a cut last line reported, not treated as an error.
//!
//! A recording into a file ([`record_to_file`]) never harms what the target held before: it
//! is written to `TARGET.partial` ([`partial_path`]) and only [`Recorder::finish`] syncs it
//! and renames it over the target. A recording that is killed, or that its caller abandons
//! without finishing, leaves the old target untouched and the rows it got in
//! `TARGET.partial`, a capture like any other under a name no `*.csv` scan picks up.

use std::ffi::OsString;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use capture::{CaptureError, CaptureErrorKind, CaptureReader, CaptureWriter, Metadata};

use crate::error::HapticsError;
use crate::rt::HapticSample;

/// Recorder settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecorderConfig {
    /// Ring capacity in samples (4096: four seconds at 1 kHz before anything is dropped).
    pub capacity: usize,
    /// Longest time between flushes to the file (at most 100 ms).
    pub flush_interval: Duration,
    /// Also keep every sample drained, in order, for [`Recorder::finish_with_samples`] (a
    /// session's report reads them); the recorder thread holds them, never the haptic thread.
    pub keep_samples: bool,
}

impl Default for RecorderConfig {
    fn default() -> Self {
        Self {
            capacity: 4096,
            flush_interval: Duration::from_millis(50),
            keep_samples: false,
        }
    }
}

/// Counters the recorder thread updates, readable from anywhere.
#[derive(Debug, Default)]
pub struct RecorderStats {
    written: AtomicU64,
    flushed: AtomicU64,
    rejected: AtomicU64,
    flushes: AtomicU64,
}

impl RecorderStats {
    /// Rows accepted by the writer.
    pub fn rows_written(&self) -> u64 {
        self.written.load(Ordering::Acquire)
    }

    /// Rows known to be in the file (as of the last flush).
    pub fn rows_flushed(&self) -> u64 {
        self.flushed.load(Ordering::Acquire)
    }

    /// Samples the writer rejected (non-finite values, time not increasing).
    pub fn rows_rejected(&self) -> u64 {
        self.rejected.load(Ordering::Acquire)
    }

    /// Flushes done.
    pub fn flushes(&self) -> u64 {
        self.flushes.load(Ordering::Acquire)
    }
}

/// Turns a sample into a capture row (`row` is cleared before the call); returns false to skip
/// the sample (e.g. outside the protocol's recording phase). Any `FnMut(&HapticSample, &mut
/// Vec<f64>) -> bool` is one; [`annotate_then`] also lets work that must stay off the haptic
/// thread write into the sample first.
pub trait RowMap: Send + 'static {
    /// Fills `row` from `sample`, which it may annotate (the recorder keeps the sample as this
    /// leaves it).
    fn map(&mut self, sample: &mut HapticSample, row: &mut Vec<f64>) -> bool;
}

impl<F: FnMut(&HapticSample, &mut Vec<f64>) -> bool + Send + 'static> RowMap for F {
    fn map(&mut self, sample: &mut HapticSample, row: &mut Vec<f64>) -> bool {
        self(sample, row)
    }
}

/// A [`RowMap`] that first lets `annotate` write into each sample (e.g. the live recognizer's
/// decision, computed on the recorder thread instead of in the tick), then maps it with `map`.
pub fn annotate_then<A, M>(annotate: A, map: M) -> AnnotateThen<A, M>
where
    A: FnMut(&mut HapticSample) + Send + 'static,
    M: FnMut(&HapticSample, &mut Vec<f64>) -> bool + Send + 'static,
{
    AnnotateThen { annotate, map }
}

/// See [`annotate_then`].
#[derive(Debug)]
pub struct AnnotateThen<A, M> {
    annotate: A,
    map: M,
}

impl<A, M> RowMap for AnnotateThen<A, M>
where
    A: FnMut(&mut HapticSample) + Send + 'static,
    M: FnMut(&HapticSample, &mut Vec<f64>) -> bool + Send + 'static,
{
    fn map(&mut self, sample: &mut HapticSample, row: &mut Vec<f64>) -> bool {
        (self.annotate)(sample);
        (self.map)(sample, row)
    }
}

/// What the recorder did.
#[derive(Debug)]
pub struct RecorderSummary {
    /// Rows in the file.
    pub rows: u64,
    /// Samples rejected by the writer.
    pub rejected: u64,
    /// The first rejection, if any.
    pub first_rejection: Option<CaptureError>,
}

/// What the recorder thread hands back: the writer and summary, and the samples it kept.
type Finished<W> = (Result<(W, RecorderSummary), HapticsError>, Vec<HapticSample>);

/// A running recorder thread.
#[derive(Debug)]
pub struct Recorder<W: Write + Send + 'static> {
    stats: Arc<RecorderStats>,
    stop: Arc<AtomicBool>,
    thread: JoinHandle<Finished<W>>,
    /// Where a file recording goes once it has finished; `None` for a plain writer.
    placement: Option<Placement<W>>,
}

/// A file recording written under a temporary name, to be put in place when it finishes.
struct Placement<W> {
    partial: PathBuf,
    target: PathBuf,
    /// Makes the written bytes durable before the rename publishes them.
    sync: fn(&W) -> io::Result<()>,
}

impl<W> std::fmt::Debug for Placement<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Placement")
            .field("partial", &self.partial)
            .field("target", &self.target)
            .finish_non_exhaustive()
    }
}

impl<W> Placement<W> {
    /// Syncs the finished file and renames it over the target, so that the target holds
    /// either its old content or the whole new recording, never a mix.
    fn place(&self, file: &W) -> Result<(), HapticsError> {
        (self.sync)(file).map_err(|source| HapticsError::Io {
            action: "sync",
            path: self.partial.clone(),
            source,
        })?;
        std::fs::rename(&self.partial, &self.target).map_err(|source| HapticsError::RecordingNotPlaced {
            partial: self.partial.clone(),
            target: self.target.clone(),
            source,
        })
    }
}

/// The file a recording into `target` is written to until it finishes: `target` with
/// `.partial` appended (`run.csv` → `run.csv.partial`). After a crash it holds the rows the
/// recording got, readable with [`read_recording`] or as any capture; its name keeps it out
/// of folder scans for `*.csv` captures, so a cut recording is never taken for a whole one.
pub fn partial_path(target: &Path) -> PathBuf {
    let mut name = OsString::from(target.as_os_str());
    name.push(".partial");
    PathBuf::from(name)
}

/// Starts recording into `path`; returns the ring's producer for the haptic loop and the
/// recorder.
///
/// The rows go to [`partial_path`]`(path)` (created afresh, replacing a leftover one), and
/// [`Recorder::finish`] syncs that file and renames it over `path`: an existing `path` is
/// replaced only by a recording that finished. A recording that is killed or abandoned leaves
/// `path` as it was and the partial file beside it; one that recorded no row leaves no
/// partial file.
pub fn record_to_file(
    path: &Path,
    meta: &Metadata,
    columns: &[&str],
    map: impl RowMap,
    config: RecorderConfig,
) -> Result<(rtrb::Producer<HapticSample>, Recorder<File>), HapticsError> {
    // Refused now rather than by the rename after the whole recording.
    if path.is_dir() {
        return Err(HapticsError::Io {
            action: "create",
            path: path.to_owned(),
            source: io::Error::new(io::ErrorKind::IsADirectory, "it is a directory"),
        });
    }
    let partial = partial_path(path);
    let file = File::create(&partial).map_err(|source| HapticsError::Io {
        action: "create",
        path: partial.clone(),
        source,
    })?;
    // Errors name the file the rows are in.
    let writer = CaptureWriter::with_source(file, &partial, meta, columns)?;
    let (producer, mut recorder) = Recorder::spawn(writer, map, config)?;
    recorder.placement = Some(Placement {
        partial,
        target: path.to_owned(),
        sync: File::sync_all,
    });
    Ok((producer, recorder))
}

impl<W: Write + Send + 'static> Recorder<W> {
    /// Starts a recorder thread writing through `writer`.
    pub fn spawn(
        mut writer: CaptureWriter<W>,
        mut map: impl RowMap,
        config: RecorderConfig,
    ) -> Result<(rtrb::Producer<HapticSample>, Self), HapticsError> {
        let (producer, mut consumer) = rtrb::RingBuffer::new(config.capacity.max(1));
        let stats = Arc::new(RecorderStats::default());
        let stop = Arc::new(AtomicBool::new(false));
        let (thread_stats, thread_stop) = (stats.clone(), stop.clone());
        let interval = config.flush_interval.min(Duration::from_millis(100));
        // The header is on disk before the first sample arrives.
        writer.flush()?;
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || {
                let mut kept = Vec::new();
                let result = (|| {
                    let mut row = Vec::with_capacity(writer.columns().len());
                    let mut summary = RecorderSummary {
                        rows: 0,
                        rejected: 0,
                        first_rejection: None,
                    };
                    let keep = config.keep_samples;
                    let mut last_flush = Instant::now();
                    loop {
                        let mut drained = 0;
                        while let Ok(mut sample) = consumer.pop() {
                            drained += 1;
                            row.clear();
                            let mapped = map.map(&mut sample, &mut row);
                            if keep {
                                kept.push(sample);
                            }
                            if !mapped {
                                continue;
                            }
                            match writer.write_row(&row) {
                                Ok(()) => {
                                    summary.rows += 1;
                                    thread_stats.written.store(summary.rows, Ordering::Release);
                                }
                                Err(e) if matches!(e.kind, CaptureErrorKind::Io(_)) => return Err(e.into()),
                                Err(e) => {
                                    summary.rejected += 1;
                                    thread_stats.rejected.store(summary.rejected, Ordering::Release);
                                    summary.first_rejection.get_or_insert(e);
                                }
                            }
                            if drained % 256 == 0 && last_flush.elapsed() >= interval {
                                break;
                            }
                        }
                        let finished = consumer.is_empty()
                            && (thread_stop.load(Ordering::Acquire) || consumer.is_abandoned());
                        if last_flush.elapsed() >= interval || finished {
                            writer.flush()?;
                            last_flush = Instant::now();
                            thread_stats.flushed.store(summary.rows, Ordering::Release);
                            thread_stats.flushes.fetch_add(1, Ordering::AcqRel);
                        }
                        if finished {
                            break;
                        }
                        if drained == 0 {
                            std::thread::sleep(Duration::from_millis(2).min(interval));
                        }
                    }
                    let inner = writer.finish()?;
                    Ok((inner, summary))
                })();
                (result, kept)
            })
            .map_err(|source| HapticsError::Spawn {
                thread: "recorder",
                source,
            })?;
        Ok((
            producer,
            Self {
                stats,
                stop,
                thread,
                placement: None,
            },
        ))
    }

    /// Live counters.
    pub fn stats(&self) -> &Arc<RecorderStats> {
        &self.stats
    }

    /// Drains what is left in the ring, finishes the file and returns the underlying writer;
    /// a recording from [`record_to_file`] is then synced and renamed over its target. Call
    /// after the haptic loop has stopped (or drop its producer). Fails with
    /// [`CaptureErrorKind::NoSamples`] when nothing was recorded.
    ///
    /// A recorder dropped without this call stops when its producer is dropped and leaves a
    /// file recording under its partial name.
    pub fn finish(self) -> Result<(W, RecorderSummary), HapticsError> {
        self.finish_with_samples().0
    }

    /// As [`Recorder::finish`], and every sample drained, in order, when
    /// [`RecorderConfig::keep_samples`] was set (else none) — whether or not the file could be
    /// finished (a run that never reached its recording phase has samples but no rows).
    pub fn finish_with_samples(self) -> Finished<W> {
        self.finish_placing(true)
    }

    /// As [`Recorder::finish_with_samples`] for a run that failed: every row is flushed, but a
    /// recording from [`record_to_file`] stays under its partial name, so a failed run never
    /// replaces a good file at the target.
    pub fn abandon(self) -> Finished<W> {
        self.finish_placing(false)
    }

    fn finish_placing(self, place: bool) -> Finished<W> {
        self.stop.store(true, Ordering::Release);
        let (result, kept) = self
            .thread
            .join()
            .unwrap_or_else(|_| (Err(HapticsError::Panicked { thread: "recorder" }), Vec::new()));
        let Some(placement) = self.placement.filter(|_| place) else {
            return (result, kept);
        };
        let result = match result {
            Ok((file, summary)) => placement.place(&file).map(|()| (file, summary)),
            Err(e) => {
                // A header and no row is no recording worth keeping; anything else that
                // failed keeps what it got under the partial name.
                if matches!(&e, HapticsError::Capture(c) if matches!(c.kind, CaptureErrorKind::NoSamples)) {
                    let _ = std::fs::remove_file(&placement.partial);
                }
                Err(e)
            }
        };
        (result, kept)
    }
}

/// A recording read back.
#[derive(Debug)]
pub struct Recording {
    /// The metadata line.
    pub metadata: Metadata,
    /// Column names.
    pub columns: Vec<String>,
    /// Rows, in order.
    pub rows: Vec<Vec<f64>>,
    /// Whether the file ended in a cut line (the recording process died between flushes);
    /// that line is not in `rows`.
    pub truncated: bool,
}

/// Reads a recording that may have been cut short: every whole row, and whether a partial
/// last line was dropped. Any other defect is an error, as for every capture.
pub fn read_recording(path: &Path) -> Result<Recording, CaptureError> {
    let file = File::open(path).map_err(|e| CaptureError::new(path, CaptureErrorKind::Io(e)))?;
    read_recording_from(BufReader::new(file), path)
}

fn read_recording_from<R: BufRead>(inner: R, path: &Path) -> Result<Recording, CaptureError> {
    let mut reader = CaptureReader::new(inner, path, None)?;
    let mut rows = Vec::new();
    let mut row = Vec::new();
    let mut truncated = false;
    loop {
        match reader.read_row(&mut row) {
            Ok(true) => rows.push(row.clone()),
            Ok(false) => break,
            Err(e) if matches!(e.kind, CaptureErrorKind::TruncatedLastLine) => {
                truncated = true;
                break;
            }
            Err(e) if matches!(e.kind, CaptureErrorKind::NoSamples) && rows.is_empty() => break,
            Err(e) => return Err(e),
        }
    }
    Ok(Recording {
        metadata: reader.metadata().clone(),
        columns: reader.columns().to_vec(),
        rows,
        truncated,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use capture::CaptureKind;
    use capture::kind::{AXIAL_FORCE_N, DEPTH_M, TIME_S};

    fn meta() -> Metadata {
        Metadata::new(CaptureKind::Insertion, "sim-omega7", 1000.0)
    }

    const COLUMNS: &[&str] = &[TIME_S, DEPTH_M, AXIAL_FORCE_N];

    fn map(s: &HapticSample, row: &mut Vec<f64>) -> bool {
        row.extend([s.time_s, s.state.position_m.z, s.channels[0]]);
        s.tick.is_multiple_of(2)
    }

    #[test]
    fn records_every_sample_the_map_keeps_and_counts_rejections() {
        let writer = CaptureWriter::new(Vec::new(), &meta(), COLUMNS).unwrap();
        let (mut producer, recorder) = Recorder::spawn(writer, map, RecorderConfig::default()).unwrap();
        for tick in 0..1000u64 {
            let mut s = HapticSample {
                tick,
                time_s: tick as f64 * 1e-3,
                ..HapticSample::default()
            };
            if tick == 500 {
                s.channels[0] = f64::NAN;
            }
            while producer.push(s).is_err() {
                std::thread::yield_now();
            }
        }
        drop(producer);
        let (bytes, summary) = recorder.finish().unwrap();
        assert_eq!(summary.rows, 499);
        assert_eq!(summary.rejected, 1);
        assert!(matches!(
            summary.first_rejection.unwrap().kind,
            CaptureErrorKind::NotFinite
        ));
        let text = String::from_utf8(bytes).unwrap();
        assert_eq!(text.lines().count(), 2 + 499);
    }

    #[test]
    fn kept_samples_are_every_sample_drained_in_order() {
        let writer = CaptureWriter::new(Vec::new(), &meta(), COLUMNS).unwrap();
        let config = RecorderConfig {
            keep_samples: true,
            ..RecorderConfig::default()
        };
        let (mut producer, recorder) = Recorder::spawn(writer, map, config).unwrap();
        for tick in 0..100u64 {
            let s = HapticSample {
                tick,
                time_s: tick as f64 * 1e-3,
                ..HapticSample::default()
            };
            while producer.push(s).is_err() {
                std::thread::yield_now();
            }
        }
        drop(producer);
        let (result, samples) = recorder.finish_with_samples();
        // The map keeps every other row; the kept samples are all of them.
        assert_eq!(result.unwrap().1.rows, 50);
        let ticks: Vec<u64> = samples.iter().map(|s| s.tick).collect();
        assert_eq!(ticks, (0..100).collect::<Vec<_>>());
    }

    #[test]
    fn a_cut_last_line_is_reported_not_fatal() {
        let text = "# palpus-capture format=1 kind=insertion device=sim-omega7 rate_hz=1000 units=si\n\
                    time_s,depth_m,axial_force_n\n0.0,0.0,0.0\n0.001,0.0,0.1\n0.002,0.0";
        let r = read_recording_from(text.as_bytes(), Path::new("cut.csv")).unwrap();
        assert_eq!(r.rows.len(), 2);
        assert!(r.truncated);
        let bad = "# palpus-capture format=1 kind=insertion device=sim-omega7 rate_hz=1000 units=si\n\
                   time_s,depth_m,axial_force_n\n0.0,0.0,0.0\n0.0,0.0,0.1\n";
        assert!(read_recording_from(bad.as_bytes(), Path::new("bad.csv")).is_err());
    }
}
