//! Best-effort real-time scheduling for the haptic thread: SCHED_FIFO and core pinning where
//! the system permits, and a report of what was granted, so that a loop running without them
//! says so instead of failing silently.

/// What the haptic thread asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RtRequest {
    /// SCHED_FIFO priority to ask for (1–99), or None to stay in the normal scheduler.
    pub fifo_priority: Option<i32>,
    /// Core to pin to.
    pub pin: PinRequest,
}

impl Default for RtRequest {
    fn default() -> Self {
        Self {
            fifo_priority: Some(80),
            pin: PinRequest::LastCoreIfRealtime,
        }
    }
}

impl RtRequest {
    /// Asks for nothing: normal scheduling, no pinning (tests).
    pub const NONE: RtRequest = RtRequest {
        fifo_priority: None,
        pin: PinRequest::None,
    };
}

/// Which core to pin the haptic thread to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PinRequest {
    /// Do not pin.
    None,
    /// Pin to this core.
    Core(usize),
    /// Pin to the last core, but only when SCHED_FIFO was granted: without real-time priority
    /// a pinned thread cannot escape to an idle core when its own is busy, which makes it
    /// later, not earlier.
    LastCoreIfRealtime,
}

/// The scheduling class the haptic thread got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Priority {
    /// SCHED_FIFO at this priority.
    Fifo(i32),
    /// Not asked for.
    Normal,
    /// Asked for and refused (errno, e.g. EPERM without CAP_SYS_NICE or an rtprio limit).
    Refused {
        /// The errno returned.
        errno: i32,
    },
    /// This platform has no SCHED_FIFO.
    Unsupported,
}

/// Where the haptic thread runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pinning {
    /// Pinned to this core.
    Core(usize),
    /// Left to the scheduler.
    Floating,
    /// Asked for and refused (errno).
    Refused {
        /// The core asked for.
        core: usize,
        /// The errno returned.
        errno: i32,
    },
}

/// What the haptic thread was granted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RtStatus {
    /// Scheduling class.
    pub priority: Priority,
    /// Core affinity.
    pub pinning: Pinning,
}

impl std::fmt::Display for RtStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.priority {
            Priority::Fifo(p) => write!(f, "SCHED_FIFO priority {p}")?,
            Priority::Normal => write!(f, "normal scheduling (real-time not requested)")?,
            Priority::Refused { errno } => write!(
                f,
                "normal scheduling: SCHED_FIFO refused (errno {errno}; grant CAP_SYS_NICE or an rtprio limit)"
            )?,
            Priority::Unsupported => write!(f, "normal scheduling: no SCHED_FIFO on this platform")?,
        }
        match self.pinning {
            Pinning::Core(c) => write!(f, ", pinned to core {c}"),
            Pinning::Floating => write!(f, ", not pinned"),
            Pinning::Refused { core, errno } => write!(f, ", pinning to core {core} refused (errno {errno})"),
        }
    }
}

/// Applies `request` to the calling thread and reports what was granted. Never fails: a refusal
/// is a reported fallback. Allocation-free.
pub fn apply_to_current_thread(request: &RtRequest) -> RtStatus {
    let priority = match request.fifo_priority {
        None => Priority::Normal,
        Some(p) => set_fifo(p),
    };
    let core = match request.pin {
        PinRequest::None => None,
        PinRequest::Core(c) => Some(c),
        PinRequest::LastCoreIfRealtime => match priority {
            Priority::Fifo(_) => Some(core_count().saturating_sub(1)),
            _ => None,
        },
    };
    let pinning = match core {
        None => Pinning::Floating,
        Some(c) => pin(c),
    };
    RtStatus { priority, pinning }
}

/// Number of online cores (at least 1).
pub fn core_count() -> usize {
    std::thread::available_parallelism().map_or(1, std::num::NonZero::get)
}

#[cfg(target_os = "linux")]
fn set_fifo(priority: i32) -> Priority {
    let param = libc::sched_param {
        sched_priority: priority.clamp(1, 99),
    };
    // SAFETY: pthread_self() is always a valid handle for the calling thread and `param` is a
    // fully initialised sched_param that outlives the call.
    let rc = unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param) };
    if rc == 0 {
        Priority::Fifo(param.sched_priority)
    } else {
        Priority::Refused { errno: rc }
    }
}

#[cfg(not(target_os = "linux"))]
fn set_fifo(_priority: i32) -> Priority {
    Priority::Unsupported
}

#[cfg(target_os = "linux")]
fn pin(core: usize) -> Pinning {
    if core >= libc::CPU_SETSIZE as usize {
        return Pinning::Refused {
            core,
            errno: libc::EINVAL,
        };
    }
    // SAFETY: cpu_set_t is plain data for which all-zero is the empty set; CPU_SET writes
    // inside it for core < CPU_SETSIZE (checked above); sched_setaffinity reads
    // size_of::<cpu_set_t>() bytes from a live reference. Pid 0 is the calling thread.
    let rc = unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(core, &mut set);
        libc::sched_setaffinity(0, size_of::<libc::cpu_set_t>(), &set)
    };
    if rc == 0 {
        Pinning::Core(core)
    } else {
        Pinning::Refused {
            core,
            errno: std::io::Error::last_os_error().raw_os_error().unwrap_or(0),
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn pin(core: usize) -> Pinning {
    Pinning::Refused { core, errno: 0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_are_granted_or_reported_never_fatal() {
        std::thread::spawn(|| {
            let status = apply_to_current_thread(&RtRequest::default());
            match status.priority {
                Priority::Fifo(p) => assert_eq!(p, 80),
                Priority::Refused { errno } => assert!(errno > 0),
                other => panic!("{other:?}"),
            }
            // Pinning follows the priority: no pin without real time.
            match (status.priority, status.pinning) {
                (Priority::Fifo(_), p) => assert!(matches!(p, Pinning::Core(_) | Pinning::Refused { .. })),
                (_, p) => assert_eq!(p, Pinning::Floating),
            }
            assert!(!status.to_string().is_empty());
        })
        .join()
        .unwrap();
        let none = apply_to_current_thread(&RtRequest::NONE);
        assert_eq!(none.priority, Priority::Normal);
        assert_eq!(none.pinning, Pinning::Floating);
    }

    #[test]
    fn pinning_to_core_zero_works_or_is_reported() {
        std::thread::spawn(|| {
            let s = apply_to_current_thread(&RtRequest {
                fifo_priority: None,
                pin: PinRequest::Core(0),
            });
            assert!(matches!(
                s.pinning,
                Pinning::Core(0) | Pinning::Refused { core: 0, .. }
            ));
            let s = apply_to_current_thread(&RtRequest {
                fifo_priority: None,
                pin: PinRequest::Core(1 << 20),
            });
            assert!(matches!(s.pinning, Pinning::Refused { .. }));
        })
        .join()
        .unwrap();
    }
}
