//! Loop runs the haptics tests share: unpaced, in the test's own thread.
// Each test binary uses some of these, none all of them.
#![allow(dead_code)]

use haptics::HapticDevice;
use haptics::rt::{self, Controller, HapticSample, LoopConfig, LoopIo, LoopShared};

/// An unpaced run that stops after `ticks` ticks.
pub fn unpaced(ticks: u64) -> LoopConfig {
    LoopConfig {
        max_ticks: Some(ticks),
        ..LoopConfig::unpaced()
    }
}

/// Runs `controller` on `device` here for `ticks` unpaced ticks; returns every sample the loop
/// recorded.
pub fn run_unpaced<D, C>(device: &mut D, controller: &mut C, ticks: u64) -> Vec<HapticSample>
where
    D: HapticDevice + ?Sized,
    C: Controller + ?Sized,
{
    let config = unpaced(ticks);
    let shared = LoopShared::new(config.period().unwrap());
    // Room for every tick's sample: an unpaced loop waits for a full ring to drain.
    let (producer, mut consumer) = rtrb::RingBuffer::new(ticks as usize + 1);
    let mut io = LoopIo {
        samples: Some(producer),
        ..LoopIo::default()
    };
    rt::run(device, controller, &mut io, &shared, &config).unwrap();
    std::iter::from_fn(|| consumer.pop().ok()).collect()
}
