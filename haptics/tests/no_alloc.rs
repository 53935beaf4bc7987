//! The haptic thread never allocates: a counting global allocator watches 10 000+ ticks of the
//! full path (simulated Omega.7 with a hand and tissue, observers, needle law, admittance,
//! safety, recorder ring, live triple buffer, rate monitor, pacing), and the live view's
//! writers.

#![allow(clippy::unwrap_used)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;
use haptics::rt::{
    self, HapticSample, LoopConfig, LoopIo, LoopShared, Pacing, RateStats, RtRequest, StopReason,
};
use haptics::{Admittance, AdmittanceConfig};
use haptics::{NeedleEnvironment, NeedleLaw, NeedleLawConfig, NeedleQuasiStatic};
use haptics::{SimOmega7, SimOmega7Config, SimWorld};
use sim::{HandImpedance, Waypoints};
use sim::{NeedleSite, NeedleTissue};

struct Counting;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

thread_local! {
    // `const` initialisation: reading it never allocates (no lazy init).
    static WATCHED: Cell<bool> = const { Cell::new(false) };
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if WATCHED.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as ours.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as ours.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if WATCHED.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as ours.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn ten_thousand_ticks_allocate_nothing() {
    const TICKS: u64 = 12_000;
    let surface_z_m = -0.02;
    // Tissue on the device side too (the simulated world's needle site), and the same tissue
    // rendered virtually: the hand inserts 20 mm, punctures, withdraws.
    let mut device = SimOmega7::new(
        SimOmega7Config {
            period_s: 1e-4,
            start_m: DVec3::new(0.0, 0.0, surface_z_m + 0.003),
            ..SimOmega7Config::default()
        },
        SimWorld::needle(NeedleSite::new(NeedleTissue::bovine_liver()), surface_z_m - 0.001),
    )
    .with_hand(HandImpedance::default(), Box::new(fast_insertion(surface_z_m)))
    .with_trace(TICKS as usize);
    let law = NeedleLaw::new(
        NeedleQuasiStatic::new(NeedleTissue::bovine_liver()),
        NeedleLawConfig::default(),
    );
    let mut controller = Admittance::new(
        NeedleEnvironment::new(law, surface_z_m, [0.0, 0.0]),
        AdmittanceConfig::default(),
    );
    let (producer, mut consumer) = rtrb::RingBuffer::<HapticSample>::new(TICKS as usize + 16);
    let (live, _live_out) = triple_buffer::triple_buffer(&HapticSample::default());
    let mut io = LoopIo {
        samples: Some(producer),
        live: Some(live),
    };
    // 10 kHz real-time pacing: the sleep-and-spin path is exercised and 12 000 ticks take
    // about 1.2 s.
    let config = LoopConfig {
        rate_hz: 10_000.0,
        pacing: Pacing::REALTIME,
        rt: RtRequest::NONE,
        watchdog: None,
        max_ticks: Some(TICKS),
    };
    let shared = LoopShared::new(config.period().unwrap());
    let summary = std::thread::spawn(move || {
        WATCHED.with(|w| w.set(true));
        let summary = rt::run(&mut device, &mut controller, &mut io, &shared, &config);
        WATCHED.with(|w| w.set(false));
        (summary.unwrap(), device, shared)
    })
    .join()
    .unwrap();
    let (summary, device, shared) = summary;
    assert_eq!(summary.reason, StopReason::TickLimit);
    assert_eq!(summary.ticks, TICKS);
    assert_eq!(shared.monitor.ticks(), TICKS);
    assert_eq!(
        ALLOCATIONS.load(Ordering::Relaxed),
        0,
        "the haptic thread allocated"
    );
    // The run did something: samples went through the ring, the needle was inserted and the
    // tissue punctured.
    let mut n = 0;
    let mut deepest_state: f64 = 0.0;
    while let Ok(sample) = consumer.pop() {
        n += 1;
        deepest_state = deepest_state.max(sample.channels[haptics::admittance_channel::ENV_STATE]);
    }
    assert_eq!(n, TICKS);
    assert!(
        deepest_state >= haptics::PunctureState::Insertion.code(),
        "{deepest_state}"
    );
    assert!(device.world().needle_site(0.0).unwrap().punctured() >= 1);
}

#[test]
fn the_live_view_writers_allocate_nothing_and_the_reader_gets_the_newest() {
    const CAPACITY: usize = 64;
    let (feed, mut view) = haptics::live_channel(CAPACITY);
    let sample = |tick: u64| HapticSample {
        tick,
        time_s: tick as f64 * 1e-3,
        ..HapticSample::default()
    };
    // Each writer on a thread of its own, as in a session: the newest sample on the haptic
    // thread, the recent samples on the recorder's, the statistics on the supervisor's. More
    // samples than the ring holds, so that the full-ring path runs too.
    let haptics::LiveFeed {
        mut newest,
        mut recent,
        mut stats,
    } = feed;
    let watched = |f: &mut dyn FnMut()| {
        WATCHED.with(|w| w.set(true));
        f();
        WATCHED.with(|w| w.set(false));
    };
    let newest_thread = std::thread::spawn(move || {
        watched(&mut || {
            for tick in 0..1000 {
                newest.write(sample(tick));
            }
        });
    });
    let recent_thread = std::thread::spawn(move || {
        let mut pushed = 0;
        watched(&mut || {
            for tick in 0..1000 {
                pushed += usize::from(recent.push(&sample(tick)));
            }
        });
        (pushed, recent.dropped())
    });
    let stats_thread = std::thread::spawn(move || {
        watched(&mut || {
            for ticks in 1..=100 {
                stats.publish(RateStats {
                    ticks,
                    ..RateStats::default()
                });
            }
        });
    });
    newest_thread.join().unwrap();
    let (pushed, dropped) = recent_thread.join().unwrap();
    stats_thread.join().unwrap();
    assert_eq!(
        ALLOCATIONS.load(Ordering::Relaxed),
        0,
        "a live view writer allocated"
    );
    assert_eq!(view.newest().map(|s| s.tick), Some(999));
    assert_eq!(view.stats().map(|s| s.ticks), Some(100));
    assert_eq!((pushed, dropped), (CAPACITY, 1000 - CAPACITY as u64));
    let mut ticks = Vec::new();
    view.drain(|s| ticks.push(s.tick));
    assert_eq!(ticks, (0..CAPACITY as u64).collect::<Vec<_>>());
}

/// Down 43 mm at 80 mm/s, back up: a puncture within the 1.2 s the test runs.
fn fast_insertion(surface_z_m: f64) -> Waypoints {
    let top = DVec3::new(0.0, 0.0, surface_z_m + 0.003);
    let bottom = DVec3::new(0.0, 0.0, surface_z_m - 0.040);
    Waypoints::new(&[(0.0, top), (0.05, top), (0.6, bottom), (0.7, bottom), (1.2, top)])
}

#[test]
fn the_phase_aware_needle_law_allocates_nothing_along_a_recording() {
    use haptics::{AxialLaw, PhasedNeedleLaw};
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/captures/li_bi/needle_train.csv");
    let capture = capture::Capture::read_file(&path, capture::CaptureKind::Insertion).unwrap();
    let model = identify::identify(
        &capture,
        None,
        &identify::IdentifyOptions::new(identify::ModelKind::NeedlePhases),
    )
    .unwrap()
    .model;
    let mut law = PhasedNeedleLaw::from_file(&model, NeedleLawConfig::default()).unwrap();
    let depth = capture.column("depth_m").unwrap().to_vec();
    let velocity = capture.column("velocity_mps").unwrap().to_vec();
    let (punctures, allocations) = std::thread::spawn(move || {
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        WATCHED.with(|w| w.set(true));
        let mut punctures = 0u32;
        let mut last = haptics::PunctureState::Approach;
        for (&d, &v) in depth.iter().zip(&velocity) {
            let out = law.step(d, v);
            if out.state == haptics::PunctureState::Puncture && last != out.state {
                punctures += 1;
            }
            last = out.state;
        }
        WATCHED.with(|w| w.set(false));
        (punctures, ALLOCATIONS.load(Ordering::Relaxed) - before)
    })
    .join()
    .unwrap();
    assert_eq!(allocations, 0, "the phase-aware law allocated");
    // Five insertions through two layers each.
    assert_eq!(punctures, 10);
}
