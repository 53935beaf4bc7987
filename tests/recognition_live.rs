//! The live recognizer against the offline pipeline on Nakano's simulated rubbing runs: the
//! same decisions on the same windows, no allocation per sample, and the errors of a recognizer
//! that cannot run live.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use haptics::HapticsError;
use haptics::live_recognizer::LiveRecognizer;
use haptics::sim::protocols::nakano::{RUNS, rubbing_run};
use haptics::sim::world::surface::{SurfacePatch, nakano_surfaces};
use recognize::{CellScale, KnnParams, LabelledCapture, NakanoWindowing, RecognizerFile, SomParams};

/// Counts allocations made by the thread that set [`COUNTING`].
struct CountingAllocator;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
static COUNTING: AtomicBool = AtomicBool::new(false);

thread_local! {
    static THIS_THREAD: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) && THIS_THREAD.try_with(|t| t.get()).unwrap_or(false) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same layout contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) && THIS_THREAD.try_with(|t| t.get()).unwrap_or(false) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// `runs[surface][run]`, labelled, generated in memory (seed 1).
fn runs() -> Vec<Vec<LabelledCapture>> {
    nakano_surfaces()
        .iter()
        .map(|surface| {
            let patch = SurfacePatch::new(surface);
            (0..RUNS)
                .map(|run| {
                    let capture = rubbing_run(&patch, run, 1).expect("run");
                    let name = format!("{}_run{run}.csv", surface.name);
                    LabelledCapture::new(capture, Path::new(&name), String::new()).expect("labelled")
                })
                .collect()
        })
        .collect()
}

#[test]
fn live_decisions_equal_offline_decisions_without_allocating() {
    let runs = runs();
    let train: Vec<LabelledCapture> = runs.iter().map(|r| r[0].clone()).collect();
    let windowing = NakanoWindowing::protocol(1000.0).expect("valid");
    let model = RecognizerFile::train_som(&train, windowing, SomParams::default()).expect("train");
    // A copy, as a scene hands each haptic thread: it must have all its storage too.
    let mut live = LiveRecognizer::new(&model, 1000.0)
        .expect("som recognizer")
        .clone();
    assert_eq!(live.classes(), model.classes.as_slice());
    let (mut compared, mut correct) = (0, 0);
    // The counter sees this thread's allocations (a control, so a zero below means something).
    THIS_THREAD.with(|t| t.set(true));
    COUNTING.store(true, Ordering::Relaxed);
    let control: Vec<u8> = Vec::with_capacity(16);
    COUNTING.store(false, Ordering::Relaxed);
    assert_eq!(ALLOCATIONS.swap(0, Ordering::Relaxed), 1);
    drop(control);
    for surface_runs in &runs {
        for c in &surface_runs[1..] {
            let offline = model.decisions(c, None).expect("offline decisions");
            let x = c.capture.column("tangential_position_m").expect("x");
            let z = c.capture.column("normal_position_m").expect("z");
            let f = c.capture.column("friction_force_n").expect("friction");
            live.reset();
            let mut online = Vec::with_capacity(offline.len());
            ALLOCATIONS.store(0, Ordering::Relaxed);
            THIS_THREAD.with(|t| t.set(true));
            COUNTING.store(true, Ordering::Relaxed);
            for i in 0..x.len() {
                // `online` has room for every decision, so pushing onto it never allocates.
                if let Some(d) = live.push(x[i], z[i], f[i]).expect("finite samples")
                    && online.len() < online.capacity()
                {
                    online.push((i, d));
                }
            }
            COUNTING.store(false, Ordering::Relaxed);
            THIS_THREAD.with(|t| t.set(false));
            assert_eq!(
                ALLOCATIONS.load(Ordering::Relaxed),
                0,
                "allocated while recognizing"
            );
            assert_eq!(online.len(), offline.len(), "{}", c.reference.path.display());
            assert!(offline.len() > 15);
            for ((i, live_d), off) in online.iter().zip(&offline) {
                assert_eq!(*i, off.decided_at);
                assert_eq!(live_d.window_start as usize, off.window_start);
                assert_eq!(live_d.label, off.label, "window at {}", off.window_start);
                assert!((live_d.confidence - off.confidence).abs() < 1e-6);
                assert!((0.0..=1.0).contains(&live_d.confidence));
            }
            assert_eq!(live.current().map(|d| d.label), offline.last().map(|d| d.label));
            compared += offline.len();
            correct += offline
                .iter()
                .filter(|d| model.classes[d.label] == c.label)
                .count();
        }
    }
    // 3 s decision windows from 5 mm of travel on: 17 per 6.1 s run.
    assert_eq!(compared, 14 * 17);
    assert!(correct as f64 / compared as f64 > 0.95, "{correct}/{compared}");
}

#[test]
fn only_a_som_at_its_own_rate_runs_live() {
    let runs = runs();
    let train: Vec<LabelledCapture> = runs.iter().map(|r| r[0].clone()).collect();
    let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let model = RecognizerFile::train_som(&train, windowing, SomParams::default()).expect("train");
    assert!(matches!(
        LiveRecognizer::new(&model, 500.0),
        Err(HapticsError::LiveRate { .. })
    ));
    let mut live = LiveRecognizer::new(&model, 1000.0).expect("som");
    let c = &runs[0][1].capture;
    let (x, z, f) = (
        c.column("tangential_position_m").expect("x"),
        c.column("normal_position_m").expect("z"),
        c.column("friction_force_n").expect("f"),
    );
    for i in 0..x.len() {
        live.push(x[i], z[i], f[i]).expect("finite");
    }
    // A NaN is refused at once and never turned into a label; the last decision stands, and
    // the stroke starts afresh: the samples after it give exactly the decisions a fresh
    // recognizer makes on them.
    let before = live.current();
    assert!(before.is_some());
    assert!(matches!(
        live.push(x[0], f64::NAN, f[0]),
        Err(HapticsError::NotFiniteSample { .. })
    ));
    assert_eq!(live.current(), before);
    let mut fresh = LiveRecognizer::new(&model, 1000.0).expect("som");
    let mut decided = 0;
    for i in 0..x.len() {
        let recovered = live.push(x[i], z[i], f[i]).expect("finite");
        assert_eq!(
            recovered,
            fresh.push(x[i], z[i], f[i]).expect("finite"),
            "sample {i}"
        );
        decided += usize::from(recovered.is_some());
    }
    assert!(decided > 10, "{decided}");
    assert_eq!(live.current(), fresh.current());
    live.reset();
    assert_eq!(live.current(), None);

    // A k-NN recognizer needs whole scratches: it cannot run live.
    let scratches: Vec<LabelledCapture> = haptics::sim::world::scratch::household_surfaces()
        .iter()
        .take(2)
        .flat_map(|s| {
            (0..3).map(move |t| {
                let c = haptics::sim::protocols::sinapov::scratch_capture(
                    s,
                    haptics::sim::world::scratch::Behaviour::ALL[0],
                    t,
                    1,
                )
                .expect("scratch");
                LabelledCapture::new(c, Path::new("scratch.csv"), String::new()).expect("labelled")
            })
        })
        .collect();
    let knn = RecognizerFile::train_knn(&scratches, KnnParams::default(), CellScale::Mean).expect("knn");
    assert!(matches!(
        LiveRecognizer::new(&knn, 1000.0),
        Err(HapticsError::LiveMethod {
            method: "knn",
            features: "spectral"
        })
    ));
}

/// The recognizer inside the haptic tick, on the simulated Omega.7 rubbing a track none of the
/// committed recognizer's training captures used: the loop allocates nothing, and the
/// decisions the tick writes into the samples are exactly the offline pipeline's on the capture
/// recorded from the same samples.
#[test]
fn the_haptic_tick_decides_as_the_offline_pipeline_on_its_own_recording() {
    use capture::{Capture, Metadata};
    use haptics::acquire::{CaptureOptions, Protocol, controller, row, sim_device};
    use haptics::live_recognizer::{Recognizing, channel, decision_in};
    use haptics::rt::{self, LoopConfig, LoopIo, LoopShared, Pacing, RtRequest};

    let model_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/nakano_som.json");
    let model = RecognizerFile::load(&model_path).expect("committed recognizer");
    let (mut compared, mut correct) = (0, 0);
    for surface in ["sandpaper_400", "styrol_smooth"] {
        let mut options = CaptureOptions::new(Protocol::Rubbing);
        options.pacing = Pacing::Unpaced;
        options.surface = surface.to_owned();
        options.track_offset_m = 0.25;
        let mut device = sim_device(&options).expect("sim");
        // A copy, as a scene hands each haptic thread.
        let live = LiveRecognizer::new(&model, 1000.0).expect("som").clone();
        let mut c = Recognizing::new(controller(Protocol::Rubbing), live);
        let config = LoopConfig {
            pacing: Pacing::Unpaced,
            rt: RtRequest::NONE,
            watchdog: None,
            max_ticks: Some(12_000),
            ..LoopConfig::default()
        };
        let shared = LoopShared::new(config.period().expect("period"));
        let (producer, mut consumer) = rtrb::RingBuffer::new(12_000);
        let mut io = LoopIo {
            samples: Some(producer),
            live: None,
        };
        // The whole loop, recognizer inside every tick, on this thread: nothing may allocate.
        ALLOCATIONS.store(0, Ordering::Relaxed);
        THIS_THREAD.with(|t| t.set(true));
        COUNTING.store(true, Ordering::Relaxed);
        let run = rt::run(&mut device, &mut c, &mut io, &shared, &config);
        COUNTING.store(false, Ordering::Relaxed);
        THIS_THREAD.with(|t| t.set(false));
        run.expect("loop");
        assert_eq!(
            ALLOCATIONS.load(Ordering::Relaxed),
            0,
            "{surface}: the haptic loop allocated"
        );
        let mut samples = Vec::new();
        while let Ok(s) = consumer.pop() {
            samples.push(s);
        }
        // The capture those samples make, and the tick's decisions by capture row.
        let (mut data, mut tick_decisions) = (Vec::new(), Vec::new());
        let mut made = 0.0;
        for s in &samples {
            let mut r = Vec::new();
            if !row(Protocol::Rubbing, s, &mut r) {
                continue;
            }
            data.push(r);
            let count = s.channels[channel::DECISIONS];
            if count != made {
                made = count;
                tick_decisions.push((data.len() - 1, decision_in(&s.channels).expect("decided")));
            }
        }
        let meta =
            Metadata::new(capture::CaptureKind::Rubbing, "sim-omega7", 1000.0).with("surface", surface);
        let columns = Protocol::Rubbing
            .columns()
            .iter()
            .map(|c| (*c).to_owned())
            .collect();
        let by_column = (0..data[0].len())
            .map(|j| data.iter().map(|r| r[j]).collect())
            .collect();
        let capture = Capture::new(meta, columns, by_column).expect("capture");
        let labelled = LabelledCapture::new(capture, Path::new(surface), String::new()).expect("labelled");
        let offline = model.decisions(&labelled, None).expect("offline");
        assert!(offline.len() > 10, "{surface}: {}", offline.len());
        assert_eq!(tick_decisions.len(), offline.len(), "{surface}");
        for ((at, (label, confidence)), off) in tick_decisions.iter().zip(&offline) {
            assert_eq!(*at, off.decided_at, "{surface}");
            assert_eq!(*label, off.label, "{surface} at {at}");
            assert!((confidence - off.confidence).abs() < 1e-6);
        }
        compared += offline.len();
        correct += offline
            .iter()
            .filter(|d| model.classes[d.label] == surface)
            .count();
    }
    // The two closest surfaces, on a track the recognizer never saw.
    assert!(correct as f64 / compared as f64 > 0.9, "{correct}/{compared}");
}
